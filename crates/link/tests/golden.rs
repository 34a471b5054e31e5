//! The encoder, decoder and replay window against the golden vectors of the independent Python
//! implementation (`golden/generate.py`).

use crackbot_link::wire::{self, Body, DecodeError, Header, Kind};
use crackbot_link::{
    Key, Message, ReplayWindow, Signer, Verdict, GOLDEN_VECTORS_JSON, MAX_PAYLOAD, SCHEMA,
    SCHEMA_HASH, TAG_LEN, WINDOW,
};
use crackbot_testkit::hex;
use serde::Deserialize;
use serde_json::Value;

#[derive(Deserialize)]
struct GoldenHeader {
    ack_requested: bool,
    sender: u8,
    link_id: u16,
    epoch: u32,
    counter: u64,
    seq: u32,
}

#[derive(Deserialize)]
struct Valid {
    name: String,
    signed: bool,
    kind: String,
    header: GoldenHeader,
    body: Value,
    payload: String,
    wire: String,
}

#[derive(Deserialize)]
struct Invalid {
    name: String,
    wire: String,
    signed_link: bool,
    error: String,
}

#[derive(Deserialize)]
struct Step {
    counter: u64,
    verdict: String,
}

#[derive(Deserialize)]
struct Sequence {
    name: String,
    start: Option<u64>,
    steps: Vec<Step>,
}

#[derive(Deserialize)]
struct Golden {
    wire_version: u8,
    header_len: usize,
    tag_len: usize,
    max_payload: usize,
    window: u64,
    max_jump: u64,
    schema_sha256: String,
    schema_hash: String,
    key: String,
    valid: Vec<Valid>,
    invalid: Vec<Invalid>,
    replay: Vec<Sequence>,
}

fn golden() -> Golden {
    serde_json::from_str(GOLDEN_VECTORS_JSON).expect("golden file parses")
}

fn signer(g: &Golden) -> Signer {
    Signer::new(&Key::from_bytes(&hex(&g.key)).expect("golden key"))
}

fn body(v: &Valid) -> Body {
    match v.kind.as_str() {
        "Data" => {
            Body::Data(serde_json::from_value::<Message>(v.body.clone()).expect("golden message"))
        }
        "Ack" => Body::Ack,
        "Challenge" => Body::Challenge,
        "Response" => Body::Response {
            epoch: v.body["epoch"].as_u64().expect("epoch") as u32,
            counter: v.body["counter"].as_u64().expect("counter"),
        },
        k => panic!("unknown kind {k}"),
    }
}

fn header(v: &Valid) -> Header {
    Header {
        ack_requested: v.header.ack_requested,
        sender: v.header.sender,
        link_id: v.header.link_id,
        schema: SCHEMA_HASH,
        epoch: v.header.epoch,
        counter: v.header.counter,
        seq: v.header.seq,
    }
}

#[test]
fn constants_and_schema_hash_match_the_golden_file() {
    let g = golden();
    assert_eq!(g.wire_version, wire::WIRE_VERSION);
    assert_eq!(g.header_len, wire::HEADER_LEN);
    assert_eq!(g.tag_len, TAG_LEN);
    assert_eq!(g.max_payload, MAX_PAYLOAD);
    assert_eq!(g.window, WINDOW);
    assert_eq!(g.max_jump, crackbot_link::DEFAULT_MAX_JUMP);
    assert_eq!(hex(&g.schema_hash), SCHEMA_HASH);
    // The Python side hashes its own copy of the schema text: the same text.
    use sha2::Digest;
    let full = sha2::Sha256::digest(SCHEMA.as_bytes());
    assert_eq!(hex(&g.schema_sha256), full.to_vec());
}

#[test]
fn encoder_produces_the_golden_bytes() {
    let g = golden();
    let s = signer(&g);
    assert!(g.valid.len() > 20);
    for v in &g.valid {
        let mut out = [0u8; crackbot_link::MAX_DATAGRAM];
        let signer = v.signed.then_some(&s);
        let n = wire::encode(&header(v), &body(v), signer, &mut out).expect(&v.name);
        assert_eq!(hex::encode(&out[..n]), v.wire, "vector {}", v.name);
        if let Body::Data(m) = body(v) {
            let mut p = [0u8; MAX_PAYLOAD];
            let n = wire::encode_message(&m, &mut p).expect("payload");
            assert_eq!(hex::encode(&p[..n]), v.payload, "payload of {}", v.name);
        }
    }
}

