//! The sampling loop against mock ADCs and UARTs, driven by a virtual clock.

use crackbot_firmware::{FirmwareStats, SampleAdc, Sampler};
use crackbot_protocol::{Channel, Decoder, DecoderStats, Frame, SAMPLE_PERIOD_US, WIRE_LEN};
use embedded_hal_nb::serial::{ErrorKind, ErrorType, Write};
use serde::Deserialize;

/// Ring buffer used by the tests: room for two frames and a bit.
const TX: usize = 64;

// ---------------------------------------------------------------------------------------------
// Mock ADCs

/// Deterministic, never saturated readings for read number `k` (the sequence number of its frame).
fn reading(k: u32) -> [u16; 4] {
    [
        (600 + k % 97) as u16,
        (400 + k % 89) as u16,
        (700 + k % 83) as u16,
        (1 + k % 1021) as u16,
    ]
}

/// Returns [`reading`]`(k)` on read `k`.
#[derive(Default)]
struct CountingAdc {
    reads: u32,
}

impl SampleAdc for CountingAdc {
    type Error = ();
    fn read_all(&mut self) -> Result<[u16; 4], ()> {
        let r = reading(self.reads);
        self.reads += 1;
        Ok(r)
    }
}

/// Returns the scripted readings in turn (`None`: a failed read), then [`reading`] values.
struct ScriptedAdc {
    script: Vec<Option<[u16; 4]>>,
    reads: usize,
}

#[derive(Debug)]
struct AdcFault;

