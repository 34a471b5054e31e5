//! Properties of the codec, the tag and the replay window (proptest).

use std::collections::BTreeSet;

use crackbot_link::wire::{self, Body, Header};
use crackbot_link::{
    Contact, CoreConfig, ErrorCode, ErrorReport, Event, Key, LinkCore, Message, Mode, MoveTo,
    Point2, Pose, ReplayWindow, Signer, Slide, State, Velocity, Verdict, MAX_DATAGRAM, SCHEMA_HASH,
    WINDOW,
};
use proptest::prelude::*;

fn f32s() -> impl Strategy<Value = f32> {
    prop_oneof![
        prop::num::f32::NORMAL
            | prop::num::f32::SUBNORMAL
            | prop::num::f32::ZERO
            | prop::num::f32::INFINITE,
        -2000.0f32..2000.0,
    ]
}

fn pose() -> impl Strategy<Value = Pose> {
    (f32s(), f32s(), f32s()).prop_map(|(x_mm, y_mm, z_mm)| Pose { x_mm, y_mm, z_mm })
}

fn point() -> impl Strategy<Value = Point2> {
    (f32s(), f32s()).prop_map(|(x_mm, y_mm)| Point2 { x_mm, y_mm })
}

fn mode() -> impl Strategy<Value = Mode> {
    prop_oneof![
        Just(Mode::Idle),
        Just(Mode::Moving),
        any::<u32>().prop_map(|id| Mode::Sliding { id }),
        Just(Mode::Stopped),
        any::<u16>().prop_map(|code| Mode::Fault { code }),
    ]
}

fn code() -> impl Strategy<Value = ErrorCode> {
    prop_oneof![
        Just(ErrorCode::OutsideWorkspace),
        Just(ErrorCode::OverSpeedLimit),
        Just(ErrorCode::InvalidCommand),
        Just(ErrorCode::Busy),
        Just(ErrorCode::Faulted),
        Just(ErrorCode::Unsupported),
        Just(ErrorCode::Other),
        Just(ErrorCode::Expired),
    ]
}

fn message() -> impl Strategy<Value = Message> {
    prop_oneof![
        Just(Message::Heartbeat),
        Just(Message::Stop),
        (pose(), f32s(), any::<u64>()).prop_map(|(pose, speed_mm_s, valid_until_us)| {
            Message::MoveTo(MoveTo {
                pose,
                speed_mm_s,
                valid_until_us,
            })
        }),
        (
            any::<u32>(),
            point(),
            point(),
            f32s(),
            f32s(),
            any::<bool>(),
            any::<u64>()
        )
            .prop_map(|(id, start, end, speed_mm_s, c, depth, valid_until_us)| {
                Message::Slide(Slide {
                    id,
                    start,
                    end,
                    speed_mm_s,
                    contact: if depth {
                        Contact::DepthMm(c)
                    } else {
                        Contact::ForceN(c)
                    },
                    valid_until_us,
                })
            }),
        (any::<u64>(), pose(), pose(), mode(), f32s()).prop_map(|(t, p, v, mode, progress)| {
            Message::State(State {
                controller_time_us: t,
                pose: p,
                velocity: Velocity {
                    x_mm_s: v.x_mm,
                    y_mm_s: v.y_mm,
                    z_mm_s: v.z_mm,
                },
                mode,
                slide_progress: progress,
            })
        }),
        (any::<u32>(), code(), "[a-zA-Z0-9 éµ°ß€-]{0,70}")
            .prop_map(|(seq, code, text)| Message::Error(ErrorReport::new(seq, code, &text))),
        any::<u32>().prop_map(|slide_id| Message::Done { slide_id }),
    ]
}

fn header() -> impl Strategy<Value = Header> {
    (
        any::<bool>(),
        any::<u8>(),
        any::<u16>(),
        any::<u32>(),
        any::<u64>(),
        any::<u32>(),
    )
        .prop_map(
            |(ack_requested, sender, link_id, epoch, counter, seq)| Header {
                ack_requested,
                sender,
                link_id,
                schema: SCHEMA_HASH,
                epoch,
                counter,
                seq,
            },
        )
}

