//! The suite's side of the link: a host that listens to the controller's state stream, sends
//! commands with deadlines from the controller's own clock, and collects refusals and `Done`s.

use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use crackbot_link::{
    EpochSource, ErrorReport, LinkConfig, LinkEndpoint, LinkError, Message, Mode, State,
};

/// A state and when it arrived (on the suite's clock).
#[derive(Debug, Clone, Copy)]
pub struct Heard {
    /// The state.
    pub state: State,
    /// When it arrived.
    pub at: Instant,
}

/// The suite's end of the link.
#[derive(Debug)]
pub struct Host {
    ep: LinkEndpoint,
    /// Every state heard since the last [`Host::take_states`].
    states: Vec<Heard>,
    last: Option<Heard>,
    errors: Vec<ErrorReport>,
    done: Vec<u32>,
}

/// Why the host could not go on.
#[derive(Debug, thiserror::Error)]
pub enum HostError {
    /// The link failed.
    #[error("link: {0}")]
    Link(#[from] LinkError),
    /// The socket failed.
    #[error("socket: {0}")]
    Io(#[from] std::io::Error),
    /// The controller sent no state.
    #[error("no state from the controller in {0:?}: is it running, with this key and link id?")]
    Silent(Duration),
}

impl Host {
    /// Binds `bind` and talks to the controller at `controller` with `link`.
    pub fn connect(
        bind: SocketAddr,
        controller: SocketAddr,
        link: LinkConfig,
    ) -> Result<Host, HostError> {
        let socket = UdpSocket::bind(bind)?;
        Ok(Host {
            ep: LinkEndpoint::from_socket(socket, controller, link)?,
            states: Vec::new(),
            last: None,
            errors: Vec::new(),
            done: Vec::new(),
        })
    }

    /// A host config signed with `security`, its epoch counter in `epoch_file`.
    pub fn link_config(
        security: crackbot_link::Security,
        epoch_file: std::path::PathBuf,
        link_id: u16,
    ) -> LinkConfig {
        LinkConfig::host(security, EpochSource::File(epoch_file)).with_link_id(link_id)
    }

    fn note(&mut self, message: Message, at: Instant) {
        match message {
            Message::State(state) => {
                let h = Heard { state, at };
                self.states.push(h);
                self.last = Some(h);
            }
            Message::Error(e) => self.errors.push(e),
            Message::Done { slide_id } => self.done.push(slide_id),
            _ => {}
        }
    }

    /// Listens for `d` (a heartbeat every 200 ms keeps the watchdog quiet).
    pub fn pump(&mut self, d: Duration) -> Result<(), HostError> {
        self.pump_until(d, |_| false).map(|_| ())
    }

    /// Listens until `done` holds (true) or `d` passed (false).
    pub fn pump_until(
        &mut self,
        d: Duration,
        mut done: impl FnMut(&Host) -> bool,
    ) -> Result<bool, HostError> {
        let end = Instant::now() + d;
        let mut beat = Instant::now();
        while Instant::now() < end {
            if done(self) {
                return Ok(true);
            }
            if beat.elapsed() > Duration::from_millis(200) {
                self.ep.send_unreliable(&Message::Heartbeat)?;
                beat = Instant::now();
            }
            if let Some(r) = self.ep.recv(Duration::from_millis(2))? {
                self.note(r.message, r.at);
            }
        }
        Ok(done(self))
    }

    /// Listens without sending anything (the watchdog's case).
    pub fn listen_silently(&mut self, d: Duration) -> Result<(), HostError> {
        let end = Instant::now() + d;
        while Instant::now() < end {
            if let Some(r) = self.ep.recv(Duration::from_millis(2))? {
                self.note(r.message, r.at);
            }
        }
        Ok(())
    }

    /// Waits up to `d` for the first state.
    pub fn wait_for_state(&mut self, d: Duration) -> Result<(), HostError> {
        if self.pump_until(d, |h| h.last.is_some())? {
            Ok(())
        } else {
            Err(HostError::Silent(d))
        }
    }

    /// The newest state.
    pub fn last(&self) -> Option<State> {
        self.last.map(|h| h.state)
    }

    /// The newest mode (`Idle` before any state).
    pub fn mode(&self) -> Mode {
        self.last.map_or(Mode::Idle, |h| h.state.mode)
    }

    /// The newest pose, mm.
    pub fn pose(&self) -> [f64; 3] {
        self.last.map_or([f64::NAN; 3], |h| {
            let p = h.state.pose;
            [f64::from(p.x_mm), f64::from(p.y_mm), f64::from(p.z_mm)]
        })
    }

    /// The controller's clock now, from the newest state, µs.
    pub fn controller_now_us(&self) -> u64 {
        self.last.map_or(0, |h| {
            h.state.controller_time_us + h.at.elapsed().as_micros() as u64
        })
    }

    /// A deadline `ahead` from now on the controller's clock.
    pub fn deadline(&self, ahead: Duration) -> u64 {
        self.controller_now_us() + ahead.as_micros() as u64
    }

    /// Sends a command reliably; its sequence number.
    pub fn send(&mut self, m: &Message) -> Result<u32, HostError> {
        Ok(self.ep.send_reliable(m)?)
    }

    /// The refusal of the command numbered `seq`, waiting up to `d`.
    pub fn refusal_of(&mut self, seq: u32, d: Duration) -> Result<Option<ErrorReport>, HostError> {
        self.pump_until(d, |h| h.errors.iter().any(|e| e.seq == seq))?;
        Ok(self.errors.iter().find(|e| e.seq == seq).cloned())
    }

    /// Whether slide `id` was reported done.
    pub fn done(&self, id: u32) -> bool {
        self.done.contains(&id)
    }

    /// The states heard since the last call.
    pub fn take_states(&mut self) -> Vec<Heard> {
        std::mem::take(&mut self.states)
    }
}
