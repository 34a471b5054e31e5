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
                raw: [row.d1, row.d2, row.d3, row.p].map(to_count),
                flags,
                missing_before: 0,
            }
        })
        .collect()
}
