//! Test harness: endpoints on 127.0.0.1, one pumped in its own thread, a tap between host and
//! controller that records (and may withhold) what the host sends, and an attacker socket.
#![allow(
    dead_code,
    reason = "included by several test or bench crates, each using a subset: dead in some, not in others"
)]

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crackbot_link::wire::{self, Body, Header, Kind};
use crackbot_link::{
    EpochSource, Key, LinkConfig, LinkEndpoint, LinkStats, Message, Received, Security, Signer,
    NODE_HOST, SCHEMA_HASH,
};

pub const LOCALHOST: &str = "127.0.0.1:0";

pub fn key() -> Key {
    Key::from_bytes(b"crackbot link test key, 32 bytes").expect("key")
}

pub fn other_key() -> Key {
    Key::from_bytes(b"another link key of 32 bytes....").expect("key")
}

pub fn socket() -> UdpSocket {
    UdpSocket::bind(LOCALHOST).expect("bind 127.0.0.1")
}

/// A temporary folder for epoch files.
pub struct Dir(pub tempfile::TempDir);

impl Dir {
    pub fn new() -> Self {
        Dir(tempfile::tempdir().expect("tempdir"))
    }

    pub fn epoch(&self, name: &str) -> EpochSource {
        EpochSource::File(self.path(name))
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }
}

/// Short timeouts for tests.
pub fn fast(mut c: LinkConfig) -> LinkConfig {
    c.ack_timeout = Duration::from_millis(40);
    c.max_attempts = 8;
    c
}

pub fn host_config(key: Key, dir: &Dir) -> LinkConfig {
    fast(LinkConfig::host(
        Security::Signed(key),
        dir.epoch("host.epoch"),
    ))
}

pub fn controller_config(key: Key, dir: &Dir) -> LinkConfig {
    fast(LinkConfig::controller(
        Security::Signed(key),
        dir.epoch("controller.epoch"),
    ))
}

#[derive(Default)]
struct Shared {
    delivered: Vec<Received>,
    stats: LinkStats,
}

/// An endpoint pumped by its own thread (as the controller's loop would), recording what it
/// delivers and its counters.
pub struct Remote {
    pub addr: SocketAddr,
    stop: Arc<AtomicBool>,
    shared: Arc<Mutex<Shared>>,
    handle: Option<JoinHandle<LinkEndpoint>>,
}

impl Remote {
    pub fn spawn(mut ep: LinkEndpoint) -> Self {
        let addr = ep.local_addr();
        let stop = Arc::new(AtomicBool::new(false));
        let shared = Arc::new(Mutex::new(Shared::default()));
        let (s, sh) = (stop.clone(), shared.clone());
        let handle = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                let r = ep.recv(Duration::from_millis(2)).expect("recv");
                let mut g = sh.lock().expect("lock");
                if let Some(r) = r {
                    g.delivered.push(r);
                }
                g.stats = ep.stats();
            }
            ep
        });
        Self {
            addr,
            stop,
            shared,
            handle: Some(handle),
        }
    }

    pub fn delivered(&self) -> Vec<Received> {
        self.shared.lock().expect("lock").delivered.clone()
    }

    pub fn stats(&self) -> LinkStats {
        self.shared.lock().expect("lock").stats
    }

    /// Waits until `pred` holds (true) or `timeout` passes (false).
    pub fn wait_until(
        &self,
        timeout: Duration,
        pred: impl Fn(&[Received], &LinkStats) -> bool,
    ) -> bool {
        let end = Instant::now() + timeout;
        loop {
            {
                let g = self.shared.lock().expect("lock");
                if pred(&g.delivered, &g.stats) {
                    return true;
                }
            }
            if Instant::now() > end {
                return false;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Lets the thread run a little longer (so that what is in flight gets processed).
    #[expect(
        clippy::unused_self,
        reason = "a verb of the remote, as the tests read it: `remote.settle()`"
    )]
    pub fn settle(&self) {
        std::thread::sleep(Duration::from_millis(30));
    }

    /// Stops the thread and returns the endpoint (this `Remote` is then inert).
    pub fn stop(&mut self) -> LinkEndpoint {
        self.stop.store(true, Ordering::Relaxed);
        self.handle
            .take()
            .expect("running")
            .join()
            .expect("remote thread")
    }
}

