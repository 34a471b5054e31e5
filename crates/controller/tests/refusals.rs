//! The simulated controller over real UDP on loopback, signed: commands whose values are out of
//! range, not finite or too late are refused with an `Error` naming the field, and nothing moves;
//! a good command moves the arm and a stop stops it.

use std::net::UdpSocket;
use std::time::{Duration, Instant};

use crackbot_controller::{ServerConfig, SimController};
use crackbot_link::{
    Contact, EpochSource, ErrorCode, ErrorReport, Key, LinkConfig, LinkEndpoint, Message, Mode,
    MoveTo, Point2, Pose, Security, Slide, State,
};
use crackbot_sim::Scene;

struct Host {
    ep: LinkEndpoint,
    last: Option<(State, Instant)>,
    errors: Vec<ErrorReport>,
}

impl Host {
    fn pump(&mut self, d: Duration) {
        let end = Instant::now() + d;
        while Instant::now() < end {
            if let Some(r) = self.ep.recv(Duration::from_millis(2)).expect("recv") {
                match r.message {
                    Message::State(s) => self.last = Some((s, r.at)),
                    Message::Error(e) => self.errors.push(e),
                    _ => {}
                }
            }
        }
    }

    /// The controller's clock now, as the newest state tells it.
    fn controller_now_us(&self) -> u64 {
        let (s, at) = self.last.expect("a state arrived");
        s.controller_time_us + at.elapsed().as_micros() as u64
    }

    fn refusal(&mut self, m: &Message) -> ErrorReport {
        let seq = self.ep.send_reliable(m).expect("acknowledged");
        let end = Instant::now() + Duration::from_secs(5);
        while Instant::now() < end {
            self.pump(Duration::from_millis(10));
            if let Some(e) = self.errors.iter().find(|e| e.seq == seq) {
                return e.clone();
            }
        }
        panic!("no Error reply to {m:?}");
    }

    fn mode(&self) -> Mode {
        self.last.expect("state").0.mode
    }
}

fn slide(depth: f32, valid_until_us: u64) -> Message {
    Message::Slide(Slide {
        id: 1,
        start: Point2 {
            x_mm: 20.0,
            y_mm: 20.0,
        },
        end: Point2 {
            x_mm: 60.0,
            y_mm: 20.0,
        },
        speed_mm_s: 3.89,
        contact: Contact::DepthMm(depth),
        valid_until_us,
    })
}

fn move_to(speed: f32, valid_until_us: u64) -> Message {
    Message::MoveTo(MoveTo {
        pose: Pose {
            x_mm: 40.0,
            y_mm: 30.0,
            z_mm: 5.0,
        },
        speed_mm_s: speed,
        valid_until_us,
    })
}

#[test]
fn bad_values_and_late_commands_are_refused_by_field_and_nothing_moves() {
    let dir = tempfile::tempdir().expect("tempdir");
    let key = Key::from_bytes(b"crackbot controller test key 32B").expect("key");
    let cs = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let hs = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let host_addr = hs.local_addr().expect("addr");
    let config = ServerConfig::new(
        Scene::builtin_default(),
        Security::Signed(key.clone()),
        dir.path().join("controller.epoch"),
    );
    let ctrl = SimController::spawn(&config, cs, host_addr).expect("controller");
    let link = LinkConfig::host(
        Security::Signed(key),
        EpochSource::File(dir.path().join("host.epoch")),
    );
    let mut host = Host {
        ep: LinkEndpoint::from_socket(hs, ctrl.addr(), link).expect("host"),
        last: None,
        errors: Vec::new(),
    };
    let end = Instant::now() + Duration::from_secs(10);
    while host.last.is_none() && Instant::now() < end {
        host.pump(Duration::from_millis(20));
    }
    let start = ctrl.true_pose();
    let soon = |h: &Host| h.controller_now_us() + 1_000_000;

    for (depth, what) in [
        (1e6_f32, "1e6"),
        (-1.0, "-1"),
        (f32::NAN, "NaN"),
        (f32::INFINITY, "inf"),
    ] {
        let e = host.refusal(&slide(depth, soon(&host)));
        assert_eq!(e.code, ErrorCode::InvalidCommand, "depth {what}: {e:?}");
        assert!(
            e.text.starts_with("Slide.contact.DepthMm"),
            "depth {what}: {}",
            e.text
        );
    }
    let e = host.refusal(&move_to(1.4e-45, soon(&host)));
    assert_eq!(e.code, ErrorCode::OverSpeedLimit, "{e:?}");
    assert!(e.text.starts_with("MoveTo.speed_mm_s"), "{}", e.text);

    // A move held back on the network and released later than its deadline is not run.
    let held = move_to(20.0, host.controller_now_us() + 200_000);
    host.pump(Duration::from_millis(400));
    let e = host.refusal(&held);
    assert_eq!(e.code, ErrorCode::Expired, "{e:?}");
    assert!(e.text.starts_with("MoveTo.valid_until_us"), "{}", e.text);
    host.pump(Duration::from_millis(100));
    assert_eq!(ctrl.true_pose(), start, "a refused command moved the arm");

    // A good move runs; a stop stops it.
    let seq = host
        .ep
        .send_reliable(&move_to(20.0, soon(&host)))
        .expect("move");
    host.pump(Duration::from_millis(150));
    assert!(
        host.errors.iter().all(|e| e.seq != seq),
        "{:?}",
        host.errors
    );
    assert_ne!(
        ctrl.true_pose(),
        start,
        "the good move did not move the arm"
    );
    host.ep.send_reliable(&Message::Stop).expect("stop");
    host.pump(Duration::from_millis(100));
    assert_eq!(host.mode(), Mode::Stopped);
    let report = ctrl.shutdown().expect("shutdown");
    assert_eq!(report.refused, 6, "{report:?}");
}
