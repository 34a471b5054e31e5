//! Optics and electronics: deformation and proximity → light intensity → transducer voltage →
//! 10-bit ADC counts.
//!
//! * Deformation fibres D1 (left), D2 (right), D3 (normal): the reflected light changes linearly
//!   with small deflections of the finger's compliant part (the sensor's own calibration is a
//!   matrix, Konstantinova et al. 2017), so each channel is its resting level plus gains times
//!   the lateral deflection and the normal compression beyond the static load.
//! * Proximity fibre P: a reflective fibre pair, whose intensity over distance `d` rises from
//!   zero, peaks at `d_pk` and falls off as `1/d²`: `I(u) = 2u²/(1+u⁴)` with `u = d/d_pk`,
//!   scaled by the surface's reflectivity (colour, printed decoys). The fibre looks at the surface
//!   a fixed offset ahead of the tip, from a fixed height above the tip's lowest point: straight
//!   down over its spot, or (`proximity_cone_deg` > 0) along rays fanned across a cone, each
//!   traced to the first surface it meets and weighted by the cosine of its incidence there.
//! * Transducers saturate softly at `saturation_counts`; the ADC clamps to 0..=1023 and
//!   quantises. White noise, a slow random-walk drift, and a per-recording offset and gain change
//!   (the paper found the fibre cables' position and twisting shifted the data between sessions)
//!   are added before the ADC.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use crate::finger::Readout;
use crate::{list, SimError};

/// Channels, in the order of the recordings: D1, D2, D3, P.
pub const CHANNELS: usize = 4;

/// Optical and electronic parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OpticsParams {
    /// D1, D2, D3 at zero lateral deflection under the static load, ADC counts.
    pub rest_counts: [f64; 3],
    /// D1, D2, D3 change per mm of lateral deflection (tip behind the body is negative), counts/mm.
    pub lateral_gain: [f64; 3],
    /// D1, D2, D3 change per mm of extra normal compression, counts/mm.
    pub normal_gain: [f64; 3],
    /// D1, D2, D3 change per N·mm of the friction moment about the tip, counts/(N·mm).
    pub moment_gain: [f64; 3],
    /// Diameter of the spot the proximity fibre averages over, mm.
    pub proximity_spot_mm: f64,
    /// P with nothing in view, counts.
    pub proximity_dark_counts: f64,
    /// P above dark at the peak of the distance curve, for reflectivity 1, counts.
    pub proximity_peak_counts: f64,
    /// Distance of the peak of the proximity curve, mm.
    pub proximity_peak_mm: f64,
    /// Height of the proximity fibre's end above the tip's lowest point, mm.
    pub proximity_height_mm: f64,
    /// Where the proximity fibre looks, ahead of the tip along the slide's +x, mm.
    pub proximity_offset_mm: f64,
    /// Half-angle of the proximity fibre's cone, degrees: 0 averages the distance curve over
    /// the spot straight below; above 0 the spot's rays fan out and are traced to the first
    /// surface they meet, so a crack's walls shade its floor (see `run::ProximityGeometry`).
    pub proximity_cone_deg: f64,
    /// Transducer output ceiling, counts (the soft knee starts 10 % below).
    pub saturation_counts: f64,
    /// White-noise standard deviation per channel (D1, D2, D3, P), counts.
    pub noise_counts: [f64; 4],
    /// Random-walk drift of every channel, counts per √s.
    pub drift_counts_per_sqrt_s: f64,
    /// Standard deviation of the per-recording offset change of each channel, counts.
    pub recording_offset_sigma_counts: f64,
    /// Standard deviation of the per-recording relative gain change of each channel.
    pub recording_gain_sigma: f64,
    /// ADC resolution, bits.
    pub adc_bits: u32,
}

