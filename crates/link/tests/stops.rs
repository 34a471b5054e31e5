//! A stop always stops: whatever authentic, forged, replayed or corrupt packets came before, a
//! later `Stop` of the real host is delivered, on the state machine (property tests, no sockets)
//! and over loopback UDP (the independent client's attacks of issue 57). Also the challenge rate
//! under a flood, and epochs across fast restarts that lost their epoch file.

mod common;

use std::time::{Duration, Instant};

use common::*;
use crackbot_link::wire::MAX_DATAGRAM;
use crackbot_link::{CoreConfig, Event, Key, LinkCore, Message, Signer};
use proptest::prelude::*;

fn cores(key: &Key) -> (LinkCore, LinkCore) {
    let h = LinkCore::new(CoreConfig::host(1), Some(Signer::new(key)), 1000).expect("host");
    let c = LinkCore::new(CoreConfig::controller(1), Some(Signer::new(key)), 2000).expect("ctrl");
    (h, c)
}

/// `x` challenges `y` and takes the response (time `now`).
fn challenge(x: &mut LinkCore, y: &mut LinkCore, now: u64) {
    let mut buf = [0u8; MAX_DATAGRAM];
    let mut reply = [0u8; MAX_DATAGRAM];
    let mut sink = [0u8; MAX_DATAGRAM];
    if let Some(n) = x.poll_challenge(now, &mut buf) {
        if let Some(m) = y.receive(&buf[..n], &mut reply).reply {
            x.receive(&reply[..m], &mut sink);
        }
    }
}

/// What happens to the controller before the real host's stop.
#[derive(Debug, Clone)]
enum Step {
    /// The host sends a message (reliable or not); the controller receives it.
    HostSends { reliable: bool, stop: bool },
    /// A key holder with broken state (or an attacker with the key) sends this.
    Forged {
        epoch_delta: i64,
        counter: u64,
        seq: u32,
        ack: bool,
        stop: bool,
    },
    /// A packet the host sent earlier, again.
    Replay(prop::sample::Index),
    /// A recorded packet with one bit flipped.
    Flipped(prop::sample::Index, usize),
    /// Bytes off the wire.
    Garbage(Vec<u8>),
    /// The controller challenges and the host answers (time passes).
    Challenges,
}

fn step() -> impl Strategy<Value = Step> {
    let counter = prop_oneof![0u64..3000, Just(u64::MAX), Just(u64::MAX - 1), any::<u64>()];
    let seq = prop_oneof![0u32..300, Just(u32::MAX), any::<u32>()];
    prop_oneof![
        3 => (any::<bool>(), prop::bool::weighted(0.1))
            .prop_map(|(reliable, stop)| Step::HostSends { reliable, stop }),
        3 => (prop_oneof![Just(0i64), -2i64..3, Just(i64::from(u32::MAX))], counter, seq,
              any::<bool>(), prop::bool::weighted(0.2))
            .prop_map(|(epoch_delta, counter, seq, ack, stop)| Step::Forged {
                epoch_delta, counter, seq, ack, stop
            }),
        2 => any::<prop::sample::Index>().prop_map(Step::Replay),
        1 => (any::<prop::sample::Index>(), 0usize..400).prop_map(|(i, b)| Step::Flipped(i, b)),
        1 => prop::collection::vec(any::<u8>(), 0..80).prop_map(Step::Garbage),
        1 => Just(Step::Challenges),
    ]
}

