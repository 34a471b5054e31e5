//! The arm, through the link: commands, the state stream on the host's clock, positions at any instant.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crackbot_link::{LinkEndpoint, Message, State};

use crate::error::link_err;
use crate::inspect::report::LinkCounters;
use crate::sync::ClockSync;
use crate::MissionError;

/// Longest a move or slide command may take to reach the controller and start (its
/// `valid_until_us`; the link's retries take at most 250 ms).
pub(crate) const COMMAND_MAX_AGE: Duration = Duration::from_millis(1000);

/// One arm state (its controller time maps to the host's clock through the fit).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ArmSample {
    pub(crate) state: State,
}

pub(crate) struct Arm {
    pub(crate) ep: LinkEndpoint,
    pub(crate) sync: ClockSync,
    pub(crate) t0: Instant,
    pub(crate) states: VecDeque<ArmSample>,
    pub(crate) done: Vec<u32>,
    pub(crate) errors: Vec<crackbot_link::ErrorReport>,
    pub(crate) last_heartbeat: Instant,
    pub(crate) last_state_at: Option<Instant>,
    pub(crate) epoch: Option<u32>,
    pub(crate) restarted: bool,
}

impl Arm {
    pub(crate) fn host_us(&self, at: Instant) -> f64 {
        at.saturating_duration_since(self.t0).as_secs_f64() * 1e6
    }

    /// Takes what has arrived (waiting up to `wait`), sends a heartbeat every 200 ms.
    pub(crate) fn pump(&mut self, wait: Duration) -> Result<(), MissionError> {
        if self.last_heartbeat.elapsed() > Duration::from_millis(200) {
            self.ep
                .send_unreliable(&Message::Heartbeat)
                .map_err(talking)?;
            self.last_heartbeat = Instant::now();
        }
        let mut wait = wait;
        while let Some(r) = self.ep.recv(wait).map_err(talking)? {
            wait = Duration::ZERO;
            if let Some(e) = self.epoch {
                if e != r.peer_epoch {
                    self.restarted = true;
                }
            }
            self.epoch = Some(r.peer_epoch);
            match r.message {
                Message::State(s) => {
                    let host = self.host_us(r.at);
                    self.sync.add(s.controller_time_us as f64, host);
                    self.last_state_at = Some(r.at);
                    self.states.push_back(ArmSample { state: s });
                    while self.states.len() > 100_000 {
                        self.states.pop_front();
                    }
                }
                Message::Done { slide_id } => self.done.push(slide_id),
                Message::Error(e) => self.errors.push(e),
                _ => {}
            }
        }
        Ok(())
    }

    pub(crate) fn command(&mut self, m: &Message) -> Result<u32, MissionError> {
        self.ep.send_reliable(m).map_err(talking)
    }

    /// The `valid_until_us` of a command sent now: the controller's clock as the newest state
    /// gave it, advanced by the time since that state arrived, plus [`COMMAND_MAX_AGE`]. A
    /// command the network holds back longer is refused by the controller (`Expired`), not run
    /// late. Before any state, the controller's clock is unknown: no command can be sent.
    pub(crate) fn deadline_us(&self) -> Result<u64, MissionError> {
        let (Some(s), Some(at)) = (self.states.back(), self.last_state_at) else {
            return Err(MissionError::ControllerUnreachable {
                addr: self.ep.peer_addr().to_string(),
            });
        };
        let since = u64::try_from(at.elapsed().as_micros()).unwrap_or(u64::MAX);
        let max_age = u64::try_from(COMMAND_MAX_AGE.as_micros()).unwrap_or(u64::MAX);
        Ok(s.state
            .controller_time_us
            .saturating_add(since)
            .saturating_add(max_age))
    }

    /// Where the arm last said it was (the origin before any state came).
    pub(crate) fn here(&self) -> [f64; 3] {
        self.states.back().map_or([0.0; 3], |s| pose(&s.state))
    }

    /// The host's link counters so far.
    pub(crate) fn counters(&self) -> LinkCounters {
        let s = self.ep.stats();
        LinkCounters {
            sent: s.sent,
            retries: s.retries,
            rejected: s.rejected(),
            duplicates: s.duplicates,
        }
    }

    pub(crate) fn stop(&mut self) {
        // Best effort: the link retries; a dead controller's watchdog stops it anyway.
        let _ = self.ep.send_reliable(&Message::Stop);
    }
}

