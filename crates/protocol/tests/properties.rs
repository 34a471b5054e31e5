//! Property tests of the framing: round trip, chunking invariance, corruption safety.

use crackbot_protocol::{crc32c, Decoder, Flags, Frame, CRC_COVERED_LEN, PAYLOAD_LEN, WIRE_LEN};
use proptest::prelude::*;

fn arb_frame() -> impl Strategy<Value = Frame> {
    (any::<u16>(), any::<u32>(), any::<[u16; 4]>(), 0u8..=0x1F).prop_map(
        |(seq, timestamp_us, channels, flags)| Frame {
            seq,
            timestamp_us,
            channels,
            flags: Flags(flags),
        },
    )
}

fn decode_chunks(
    bytes: &[u8],
    chunk_ends: &[usize],
) -> Vec<Result<Frame, crackbot_protocol::DecodeError>> {
    let mut decoder = Decoder::new();
    let mut out = Vec::new();
    let mut start = 0;
    for &end in chunk_ends.iter().chain(std::iter::once(&bytes.len())) {
        let end = end.clamp(start, bytes.len());
        decoder.feed(&bytes[start..end], |r| out.push(r));
        start = end;
    }
    out
}

/// Whether a decoded frame's payload carries a CRC that matches its bytes.
fn crc_is_valid(frame: &Frame) -> bool {
    let p = frame.to_payload();
    let stored = u32::from_le_bytes([p[16], p[17], p[18], p[19]]);
    stored == crc32c(&p[..CRC_COVERED_LEN]) && p.len() == PAYLOAD_LEN
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn encode_decode_round_trip(frames in prop::collection::vec(arb_frame(), 1..40)) {
        let bytes: Vec<u8> = frames.iter().flat_map(crackbot_protocol::Frame::to_wire).collect();
        prop_assert_eq!(bytes.len(), frames.len() * WIRE_LEN);
        let got: Vec<Frame> = decode_chunks(&bytes, &[]).into_iter().map(|r| r.expect("clean stream")).collect();
        prop_assert_eq!(got, frames);
    }

    #[test]
    fn every_chunk_boundary_gives_the_same_frames(
        frames in prop::collection::vec(arb_frame(), 1..6),
        garbage in prop::collection::vec(any::<u8>(), 0..30),
    ) {
        // Garbage between frames too, so that error events must also be chunking-invariant.
        let mut bytes = Vec::new();
        for f in &frames {
            bytes.extend_from_slice(&garbage);
            bytes.extend_from_slice(&f.to_wire());
        }
        let whole = decode_chunks(&bytes, &[]);
        // Split at every single position, and into one-byte chunks.
        for split in 0..=bytes.len() {
            prop_assert_eq!(&decode_chunks(&bytes, &[split]), &whole, "split at {}", split);
        }
        let singles: Vec<usize> = (1..bytes.len()).collect();
        prop_assert_eq!(&decode_chunks(&bytes, &singles), &whole);
        let frames_out: Vec<Frame> = whole.into_iter().filter_map(Result::ok).collect();
        // Every frame comes through: the leading delimiter of each frame ends any garbage.
        for f in &frames {
            prop_assert!(frames_out.contains(f));
        }
    }

    #[test]
    fn corruption_never_yields_a_frame_with_an_invalid_crc_nor_a_frame_not_sent(
        frames in prop::collection::vec(arb_frame(), 1..30),
        flips in prop::collection::vec((any::<prop::sample::Index>(), 1u8..=255), 1..20),
        drops in prop::collection::vec(any::<prop::sample::Index>(), 0..5),
    ) {
        let clean: Vec<u8> = frames.iter().flat_map(crackbot_protocol::Frame::to_wire).collect();
        let mut bytes = clean.clone();
        let mut touched = vec![false; frames.len()];
        for (idx, mask) in &flips {
            let i = idx.index(bytes.len());
            bytes[i] ^= mask;
            touched[i / WIRE_LEN] = true;
        }
        let mut dropped: Vec<usize> = drops.iter().map(|d| d.index(bytes.len())).collect();
        dropped.sort_unstable();
        dropped.dedup();
        for &i in dropped.iter().rev() {
            bytes.remove(i);
            touched[i / WIRE_LEN] = true;
        }
        let got: Vec<Frame> = decode_chunks(&bytes, &[]).into_iter().filter_map(Result::ok).collect();
        for f in &got {
            prop_assert!(crc_is_valid(f));
            prop_assert!(frames.contains(f), "decoded a frame that was never sent: {:?}", f);
        }
        // Every untouched frame is delivered.
        for (f, t) in frames.iter().zip(&touched) {
            if !t {
                prop_assert!(got.contains(f), "untouched frame lost: {:?}", f);
            }
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic_and_are_all_counted(bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
        let mut decoder = Decoder::new();
        let mut events = 0u64;
        decoder.feed(&bytes, |_| events += 1);
        let s = *decoder.stats();
        prop_assert_eq!(s.bytes, bytes.len() as u64);
        prop_assert_eq!(s.frames + s.resyncs(), events);
    }
}