/// Runs `steps` against a synchronised pair; returns the controller's events for the last
/// packet: the real host's reliable stop, sent after everything else.
fn run(steps: &[Step], forger: &Key, key: &Key) -> (Event, Option<usize>) {
    let (mut host, mut ctrl) = cores(key);
    let mut now = 0u64;
    challenge(&mut host, &mut ctrl, now);
    challenge(&mut ctrl, &mut host, now);
    let mut buf = [0u8; MAX_DATAGRAM];
    let mut reply = [0u8; MAX_DATAGRAM];
    let mut recorded: Vec<Vec<u8>> = Vec::new();
    for s in steps {
        now += 3;
        let datagram = match s {
            Step::HostSends { reliable, stop } => {
                let m = if *stop { Message::Stop } else { move_to(1.0) };
                let sent = host
                    .encode_message(&m, *reliable, &mut buf)
                    .expect("encode");
                buf[..sent.len].to_vec()
            }
            Step::Forged {
                epoch_delta,
                counter,
                seq,
                ack,
                stop,
            } => {
                let epoch = (i64::from(host.epoch()) + epoch_delta).clamp(0, i64::from(u32::MAX));
                let m = if *stop { Message::Stop } else { move_to(2.0) };
                forge_header(
                    Some(forger),
                    host_header(epoch as u32, *counter, *seq, *ack),
                    m,
                )
            }
            Step::Replay(i) if !recorded.is_empty() => recorded[i.index(recorded.len())].clone(),
            Step::Flipped(i, bit) if !recorded.is_empty() => {
                let mut d = recorded[i.index(recorded.len())].clone();
                if !d.is_empty() {
                    let b = bit % (d.len() * 8);
                    d[b / 8] ^= 1 << (b % 8);
                }
                d
            }
            Step::Garbage(g) => g.clone(),
            Step::Challenges | Step::Replay(_) | Step::Flipped(..) => {
                now += 25;
                challenge(&mut ctrl, &mut host, now);
                challenge(&mut host, &mut ctrl, now);
                continue;
            }
        };
        ctrl.receive(&datagram, &mut reply);
        // The controller's challenges reach the host, which answers them.
        challenge(&mut ctrl, &mut host, now);
        recorded.push(datagram);
    }
    let sent = host
        .encode_message(&Message::Stop, true, &mut buf)
        .expect("encode");
    let r = ctrl.receive(&buf[..sent.len], &mut reply);
    (r.event, r.reply)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Whatever came before (authentic packets from a peer with broken state, replays, bit
    /// flips, garbage, other epochs), the real host's next stop is delivered and acknowledged.
    #[test]
    fn a_later_stop_always_runs(steps in prop::collection::vec(step(), 0..120), same_key in any::<bool>()) {
        let key = Key::from_bytes(&[0x42; 32]).expect("key");
        let other = Key::from_bytes(&[0x43; 32]).expect("key");
        let forger = if same_key { &key } else { &other };
        let (event, reply) = run(&steps, forger, &key);
        prop_assert!(
            matches!(event, Event::Message { message: Message::Stop, .. }),
            "the stop was not delivered: {:?}", event
        );
        prop_assert!(reply.is_some(), "the stop was not acknowledged");
    }
}

/// The independent client's finding: one authentic packet (next counter) with sequence number
/// 2^32−1 made every later reliable message of the epoch an acknowledged duplicate, a stop
/// included. Now the stop runs, and so does every later reliable message.
#[test]
fn a_sequence_number_at_the_end_silences_nothing() {
    let mut rig = Rig::signed();
    let k = key();
    let (epoch, c) = (rig.host.epoch(), rig.host.counter());
    rig.inject(&forge_header(
        Some(&k),
        host_header(epoch, c + 1, u32::MAX, true),
        Message::Heartbeat,
    ));
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 1));
    // The host's next packet reuses the forged counter: a replay for the window, but a stop.
    rig.host.send_reliable(&Message::Stop).expect("stop acked");
    rig.host.send_reliable(&move_to(5.0)).expect("move acked");
    rig.host.send_reliable(&Message::Stop).expect("stop acked");
    assert!(rig.controller.wait_until(WAIT, |d, _| d
        .iter()
        .filter(|r| r.message == Message::Stop)
        .count()
        == 2));
    let names: Vec<&str> = rig
        .controller
        .delivered()
        .iter()
        .map(|r| r.message.name())
        .collect();
    assert_eq!(names, ["Heartbeat", "Stop", "MoveTo", "Stop"]);
    assert!(rig.controller.stats().sequence_resyncs >= 1);
    assert_eq!(rig.controller.stats().duplicates, 0);
}

/// A stop recorded and replayed, or sent from an epoch the controller is not synchronised to,
/// is still a stop: it runs (the same harm as a dropped packet: the arm stops), while a
/// replayed move never runs twice.
#[test]
fn a_replayed_or_unsynchronised_stop_still_stops_and_a_replayed_move_does_not_move() {
    let mut rig = Rig::signed();
    rig.host.send_reliable(&move_to(1.0)).expect("move");
    rig.host.send_reliable(&Message::Stop).expect("stop");
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 2));
    let data = rig.tap.data();
    for d in &data {
        rig.inject(d);
    }
    let k = key();
    rig.inject(&forge_header(
        Some(&k),
        host_header(rig.host.epoch().wrapping_add(7), 3, 1, true),
        Message::Stop,
    ));
    // Unsigned or forged with another key: never.
    rig.inject(&forge(None, rig.host.epoch(), 1 << 40, 1, Message::Stop));
    rig.inject(&forge(
        Some(&other_key()),
        rig.host.epoch(),
        1 << 40,
        1,
        Message::Stop,
    ));
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.stops_outside_windows >= 2
            && s.rejected_unsigned >= 1
            && s.rejected_bad_tag >= 1));
    rig.controller.settle();
    let got: Vec<&str> = rig
        .controller
        .delivered()
        .iter()
        .map(|r| r.message.name())
        .collect();
    assert_eq!(got.iter().filter(|n| **n == "MoveTo").count(), 1, "{got:?}");
    assert!(got.iter().filter(|n| **n == "Stop").count() >= 3, "{got:?}");
}

