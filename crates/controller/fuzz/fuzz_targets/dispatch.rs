//! Fuzz target: the controller's whole receive path, as `crackbot-controller` runs it —
//! datagrams into the link state machine, every delivered message through the command check
//! (`crackbot_controller::check`) and, when accepted, into the simulated arm
//! (`World::apply`). Checks that nothing panics, that whatever the check accepts is finite and
//! inside the limits, and that a delivered stop always leaves the arm stopped.
//!
//! The input is split into chunks at 0xFF bytes. A chunk starting with 0 is a raw datagram (the
//! unsigned link: random bytes never carry a valid tag); any other chunk's rest is a message
//! payload that the synchronised host encodes and sends properly (reliable when the first byte is
//! odd), so the fuzzer reaches the command check with arbitrary field values.
//!
//! Run with `cargo +nightly fuzz run dispatch` in `crates/controller`.
#![no_main]

use std::cell::RefCell;

use crackbot_controller::{check, Checked, Mode, World};
use crackbot_link::wire::{self, MAX_DATAGRAM};
use crackbot_link::{CoreConfig, Event, LinkCore, Message};
use libfuzzer_sys::fuzz_target;

thread_local! {
    static WORLD: RefCell<World> = RefCell::new(
        World::new(&crackbot_sim::Scene::builtin_default(), 1).expect("default scene"),
    );
}

/// `x` challenges `y` and takes the response.
fn challenge(x: &mut LinkCore, y: &mut LinkCore) {
    let mut buf = [0u8; MAX_DATAGRAM];
    let mut reply = [0u8; MAX_DATAGRAM];
    let mut sink = [0u8; MAX_DATAGRAM];
    let n = x.poll_challenge(0, &mut buf).expect("challenge");
    let m = y.receive(&buf[..n], &mut reply).reply.expect("response");
    x.receive(&reply[..m], &mut sink);
}

fn synced() -> (LinkCore, LinkCore) {
    let mut host = LinkCore::new(CoreConfig::host(1), None, 9).expect("host");
    let mut ctrl = LinkCore::new(CoreConfig::controller(1), None, 7).expect("controller");
    challenge(&mut host, &mut ctrl);
    challenge(&mut ctrl, &mut host);
    (host, ctrl)
}

fn accepted_is_in_range(c: &Checked, w: &World) {
    let l = w.limits();
    let inside = |p: [f64; 2]| {
        (l.min_mm[0]..=l.max_mm[0]).contains(&p[0]) && (l.min_mm[1]..=l.max_mm[1]).contains(&p[1])
    };
    match c {
        Checked::Move(m) => {
            assert!(inside(m.to), "{m:?}");
            assert!(m.z_mm.is_finite() && m.speed_mm_s >= 0.1, "{m:?}");
            assert!(m.speed_mm_s <= l.max_travel_speed_mm_s, "{m:?}");
        }
        Checked::Slide(s) => {
            assert!(inside(s.start) && inside(s.end), "{s:?}");
            assert!(s.speed_mm_s >= 0.1 && s.speed_mm_s <= l.max_slide_speed_mm_s, "{s:?}");
        }
        Checked::Stop | Checked::Heartbeat => {}
    }
}

fuzz_target!(|data: &[u8]| {
    let (mut host, mut ctrl) = synced();
    let mut buf = [0u8; MAX_DATAGRAM];
    let mut reply = [0u8; MAX_DATAGRAM];
    WORLD.with(|w| {
        let mut w = w.borrow_mut();
        w.stop();
        for (i, chunk) in data.split(|&b| b == 0xFF).enumerate() {
            let datagram: &[u8] = match chunk.split_first() {
                None => continue,
                Some((0, raw)) => raw,
                Some((&sel, payload)) => {
                    let Ok(m) = wire::decode_message(payload) else { continue };
                    match host.encode_message(&m, sel % 2 == 1, &mut buf) {
                        Ok(s) => &buf[..s.len],
                        Err(_) => continue,
                    }
                }
            };
            let r = ctrl.receive(datagram, &mut reply);
            let _ = ctrl.poll_challenge(i as u64 * 10, &mut reply);
            let Event::Message { message, .. } = r.event else { continue };
            let now_us = i as u64 * 2500;
            if let Ok(c) = check(&message, w.limits(), now_us) {
                accepted_is_in_range(&c, &w);
                let _ = w.apply(c);
                if message == Message::Stop {
                    assert_eq!(w.mode(), Mode::Stopped, "a delivered stop did not stop");
                }
            }
        }
    });
});
