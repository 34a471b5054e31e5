//! Wire-protocol throughput: the streaming decoder on one core (goal ≥10 M frames/s) and the
//! encoder's cost per frame, with a byte-at-a-time decoder built on `cobs::CobsDecoder` as the
//! baseline in the same run.
//!
//! `cargo bench --bench protocol`

use std::hint::black_box;

use crackbot_protocol::{Decoder, Flags, Frame, PAYLOAD_LEN, WIRE_LEN};
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};

const FRAMES: usize = 10_000;

fn stream() -> Vec<u8> {
    (0..FRAMES)
        .flat_map(|k| {
            // Values like the authors' recordings, changing every frame.
            let k16 = k as u16;
            Frame {
                seq: k16,
                timestamp_us: (k as u32).wrapping_mul(2500),
                channels: [
                    650 + k16 % 40,
                    440 + k16 % 30,
                    720 - k16 % 50,
                    250 + k16 % 500,
                ],
                flags: Flags::empty(),
            }
            .to_wire()
        })
        .collect()
}

/// Baseline: one byte at a time through the `cobs` crate's streaming decoder, then the same
/// payload check.
fn baseline_decode(bytes: &[u8]) -> usize {
    let mut frames = 0;
    let mut dest = [0u8; 64];
    let mut payload = [0u8; PAYLOAD_LEN];
    let mut rest = bytes;
    while !rest.is_empty() {
        // cobs 0.2's decoder borrows its buffer: one decoder per frame, read after it ends.
        let mut decoder = cobs::CobsDecoder::new(&mut dest);
        let mut got = None;
        while let Some((&b, tail)) = rest.split_first() {
            rest = tail;
            match decoder.feed(b) {
                Ok(Some(n)) => {
                    got = Some(n);
                    break;
                }
                Ok(None) => {}
                Err(_) => break,
            }
        }
        if got == Some(PAYLOAD_LEN) {
            payload.copy_from_slice(&dest[..PAYLOAD_LEN]);
            frames += usize::from(Frame::from_payload(&payload).is_ok());
        }
    }
    frames
}

fn decode(c: &mut Criterion) {
    let bytes = stream();
    assert_eq!(bytes.len(), FRAMES * WIRE_LEN);
    let mut group = c.benchmark_group("decode");
    group.throughput(Throughput::Elements(FRAMES as u64));
    group.bench_function("crackbot Decoder, one 230 kB slice", |b| {
        b.iter(|| {
            let mut d = Decoder::new();
            let mut n = 0usize;
            d.feed(black_box(&bytes), |r| n += usize::from(r.is_ok()));
            assert_eq!(n, FRAMES);
            n
        });
    });
    group.bench_function("crackbot Decoder, 64-byte reads", |b| {
        b.iter(|| {
            let mut d = Decoder::new();
            let mut n = 0usize;
            for chunk in black_box(&bytes).chunks(64) {
                d.feed(chunk, |r| n += usize::from(r.is_ok()));
            }
            assert_eq!(n, FRAMES);
            n
        });
    });
    group.bench_function("baseline cobs::CobsDecoder byte by byte", |b| {
        b.iter(|| {
            let n = baseline_decode(black_box(&bytes));
            assert_eq!(n, FRAMES);
            n
        });
    });
    group.finish();
}

fn encode(c: &mut Criterion) {
    let frame = Frame {
        seq: 1234,
        timestamp_us: 987_654_321,
        channels: [660, 440, 720, 500],
        flags: Flags(0),
    };
    let mut group = c.benchmark_group("encode");
    group.throughput(Throughput::Elements(1));
    group.bench_function("Frame::to_wire", |b| {
        b.iter(|| black_box(black_box(&frame).to_wire()));
    });
    group.bench_function("Frame::to_payload (layout + CRC only)", |b| {
        b.iter_batched(
            || frame,
            |f| black_box(f.to_payload()),
            BatchSize::SmallInput,
        );
    });
    group.finish();
}

criterion_group! {
    name = benches;
    // Criterion's own plots need a system font that the workspace's plotters build does not load.
    config = Criterion::default().without_plots();
    targets = decode, encode
}
criterion_main!(benches);