/// The defaults are the calibration against the authors' recordings
/// (`crackbot sim calibrate`, repetition 1 of `../shared/data/tactile/type`; see
/// [`crate::calibrate`]): a scene that leaves `[sensor.optics]` out gets the calibrated sensor.
impl Default for OpticsParams {
    fn default() -> Self {
        OpticsParams {
            rest_counts: [656.064, 429.676, 705.952],
            lateral_gain: [2.460, 1.599, -2.810],
            normal_gain: [33.473, -0.768, -34.357],
            moment_gain: [-3.732, -1.584, 3.934],
            proximity_spot_mm: 1.128,
            // The calibration fitted 284.73 / 595.04; the real fibre reads crack floors 15-30
            // counts below 284.73, and a darker floor, the peak scaled so that the flat plate
            // stays at 519 counts, transfers to the real recordings better: 215 was chosen on
            // repetition 1 (docs/calibration.md, "A darker proximity floor, adopted").
            proximity_dark_counts: 215.0,
            proximity_peak_counts: 772.15,
            proximity_peak_mm: 0.454,
            proximity_height_mm: 1.026,
            proximity_offset_mm: 1.799,
            proximity_cone_deg: 0.0,
            saturation_counts: 1000.0,
            noise_counts: [1.384, 2.781, 5.189, 0.418],
            // Spread between repetitions of one plate (medians of repetitions 1-3: about a
            // count) and slow drift within a recording (slide medians vary by under a count
            // over 80 s).
            drift_counts_per_sqrt_s: 0.07,
            recording_offset_sigma_counts: 1.0,
            recording_gain_sigma: 0.003,
            adc_bits: 10,
        }
    }
}

impl OpticsParams {
    /// The proximity fibre these optics model, as a mission knows it.
    pub fn fibre(&self) -> crackbot_fibre::ProximityFibre {
        crackbot_fibre::ProximityFibre {
            peak_mm: self.proximity_peak_mm,
            height_mm: self.proximity_height_mm,
            dark_counts: self.proximity_dark_counts,
            offset_mm: self.proximity_offset_mm,
            spot_mm: self.proximity_spot_mm,
        }
    }

    /// The physical first guess the calibration starts from (resting levels read off the real
    /// flat recordings, gains and proximity geometry guessed).
    pub fn first_guess() -> Self {
        OpticsParams {
            rest_counts: [655.0, 431.0, 708.0],
            lateral_gain: [13.0, 5.0, -10.0],
            normal_gain: [20.0, 6.0, -25.0],
            moment_gain: [0.0, 0.0, 0.0],
            proximity_spot_mm: 1.0,
            proximity_dark_counts: 240.0,
            proximity_peak_counts: 560.0,
            proximity_peak_mm: 3.0,
            proximity_height_mm: 1.5,
            proximity_offset_mm: 2.0,
            proximity_cone_deg: 0.0,
            saturation_counts: 1000.0,
            noise_counts: [1.0, 1.0, 1.5, 2.0],
            drift_counts_per_sqrt_s: 0.3,
            recording_offset_sigma_counts: 2.0,
            recording_gain_sigma: 0.03,
            adc_bits: 10,
        }
    }

