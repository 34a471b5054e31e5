//! Analog front-end stand-ins: what the ADC of the emulated board reads.

use crackbot_recording::{Recording, Row};
use rand::Rng;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// What the 10-bit ADC makes of four channel values: rounded, clamped to 0..=1023 (values beyond
/// the rails are what the saturation flags report); a value that is not finite reads 0.
pub fn to_counts(values: [f64; 4]) -> [u16; 4] {
    values.map(|x| {
        if x.is_finite() {
            x.round().clamp(0.0, f64::from(crackbot_firmware::ADC_MAX)) as u16
        } else {
            0
        }
    })
}

/// Something that gives the four channel voltages, in ADC counts (D1, D2, D3, P), at time `t`
/// seconds after the start. Values outside 0..=1023 are clamped by the ADC (and flagged).
pub trait SignalSource {
    /// Channel values at `t` seconds.
    fn sample(&mut self, t: f64) -> [f64; 4];
}

/// A borrowed source: lets the caller keep the source (e.g. to query a [`crate::SimSource`]'s
/// error) while [`crate::run`] samples it.
impl<S: SignalSource + ?Sized> SignalSource for &mut S {
    fn sample(&mut self, t: f64) -> [f64; 4] {
        (**self).sample(t)
    }
}

/// A finger sliding back and forth over a crack, in the style of the authors' recordings:
/// periodic 16 mm strokes at 3.89 mm/s; the proximity channel rises over the crack (the fibre sees
/// further), the lateral deformation channels bend as the tip drops into and climbs out of it.
/// Resting levels and swings follow the ranges of `../shared/data/tactile/` (D1 ≈ 633–688,
/// D2 ≈ 410–472, D3 ≈ 676–767, P ≈ 242–787). This is a plausible stand-in for demos and link
/// tests, not the physics simulator.
#[derive(Debug, Clone)]
pub struct SyntheticSlide {
    /// Crack width, mm (0: flat surface).
    pub crack_width_mm: f64,
    /// Stroke length, mm.
    pub stroke_mm: f64,
    /// Sliding speed, mm/s.
    pub speed_mm_s: f64,
    /// Standard deviation of white noise added to every channel, ADC counts.
    pub noise_counts: f64,
    rng: ChaCha8Rng,
}

impl SyntheticSlide {
    /// The authors' setup over a 5 mm crack, with 1.5 counts of noise.
    pub fn new(seed: u64) -> Self {
        SyntheticSlide {
            crack_width_mm: 5.0,
            stroke_mm: 16.0,
            speed_mm_s: 3.89,
            noise_counts: 1.5,
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// Tip position along the stroke at `t`, mm from the stroke start (triangle wave).
    pub fn position_mm(&self, t: f64) -> f64 {
        let period = 2.0 * self.stroke_mm / self.speed_mm_s;
        let phase = (t / period).fract() * 2.0;
        self.stroke_mm * if phase < 1.0 { phase } else { 2.0 - phase }
    }
}

impl SignalSource for SyntheticSlide {
    fn sample(&mut self, t: f64) -> [f64; 4] {
        let x = self.position_mm(t) - self.stroke_mm / 2.0;
        let half = self.crack_width_mm / 2.0;
        // Smooth indicator of "tip over the crack" with 0.4 mm rounded edges.
        let edge = |d: f64| 1.0 / (1.0 + (-d / 0.2).exp());
        let inside = if half > 0.0 {
            edge(x + half) * edge(half - x)
        } else {
            0.0
        };
        // Edge slopes drive the lateral channels in opposite directions.
        let slope = if half > 0.0 {
            edge(x + half) * (1.0 - edge(x + half)) - edge(half - x) * (1.0 - edge(half - x))
        } else {
            0.0
        };
        let depth = inside * (self.crack_width_mm / 10.0).min(1.0);
        let sigma = self.noise_counts.max(0.0);
        let mut n = || sigma * self.rng.sample::<f64, _>(StandardNormal);
        [
            660.0 + 25.0 * slope + 8.0 * depth + n(),
            440.0 - 25.0 * slope + 8.0 * depth + n(),
            720.0 - 40.0 * depth + n(),
            260.0 + 500.0 * depth + n(),
        ]
    }
}

/// Replays the raw channels of a recording, one row per tick, looping at the end.
#[derive(Debug, Clone)]
pub struct RecordingSource {
    rows: Vec<Row>,
    next: usize,
}

impl RecordingSource {
    /// A source over `recording`; `None` if it has no rows.
    pub fn new(recording: Recording) -> Option<Self> {
        (!recording.rows.is_empty()).then_some(RecordingSource {
            rows: recording.rows,
            next: 0,
        })
    }
}

impl SignalSource for RecordingSource {
    fn sample(&mut self, _t: f64) -> [f64; 4] {
        let row = self.rows[self.next % self.rows.len()];
        self.next = (self.next + 1) % self.rows.len();
        row.channels()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn synthetic_stays_in_the_authors_ranges_and_sees_the_crack() {
        let mut s = SyntheticSlide::new(1);
        let period = 2.0 * 16.0 / 3.89;
        let mut p_max: f64 = 0.0;
        let mut p_min: f64 = 1e9;
        let rate = f64::from(crackbot_protocol::SAMPLE_RATE_HZ);
        for k in 0..(period * rate) as usize {
            let v = s.sample(k as f64 / rate);
            assert!(v.iter().all(|x| (200.0..=900.0).contains(x)), "{v:?}");
            p_max = p_max.max(v[3]);
            p_min = p_min.min(v[3]);
        }
        assert!(p_max - p_min > 150.0, "proximity swing {p_min}..{p_max}");
    }

    #[test]
    fn recording_source_loops() {
        let row = |p| Row {
            x_mm: 0.0,
            d1: 1.0,
            d2: 2.0,
            d3: 3.0,
            p,
            direction: 1,
            slide: 1,
            label: 0.0,
            repetition: 1,
        };
        let rec = Recording {
            rows: vec![row(10.0), row(20.0)],
            extra: None,
        };
        let mut s = RecordingSource::new(rec).expect("rows");
        let ps: Vec<f64> = (0..5).map(|k| s.sample(k as f64)[3]).collect();
        assert_eq!(ps, vec![10.0, 20.0, 10.0, 20.0, 10.0]);
        assert!(RecordingSource::new(Recording::default()).is_none());
    }
}
