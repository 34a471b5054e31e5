//! The failure classes real deployments of message signing have shown (MAVLink 2's among them),
//! each over real UDP sockets on 127.0.0.1: a host endpoint, a controller endpoint in its own
//! thread, a tap that records what the host sends, and an attacker socket that sends anything
//! to the controller.

mod common;

use std::time::Duration;

use common::*;
use crackbot_link::wire::{Header, FLAG_SIGNED, HEADER_LEN};
use crackbot_link::{EpochFile, LinkConfig, LinkEndpoint, LinkError, Message, Security, TAG_LEN};

/// MAVLink: a replayed packet accepted because the receiver's timestamp state was never
/// advanced. Here every accepted counter is recorded; replays inside the window and below it
/// are refused, reliable ones are not acknowledged again.
#[test]
fn replayed_packets_are_refused_inside_and_below_the_window() {
    let mut rig = Rig::signed();
    for i in 0..5 {
        rig.host.send_unreliable(&done(i)).expect("send");
    }
    rig.host.send_reliable(&done(5)).expect("reliable send");
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 6));
    let captured = rig.tap.data();
    assert_eq!(captured.len(), 6);
    let acks_before = rig.controller.stats().acks_sent;

    for d in &captured {
        rig.inject(d);
    }
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_replay >= 6));
    rig.controller.settle();
    assert_eq!(ids(&rig.controller.delivered()), vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(
        rig.controller.stats().acks_sent,
        acks_before,
        "a replay is not acknowledged"
    );

    // Move the window far beyond the captured packets: they are now too old, still refused.
    rig.send_paced(100..400);
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 306));
    let before = rig.controller.stats().rejected_replay;
    for d in &captured {
        rig.inject(d);
    }
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_replay == before + 6));
    rig.controller.settle();
    assert_eq!(rig.controller.delivered().len(), 306);
}

/// MAVLink refuses any timestamp not above the last one, so a reordered packet is lost. Here a
/// reordered packet is accepted once, and only once.
#[test]
fn reordered_packets_are_accepted_once() {
    let mut rig = Rig::signed();
    rig.tap.set_forward(false);
    for i in 0..20 {
        rig.host.send_unreliable(&done(i)).expect("send");
    }
    let captured = rig.tap.wait_data(20);
    assert_eq!(captured.len(), 20);
    // Deliver them backwards, then every one again.
    for d in captured.iter().rev() {
        rig.inject(d);
    }
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 20));
    for d in &captured {
        rig.inject(d);
    }
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_replay >= 20));
    rig.controller.settle();
    let got = ids(&rig.controller.delivered());
    assert_eq!(got, (0..20).rev().collect::<Vec<_>>());
    assert_eq!(rig.controller.stats().rejected_replay, 20);
}

/// MAVLink: the receiver's timestamp state reset by a restart, after which old packets are
/// accepted again. Here a restarted receiver knows nothing of the peer, so it accepts nothing
/// until a fresh challenge response tells it where the peer's counter stands: everything
/// recorded before is below that.
#[test]
fn a_restarted_receiver_refuses_what_was_recorded_before() {
    let mut rig = Rig::signed();
    for i in 0..5 {
        rig.host.send_unreliable(&done(i)).expect("send");
    }
    rig.host.send_reliable(&done(5)).expect("send");
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 6));
    let captured = rig.tap.data();

    // Restart the controller: same address, same key, same epoch file, fresh memory.
    let old_epoch = rig.restart_controller(|d| controller_config(key(), d));
    assert!(old_epoch > 0);

    // Replays right after the restart: not synchronised, refused; a challenge goes out.
    for d in &captured {
        rig.inject(d);
    }
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_unsynced >= 1));
    // The host answers the challenges; the controller then knows the host's counter.
    rig.pump_host(Duration::from_millis(100));
    assert!(rig.controller.wait_until(WAIT, |_, s| s.resyncs >= 1));
    for d in &captured {
        rig.inject(d);
    }
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_replay >= 6));
    rig.controller.settle();
    assert!(
        rig.controller.delivered().is_empty(),
        "nothing old delivered"
    );

    // The real host goes on as if nothing happened.
    rig.host
        .send_reliable(&done(99))
        .expect("send after the restart");
    assert!(rig.controller.wait_until(WAIT, |d, _| ids(d) == vec![99]));
}