impl SampleAdc for ScriptedAdc {
    type Error = AdcFault;
    fn read_all(&mut self) -> Result<[u16; 4], AdcFault> {
        let k = self.reads;
        self.reads += 1;
        match self.script.get(k) {
            Some(Some(values)) => Ok(*values),
            Some(None) => Err(AdcFault),
            None => Ok(reading(k as u32)),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Mock UARTs

/// A UART paced by a virtual clock at `baud` with 8N1 framing (10 bits per byte): it takes a byte
/// only if `bytes_accepted < elapsed_us * baud / 10 / 1e6`, where the clock `elapsed_us` runs
/// from when the line last went idle (a line with nothing to send banks no credit) and a one-byte
/// holding register lets it take the next byte while one is on the line.
struct PacedUart {
    baud: u64,
    now_us: u64,
    /// When the line finishes the bytes accepted so far, in µs × baud (one byte = 10⁷).
    line_free_at: u64,
    /// Accepted bytes with the time they were accepted.
    sent: Vec<(u64, u8)>,
}

const BYTE_TIME: u64 = 10 * 1_000_000;

impl PacedUart {
    fn new(baud: u64) -> Self {
        PacedUart {
            baud,
            now_us: 0,
            line_free_at: 0,
            sent: Vec::new(),
        }
    }
}

impl ErrorType for PacedUart {
    type Error = ErrorKind;
}

impl Write<u8> for PacedUart {
    fn write(&mut self, byte: u8) -> nb::Result<(), ErrorKind> {
        let now = self.now_us * self.baud;
        let start = self.line_free_at.max(now);
        // Shift register busy and holding register full: wait.
        if start - now > BYTE_TIME {
            return Err(nb::Error::WouldBlock);
        }
        self.line_free_at = start + BYTE_TIME;
        self.sent.push((self.now_us, byte));
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), ErrorKind> {
        if self.line_free_at > self.now_us * self.baud {
            Err(nb::Error::WouldBlock)
        } else {
            Ok(())
        }
    }
}

/// A UART that takes every byte at once, except that it answers `ErrorKind::Other` while `broken`
/// and once when it is about to take byte number `fail_at`.
#[derive(Default)]
struct FlakyUart {
    broken: bool,
    fail_at: Option<usize>,
    errors_returned: u32,
    bytes: Vec<u8>,
}

impl ErrorType for FlakyUart {
    type Error = ErrorKind;
}

impl Write<u8> for FlakyUart {
    fn write(&mut self, byte: u8) -> nb::Result<(), ErrorKind> {
        if self.broken || self.fail_at == Some(self.bytes.len()) {
            self.fail_at = None;
            self.errors_returned += 1;
            return Err(nb::Error::Other(ErrorKind::Other));
        }
        self.bytes.push(byte);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), ErrorKind> {
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Helpers

/// Decodes `bytes`, failing the test on any decode error.
fn decode(bytes: &[u8]) -> (Vec<Frame>, DecoderStats) {
    let mut decoder = Decoder::new();
    let mut frames = Vec::new();
    decoder.feed(bytes, |r| {
        frames.push(r.expect("the firmware only sends whole, valid frames"));
    });
    (frames, *decoder.stats())
}

struct Run {
    stats: FirmwareStats,
    /// Frames decoded on the host, with the virtual time their last byte was taken by the UART.
    frames: Vec<(u64, Frame)>,
    decoder: DecoderStats,
}

/// Ticks every 2500 µs for `seconds` simulated seconds, pumping every 100 µs in between, then
/// pumps until the ring buffer is empty. Decodes what the UART sent.
fn simulate(baud: u64, seconds: u64) -> Run {
    let mut sampler: Sampler<CountingAdc, PacedUart, TX> =
        Sampler::new(CountingAdc::default(), PacedUart::new(baud));
    let end_us = seconds * 1_000_000;
    let (mut t, mut next_tick) = (0u64, 0u64);
    while t < end_us || sampler.queued_bytes() > 0 {
        assert!(t < end_us + 100_000, "ring buffer did not drain");
        sampler.uart_mut().now_us = t;
        if t == next_tick && t < end_us {
            sampler.tick(t as u32);
            next_tick += u64::from(SAMPLE_PERIOD_US);
        } else {
            sampler.pump();
        }
        t += 100;
    }
    let stats = sampler.stats();
    let (_, uart) = sampler.release();

    let mut decoder = Decoder::new();
    let mut frames = Vec::new();
    for &(at, byte) in &uart.sent {
        decoder.feed(&[byte], |r| {
            frames.push((at, r.expect("no corrupted frame")));
        });
    }
    Run {
        stats,
        frames,
        decoder: *decoder.stats(),
    }
}

fn no_decode_errors(s: &DecoderStats) {
    assert_eq!(s.resyncs(), 0, "decoder errors: {s:?}");
    assert_eq!(s.discarded_bytes, 0);
}

// ---------------------------------------------------------------------------------------------
// Tests

#[test]
fn at_115200_baud_every_frame_arrives_at_400_hz() {
    let run = simulate(115_200, 5);
    assert_eq!(
        run.stats,
        FirmwareStats {
            ticks: 2000,
            frames_queued: 2000,
            frames_dropped: 0,
            adc_errors: 0,
            uart_errors: 0
        }
    );
    no_decode_errors(&run.decoder);
    assert_eq!(run.frames.len(), 2000);
    for (k, (at, frame)) in run.frames.iter().enumerate() {
        let tick_us = k as u64 * u64::from(SAMPLE_PERIOD_US);
        assert_eq!(frame.seq, k as u16);
        assert_eq!(u64::from(frame.timestamp_us), tick_us);
        assert_eq!(frame.channels, reading(k as u32));
        assert_eq!(frame.flags.0, 0, "no saturation, no overrun");
        // 23 bytes take 1997 µs at 115200 baud: each frame is out before the next tick.
        assert!(
            *at - tick_us < u64::from(SAMPLE_PERIOD_US),
            "frame {k} late: {at} µs"
        );
    }
    // 400 frames reach the host in every simulated second.
    for second in 0..5 {
        let window = second * 1_000_000..(second + 1) * 1_000_000;
        let n = run
            .frames
            .iter()
            .filter(|(at, _)| window.contains(at))
            .count();
        assert_eq!(n, 400, "frames received in second {second}");
    }
}

#[test]
fn at_57600_baud_whole_frames_are_dropped_and_flagged() {
    let run = simulate(57_600, 5);
    let s = run.stats;
    assert_eq!(s.ticks, 2000);
    assert!(s.frames_dropped > 0);
    assert_eq!(s.frames_queued + s.frames_dropped, s.ticks);
    assert_eq!((s.adc_errors, s.uart_errors), (0, 0));
    // 57600 baud carries 5760 bytes/s = 250 frames/s of the 400 produced.
    assert!((1200..=1300).contains(&s.frames_queued), "{s:?}");

    no_decode_errors(&run.decoder);
    assert_eq!(run.frames.len(), s.frames_queued as usize);
    let frames: Vec<Frame> = run.frames.iter().map(|&(_, f)| f).collect();
    assert_eq!(frames[0].seq, 0);
    assert!(!frames[0].flags.overrun());
    let mut missing = 0u32;
    let mut gaps = 0;
    for pair in frames.windows(2) {
        let (prev, next) = (pair[0], pair[1]);
        let step = next.seq.wrapping_sub(prev.seq);
        assert!(step >= 1);
        if step > 1 {
            gaps += 1;
        }
        assert_eq!(
            next.flags.overrun(),
            step > 1,
            "overrun flag iff a gap before seq {}",
            next.seq
        );
        missing += u32::from(step - 1);
    }
    assert!(gaps > 0);
    assert_eq!(
        missing, s.frames_dropped,
        "every dropped frame shows as a sequence gap"
    );
    for f in &frames {
        assert_eq!(
            u64::from(f.timestamp_us),
            u64::from(f.seq) * u64::from(SAMPLE_PERIOD_US)
        );
        assert_eq!(
            f.channels,
            reading(u32::from(f.seq)),
            "frame {} intact",
            f.seq
        );
        assert!(!f.flags.any_saturated());
    }
}

#[test]
fn saturation_flags_follow_the_adc_rails() {
    // (readings, expected saturation bits D1=1, D2=2, D3=4, P=8)
    let cases: [([u16; 4], u8); 7] = [
        ([0, 1023, 1, 1022], 0b0011),
        ([1, 1022, 0, 1023], 0b1100),
        ([512, 512, 512, 512], 0b0000),
        ([0, 0, 0, 0], 0b1111),
        ([1023, 1023, 1023, 1023], 0b1111),
        ([1023, 1, 1, 0xFFFF], 0b1001),
        ([1, 1024, 1022, 2], 0b0010),
    ];
    let adc = ScriptedAdc {
        script: cases.iter().map(|&(v, _)| Some(v)).collect(),
        reads: 0,
    };
    let mut sampler: Sampler<_, _, TX> = Sampler::new(adc, FlakyUart::default());
    for k in 0..cases.len() as u32 {
        sampler.tick(k * SAMPLE_PERIOD_US);
    }
    let (frames, _) = decode(&sampler.uart_mut().bytes);
    assert_eq!(frames.len(), cases.len());
    for (frame, &(values, bits)) in frames.iter().zip(&cases) {
        assert_eq!(frame.channels, values);
        assert_eq!(frame.flags.0, bits, "flags of {values:?}");
        for (i, channel) in Channel::ALL.into_iter().enumerate() {
            assert_eq!(frame.flags.saturated(channel), bits & (1 << i) != 0);
        }
    }
}

#[derive(Deserialize)]
struct Golden {
    firmware_sequence: Vec<GoldenStep>,
}

#[derive(Deserialize)]
struct GoldenStep {
    adc: [u16; 4],
    wire: String,
}

fn hex(s: &str) -> Vec<u8> {
    assert_eq!(s.len() % 2, 0);
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex"))
        .collect()
}

#[test]
fn bytes_match_the_golden_firmware_sequence() {
    let golden: Golden =
        serde_json::from_str(crackbot_protocol::GOLDEN_VECTORS_JSON).expect("golden vectors parse");
    assert!(golden.firmware_sequence.len() >= 10);
    let adc = ScriptedAdc {
        script: golden
            .firmware_sequence
            .iter()
            .map(|s| Some(s.adc))
            .collect(),
        reads: 0,
    };
    let mut sampler: Sampler<_, _, TX> = Sampler::new(adc, FlakyUart::default());
    let mut expected = Vec::new();
    for (k, step) in golden.firmware_sequence.iter().enumerate() {
        sampler.tick(k as u32 * SAMPLE_PERIOD_US);
        let wire = hex(&step.wire);
        assert_eq!(wire.len(), WIRE_LEN);
        expected.extend(wire);
    }
    assert_eq!(sampler.uart_mut().bytes, expected);
}

#[test]
fn adc_error_skips_one_frame_and_one_sequence_number() {
    let adc = ScriptedAdc {
        script: vec![Some(reading(0)), Some(reading(1)), None],
        reads: 0,
    };
    let mut sampler: Sampler<_, _, TX> = Sampler::new(adc, FlakyUart::default());
    for k in 0..5 {
        sampler.tick(k * SAMPLE_PERIOD_US);
    }
    let s = sampler.stats();
    assert_eq!(
        (s.ticks, s.frames_queued, s.frames_dropped, s.adc_errors),
        (5, 4, 0, 1)
    );
    let (frames, _) = decode(&sampler.uart_mut().bytes);
    let seqs: Vec<u16> = frames.iter().map(|f| f.seq).collect();
    assert_eq!(seqs, [0, 1, 3, 4]);
    assert_eq!(frames[2].timestamp_us, 3 * SAMPLE_PERIOD_US);
    assert_eq!(frames[2].channels, reading(3));
    assert!(
        frames.iter().all(|f| !f.flags.overrun()),
        "an ADC error is not a UART overrun"
    );
}

#[test]
fn uart_error_is_counted_and_loses_no_byte() {
    let uart = FlakyUart {
        fail_at: Some(10),
        ..FlakyUart::default()
    };
    let mut sampler: Sampler<_, _, TX> = Sampler::new(CountingAdc::default(), uart);
    sampler.tick(0);
    assert_eq!(sampler.stats().uart_errors, 1);
    assert_eq!(sampler.uart_mut().bytes.len(), 10);
    assert_eq!(sampler.queued_bytes(), WIRE_LEN - 10);
    sampler.pump();
    assert_eq!(sampler.queued_bytes(), 0);

    // A UART that fails for a while: nothing moves, then everything arrives in order.
    sampler.uart_mut().broken = true;
    sampler.tick(2500);
    sampler.pump();
    sampler.tick(5000);
    assert_eq!(sampler.stats().uart_errors, 4);
    assert_eq!(sampler.queued_bytes(), 2 * WIRE_LEN);
    sampler.uart_mut().broken = false;
    sampler.pump();
    assert_eq!(sampler.queued_bytes(), 0);

    let s = sampler.stats();
    assert_eq!(
        (s.ticks, s.frames_queued, s.frames_dropped, s.uart_errors),
        (3, 3, 0, 4)
    );
    let (_, uart) = sampler.release();
    assert_eq!(uart.errors_returned, 4);
    let expected: Vec<u8> = (0..3u16)
        .flat_map(|k| {
            let channels = reading(u32::from(k));
            Frame {
                seq: k,
                timestamp_us: u32::from(k) * 2500,
                channels,
                flags: Default::default(),
            }
            .to_wire()
        })
        .collect();
    assert_eq!(uart.bytes, expected);
}

/// A UART that takes every byte while `open`, and answers `WouldBlock` otherwise.
#[derive(Default)]
struct GateUart {
    open: bool,
    bytes: Vec<u8>,
}

impl ErrorType for GateUart {
    type Error = ErrorKind;
}

impl Write<u8> for GateUart {
    fn write(&mut self, byte: u8) -> nb::Result<(), ErrorKind> {
        if !self.open {
            return Err(nb::Error::WouldBlock);
        }
        self.bytes.push(byte);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), ErrorKind> {
        Ok(())
    }
}

#[test]
fn full_ring_drops_whole_frames_and_flags_the_next_one() {
    let mut sampler: Sampler<_, _, TX> = Sampler::new(CountingAdc::default(), GateUart::default());
    // 64 bytes hold two 23-byte frames; frames 2 and 3 find no room for all their bytes.
    for (k, queued) in [
        (0, WIRE_LEN),
        (1, 2 * WIRE_LEN),
        (2, 2 * WIRE_LEN),
        (3, 2 * WIRE_LEN),
    ] {
        sampler.tick(k * SAMPLE_PERIOD_US);
        assert_eq!(sampler.queued_bytes(), queued, "after tick {k}");
    }
    let s = sampler.stats();
    assert_eq!((s.ticks, s.frames_queued, s.frames_dropped), (4, 2, 2));

    sampler.uart_mut().open = true;
    sampler.pump();
    sampler.tick(4 * SAMPLE_PERIOD_US);
    sampler.tick(5 * SAMPLE_PERIOD_US);
    let (frames, _) = decode(&sampler.uart_mut().bytes);
    let summary: Vec<(u16, bool)> = frames.iter().map(|f| (f.seq, f.flags.overrun())).collect();
    assert_eq!(summary, [(0, false), (1, false), (4, true), (5, false)]);
    assert_eq!(
        sampler.stats().frames_queued + sampler.stats().frames_dropped,
        6
    );
}

#[test]
fn ring_smaller_than_a_frame_drops_everything_without_panicking() {
    let mut sampler: Sampler<_, _, 16> = Sampler::new(CountingAdc::default(), FlakyUart::default());
    for k in 0..10 {
        sampler.tick(k * SAMPLE_PERIOD_US);
    }
    let s = sampler.stats();
    assert_eq!((s.ticks, s.frames_queued, s.frames_dropped), (10, 0, 10));
    assert!(sampler.uart_mut().bytes.is_empty());
}

#[test]
fn sequence_number_and_timestamp_wrap() {
    let mut sampler: Sampler<_, _, TX> = Sampler::new(CountingAdc::default(), FlakyUart::default());
    let mut decoder = Decoder::new();
    let mut frames = Vec::new();
    let start = u32::MAX - 1000;
    let mut picked = Vec::new();
    for k in 0..=65_536u32 {
        sampler.tick(start.wrapping_add(k * SAMPLE_PERIOD_US));
        let uart = sampler.uart_mut();
        decoder.feed(&uart.bytes, |r| frames.push(r.expect("valid frame")));
        uart.bytes.clear();
        if k <= 1 || k >= 65_534 {
            picked.append(&mut frames);
        }
        frames.clear();
    }
    assert_eq!(decoder.stats().frames, 65_537);
    let got: Vec<(u16, u32)> = picked.iter().map(|f| (f.seq, f.timestamp_us)).collect();
    assert_eq!(
        got,
        [
            (0, u32::MAX - 1000),
            (1, 1499),
            (65_534, start.wrapping_add(65_534 * 2500)),
            (65_535, start.wrapping_add(65_535 * 2500)),
            (0, start.wrapping_add(65_536 * 2500)),
        ]
    );
}