#[test]
fn decoder_reads_the_golden_bytes() {
    let g = golden();
    let s = signer(&g);
    for v in &g.valid {
        let bytes = hex(&v.wire);
        let signer = v.signed.then_some(&s);
        let p = wire::decode(&bytes, signer).unwrap_or_else(|e| panic!("{}: {e}", v.name));
        assert_eq!(p.header, header(v), "vector {}", v.name);
        assert_eq!(p.body, body(v), "vector {}", v.name);
        let parsed = wire::parse(&bytes).expect("parse");
        let kind = match parsed.kind {
            Kind::Data => "Data",
            Kind::Ack => "Ack",
            Kind::Challenge => "Challenge",
            Kind::Response => "Response",
        };
        assert_eq!(kind, v.kind);
    }
}

#[test]
fn decoder_rejects_the_invalid_vectors_with_the_named_error() {
    let g = golden();
    let s = signer(&g);
    assert!(g.invalid.len() > 20);
    for v in &g.invalid {
        let signer = v.signed_link.then_some(&s);
        let err = wire::decode(&hex(&v.wire), signer).expect_err(&v.name);
        let kind = match err {
            DecodeError::Truncated => "truncated",
            DecodeError::BadMagic => "magic",
            DecodeError::UnsupportedVersion { .. } => "version",
            DecodeError::ReservedFlags { .. } => "flags",
            DecodeError::UnknownKind { .. } => "kind",
            DecodeError::LengthMismatch { .. } => "length",
            DecodeError::PayloadTooLong { .. } => "payload_too_long",
            DecodeError::BadControl => "control",
            DecodeError::Payload => "payload",
            DecodeError::NonCanonical => "non_canonical",
            DecodeError::Unsigned => "unsigned",
            DecodeError::UnexpectedTag => "unexpected_tag",
            DecodeError::BadTag => "bad_tag",
            _ => "unknown",
        };
        assert_eq!(kind, v.error, "vector {}: {err}", v.name);
        assert!(!err.to_string().is_empty());
    }
}

#[test]
fn replay_window_follows_the_golden_sequences() {
    let g = golden();
    for seq in &g.replay {
        let mut w = match seq.start {
            None => ReplayWindow::new(),
            Some(c) => ReplayWindow::starting_at(c),
        };
        for (i, step) in seq.steps.iter().enumerate() {
            let v = w.check(step.counter, g.max_jump);
            let name = match v {
                Verdict::Fresh => "fresh",
                Verdict::Replay => "replay",
                Verdict::TooOld => "too_old",
                Verdict::TooFarAhead => "future",
            };
            assert_eq!(
                name, step.verdict,
                "{} step {i} (counter {})",
                seq.name, step.counter
            );
            if v == Verdict::Fresh {
                w.accept(step.counter);
            }
        }
    }
}

/// Hex without a dependency.
mod hex {
    pub fn encode(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }
}

/// The examples written in docs/wire-format.md.
#[test]
fn the_documented_examples_hold() {
    let mut p = [0u8; MAX_PAYLOAD];
    let cases: [(Message, &str); 4] = [
        (Message::Heartbeat, "00"),
        (Message::Done { slide_id: 7 }, "0607"),
        (Message::Done { slide_id: 300 }, "06ac02"),
        (
            Message::MoveTo(crackbot_link::MoveTo {
                pose: crackbot_link::Pose {
                    x_mm: 1.0,
                    y_mm: 2.0,
                    z_mm: 3.0,
                },
                speed_mm_s: 20.0,
                valid_until_us: 300,
            }),
            "01 0000803f 00000040 00004040 0000a041 ac02",
        ),
    ];
    for (m, hex_bytes) in cases {
        let n = wire::encode_message(&m, &mut p).expect("encode");
        assert_eq!(hex::encode(&p[..n]), hex_bytes.replace(' ', ""), "{m:?}");
    }
    let g = golden();
    let ack = g
        .valid
        .iter()
        .find(|v| v.name == "ack")
        .expect("ack vector");
    assert!(ack.wire.starts_with(
        concat!(
            "434c010101020100 6e48020f29792594",
            "090000004d00000000000000",
            "2a0000000000"
        )
        .replace(' ', "")
        .as_str()
    ));
    assert_eq!(hex(&ack.wire).len(), wire::HEADER_LEN + TAG_LEN);
}