    /// Checks every parameter, naming the first bad one.
    pub fn validate(&self) -> Result<(), SimError> {
        let arrays: [(&str, &[f64]); 5] = [
            ("rest_counts", &self.rest_counts),
            ("lateral_gain", &self.lateral_gain),
            ("normal_gain", &self.normal_gain),
            ("moment_gain", &self.moment_gain),
            ("noise_counts", &self.noise_counts),
        ];
        for (name, values) in arrays {
            if !values.iter().all(|v| v.is_finite()) {
                return Err(SimError::setting(
                    format!("sensor.optics.{name}"),
                    list(values),
                    "finite",
                ));
            }
        }
        for (name, v) in [
            ("proximity_dark_counts", self.proximity_dark_counts),
            ("proximity_peak_counts", self.proximity_peak_counts),
            ("proximity_height_mm", self.proximity_height_mm),
            ("proximity_offset_mm", self.proximity_offset_mm),
            ("proximity_spot_mm", self.proximity_spot_mm),
        ] {
            if !v.is_finite() {
                return Err(SimError::setting(
                    format!("sensor.optics.{name}"),
                    v,
                    "finite",
                ));
            }
        }
        if !(self.proximity_peak_mm.is_finite() && self.proximity_peak_mm > 0.0) {
            return Err(SimError::setting(
                "sensor.optics.proximity_peak_mm",
                self.proximity_peak_mm,
                "> 0 mm",
            ));
        }
        if !(self.proximity_cone_deg.is_finite() && (0.0..80.0).contains(&self.proximity_cone_deg))
        {
            return Err(SimError::setting(
                "sensor.optics.proximity_cone_deg",
                self.proximity_cone_deg,
                "in [0, 80) degrees",
            ));
        }
        if !(1..=16).contains(&self.adc_bits) {
            return Err(SimError::setting(
                "sensor.optics.adc_bits",
                self.adc_bits,
                "in 1..=16",
            ));
        }
        let full = self.adc_full_scale();
        if !(self.saturation_counts.is_finite()
            && self.saturation_counts > 0.0
            && self.saturation_counts <= full)
        {
            return Err(SimError::setting(
                "sensor.optics.saturation_counts",
                self.saturation_counts,
                format!("in (0, {full}]"),
            ));
        }
        for (name, v) in [
            ("drift_counts_per_sqrt_s", self.drift_counts_per_sqrt_s),
            (
                "recording_offset_sigma_counts",
                self.recording_offset_sigma_counts,
            ),
            ("recording_gain_sigma", self.recording_gain_sigma),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimError::setting(format!("sensor.optics.{name}"), v, "≥ 0"));
            }
        }
        if self.noise_counts.iter().any(|v| *v < 0.0) {
            return Err(SimError::setting(
                "sensor.optics.noise_counts",
                list(&self.noise_counts),
                "≥ 0 in every channel",
            ));
        }
        Ok(())
    }

    /// Largest ADC code.
    pub fn adc_full_scale(&self) -> f64 {
        ((1u32 << self.adc_bits.clamp(1, 16)) - 1) as f64
    }

    /// Relative intensity of the proximity fibre at distance `d_mm` (1 at the peak).
    pub fn proximity_curve(&self, d_mm: f64) -> f64 {
        proximity_intensity(d_mm, self.proximity_peak_mm)
    }

    /// The transducer's soft saturation.
    pub fn saturate(&self, v: f64) -> f64 {
        let sat = self.saturation_counts;
        let knee = 0.9 * sat;
        if v <= knee {
            v
        } else {
            let room = sat - knee;
            sat - room * (-(v - knee) / room).exp()
        }
    }
}

pub use crackbot_fibre::intensity as proximity_intensity;

/// What the proximity fibre sees at one instant: its relative intensity (the distance curve
/// averaged over its spot, times the reflectivity there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scene1d {
    /// Mean distance from the proximity fibre to the spot it looks at, mm (for reports).
    pub proximity_distance_mm: f64,
    /// Relative intensity, 1 = the curve's peak over a plate of reflectivity 1.
    pub intensity: f64,
}

/// The electronics of one recording: its noise generator, drift state and the recording's own
/// offset/gain changes.
#[derive(Debug, Clone)]
pub struct Electronics {
    params: OpticsParams,
    static_compression_mm: f64,
    offset: [f64; CHANNELS],
    gain: [f64; CHANNELS],
    drift: [f64; CHANNELS],
    rng: ChaCha8Rng,
}

impl Electronics {
    /// Electronics for one recording: draws the recording's offsets and gains from `rng`.
    /// `static_compression_mm` is the finger's compression under the body's weight on a flat
    /// surface (the deformation channels read their rest level there).
    pub fn new(params: &OpticsParams, static_compression_mm: f64, mut rng: ChaCha8Rng) -> Self {
        let mut normal = |s: f64| s * rng.sample::<f64, _>(StandardNormal);
        let offset = std::array::from_fn(|_| normal(params.recording_offset_sigma_counts));
        let gain = std::array::from_fn(|_| 1.0 + normal(params.recording_gain_sigma));
        Electronics {
            params: params.clone(),
            static_compression_mm,
            offset,
            gain,
            drift: [0.0; CHANNELS],
            rng,
        }
    }

    /// The analog channel values (counts, before the ADC) for a readout, advancing the drift by
    /// `dt` seconds.
    pub fn analog(&mut self, r: &Readout, view: &Scene1d, dt: f64) -> [f64; CHANNELS] {
        let p = &self.params;
        let lat = r.lateral * 1e3;
        let nor = r.normal * 1e3 - self.static_compression_mm;
        let mom = r.moment * 1e3;
        let mut v: [f64; CHANNELS] = std::array::from_fn(|c| {
            if c < 3 {
                p.rest_counts[c]
                    + self.gain[c]
                        * (p.lateral_gain[c] * lat
                            + p.normal_gain[c] * nor
                            + p.moment_gain[c] * mom)
            } else {
                p.proximity_dark_counts
                    + self.gain[3] * p.proximity_peak_counts * view.intensity.max(0.0)
            }
        });
        let walk = p.drift_counts_per_sqrt_s * dt.max(0.0).sqrt();
        for (c, value) in v.iter_mut().enumerate() {
            let n: f64 = self.rng.sample(StandardNormal);
            let w: f64 = self.rng.sample(StandardNormal);
            self.drift[c] += walk * w;
            *value = p.saturate(*value + self.offset[c] + self.drift[c] + p.noise_counts[c] * n);
        }
        v
    }

