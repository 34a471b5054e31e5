//! Traces for the board emulator (`firmware/emulate.sh --trace`): what a [`SignalSource`] puts
//! on the ADC, as raw counts, one sample a line.
//!
//! Format (`firmware/README.md`): a header line `d1,d2,d3,p`, then one line per 1/400 s sample
//! with the four channels' 10-bit counts (0..=1023), comma-separated. The emulated board's ADC
//! reads line k at its k-th tick after reset, looping at the end.

use std::io::{self, Write};

use crackbot_protocol::SAMPLE_RATE_HZ;
use crackbot_sim::Scene;

use crate::signal::{to_counts, SignalSource};

/// The trace file's header line.
pub const TRACE_HEADER: &str = "d1,d2,d3,p";

/// Samples of one slide stroke of `scene` (its stroke length over its slide speed, at 400 Hz).
pub fn stroke_samples(scene: &Scene) -> u64 {
    let m = &scene.manipulator;
    (m.stroke_mm / m.slide_speed_mm_s * f64::from(SAMPLE_RATE_HZ)).ceil() as u64
}

/// Writes `samples` samples of `source`, at 400 Hz, as the ADC converts them ([`to_counts`],
/// as [`crate::run`] does) in the trace format.
pub fn write_trace<S: SignalSource, W: Write>(
    mut source: S,
    samples: u64,
    mut out: W,
) -> io::Result<()> {
    writeln!(out, "{TRACE_HEADER}")?;
    for k in 0..samples {
        let t = k as f64 / f64::from(SAMPLE_RATE_HZ);
        let [d1, d2, d3, p] = to_counts(source.sample(t));
        writeln!(out, "{d1},{d2},{d3},{p}")?;
    }
    out.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Ramp(f64);
    impl SignalSource for Ramp {
        fn sample(&mut self, _t: f64) -> [f64; 4] {
            self.0 += 400.0;
            [self.0 - 800.0, 511.6, f64::NAN, self.0]
        }
    }

    #[test]
    fn counts_are_rounded_and_clamped_one_sample_a_line() {
        let mut out = Vec::new();
        write_trace(Ramp(0.0), 3, &mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "d1,d2,d3,p\n0,512,0,400\n0,512,0,800\n400,512,0,1023\n"
        );
    }

    #[test]
    fn the_default_scene_strokes_for_its_length_over_its_speed() {
        let scene = Scene::builtin_default();
        let n = stroke_samples(&scene);
        let m = &scene.manipulator;
        let expected = m.stroke_mm / m.slide_speed_mm_s * 400.0;
        assert!((n as f64 - expected).abs() < 1.0, "{n} vs {expected}");
    }
}