/// The sender restarts: it takes a new epoch from its epoch file, and its old packets (old
/// epoch) are never accepted again, neither before nor after the receiver resynchronises.
#[test]
fn a_restarted_sender_cannot_have_its_old_packets_replayed() {
    let mut rig = Rig::signed();
    for i in 0..5 {
        rig.host.send_unreliable(&done(i)).expect("send");
    }
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 5));
    let captured = rig.tap.data();
    let old_epoch = rig.host.epoch();
    let epoch_file = EpochFile::new(rig.dir.path("host.epoch"));
    assert_eq!(epoch_file.last().expect("epoch file"), Some(old_epoch));

    // Restart the host on the same port with the same epoch file.
    assert_eq!(rig.restart_host(|d| host_config(key(), d)), old_epoch);
    assert!(rig.host.epoch() > old_epoch);
    assert_eq!(
        epoch_file.last().expect("epoch file"),
        Some(rig.host.epoch())
    );

    rig.host
        .send_reliable(&done(10))
        .expect("send in the new epoch");
    assert!(rig.controller.wait_until(WAIT, |d, _| ids(d).contains(&10)));
    let before = rig.controller.stats();
    for d in &captured {
        rig.inject(d);
    }
    // Old epoch: authentic but not the epoch we are synchronised to; a challenge follows, which
    // the live host answers with its current epoch, so nothing changes.
    assert!(rig.controller.wait_until(WAIT, |_, s| s.rejected_unsynced
        >= before.rejected_unsynced + 5));
    rig.pump_host(Duration::from_millis(100));
    rig.controller.settle();
    assert_eq!(ids(&rig.controller.delivered()), vec![0, 1, 2, 3, 4, 10]);
    rig.host
        .send_reliable(&done(11))
        .expect("the host still gets through");
    assert!(rig.controller.wait_until(WAIT, |d, _| ids(d).contains(&11)));
}

/// Unsigned packets while signing is configured: refused, whatever they claim, and an unsigned
/// endpoint gets nothing through to a signed one.
#[test]
fn unsigned_packets_are_refused_while_signing_is_configured() {
    let mut rig = Rig::signed();
    let epoch = rig.host.epoch();
    let next = rig.host.counter() + 1;
    for i in 0..5 {
        rig.inject(&forge(None, epoch, next + i, 100 + i as u32, move_to(1.0)));
    }
    // A real packet with its tag stripped and the signed flag cleared.
    rig.tap.set_forward(false);
    rig.host.send_unreliable(&done(1)).expect("send");
    let mut stripped = rig.tap.wait_data(1)[0].clone();
    stripped.truncate(stripped.len() - TAG_LEN);
    stripped[3] &= !FLAG_SIGNED;
    rig.inject(&stripped);
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_unsigned == 6));
    rig.controller.settle();
    assert!(rig.controller.delivered().is_empty());

    // An endpoint configured unsigned cannot talk to a signed one.
    let dir = Dir::new();
    let (hs, cs) = (socket(), socket());
    let ctrl_addr = cs.local_addr().expect("addr");
    let ctrl = LinkEndpoint::from_socket(
        cs,
        hs.local_addr().expect("addr"),
        controller_config(key(), &dir),
    )
    .expect("controller");
    let remote = Remote::spawn(ctrl);
    let mut unsigned = LinkEndpoint::from_socket(
        hs,
        ctrl_addr,
        fast(LinkConfig::host(
            Security::UnsignedInsecure,
            dir.epoch("h.epoch"),
        )),
    )
    .expect("unsigned host");
    match unsigned.send_reliable(&Message::Stop) {
        Err(LinkError::Timeout { attempts, .. }) => assert_eq!(attempts, 8),
        other => panic!("an unsigned host got through: {other:?}"),
    }
    assert!(remote.wait_until(WAIT, |_, s| s.rejected_unsigned >= 8));
    assert!(remote.delivered().is_empty());
}