    /// The ADC: clamps to the full scale and rounds to the nearest code.
    pub fn quantise(&self, v: &[f64; CHANNELS]) -> [f64; CHANNELS] {
        let full = self.params.adc_full_scale();
        v.map(|x| {
            if x.is_nan() {
                0.0
            } else {
                x.clamp(0.0, full).round()
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn the_calibrated_fibre_is_the_one_a_mission_knows_by_default() {
        // A mission on hardware without a site file assumes the fibre the simulator was
        // calibrated to; the two defaults must not drift apart.
        assert_eq!(
            OpticsParams::default().fibre(),
            crackbot_fibre::ProximityFibre::default()
        );
    }

    #[test]
    fn proximity_curve_peaks_and_falls_off() {
        let p = OpticsParams::default();
        assert!((p.proximity_curve(p.proximity_peak_mm) - 1.0).abs() < 1e-12);
        assert_eq!(p.proximity_curve(0.0), 0.0);
        assert!(p.proximity_curve(20.0 * p.proximity_peak_mm) < 0.01);
        assert!(
            p.proximity_curve(2.0 * p.proximity_peak_mm)
                > p.proximity_curve(3.0 * p.proximity_peak_mm)
        );
        assert!(p.proximity_curve(0.5 * p.proximity_peak_mm) < 1.0);
    }

    #[test]
    fn saturation_is_soft_and_bounded() {
        let p = OpticsParams::default();
        assert_eq!(p.saturate(500.0), 500.0);
        assert!(p.saturate(1e12) <= p.saturation_counts);
        assert!(p.saturate(950.0) < 950.0 && p.saturate(950.0) > 900.0);
        let mut last = 0.0;
        for k in 0..2000 {
            let y = p.saturate(k as f64);
            assert!(y >= last);
            last = y;
        }
    }

    #[test]
    fn adc_quantises_and_clamps() {
        let e = Electronics::new(&OpticsParams::default(), 1.0, ChaCha8Rng::seed_from_u64(0));
        assert_eq!(
            e.quantise(&[-5.0, 1e9, 12.4, f64::NAN]),
            [0.0, 1023.0, 12.0, 0.0]
        );
    }

    /// The field `p` is refused for, after checking the message names it with its value.
    fn refused_field(p: &OpticsParams) -> String {
        let err = p.validate().unwrap_err();
        let SimError::Setting { field, value, .. } = &err else {
            panic!("expected SimError::Setting, got {err:?}");
        };
        assert!(
            err.to_string().contains(&format!("{field} = {value}")),
            "{err}"
        );
        field.clone()
    }

    #[test]
    fn bad_optics_are_settings_named_as_a_scene_names_them() {
        let good = OpticsParams::default();
        good.validate().unwrap();
        let mut p = good.clone();
        p.saturation_counts = 2000.0;
        let err = p.validate().unwrap_err();
        assert_eq!(
            err.to_string(),
            "invalid setting sensor.optics.saturation_counts = 2000: it must be in (0, 1023]"
        );
        let mut p = good.clone();
        p.lateral_gain[1] = f64::NAN;
        assert_eq!(refused_field(&p), "sensor.optics.lateral_gain");
        let mut p = good.clone();
        p.proximity_spot_mm = f64::INFINITY;
        assert_eq!(refused_field(&p), "sensor.optics.proximity_spot_mm");
        let mut p = good.clone();
        p.adc_bits = 0;
        assert_eq!(refused_field(&p), "sensor.optics.adc_bits");
        let mut p = good.clone();
        p.recording_gain_sigma = -0.1;
        assert_eq!(refused_field(&p), "sensor.optics.recording_gain_sigma");
        let mut p = good;
        p.noise_counts[2] = -1.0;
        assert_eq!(refused_field(&p), "sensor.optics.noise_counts");
    }
}
