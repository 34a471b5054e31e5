//! The firmware, emulated on the host, streaming to the acquisition over a real pseudo-terminal.

use std::collections::BTreeSet;
use std::time::Duration;

use crackbot_acquisition::{AcquisitionError, LinkStats, PortConfig, Sample, SensorStream};
use crackbot_tests::{read_all, Emulator};

/// Reads until the stream ends; returns the samples, the error that ended it and the stats.
fn run_link(
    frames: u64,
    extra: &[&str],
) -> (
    Vec<Sample>,
    Option<AcquisitionError>,
    LinkStats,
    serde_json::Value,
    Vec<u16>,
) {
    let log = tempfile::NamedTempFile::new().expect("temp file");
    let log_path = log.path().to_str().expect("utf-8 path").to_string();
    let frames_arg = frames.to_string();
    let mut args = vec![
        "--frames",
        &frames_arg,
        "--corruption-log",
        &log_path,
        "--linger-ms",
        "400",
    ];
    args.extend_from_slice(extra);
    let mut emulator = Emulator::spawn(&args);
    let mut stream = SensorStream::open(&PortConfig::new(&emulator.pty)).expect("opening the PTY");
    emulator.start();
    let (samples, error, stats) = read_all(&mut stream, Duration::from_secs(frames / 400 + 30));
    let report = emulator.wait();
    let log: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(log.path()).expect("log")).expect("log json");
    let touched = log["damaged_seqs"]
        .as_array()
        .expect("damaged_seqs")
        .iter()
        .map(|v| v.as_u64().expect("seq") as u16)
        .collect();
    (samples, error, stats, report, touched)
}

#[test]
fn clean_link_delivers_every_frame_at_400_hz_for_5_s() {
    let frames = 2100; // 5.25 s
    let (samples, error, stats, report, touched) = run_link(frames, &[]);
    assert!(touched.is_empty());
    assert_eq!(report["frames_dropped"], 0, "{report}");
    // The emulator exits and its PTY goes away: that is how this stream ends.
    assert!(
        matches!(error, Some(AcquisitionError::Disconnected { .. })),
        "{error:?}"
    );
    assert_eq!(samples.len() as u64, frames, "zero lost frames");
    assert_eq!(stats.decoder.frames, frames);
    assert_eq!(
        (
            stats.gaps,
            stats.missing_frames,
            stats.resyncs,
            stats.decoder.crc_errors
        ),
        (0, 0, 0, 0)
    );
    for (k, s) in samples.iter().enumerate() {
        assert_eq!(s.seq, k as u16);
        assert_eq!(s.missing_before, 0);
        assert_eq!(
            s.device_time_us,
            k as u64 * 2500,
            "device clock at sample {k}"
        );
    }
    assert!(
        samples.windows(2).all(|w| w[1].host_time >= w[0].host_time),
        "host times monotonic"
    );
    let span = (samples[samples.len() - 1].host_time - samples[0].host_time).as_secs_f64();
    assert!(span >= 5.0, "streamed for {span} s");
    let rate = (samples.len() - 1) as f64 / span;
    assert!(
        (rate - 400.0).abs() / 400.0 < 0.01,
        "measured rate {rate:.2} Hz is not within 1% of 400 Hz"
    );
}

/// Every frame the line left untouched is delivered, every touched one is rejected, and the
/// decoder is back in sync with the very next untouched frame.
fn assert_exact_delivery(samples: &[Sample], stats: &LinkStats, touched: &[u16], frames: u64) {
    let delivered: BTreeSet<u16> = samples.iter().map(|s| s.seq).collect();
    assert_eq!(delivered.len(), samples.len(), "no frame delivered twice");
    let touched: BTreeSet<u16> = touched.iter().copied().collect();
    assert!(!touched.is_empty(), "the test must corrupt something");
    for seq in 0..frames as u16 {
        if touched.contains(&seq) {
            assert!(
                !delivered.contains(&seq),
                "corrupted frame {seq} was delivered"
            );
        } else {
            assert!(delivered.contains(&seq), "untouched frame {seq} was lost");
        }
    }
    // Resync within one frame: after every corrupted frame, the next untouched frame arrives.
    for &bad in &touched {
        let next = bad.wrapping_add(1);
        if u64::from(next) < frames && !touched.contains(&next) {
            assert!(delivered.contains(&next), "no resync after frame {bad}");
        }
    }
    assert!(stats.resyncs > 0);
    assert_eq!(stats.decoder.frames as usize, samples.len());
    // Each run of rejected frames shows up as a sequence gap of the right size.
    let lost_between: u64 = samples.iter().map(|s| u64::from(s.missing_before)).sum();
    let leading = u64::from(samples[0].seq);
    let trailing = frames - 1 - u64::from(samples[samples.len() - 1].seq);
    assert_eq!(lost_between + leading + trailing, touched.len() as u64);
    assert!(
        samples
            .windows(2)
            .all(|w| w[1].device_time_us > w[0].device_time_us),
        "device time monotonic"
    );
}

