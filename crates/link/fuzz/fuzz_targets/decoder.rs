//! Fuzz target: arbitrary datagrams through the packet decoder and the link state machine (the
//! `no_std` core, as the controller runs it). Checks that nothing panics, that whatever decodes
//! re-encodes to the same bytes (the encoding is canonical), and that the state machine never
//! delivers a message twice (a `Stop` excepted: it is delivered whatever the windows say) nor
//! anything the tag does not cover.
//!
//! Run with `cargo fuzz run decoder` in `crates/link` (nightly); `cargo check` here builds it on
//! stable.
#![no_main]

use crackbot_link::wire::{self, Body};
use crackbot_link::{CoreConfig, Event, Key, LinkCore, Message, Signer, MAX_DATAGRAM};
use libfuzzer_sys::fuzz_target;

const KEY: [u8; 32] = *b"crackbot link fuzzing key 32 B!!";

fuzz_target!(|data: &[u8]| {
    let signer = Signer::new(&Key::from_bytes(&KEY).expect("key"));

    // The stateless decoder, signed and unsigned.
    for s in [Some(&signer), None] {
        if let Ok(p) = wire::decode(data, s) {
            let mut again = [0u8; MAX_DATAGRAM];
            let n = wire::encode(&p.header, &p.body, s, &mut again).expect("re-encode");
            assert_eq!(&again[..n], data, "decoded packet re-encodes differently");
            if let Body::Data(m) = &p.body {
                let mut payload = [0u8; 256];
                let k = wire::encode_message(m, &mut payload).expect("payload");
                assert_eq!(&payload[..k], wire::parse(data).expect("parsed").payload);
            }
        }
    }

    // The state machines, signed and unsigned (random bytes never carry a valid tag, so the
    // unsigned one is where the fuzzer reaches the window, the challenges and the payloads),
    // fed the input split into datagrams at 0xFF bytes.
    for signed in [true, false] {
        let s = signed.then(|| signer.clone());
        let mut core = LinkCore::new(CoreConfig::controller(1), s.clone(), 7).expect("core");
        let mut reply = [0u8; MAX_DATAGRAM];
        let mut seen = std::collections::BTreeSet::new();
        for (now, datagram) in data.split(|&b| b == 0xFF).enumerate() {
            let r = core.receive(datagram, &mut reply);
            if let Some(n) = r.reply {
                // Our replies always decode under our key (or none).
                wire::decode(&reply[..n], s.as_ref()).expect("our reply decodes");
            }
            let _ = core.poll_challenge(now as u64 * 10, &mut reply);
            if let Event::Message { header, message } = r.event {
                assert!(wire::decode(datagram, s.as_ref()).is_ok());
                assert!(
                    seen.insert((header.epoch, header.counter)) || message == Message::Stop,
                    "delivered twice"
                );
            }
        }
    }
});