/// "Signing on but no key": a key cannot be empty, short or all zero, a key file that is
/// missing or empty is refused, and packets signed with no key, an all-zero key, another key or
/// carrying a zero tag are refused by a signed endpoint.
#[test]
fn signing_without_a_key_accepts_nothing() {
    use crackbot_link::Key;
    assert!(Key::from_bytes(&[]).is_err());
    assert!(Key::from_bytes(&[0; 32]).is_err());
    assert!(Key::from_bytes(&[1; 16]).is_err());
    let dir = Dir::new();
    assert!(Key::from_file(dir.path("missing.key")).is_err());
    let empty = dir.path("empty.key");
    std::fs::write(&empty, "").expect("write");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&empty, std::fs::Permissions::from_mode(0o600)).expect("chmod");
    }
    assert!(Key::from_file(&empty).is_err());

    let mut rig = Rig::signed();
    let epoch = rig.host.epoch();
    let c = rig.host.counter();
    // HMAC with an empty key is computable: a "no key" implementation would produce this.
    let empty_key_tag = {
        use hmac::{KeyInit, Mac};
        let mut p = forge(None, epoch, c + 1, 50, Message::Stop);
        p[3] |= FLAG_SIGNED;
        let mac = <hmac::Hmac<sha2::Sha256> as KeyInit>::new_from_slice(&[]).expect("mac");
        let tag = mac.chain_update(&p).finalize().into_bytes();
        p.extend_from_slice(&tag[..TAG_LEN]);
        p
    };
    let zero_tag = {
        let mut p = forge(Some(&key()), epoch, c + 2, 51, Message::Stop);
        let n = p.len();
        p[n - TAG_LEN..].fill(0);
        p
    };
    let zero_key_tag = {
        let mut p = forge(None, epoch, c + 3, 52, Message::Stop);
        p[3] |= FLAG_SIGNED;
        use hmac::{KeyInit, Mac};
        let mac = <hmac::Hmac<sha2::Sha256> as KeyInit>::new_from_slice(&[0; 32]).expect("mac");
        let tag = mac.chain_update(&p).finalize().into_bytes();
        p.extend_from_slice(&tag[..TAG_LEN]);
        p
    };
    let wrong_key = forge(Some(&other_key()), epoch, c + 4, 53, Message::Stop);
    for p in [&empty_key_tag, &zero_tag, &zero_key_tag, &wrong_key] {
        rig.inject(p);
    }
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_bad_tag == 4));
    rig.controller.settle();
    assert!(rig.controller.delivered().is_empty());
    // None of them burned a counter: the host's next packets get through.
    rig.host.send_reliable(&done(1)).expect("send");
    assert!(rig.controller.wait_until(WAIT, |d, _| ids(d) == vec![1]));
}

/// A packet with a corrupt tag (or a corrupt header or payload under a good tag) is never
/// delivered, and does not consume the counter of the real packet.
#[test]
fn a_packet_with_a_corrupt_tag_is_never_delivered() {
    let mut rig = Rig::signed();
    rig.tap.set_forward(false);
    rig.host.send_unreliable(&move_to(5.0)).expect("send");
    let good = rig.tap.wait_data(1)[0].clone();
    let n = good.len();
    let mut bad_tag = good.clone();
    bad_tag[n - 1] ^= 0x01;
    let mut bad_payload = good.clone();
    bad_payload[HEADER_LEN + 3] ^= 0x40; // inside the x coordinate
    let mut bad_seq = good.clone();
    bad_seq[28] ^= 0x01;
    let mut bad_counter = good.clone();
    bad_counter[27] ^= 0x01; // counter + 2^56
    for p in [&bad_tag, &bad_payload, &bad_seq, &bad_counter] {
        rig.inject(p);
    }
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_bad_tag == 4));
    rig.controller.settle();
    assert!(rig.controller.delivered().is_empty());
    rig.inject(&good);
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 1));
    assert_eq!(rig.controller.delivered()[0].message, move_to(5.0));
}

/// A packet recorded on one link and replayed on another that shares the key is refused: the
/// link id is in the signed header.
#[test]
fn a_replay_from_another_link_is_refused() {
    let mut one = Rig::signed();
    let mut two = Rig::with(
        |d| host_config(key(), d).with_link_id(2),
        |d| controller_config(key(), d).with_link_id(2),
    );
    one.tap.set_forward(false);
    one.host.send_unreliable(&Message::Stop).expect("send");
    let p = one.tap.wait_data(1)[0].clone();
    two.inject(&p);
    // The same bytes with the link id rewritten to 2: the tag no longer verifies.
    let mut relabelled = p.clone();
    relabelled[6] = 2;
    two.inject(&relabelled);
    // Re-signed for link 2 would need the key: that is what the key is for.
    assert!(two
        .controller
        .wait_until(WAIT, |_, s| s.rejected_wrong_link == 1
            && s.rejected_bad_tag == 1));
    two.controller.settle();
    assert!(two.controller.delivered().is_empty());
    // Link two still works.
    two.host.send_reliable(&done(2)).expect("send");
    assert!(two.controller.wait_until(WAIT, |d, _| ids(d) == vec![2]));
    let _ = one.pump_host(Duration::from_millis(1));
}