fn signer() -> Signer {
    Signer::new(&Key::from_bytes(&[0x5a; 32]).expect("key"))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn signed_and_unsigned_packets_round_trip(h in header(), m in message(), signed in any::<bool>()) {
        let s = signer();
        let signer = signed.then_some(&s);
        let mut out = [0u8; MAX_DATAGRAM];
        let n = wire::encode(&h, &Body::Data(m.clone()), signer, &mut out).expect("encode");
        let p = wire::decode(&out[..n], signer).expect("decode");
        prop_assert_eq!(p.header, h);
        prop_assert_eq!(&p.body, &Body::Data(m));
        // Bit for bit (-0.0 and 0.0 compare equal as floats).
        let mut again = [0u8; MAX_DATAGRAM];
        let k = wire::encode(&p.header, &p.body, signer, &mut again).expect("encode");
        prop_assert_eq!(&out[..n], &again[..k]);
    }

    #[test]
    fn any_single_bit_flip_of_a_signed_packet_is_refused(
        h in header(), m in message(), bit in any::<prop::sample::Index>()
    ) {
        let s = signer();
        let mut out = [0u8; MAX_DATAGRAM];
        let n = wire::encode(&h, &Body::Data(m), Some(&s), &mut out).expect("encode");
        let i = bit.index(n * 8);
        out[i / 8] ^= 1 << (i % 8);
        prop_assert!(wire::decode(&out[..n], Some(&s)).is_err());
    }

    #[test]
    fn arbitrary_bytes_never_panic_and_what_decodes_re_encodes_identically(
        bytes in prop::collection::vec(any::<u8>(), 0..400),
        signed in any::<bool>(),
    ) {
        let s = signer();
        let signer = signed.then_some(&s);
        if let Ok(p) = wire::decode(&bytes, signer) {
            let mut again = [0u8; MAX_DATAGRAM];
            let k = wire::encode(&p.header, &p.body, signer, &mut again).expect("encode");
            prop_assert_eq!(&bytes[..], &again[..k]);
        }
        let _ = wire::parse(&bytes);
    }

    /// Arbitrary payload bytes behind a valid header: only canonical messages decode.
    #[test]
    fn payloads_decode_only_when_canonical(payload in prop::collection::vec(any::<u8>(), 1..80)) {
        if let Ok(m) = wire::decode_message(&payload) {
            let mut again = [0u8; 256];
            let k = wire::encode_message(&m, &mut again).expect("encode");
            prop_assert_eq!(&payload[..], &again[..k]);
        }
    }

}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// The window against a model that remembers every accepted counter.
    #[test]
    fn the_window_accepts_each_counter_at_most_once_and_exactly_as_specified(
        steps in prop::collection::vec(
            prop_oneof![0u64..400, 0u64..3000, Just(u64::MAX), any::<u64>()], 1..300),
        max_jump in prop_oneof![Just(1024u64), 1u64..200],
    ) {
        let mut w = ReplayWindow::new();
        let mut accepted = BTreeSet::from([0u64]);
        let mut top = 0u64;
        for c in steps {
            let expected = if c > top {
                if c - top > max_jump { Verdict::TooFarAhead } else { Verdict::Fresh }
            } else if top - c >= WINDOW {
                Verdict::TooOld
            } else if accepted.contains(&c) {
                Verdict::Replay
            } else {
                Verdict::Fresh
            };
            let got = w.check(c, max_jump);
            prop_assert_eq!(got, expected, "counter {}", c);
            if got == Verdict::Fresh {
                prop_assert!(accepted.insert(c), "accepted twice: {}", c);
                w.accept(c);
                top = top.max(c);
            }
            prop_assert_eq!(w.top(), top);
        }
    }


    /// Two link ends over a network that drops, duplicates and reorders at will (decided by
    /// proptest), without sockets: a message is delivered at most once, only if it was sent,
    /// and a reliable one is acknowledged once it arrives.
    #[test]
    fn two_link_cores_deliver_each_message_at_most_once(
        schedule in prop::collection::vec((0u8..6, any::<prop::sample::Index>()), 1..400),
    ) {
        let key = Key::from_bytes(&[9; 40]).expect("key");
        let mut a = LinkCore::new(CoreConfig::host(3), Some(Signer::new(&key)), 100).expect("a");
        let mut b = LinkCore::new(CoreConfig::controller(3), Some(Signer::new(&key)), 200)
            .expect("b");
        // In flight towards a and towards b.
        let mut to_a: Vec<Vec<u8>> = Vec::new();
        let mut to_b: Vec<Vec<u8>> = Vec::new();
        let mut buf = [0u8; MAX_DATAGRAM];
        let mut reply = [0u8; MAX_DATAGRAM];
        let mut sent = BTreeSet::new();
        let mut delivered = Vec::new();
        let mut now = 0u64;
        let mut next_id = 0u32;
        for (action, pick) in schedule {
            now += 7;
            match action {
                // a sends a new message (reliable or not), or a retry of the last one.
                0 | 1 => {
                    let m = Message::Done { slide_id: next_id };
                    let s = a.encode_message(&m, action == 0, &mut buf).expect("encode");
                    sent.insert(next_id);
                    next_id += 1;
                    to_b.push(buf[..s.len].to_vec());
                }
                // Deliver one packet towards b (removing it), or duplicate it.
                2 | 3 if !to_b.is_empty() => {
                    let i = pick.index(to_b.len());
                    let p = if action == 2 { to_b.remove(i) } else { to_b[i].clone() };
                    let r = b.receive(&p, &mut reply);
                    if let Some(n) = r.reply { to_a.push(reply[..n].to_vec()); }
                    if let Some(n) = b.poll_challenge(now, &mut reply) { to_a.push(reply[..n].to_vec()); }
                    if let Event::Message { message: Message::Done { slide_id }, .. } = r.event {
                        prop_assert!(sent.contains(&slide_id));
                        delivered.push(slide_id);
                    }
                }
                // Deliver one packet towards a.
                4 if !to_a.is_empty() => {
                    let i = pick.index(to_a.len());
                    let p = to_a.remove(i);
                    let r = a.receive(&p, &mut reply);
                    if let Some(n) = r.reply { to_b.push(reply[..n].to_vec()); }
                    if let Some(n) = a.poll_challenge(now, &mut reply) { to_b.push(reply[..n].to_vec()); }
                }
                // Lose a packet.
                5 if !to_b.is_empty() => { let i = pick.index(to_b.len()); to_b.remove(i); }
                _ => {}
            }
        }
        let unique: BTreeSet<_> = delivered.iter().collect();
        prop_assert_eq!(unique.len(), delivered.len(), "delivered twice: {:?}", delivered);
        prop_assert_eq!(b.stats().delivered as usize, delivered.len());
    }
}
