//! What a run of samples looked like: counts, rates on both clocks, channel ranges and means,
//! the link's health, and the means in physical units when a calibration is given.

use std::time::Duration;

use crackbot_protocol::Channel;
use serde::Serialize;

use crate::calibration::Calibration;
use crate::{LinkStats, Sample};

/// Running statistics of the samples of a stream; feed it with [`StreamSummary::add`] and turn it
/// into a [`StreamReport`] at the end.
#[derive(Debug, Clone, Default)]
pub struct StreamSummary {
    samples: u64,
    first_host: Option<Duration>,
    last_host: Duration,
    first_device: Option<u64>,
    last_device: u64,
    backwards_device_time: u64,
    min: [u16; 4],
    max: [u16; 4],
    sum: [f64; 4],
}

/// The channel means in physical units (see [`Calibration`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibratedMean {
    /// The calibrated sensor's id.
    pub sensor: String,
    /// Name of each physical output.
    pub outputs: [String; 4],
    /// Unit of each physical output.
    pub units: [String; 4],
    /// Mean of each output over the run.
    pub mean: [f64; 4],
}

/// The summary of a stream, as printed by `crackbot record`, `replay` and `demo` (`--json`).
///
/// Rates are `null` with fewer than two samples; means are `null` with none.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StreamReport {
    /// Samples received.
    pub samples: u64,
    /// Sample rate by the host's receive clock, Hz.
    pub host_rate_hz: Option<f64>,
    /// Sample rate by the device's clock, Hz.
    pub device_rate_hz: Option<f64>,
    /// Whether the device clock never went backwards.
    pub device_time_monotonic: bool,
    /// Channel names, in the order of `min`, `max` and `mean`.
    pub channels: [&'static str; 4],
    /// Smallest raw count per channel.
    pub min: [u16; 4],
    /// Largest raw count per channel.
    pub max: [u16; 4],
    /// Mean raw count per channel.
    pub mean: [f64; 4],
    /// The means through the calibration, when one was given.
    pub calibrated_mean: Option<CalibratedMean>,
    /// The link's counters.
    pub link: LinkStats,
    /// Fraction of the frames sent that arrived ([`LinkStats::delivery_ratio`]).
    pub delivery_ratio: f64,
}

impl StreamSummary {
    /// A summary of no samples.
    pub fn new() -> Self {
        Self::default()
    }

    /// Accounts one sample.
    pub fn add(&mut self, s: &Sample) {
        if self.samples == 0 {
            self.min = s.raw;
            self.max = s.raw;
        }
        if self.first_device.is_some() && s.device_time_us < self.last_device {
            self.backwards_device_time += 1;
        }
        self.samples += 1;
        self.first_host.get_or_insert(s.host_time);
        self.first_device.get_or_insert(s.device_time_us);
        self.last_host = s.host_time;
        self.last_device = s.device_time_us;
        for c in 0..4 {
            self.min[c] = self.min[c].min(s.raw[c]);
            self.max[c] = self.max[c].max(s.raw[c]);
            self.sum[c] += f64::from(s.raw[c]);
        }
    }

    /// Samples accounted so far.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    fn rate(span_us: f64, samples: u64) -> Option<f64> {
        (samples > 1 && span_us > 0.0).then(|| (samples - 1) as f64 / (span_us * 1e-6))
    }

    /// The report of the samples so far, with the link's counters and, if given, the means in
    /// physical units.
    pub fn report(&self, link: &LinkStats, calibration: Option<&Calibration>) -> StreamReport {
        let host_span = self
            .last_host
            .saturating_sub(self.first_host.unwrap_or_default())
            .as_micros() as f64;
        let device_span = self
            .last_device
            .saturating_sub(self.first_device.unwrap_or(0)) as f64;
        let mean = self.sum.map(|s| {
            if self.samples > 0 {
                s / self.samples as f64
            } else {
                f64::NAN
            }
        });
        let calibrated_mean = calibration.map(|c| CalibratedMean {
            sensor: c.sensor_id.clone(),
            outputs: c.outputs.clone(),
            units: c.units.clone(),
            mean: c.apply(mean.map(|m| m.round().clamp(0.0, 65535.0) as u16)),
        });
        StreamReport {
            samples: self.samples,
            host_rate_hz: Self::rate(host_span, self.samples),
            device_rate_hz: Self::rate(device_span, self.samples),
            device_time_monotonic: self.backwards_device_time == 0,
            channels: Channel::ALL.map(Channel::name),
            min: self.min,
            max: self.max,
            mean,
            calibrated_mean,
            link: *link,
            delivery_ratio: link.delivery_ratio(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_protocol::Flags;

    fn sample(k: u64, raw: [u16; 4], device_time_us: u64) -> Sample {
        Sample {
            seq: k as u16,
            device_time_us,
            host_time: Duration::from_micros(2_500 * k),
            raw,
            flags: Flags::empty(),
            missing_before: 0,
            restarted: false,
        }
    }

    #[test]
    fn rates_ranges_and_means_of_a_run() {
        let mut s = StreamSummary::new();
        for k in 0..401u64 {
            s.add(&sample(k, [k as u16, 10, 20, 1000 - k as u16], 2_500 * k));
        }
        let r = s.report(&LinkStats::default(), None);
        assert_eq!(r.samples, 401);
        assert!((r.host_rate_hz.unwrap() - 400.0).abs() < 1e-9);
        assert!((r.device_rate_hz.unwrap() - 400.0).abs() < 1e-9);
        assert!(r.device_time_monotonic);
        assert_eq!(r.min, [0, 10, 20, 600]);
        assert_eq!(r.max, [400, 10, 20, 1000]);
        assert_eq!(r.mean, [200.0, 10.0, 20.0, 800.0]);
        assert_eq!(r.channels, ["D1", "D2", "D3", "P"]);
        assert!(r.calibrated_mean.is_none());
    }

    #[test]
    fn an_empty_run_has_no_rates_and_null_means_in_json() {
        let r = StreamSummary::new().report(&LinkStats::default(), None);
        assert_eq!(r.host_rate_hz, None);
        let json = serde_json::to_value(&r).unwrap();
        assert!(json["mean"][0].is_null());
        assert_eq!(json["delivery_ratio"], 1.0);
        assert!(json["link"]["crc_errors"].is_u64());
    }

    #[test]
    fn a_device_clock_going_backwards_is_reported() {
        let mut s = StreamSummary::new();
        s.add(&sample(0, [1; 4], 5_000));
        s.add(&sample(1, [1; 4], 2_500));
        let r = s.report(&LinkStats::default(), None);
        assert!(!r.device_time_monotonic);
        assert_eq!(r.device_rate_hz, None, "no positive device span");
    }

    #[test]
    fn calibrated_means_go_through_the_calibration() {
        let mut s = StreamSummary::new();
        s.add(&sample(0, [100, 200, 300, 400], 0));
        let cal = Calibration::identity("test");
        let r = s.report(&LinkStats::default(), Some(&cal));
        let c = r.calibrated_mean.unwrap();
        assert_eq!(c.sensor, "test");
        assert_eq!(c.mean, cal.apply([100, 200, 300, 400]));
    }
}