#[test]
fn one_percent_byte_corruption() {
    let frames = 2000;
    let (samples, _, stats, report, touched) =
        run_link(frames, &["--flip-rate", "0.01", "--seed", "11"]);
    assert_eq!(report["frames_dropped"], 0);
    assert_exact_delivery(&samples, &stats, &touched, frames);
    assert!(stats.decoder.crc_errors + stats.decoder.truncated + stats.decoder.overlong > 0);
    // 23 bytes per frame: about 1 − 0.99^23 ≈ 21% of the frames are hit.
    let hit = touched.len() as f64 / frames as f64;
    assert!((0.15..0.28).contains(&hit), "{hit}");
}

#[test]
fn fifteen_percent_byte_corruption() {
    let frames = 2000;
    let (samples, _, stats, _, touched) =
        run_link(frames, &["--flip-rate", "0.15", "--seed", "12"]);
    assert_exact_delivery(&samples, &stats, &touched, frames);
    // 0.85^23 ≈ 2.4% of the frames survive.
    assert!(
        samples.len() > 10 && samples.len() < 150,
        "{} survived",
        samples.len()
    );
}

#[test]
fn dropped_bytes_and_garbage_bursts() {
    let frames = 1200;
    let (samples, _, stats, report, touched) = run_link(
        frames,
        &[
            "--drop-rate",
            "0.005",
            "--garbage-rate",
            "0.05",
            "--seed",
            "13",
        ],
    );
    assert!(
        report["corruption"]["garbage_bursts"]
            .as_u64()
            .expect("bursts")
            > 20
    );
    assert!(
        report["corruption"]["dropped_bytes"]
            .as_u64()
            .expect("drops")
            > 20
    );
    assert_exact_delivery(&samples, &stats, &touched, frames);
}

#[test]
fn a_port_that_does_not_exist_is_a_clear_error() {
    let err =
        SensorStream::open(&PortConfig::new("/dev/crackbot-no-such-port")).expect_err("must fail");
    assert!(matches!(err, AcquisitionError::PortNotFound { .. }));
    assert!(
        err.to_string().contains("/dev/crackbot-no-such-port"),
        "{err}"
    );
    // A path that exists but is not a serial device.
    let err = SensorStream::open(&PortConfig::new("/dev/null")).expect_err("/dev/null is no tty");
    assert!(err.to_string().contains("/dev/null"), "{err}");
}

#[test]
fn a_port_that_vanishes_mid_stream_ends_the_stream_with_an_error_after_every_sample() {
    let mut emulator = Emulator::spawn(&[]);
    let pty = emulator.pty.clone();
    let mut stream = SensorStream::open(&PortConfig::new(&pty)).expect("opening the PTY");
    emulator.start();
    let mut samples = Vec::new();
    while samples.len() < 400 {
        samples.push(
            stream
                .blocking_next()
                .expect("stream open")
                .expect("sample"),
        );
    }
    emulator.kill();
    let (rest, error, stats) = read_all(&mut stream, Duration::from_secs(10));
    samples.extend(rest);
    let error = error.expect("a disconnect error");
    assert!(
        matches!(error, AcquisitionError::Disconnected { .. }),
        "{error:?}"
    );
    assert!(
        error.to_string().contains(&pty) && error.to_string().contains("disconnected"),
        "{error}"
    );
    assert_eq!(
        stats.decoder.frames as usize,
        samples.len(),
        "every decoded frame was handed over"
    );
    assert!(
        stream.blocking_next().is_none(),
        "the stream ends after the error"
    );
    assert!(samples
        .windows(2)
        .all(|w| w[1].seq == w[0].seq.wrapping_add(1)));
}

#[test]
fn a_too_slow_uart_drops_frames_and_the_host_sees_the_gaps_and_overrun_flags() {
    let frames = 800;
    let (samples, _, stats, report, touched) = run_link(frames, &["--baud", "57600"]);
    assert!(touched.is_empty());
    let dropped = report["frames_dropped"].as_u64().expect("dropped");
    assert!(dropped > 200, "57600 baud carries ~63% of 400 Hz: {report}");
    assert_eq!(
        stats.decoder.frames,
        report["frames_queued"].as_u64().expect("queued"),
        "every queued frame arrives"
    );
    let last = u64::from(samples[samples.len() - 1].seq);
    assert_eq!(
        stats.missing_frames + stats.decoder.frames,
        last + 1,
        "{stats:?}"
    );
    assert!(stats.gaps > 0 && stats.overrun_flags > 0);
    for s in &samples {
        assert_eq!(
            s.missing_before > 0,
            s.flags.overrun(),
            "overrun flag marks exactly the frames after a gap"
        );
    }
}