/// Replayed old-epoch packets made the controller send about 400 challenges a second while the
/// host answered each. Now at most one per interval (20 ms) leaves, answered or not.
#[test]
fn a_flood_of_old_epoch_packets_gets_at_most_one_challenge_per_interval() {
    let key = Key::from_bytes(&[0x42; 32]).expect("key");
    let (mut host, mut ctrl) = cores(&key);
    challenge(&mut host, &mut ctrl, 0);
    challenge(&mut ctrl, &mut host, 0);
    let old = forge_header(
        Some(&key),
        host_header(999, 5, 1, false),
        Message::Heartbeat,
    );
    let mut buf = [0u8; MAX_DATAGRAM];
    let mut reply = [0u8; MAX_DATAGRAM];
    let mut sink = [0u8; MAX_DATAGRAM];
    let before = ctrl.stats().challenges_sent;
    // 10 000 replays over one second (0.1 ms apart), every challenge answered at once.
    for i in 0..10_000u64 {
        let now_ms = i / 10;
        ctrl.receive(&old, &mut reply);
        if let Some(n) = ctrl.poll_challenge(now_ms, &mut buf) {
            if let Some(m) = host.receive(&buf[..n], &mut reply).reply {
                ctrl.receive(&reply[..m], &mut sink);
            }
        }
    }
    let sent = ctrl.stats().challenges_sent - before;
    assert!(
        (45..=51).contains(&sent),
        "{sent} challenges in one second of flood (at most 1000 / 20 + 1)"
    );
    // The real host is still heard.
    let s = host
        .encode_message(&Message::Heartbeat, false, &mut buf)
        .expect("encode");
    assert!(matches!(
        ctrl.receive(&buf[..s.len], &mut reply).event,
        Event::Message { .. }
    ));
}

/// Packets and challenges of epoch 0 (which no sender uses) are refused before anything else.
#[test]
fn epoch_zero_is_refused() {
    let key = Key::from_bytes(&[0x42; 32]).expect("key");
    let (_, mut ctrl) = cores(&key);
    let mut host0 = LinkCore::new(CoreConfig::host(1), Some(Signer::new(&key)), 1).expect("host");
    let mut buf = [0u8; MAX_DATAGRAM];
    let n = host0.poll_challenge(0, &mut buf).expect("challenge");
    // Rewrite the challenge's epoch to 0 and sign it again.
    buf[16..20].copy_from_slice(&0u32.to_le_bytes());
    host0.resign(&mut buf[..n]).expect("resign");
    let mut reply = [0u8; MAX_DATAGRAM];
    let r = ctrl.receive(&buf[..n], &mut reply);
    assert_eq!(
        r.event,
        Event::Rejected(crackbot_link::Reject::ZeroEpoch),
        "{r:?}"
    );
    assert!(r.reply.is_none());
    assert_eq!(ctrl.stats().rejected_zero_epoch, 1);
}

/// Issue 57, "an epoch reused": with its epoch file lost and restarted within the same second,
/// the controller took the same epoch again, so a recording of the host's answer to its first
/// challenge and of the host's `MoveTo` moved the arm without the key. Restarted twice within
/// one second, the file deleted each time, it takes new epochs and refuses the recording.
#[test]
fn restarts_within_one_second_without_the_epoch_file_refuse_the_recorded_exchange() {
    let mut rig = Rig::signed();
    rig.host.send_reliable(&move_to(7.0)).expect("move");
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 1));
    let recorded = rig.tap.captured();
    assert!(
        recorded.len() >= 2,
        "the response and the move were recorded"
    );
    // The real host goes away; only the recording is left.
    rig.tap.set_forward(false);
    let file = rig.dir.path("controller.epoch");
    let mut epochs = Vec::new();
    let started = Instant::now();
    for _ in 0..2 {
        std::fs::remove_file(&file).expect("lose the epoch file");
        let old = rig.restart_controller(|d| controller_config(key(), d));
        epochs.push(old);
        // The new controller challenges; the recording answers.
        std::thread::sleep(Duration::from_millis(30));
        for d in &recorded {
            rig.inject(d);
        }
        rig.controller.settle();
        assert!(
            rig.controller.delivered().is_empty(),
            "a recorded packet was accepted after a restart"
        );
        assert_eq!(rig.controller.stats().resyncs, 0);
    }
    assert!(
        started.elapsed() < Duration::from_secs(1),
        "the restarts took {:?}: not within one second",
        started.elapsed()
    );
    let last = rig.controller.stop().epoch();
    epochs.push(last);
    let mut unique = epochs.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), 3, "epochs repeated: {epochs:?}");
}