/// MAVLink: one packet with a timestamp far in the future moves the state so that the real
/// peer's packets are refused for ever. Here a counter more than the jump limit ahead, or an
/// unknown epoch, is refused without moving the state, and makes the receiver challenge the
/// peer, whose fresh answer keeps it where the real peer is. (The forger holds the key: a
/// peer with a broken clock or state.)
#[test]
fn a_far_future_counter_or_epoch_does_not_lock_out_the_real_peer() {
    let mut rig = Rig::signed();
    rig.host.send_reliable(&done(0)).expect("send");
    let epoch = rig.host.epoch();
    let c = rig.host.counter();
    let k = key();
    rig.inject(&forge(Some(&k), epoch, u64::MAX - 1, 900, done(900)));
    rig.inject(&forge(Some(&k), epoch, c + 1_000_000_000, 901, done(901)));
    rig.inject(&forge(Some(&k), epoch, c + 2_000, 902, done(902)));
    rig.inject(&forge(Some(&k), u32::MAX, 5, 903, done(903)));
    rig.inject(&forge(Some(&k), epoch.wrapping_add(1), 5, 904, done(904)));
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_future == 3
            && s.rejected_unsynced == 2));
    // The challenges reach the host, which answers with where it really is.
    rig.pump_host(Duration::from_millis(50));
    rig.controller.settle();
    // The real host is not locked out, not even for one packet.
    for i in 1..=20 {
        rig.host.send_unreliable(&done(i)).expect("send");
    }
    rig.host.send_reliable(&done(21)).expect("reliable send");
    assert!(rig.controller.wait_until(WAIT, |d, _| d.len() == 22));
    assert_eq!(
        ids(&rig.controller.delivered()),
        (0..=21).collect::<Vec<_>>()
    );
}

/// A counter ahead by less than the jump limit is accepted (the forger has the key); the real
/// peer, now behind, is refused only until its counter passes the forged one: a bounded
/// lockout, never a permanent one.
#[test]
fn a_near_future_counter_locks_out_the_real_peer_for_a_bounded_time_only() {
    let mut rig = Rig::signed();
    let epoch = rig.host.epoch();
    let c = rig.host.counter();
    let ahead = 300;
    rig.inject(&forge(Some(&key()), epoch, c + ahead, 999, done(999)));
    assert!(rig.controller.wait_until(WAIT, |d, _| ids(d) == vec![999]));
    rig.send_paced(0..400);
    assert!(rig
        .controller
        .wait_until(WAIT, |d, _| d.len() >= 2 && ids(d).last() == Some(&399)));
    rig.controller.settle();
    let got = ids(&rig.controller.delivered());
    let lost = 400 - (got.len() as u64 - 1);
    // Lost: the host's counters more than a window below the forged one, and the forged one.
    assert!(
        lost <= ahead,
        "{lost} packets refused, more than the jump of {ahead}"
    );
    assert!(lost >= ahead - crackbot_link::WINDOW);
}

/// Our own packets sent back to us (a reflection) are refused: the sender id is signed.
#[test]
fn a_reflected_packet_is_refused() {
    let mut rig = Rig::signed();
    rig.tap.set_forward(false);
    rig.host.send_unreliable(&Message::Stop).expect("send");
    let p = rig.tap.wait_data(1)[0].clone();
    rig.attacker
        .send_to(&p, rig.host.local_addr())
        .expect("reflect");
    let got = rig.pump_host(Duration::from_millis(50));
    assert!(got.is_empty());
    assert_eq!(rig.host.stats().rejected_wrong_sender, 1);
}

/// Peers with different message definitions refuse each other.
#[test]
fn a_peer_with_another_schema_is_refused() {
    let rig = Rig::signed();
    let mut h: Header = header_of(&forge(None, 1, 1, 1, Message::Stop));
    h.epoch = rig.host.epoch();
    h.counter = rig.host.counter() + 1;
    h.schema[0] ^= 0xFF;
    rig.inject(&forge_header(Some(&key()), h, Message::Stop));
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_schema == 1));
    rig.controller.settle();
    assert!(rig.controller.delivered().is_empty());
    // And so do truncated, garbage and foreign datagrams, counted as malformed.
    rig.inject(b"");
    rig.inject(b"hello");
    rig.inject(&[0u8; 100]);
    assert!(rig
        .controller
        .wait_until(WAIT, |_, s| s.rejected_malformed == 3));
}
