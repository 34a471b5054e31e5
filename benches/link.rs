//! The manipulator link: what signing costs per message (encode + sign against encode only,
//! verify + decode against decode only, the whole receive path of the state machine) and the
//! round trip of a reliable message over loopback UDP (send, ack), signed and unsigned, each with
//! its unsigned baseline in the same run.
//!
//! `cargo bench --bench link` (briefly: `-- --warm-up-time 1 --measurement-time 3`)

use std::hint::black_box;
use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use crackbot_link::wire::{self, Body, Header};
use crackbot_link::{
    CoreConfig, EpochSource, Key, LinkConfig, LinkCore, LinkEndpoint, Message, Mode, MoveTo, Pose,
    Security, Signer, State, Velocity, MAX_DATAGRAM, SCHEMA_HASH,
};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn key() -> Key {
    Key::from_bytes(b"crackbot link bench key, 32 byte").expect("key")
}

/// The controller's 100 Hz state: the most frequent message.
fn state() -> Message {
    Message::State(State {
        controller_time_us: 123_456_789,
        pose: Pose {
            x_mm: 412.5,
            y_mm: -87.25,
            z_mm: 12.0,
        },
        velocity: Velocity {
            x_mm_s: 5.0,
            y_mm_s: 0.0,
            z_mm_s: -0.25,
        },
        mode: Mode::Sliding { id: 17 },
        slide_progress: 0.42,
    })
}

fn header() -> Header {
    Header {
        ack_requested: false,
        sender: 2,
        link_id: 1,
        schema: SCHEMA_HASH,
        epoch: 1_760_000_000,
        counter: 1_000_000,
        seq: 5_000,
    }
}

fn codec(c: &mut Criterion) {
    let signer = Signer::new(&key());
    let body = Body::Data(state());
    let h = header();
    let mut g = c.benchmark_group("link/encode");
    g.throughput(Throughput::Elements(1));
    let mut out = [0u8; MAX_DATAGRAM];
    g.bench_function("state, unsigned (baseline)", |b| {
        b.iter(|| wire::encode(black_box(&h), black_box(&body), None, &mut out).expect("encode"));
    });
    g.bench_function("state, signed", |b| {
        b.iter(|| {
            wire::encode(black_box(&h), black_box(&body), Some(&signer), &mut out).expect("encode")
        });
    });
    g.finish();

    let mut unsigned = [0u8; MAX_DATAGRAM];
    let nu = wire::encode(&h, &body, None, &mut unsigned).expect("encode");
    let mut signed = [0u8; MAX_DATAGRAM];
    let ns = wire::encode(&h, &body, Some(&signer), &mut signed).expect("encode");
    let mut g = c.benchmark_group("link/decode");
    g.throughput(Throughput::Elements(1));
    g.bench_function("state, unsigned (baseline)", |b| {
        b.iter(|| wire::decode(black_box(&unsigned[..nu]), None).expect("decode"));
    });
    g.bench_function("state, verify and decode", |b| {
        b.iter(|| wire::decode(black_box(&signed[..ns]), Some(&signer)).expect("decode"));
    });
    g.bench_function("state, verify only", |b| {
        b.iter(|| {
            let p = wire::parse(black_box(&signed[..ns])).expect("parse");
            assert!(p.verify(&signer));
        });
    });
    g.finish();

    // The whole path of one message through two state machines: encode (and sign) on one,
    // receive (window, verify, decode) on the other.
    let mut g = c.benchmark_group("link/core send+receive");
    g.throughput(Throughput::Elements(1));
    for signed in [false, true] {
        let name = if signed {
            "state, signed"
        } else {
            "state, unsigned (baseline)"
        };
        let s = signed.then(|| Signer::new(&key()));
        let mut a = LinkCore::new(CoreConfig::controller(1), s.clone(), 10).expect("core");
        let mut b = LinkCore::new(CoreConfig::host(1), s, 20).expect("core");
        let (mut buf, mut reply, mut reply2) = (
            [0u8; MAX_DATAGRAM],
            [0u8; MAX_DATAGRAM],
            [0u8; MAX_DATAGRAM],
        );
        // b challenges a, a answers: b accepts a's packets from then on.
        let n = b.poll_challenge(0, &mut buf).expect("challenge");
        let r = a.receive(&buf[..n], &mut reply).reply.expect("response");
        b.receive(&reply[..r], &mut reply2);
        assert!(b.is_synced());
        let m = state();
        g.bench_function(name, |bench| {
            bench.iter(|| {
                let sent = a.encode_message(&m, false, &mut buf).expect("encode");
                let r = b.receive(&buf[..sent.len], &mut reply);
                black_box(r.event);
            });
        });
    }
    g.finish();
}

/// A controller endpoint pumped by its own thread.
struct Peer {
    stop: Arc<AtomicBool>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl Drop for Peer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

fn pair(security: impl Fn() -> Security, dir: &std::path::Path) -> (LinkEndpoint, Peer) {
    let (hs, cs) = (
        UdpSocket::bind("127.0.0.1:0").expect("bind"),
        UdpSocket::bind("127.0.0.1:0").expect("bind"),
    );
    let (ha, ca) = (
        hs.local_addr().expect("addr"),
        cs.local_addr().expect("addr"),
    );
    let tag = if matches!(security(), Security::Signed(_)) {
        "signed"
    } else {
        "unsigned"
    };
    let host = LinkEndpoint::from_socket(
        hs,
        ca,
        LinkConfig::host(
            security(),
            EpochSource::File(dir.join(format!("host-{tag}.epoch"))),
        ),
    )
    .expect("host");
    let mut ctrl = LinkEndpoint::from_socket(
        cs,
        ha,
        LinkConfig::controller(
            security(),
            EpochSource::File(dir.join(format!("ctrl-{tag}.epoch"))),
        ),
    )
    .expect("controller");
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let handle = std::thread::spawn(move || {
        while !s.load(Ordering::Relaxed) {
            let _ = ctrl.recv(Duration::from_millis(5)).expect("recv");
        }
    });
    (
        host,
        Peer {
            stop,
            handle: Some(handle),
        },
    )
}

fn round_trip(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut g = c.benchmark_group("link/loopback round trip");
    g.throughput(Throughput::Elements(1));
    let command = Message::MoveTo(MoveTo {
        pose: Pose {
            x_mm: 100.0,
            y_mm: 50.0,
            z_mm: 20.0,
        },
        speed_mm_s: 30.0,
        valid_until_us: u64::MAX,
    });
    for signed in [false, true] {
        let security = || {
            if signed {
                Security::Signed(key())
            } else {
                Security::UnsignedInsecure
            }
        };
        let (mut host, _peer) = pair(security, dir.path());
        // The first send synchronises both ends (challenges); not measured.
        host.send_reliable(&command).expect("first send");
        let name = if signed {
            "send_reliable, signed"
        } else {
            "send_reliable, unsigned (baseline)"
        };
        g.bench_function(name, |b| {
            b.iter(|| host.send_reliable(black_box(&command)).expect("acked"));
        });
        let s = host.stats();
        assert_eq!(s.timeouts, 0, "{s:?}");
    }
    g.finish();
}

criterion_group!(benches, codec, round_trip);
criterion_main!(benches);
