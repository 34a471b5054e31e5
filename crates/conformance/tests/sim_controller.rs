//! The conformance suite against crackbot's simulated controller with a planted fault, in this
//! process over real UDP on loopback: it fails the matching cases and passes the others. (The
//! controller without a fault passes every case: `tests/robot_cli.rs`,
//! `the_conformance_suite_passes_on_the_controller_process`.)

use std::net::UdpSocket;

use crackbot_conformance::{run_cases, table, Case, CaseResult, Expect, Host, CASES};
use crackbot_controller::sim::sensor::SensorControl;
use crackbot_controller::sim::{shared_world, SimArm};
use crackbot_controller::{
    Arm, ArmState, Checked, ControllerClock, Limits, LinkServer, LinkSettings, Refusal, SimSensor,
};
use crackbot_link::{Key, Security};
use crackbot_sim::Scene;

/// A planted fault: an arm that does not stop.
struct IgnoresStop(SimArm);

/// A planted fault: an arm that claims a workspace twice the scene's (its commands are not
/// checked against the real one).
struct WidenedLimits(SimArm);

macro_rules! delegate {
    ($t:ty, $limits:expr, $stop:expr, $apply:expr) => {
        impl Arm for $t {
            fn limits(&self) -> Limits {
                $limits(&self.0)
            }
            fn now_us(&self) -> u64 {
                self.0.now_us()
            }
            fn apply(&mut self, c: Checked) -> Result<Option<u32>, Refusal> {
                $apply(&mut self.0, c)
            }
            fn stop(&mut self) {
                $stop(&mut self.0)
            }
            fn is_busy(&self) -> bool {
                self.0.is_busy()
            }
            fn state(&self) -> Option<ArmState> {
                self.0.state()
            }
            fn take_finished(&mut self) -> Vec<u32> {
                self.0.take_finished()
            }
            fn fault(&self) -> Option<(u16, String)> {
                self.0.fault()
            }
        }
    };
}

delegate!(
    IgnoresStop,
    |a: &SimArm| a.limits(),
    |_: &mut SimArm| {},
    |a: &mut SimArm, c: Checked| match c {
        Checked::Stop => Ok(None),
        c => a.apply(c),
    }
);
delegate!(
    WidenedLimits,
    |a: &SimArm| {
        let mut l = a.limits();
        l.max_mm = [l.max_mm[0] * 2.0, l.max_mm[1] * 2.0];
        l
    },
    |a: &mut SimArm| a.stop(),
    |a: &mut SimArm, c: Checked| a.apply(c)
);

/// Serves `wrap(the simulated arm)` and runs `cases` against it.
fn check<A: Arm + 'static>(wrap: impl FnOnce(SimArm) -> A, cases: &[Case]) -> Vec<CaseResult> {
    let dir = tempfile::tempdir().expect("tempdir");
    let key = Key::from_bytes(b"crackbot conformance test key 32").expect("key");
    let scene = Scene::builtin_default();
    let shared = shared_world(&scene, 5).expect("world");
    let sensor = SimSensor::spawn(shared.clone(), 1.0).expect("sensor");
    let control: SensorControl = sensor.control();
    let arm = wrap(SimArm::new(
        shared,
        ControllerClock::default(),
        Some(control),
    ));
    let cs = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let hs = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let host_addr = hs.local_addr().expect("addr");
    drop(hs);
    let settings = LinkSettings::new(
        Security::Signed(key.clone()),
        dir.path().join("controller.epoch"),
    );
    let server = LinkServer::spawn(arm, settings, cs, host_addr).expect("controller");
    let link = Host::link_config(Security::Signed(key), dir.path().join("host.epoch"), 1);
    let mut host = Host::connect(host_addr, server.addr(), link).expect("host");
    let results = run_cases(&mut host, &Expect::default(), cases, |r| {
        eprintln!("{}: {} ({})", r.name, r.passed, r.detail);
    })
    .expect("the suite ran");
    eprintln!("{}", table(&results));
    server.shutdown().expect("report");
    sensor.stop().expect("sensor");
    results
}

fn case(name: &str) -> Case {
    *CASES
        .iter()
        .find(|c| c.0 == name)
        .expect("a case of that name")
}

#[test]
fn a_controller_that_does_not_stop_fails_the_stop_and_watchdog_cases_only() {
    let cases = [
        case("a move inside the workspace"),
        case("a stop in every state"),
        case("the watchdog"),
    ];
    let r = check(IgnoresStop, &cases);
    assert!(r[0].passed, "{}", table(&r));
    assert!(!r[1].passed && !r[2].passed, "{}", table(&r));
    assert!(r[1].detail.contains("Stopped"), "{}", r[1].detail);
}

#[test]
fn a_controller_that_checks_a_wider_workspace_fails_the_refusals() {
    let cases = [case("refusals by field"), case("an expired deadline")];
    let r = check(WidenedLimits, &cases);
    assert!(!r[0].passed, "{}", table(&r));
    // The simulated world behind the widened check refuses the point itself, but not by field.
    assert!(
        r[0].detail.starts_with("MoveTo.pose.x_mm"),
        "{}",
        r[0].detail
    );
    assert!(r[1].passed, "{}", table(&r));
}
