//! Replaying a recording as a stream of samples.

use std::time::Duration;

use crackbot_protocol::{Flags, SAMPLE_PERIOD_US};
use crackbot_recording::Recording;

use crate::Sample;

/// How fast to replay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ReplaySpeed {
    /// At the rate the samples were recorded.
    Original,
    /// `k` times faster than recorded (`k > 0`).
    Factor(f64),
    /// No waiting at all.
    Unpaced,
}

/// A recording played back as [`Sample`]s, paced on the recording's own clock (its
/// `device_time_us` column when present, else 400 Hz).
#[derive(Debug)]
pub struct Replay {
    samples: Vec<Sample>,
    next: usize,
    speed: ReplaySpeed,
    start: Option<tokio::time::Instant>,
}

impl Replay {
    /// A replay of `recording` at `speed`. Channel values are rounded to ADC counts and clamped
    /// to `0..=65535`.
    pub fn new(recording: &Recording, speed: ReplaySpeed) -> Self {
        Replay {
            samples: samples_of(recording),
            next: 0,
            speed,
            start: None,
        }
    }

    /// Samples left.
    pub fn remaining(&self) -> usize {
        self.samples.len() - self.next
    }

    /// The next sample, waiting until it is due.
    pub async fn next(&mut self) -> Option<Sample> {
        let sample = *self.samples.get(self.next)?;
        self.next += 1;
        let factor = match self.speed {
            ReplaySpeed::Original => 1.0,
            ReplaySpeed::Factor(k) if k.is_finite() && k > 0.0 => k,
            ReplaySpeed::Factor(_) | ReplaySpeed::Unpaced => return Some(sample),
        };
        let start = *self.start.get_or_insert_with(tokio::time::Instant::now);
        let due = start + Duration::from_secs_f64(sample.device_time_us as f64 * 1e-6 / factor);
        tokio::time::sleep_until(due).await;
        Some(sample)
    }
}

/// The samples of a recording, without pacing.
pub fn samples_of(recording: &Recording) -> Vec<Sample> {
    let to_count = |v: f64| v.round().clamp(0.0, f64::from(u16::MAX)) as u16;
    let first_time = recording
        .extra
        .as_ref()
        .and_then(|e| e.first())
        .map_or(0, |e| e.device_time_us);
    recording
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let extra = recording.extra.as_ref().and_then(|e| e.get(i));
            let (seq, device_time_us, flags) = match extra {
                Some(e) => (
                    e.seq,
                    e.device_time_us.saturating_sub(first_time),
                    Flags(e.flags),
                ),
                None => (
                    i as u16,
                    i as u64 * u64::from(SAMPLE_PERIOD_US),
                    Flags::empty(),
                ),
            };
            Sample {
                seq,
                device_time_us,
                host_time: Duration::from_micros(device_time_us),
                raw: row.channels().map(to_count),
                flags,
                missing_before: 0,
                restarted: false,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_recording::{Extra, Row};

    fn recording(n: usize, with_extra: bool) -> Recording {
        let row = |i: usize| Row {
            x_mm: 0.0,
            d1: 660.4,
            d2: 440.6,
            d3: 720.0,
            p: i as f64,
            direction: 1,
            slide: 1,
            label: 1.0,
            repetition: 1,
        };
        Recording {
            rows: (0..n).map(row).collect(),
            // A recording that started at device time 1 s, one frame lost at index 5.
            extra: with_extra.then(|| {
                (0..n)
                    .map(|i| {
                        let k = if i >= 5 { i + 1 } else { i } as u64;
                        Extra {
                            device_time_us: 1_000_000 + k * 2500,
                            seq: k as u16,
                            flags: 0,
                        }
                    })
                    .collect()
            }),
        }
    }

    #[tokio::test(start_paused = true)]
    async fn original_rate_takes_the_recorded_time() {
        let rec = recording(401, false);
        let mut replay = Replay::new(&rec, ReplaySpeed::Original);
        let start = tokio::time::Instant::now();
        let mut n = 0;
        while let Some(s) = replay.next().await {
            assert_eq!(s.raw[3], n as u16);
            n += 1;
        }
        assert_eq!(n, 401);
        assert_eq!(start.elapsed(), Duration::from_secs(1));
    }

    #[tokio::test(start_paused = true)]
    async fn accelerated_rate_is_faster_by_the_factor_and_keeps_the_device_clock() {
        let rec = recording(401, true);
        let mut replay = Replay::new(&rec, ReplaySpeed::Factor(4.0));
        let start = tokio::time::Instant::now();
        let mut last = None;
        while let Some(s) = replay.next().await {
            last = Some(s);
        }
        let last = last.expect("samples");
        // 402 periods of device time (one frame missing), replayed 4x faster.
        assert_eq!(last.device_time_us, 401 * 2500);
        // tokio's timer has millisecond resolution.
        let expected = Duration::from_micros(401 * 2500 / 4);
        let elapsed = start.elapsed();
        assert!(
            elapsed >= expected && elapsed <= expected + Duration::from_millis(1),
            "{elapsed:?}"
        );
        assert_eq!(last.raw, [660, 441, 720, 400]);
    }

    #[tokio::test(start_paused = true)]
    async fn unpaced_does_not_wait() {
        let rec = recording(1000, false);
        let mut replay = Replay::new(&rec, ReplaySpeed::Unpaced);
        let start = tokio::time::Instant::now();
        let mut n = 0;
        while replay.next().await.is_some() {
            n += 1;
        }
        assert_eq!((n, start.elapsed()), (1000, Duration::ZERO));
    }
}