/// The arm's states on the host's clock, oldest first (mapped with the current clock fit).
pub(crate) fn mapped_states(arm: &mut Arm) -> Vec<(f64, State)> {
    newest_mapped(arm, usize::MAX)
}

/// The arm's newest `n` states on the host's clock, oldest first.
pub(crate) fn newest_mapped(arm: &mut Arm, n: usize) -> Vec<(f64, State)> {
    let skip = arm.states.len().saturating_sub(n);
    let (states, sync) = (&arm.states, &mut arm.sync);
    states
        .iter()
        .skip(skip)
        .filter_map(|s| {
            let host = sync.to_host(s.state.controller_time_us as f64)?;
            Some((host, s.state))
        })
        .collect()
}

/// The arm's pose and mode at host time `host_us`, interpolated between the two states around it.
pub(crate) fn position_at(
    mapped: &[(f64, State)],
    host_us: f64,
) -> Option<([f64; 3], crackbot_link::Mode)> {
    let idx = mapped.partition_point(|(h, _)| *h <= host_us);
    let (first, last) = (mapped.first()?, mapped.last()?);
    if idx == 0 {
        return Some((pose(&first.1), first.1.mode));
    }
    if idx >= mapped.len() {
        return Some((pose(&last.1), last.1.mode));
    }
    let (h0, s0) = mapped[idx - 1];
    let (h1, s1) = mapped[idx];
    let f = if h1 > h0 {
        (host_us - h0) / (h1 - h0)
    } else {
        0.0
    };
    let (p0, p1) = (pose(&s0), pose(&s1));
    Some((
        [
            p0[0] + f * (p1[0] - p0[0]),
            p0[1] + f * (p1[1] - p0[1]),
            p0[2] + f * (p1[2] - p0[2]),
        ],
        if f < 0.5 { s0.mode } else { s1.mode },
    ))
}

/// The arm's pose at host time `host_us` when the states on both sides of it show the finger
/// down (z below 0.5 mm) in slide `id`: a sample between the last state before touchdown and
/// the first one after it may have been taken in the air, and a lifted finger's signals are
/// not the surface's.
pub(crate) fn down_at(mapped: &[(f64, State)], host_us: f64, id: u32) -> Option<[f64; 3]> {
    let idx = mapped.partition_point(|(h, _)| *h <= host_us);
    if idx == 0 || idx >= mapped.len() {
        return None;
    }
    let down =
        |s: &State| s.mode == (crackbot_link::Mode::Sliding { id }) && f64::from(s.pose.z_mm) < 0.5;
    if down(&mapped[idx - 1].1) && down(&mapped[idx].1) {
        position_at(mapped, host_us).map(|(p, _)| p)
    } else {
        None
    }
}

pub(crate) fn pose(s: &State) -> [f64; 3] {
    [
        f64::from(s.pose.x_mm),
        f64::from(s.pose.y_mm),
        f64::from(s.pose.z_mm),
    ]
}

/// The link's error while talking to the controller.
fn talking(e: crackbot_link::LinkError) -> MissionError {
    link_err("talking to the controller", e)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(z: f32, mode: crackbot_link::Mode) -> State {
        State {
            controller_time_us: 0,
            pose: crackbot_link::Pose {
                x_mm: 0.0,
                y_mm: 0.0,
                z_mm: z,
            },
            velocity: crackbot_link::Velocity::default(),
            mode,
            slide_progress: 0.0,
        }
    }

    #[test]
    fn only_samples_between_two_down_states_are_in_the_stroke() {
        use crackbot_link::Mode;
        let mapped = [
            (0.0, state(5.0, Mode::Sliding { id: 3 })),
            (10.0, state(0.0, Mode::Sliding { id: 3 })),
            (20.0, state(0.0, Mode::Sliding { id: 3 })),
            (30.0, state(5.0, Mode::Idle)),
        ];
        // Before touchdown (even where z interpolates below 0.5), after lift-off, outside the
        // states, or in another slide: not in the stroke.
        for t in [-1.0, 5.0, 9.5, 20.5, 29.0, 31.0] {
            assert_eq!(down_at(&mapped, t, 3), None, "{t}");
        }
        for t in [10.0, 15.0, 19.9] {
            assert!(down_at(&mapped, t, 3).is_some(), "{t}");
        }
        assert_eq!(down_at(&mapped, 15.0, 4), None);
    }
}
