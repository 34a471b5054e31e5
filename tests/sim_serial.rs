//! The physics simulator as the emulated board's analog front end: simulator → firmware frames →
//! pseudo-terminal → acquisition, over the real serial path.

use std::time::Duration;

use crackbot_acquisition::{AcquisitionError, LinkStats, PortConfig, Sample, SensorStream};
use crackbot_tests::{read_all, Emulator};

/// Seconds streamed: a stroke starts 7 mm before the crack's near edge at 3.89 mm/s, so the tip
/// is past a 5 mm crack after about 3.1 s.
const DURATION_S: u64 = 4;
const FRAMES: u64 = DURATION_S * 400;

/// Streams `--source sim` over a crack of `width_mm` through a PTY into the acquisition; returns
/// the samples, the error that ended the stream, the link counters and the emulator's report.
fn stream_sim(
    width_mm: &str,
) -> (
    Vec<Sample>,
    Option<AcquisitionError>,
    LinkStats,
    serde_json::Value,
) {
    let duration = DURATION_S.to_string();
    let mut emulator = Emulator::spawn(&[
        "--source",
        "sim",
        "--crack-width-mm",
        width_mm,
        "--duration",
        &duration,
        "--seed",
        "5",
        "--linger-ms",
        "400",
    ]);
    let mut stream = SensorStream::open(&PortConfig::new(&emulator.pty)).expect("opening the PTY");
    emulator.start();
    let limit = Duration::from_secs(DURATION_S + 30);
    let (samples, error, stats) = read_all(&mut stream, limit);
    let report = emulator.wait();
    (samples, error, stats, report)
}

/// Every frame arrives, in order, at 400 Hz, with no CRC error.
fn assert_clean_400_hz(samples: &[Sample], error: &Option<AcquisitionError>, stats: &LinkStats) {
    assert!(
        matches!(error, Some(AcquisitionError::Disconnected { .. })),
        "the stream must end when the emulator exits: {error:?}"
    );
    assert_eq!(samples.len() as u64, FRAMES, "zero lost frames");
    assert_eq!(stats.decoder.frames, FRAMES);
    assert_eq!(
        (
            stats.decoder.crc_errors,
            stats.gaps,
            stats.missing_frames,
            stats.resyncs
        ),
        (0, 0, 0, 0),
        "{stats:?}"
    );
    for (k, s) in samples.iter().enumerate() {
        assert_eq!(s.seq, k as u16, "consecutive sequence numbers");
        assert_eq!(s.missing_before, 0);
        assert_eq!(s.device_time_us, k as u64 * 2500, "device clock at {k}");
        assert!(!s.flags.overrun(), "overrun at {k}");
    }
    let span = (samples[samples.len() - 1].host_time - samples[0].host_time).as_secs_f64();
    let rate = (samples.len() - 1) as f64 / span;
    assert!(
        (rate - 400.0).abs() / 400.0 < 0.02,
        "measured rate {rate:.2} Hz over {span:.2} s is not within 2% of 400 Hz"
    );
}

/// Proximity values read back: the 1st–99th percentile range, the resting level (median of the
/// first 0.25 s, before the fibre nears the crack) and the sample farthest from it.
fn proximity(samples: &[Sample]) -> (f64, f64, usize) {
    let p: Vec<f64> = samples.iter().map(|s| f64::from(s.raw[3])).collect();
    let median = |values: &[f64]| {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        sorted
    };
    let sorted = median(&p);
    let n = sorted.len();
    let swing = sorted[n * 99 / 100] - sorted[n / 100];
    let rest = median(&p[..100])[50];
    let farthest = p
        .iter()
        .enumerate()
        .max_by(|a, b| (a.1 - rest).abs().total_cmp(&(b.1 - rest).abs()))
        .map_or(0, |(k, _)| k);
    (swing, rest, farthest)
}

#[test]
fn simulated_finger_over_a_crack_streams_through_the_real_serial_path() {
    // Both runs at once: each takes DURATION_S of wall-clock time.
    let flat = std::thread::spawn(|| stream_sim("0"));
    let (samples, error, stats, report) = stream_sim("5");
    let (flat_samples, flat_error, flat_stats, flat_report) =
        flat.join().expect("the flat-plate run");

    for (samples, error, stats, report) in [
        (&samples, &error, &stats, &report),
        (&flat_samples, &flat_error, &flat_stats, &flat_report),
    ] {
        assert_eq!(report["frames_dropped"], 0, "{report}");
        assert_eq!(report["ticks"], FRAMES, "{report}");
        assert_clean_400_hz(samples, error, stats);
    }

    let (swing, rest, farthest) = proximity(&samples);
    let (flat_swing, _, _) = proximity(&flat_samples);
    let p = |k: usize| f64::from(samples[k].raw[3]);
    // The proximity channel leaves its resting level by more than 100 counts as the fibre,
    // then the tip, passes over the crack …
    assert!(
        swing > 100.0 && (p(farthest) - rest).abs() > 100.0,
        "proximity over a 5 mm crack: swing {swing} counts, farthest {} from rest {rest}",
        p(farthest)
    );
    // … which is 7–12 mm into the stroke (1.8–3.1 s at 3.89 mm/s; the fibre's look-ahead and
    // the tip's radius widen that a little) …
    let t = farthest as f64 / 400.0;
    assert!(
        (1.0..3.9).contains(&t),
        "the proximity channel is farthest from its resting level at {t:.2} s, not over the crack"
    );
    // … and a flat plate shows no such swing.
    assert!(
        flat_swing < 50.0,
        "proximity swing over a flat plate is {flat_swing} counts"
    );
    // The simulation is deterministic: with the same seed, the two plates give the same values
    // until the fibre nears the crack.
    let same = samples
        .iter()
        .zip(&flat_samples)
        .take_while(|(a, b)| a.raw == b.raw)
        .count();
    assert!(same >= 100, "the runs differ from sample {same} on");
    assert!(same < farthest, "the runs never differ before the crack");
}