impl Drop for Remote {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// A man in the middle on the host → controller path: records every datagram the host sends,
/// and forwards it to the controller while `forward` is on.
pub struct Tap {
    pub addr: SocketAddr,
    captured: Arc<Mutex<Vec<Vec<u8>>>>,
    forward: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

impl Tap {
    pub fn new(to: SocketAddr) -> Self {
        let sock = socket();
        sock.set_read_timeout(Some(Duration::from_millis(2)))
            .expect("timeout");
        let addr = sock.local_addr().expect("addr");
        let captured = Arc::new(Mutex::new(Vec::new()));
        let forward = Arc::new(AtomicBool::new(true));
        let stop = Arc::new(AtomicBool::new(false));
        let (c, f, s) = (captured.clone(), forward.clone(), stop.clone());
        let handle = std::thread::spawn(move || {
            let mut buf = [0u8; 2048];
            while !s.load(Ordering::Relaxed) {
                if let Ok((n, _)) = sock.recv_from(&mut buf) {
                    c.lock().expect("lock").push(buf[..n].to_vec());
                    if f.load(Ordering::Relaxed) {
                        let _ = sock.send_to(&buf[..n], to);
                    }
                }
            }
        });
        Self {
            addr,
            captured,
            forward,
            stop,
            handle: Some(handle),
        }
    }

    pub fn set_forward(&self, on: bool) {
        self.forward.store(on, Ordering::Relaxed);
    }

    /// Everything captured so far.
    pub fn captured(&self) -> Vec<Vec<u8>> {
        self.captured.lock().expect("lock").clone()
    }

    /// The data packets captured so far.
    pub fn data(&self) -> Vec<Vec<u8>> {
        self.captured()
            .into_iter()
            .filter(|d| wire::parse(d).is_ok_and(|p| p.kind == Kind::Data))
            .collect()
    }

    /// Waits for `n` data packets to have been captured.
    pub fn wait_data(&self, n: usize) -> Vec<Vec<u8>> {
        let end = Instant::now() + Duration::from_secs(5);
        loop {
            let d = self.data();
            if d.len() >= n || Instant::now() > end {
                return d;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    pub fn clear(&self) {
        self.captured.lock().expect("lock").clear();
    }
}

impl Drop for Tap {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// A host in the test thread, a controller in its own thread, and a tap between them.
pub struct Rig {
    pub host: LinkEndpoint,
    pub controller: Remote,
    pub tap: Tap,
    pub attacker: UdpSocket,
    pub dir: Dir,
}

impl Rig {
    /// Host and controller with `key`, synchronised both ways.
    pub fn signed() -> Self {
        Self::with(|d| host_config(key(), d), |d| controller_config(key(), d))
    }

    /// Host and controller made by these configurations (given the rig's folder for epoch
    /// files), synchronised both ways.
    pub fn with(
        host: impl FnOnce(&Dir) -> LinkConfig,
        controller: impl FnOnce(&Dir) -> LinkConfig,
    ) -> Self {
        let dir = Dir::new();
        let host = host(&dir);
        let hs = socket();
        let cs = socket();
        let tap = Tap::new(cs.local_addr().expect("addr"));
        let host_addr = hs.local_addr().expect("addr");
        let host = LinkEndpoint::from_socket(hs, tap.addr, host).expect("host");
        let ctrl = LinkEndpoint::from_socket(cs, host_addr, controller(&dir)).expect("controller");
        let controller = Remote::spawn(ctrl);
        let mut rig = Self {
            host,
            controller,
            tap,
            attacker: socket(),
            dir,
        };
        rig.sync();
        rig
    }

    /// Pumps the host until both ends accept each other's packets.
    pub fn sync(&mut self) {
        let end = Instant::now() + Duration::from_secs(5);
        while Instant::now() < end {
            let _ = self.host.recv(Duration::from_millis(2)).expect("recv");
            if self.host.is_synced() && self.controller.stats().resyncs >= 1 {
                return;
            }
        }
        panic!(
            "no synchronisation: host {:?}, controller {:?}",
            self.host.stats(),
            self.controller.stats()
        );
    }

    /// Restarts the controller: stops it, closes its socket, binds the same port again with
    /// `config` (fresh memory). Returns the old epoch.
    pub fn restart_controller(&mut self, config: impl FnOnce(&Dir) -> LinkConfig) -> u32 {
        let addr = self.controller.addr;
        let old = self.controller.stop();
        let epoch = old.epoch();
        drop(old);
        let s = UdpSocket::bind(addr).expect("rebind the controller's port");
        let ep = LinkEndpoint::from_socket(s, self.host.local_addr(), config(&self.dir))
            .expect("restarted controller");
        self.controller = Remote::spawn(ep);
        epoch
    }

    /// Restarts the host: closes its socket, binds the same port again with `config` (fresh
    /// memory). Returns the old epoch.
    pub fn restart_host(&mut self, config: impl FnOnce(&Dir) -> LinkConfig) -> u32 {
        let addr = self.host.local_addr();
        let epoch = self.host.epoch();
        // A stand-in while the port is closed and bound again.
        let stand_in = LinkEndpoint::from_socket(
            socket(),
            self.tap.addr,
            LinkConfig::host(Security::UnsignedInsecure, EpochSource::Fixed(1)),
        )
        .expect("stand-in");
        drop(std::mem::replace(&mut self.host, stand_in));
        let s = UdpSocket::bind(addr).expect("rebind the host's port");
        self.host =
            LinkEndpoint::from_socket(s, self.tap.addr, config(&self.dir)).expect("restarted host");
        epoch
    }

    /// Sends `done(i)` for each `i` unreliably from the host, 20 at a time, waiting after each
    /// batch until the controller has processed the datagrams (loopback drops what does not fit
    /// into the receiving socket's buffer, and a loaded machine may not run the controller's
    /// thread for a while).
    pub fn send_paced(&mut self, ids: impl IntoIterator<Item = u32>) {
        let base = self.controller.stats().received;
        let mut sent = 0;
        for i in ids {
            self.host.send_unreliable(&done(i)).expect("send");
            sent += 1;
            if sent % 20 == 0 {
                assert!(
                    self.controller
                        .wait_until(WAIT, |_, s| s.received >= base + sent),
                    "the controller did not receive {sent} datagrams"
                );
            }
        }
    }

    /// Pumps the host for `d` (answering challenges), returning what it received.
    pub fn pump_host(&mut self, d: Duration) -> Vec<Received> {
        pump(&mut self.host, d)
    }

    /// Sends raw bytes to the controller from the attacker's socket.
    pub fn inject(&self, bytes: &[u8]) {
        self.attacker
            .send_to(bytes, self.controller.addr)
            .expect("inject");
    }
}

/// Pumps `ep` for `d`, returning what it received.
pub fn pump(ep: &mut LinkEndpoint, d: Duration) -> Vec<Received> {
    let end = Instant::now() + d;
    let mut out = Vec::new();
    loop {
        let left = end.saturating_duration_since(Instant::now());
        if let Some(r) = ep.recv(left.min(Duration::from_millis(2))).expect("recv") {
            out.push(r);
        }
        if Instant::now() >= end {
            return out;
        }
    }
}

/// The header the host would write (sender host, link 1, our schema).
pub fn host_header(epoch: u32, counter: u64, seq: u32, ack_requested: bool) -> Header {
    Header {
        ack_requested,
        sender: NODE_HOST,
        link_id: 1,
        schema: SCHEMA_HASH,
        epoch,
        counter,
        seq,
    }
}

/// A `MoveTo` to `x`.
pub fn move_to(x: f32) -> Message {
    Message::MoveTo(crackbot_link::MoveTo {
        pose: crackbot_link::Pose {
            x_mm: x,
            y_mm: 2.0,
            z_mm: 3.0,
        },
        speed_mm_s: 20.0,
        valid_until_us: 1_000_000,
    })
}

/// Encodes a packet as the host would (sender host, link 1, our schema), signed with `key` or
/// unsigned.
pub fn forge(key: Option<&Key>, epoch: u32, counter: u64, seq: u32, message: Message) -> Vec<u8> {
    forge_header(key, host_header(epoch, counter, seq, false), message)
}

pub fn forge_header(key: Option<&Key>, header: Header, message: Message) -> Vec<u8> {
    let signer = key.map(Signer::new);
    let mut out = [0u8; crackbot_link::MAX_DATAGRAM];
    let n = wire::encode(&header, &Body::Data(message), signer.as_ref(), &mut out).expect("encode");
    out[..n].to_vec()
}

pub fn header_of(datagram: &[u8]) -> Header {
    wire::parse(datagram).expect("our packet").header
}

pub fn heartbeat() -> Message {
    Message::Heartbeat
}

/// A distinguishable message.
pub fn done(id: u32) -> Message {
    Message::Done { slide_id: id }
}

pub fn ids(r: &[Received]) -> Vec<u32> {
    r.iter()
        .filter_map(|r| match r.message {
            Message::Done { slide_id } => Some(slide_id),
            _ => None,
        })
        .collect()
}

pub const WAIT: Duration = Duration::from_secs(5);
