//! The finger's proximity fibre as the robot knows it: where it looks, its dark level and its
//! distance curve.
//!
//! A mission needs these on hardware as much as on the simulator: the print check reads a
//! raised pass's distance to the surface from the curve, and the planner's strokes start where
//! the fibre can no longer see a candidate. The simulator (`crackbot-sim`) models the same
//! fibre, so both share [`intensity`].
//!
//! ```
//! use crackbot_fibre::ProximityFibre;
//! let fibre = ProximityFibre::default().checked()?;
//! // The fibre sees a crack 2.4 mm before the tip's centre reaches it.
//! assert!((fibre.reach_mm() - 2.363).abs() < 1e-3);
//! # Ok::<(), crackbot_fibre::FibreError>(())
//! ```

pub mod fit;

use serde::{Deserialize, Serialize};

/// Relative intensity of a reflective fibre pair at distance `d_mm` whose curve peaks at
/// `peak_mm`: `2u²/(1+u⁴)`, `u = d/peak` (0 at contact, 1 at the peak, `2/u²` far away).
#[inline]
pub fn intensity(d_mm: f64, peak_mm: f64) -> f64 {
    let u = d_mm.max(0.0) / peak_mm;
    let u2 = u * u;
    2.0 * u2 / (1.0 + u2 * u2)
}

/// The proximity fibre of one finger. The defaults are the simulator's calibration against the
/// authors' recordings (`crates/sim/docs/calibration.md`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ProximityFibre {
    /// Distance of the peak of the distance curve, mm.
    pub peak_mm: f64,
    /// Height of the fibre's end above the tip's lowest point, mm: its distance to a flat
    /// surface in contact.
    pub height_mm: f64,
    /// The proximity channel with nothing in view, counts.
    pub dark_counts: f64,
    /// Where the fibre looks, ahead of the tip along the slide, mm.
    pub offset_mm: f64,
    /// Diameter of the spot the fibre averages over, mm.
    pub spot_mm: f64,
}

impl Default for ProximityFibre {
    fn default() -> Self {
        ProximityFibre {
            peak_mm: 0.454,
            height_mm: 1.026,
            dark_counts: 215.0,
            offset_mm: 1.799,
            spot_mm: 1.128,
        }
    }
}

/// A fibre setting out of its range, or readings that give no fibre.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FibreError {
    /// One field's value is outside what it may be.
    #[error("proximity fibre: {field} = {value} is outside {allowed}")]
    Setting {
        /// The field, as the site file names it.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What it may be.
        allowed: &'static str,
    },
    /// A finger's approach readings that give no curve ([`fit::fit_approach`]).
    #[error("the proximity fibre's approach: {what}")]
    Approach {
        /// What the readings lack.
        what: String,
    },
}

impl ProximityFibre {
    /// The fibre if every field is finite and in range (distances positive, the offset and
    /// spot under 20 mm, the dark level within a 16-bit ADC's counts).
    pub fn checked(self) -> Result<Self, FibreError> {
        let check = |field, value: f64, ok: bool, allowed| {
            if value.is_finite() && ok {
                Ok(())
            } else {
                Err(FibreError::Setting {
                    field,
                    value,
                    allowed,
                })
            }
        };
        let distance = |v: f64| v > 0.0 && v <= 20.0;
        check(
            "peak_mm",
            self.peak_mm,
            distance(self.peak_mm),
            "(0, 20] mm",
        )?;
        check(
            "height_mm",
            self.height_mm,
            distance(self.height_mm),
            "(0, 20] mm",
        )?;
        check(
            "spot_mm",
            self.spot_mm,
            distance(self.spot_mm),
            "(0, 20] mm",
        )?;
        let o = self.offset_mm;
        check("offset_mm", o, o.abs() <= 20.0, "[-20, 20] mm")?;
        let d = self.dark_counts;
        check(
            "dark_counts",
            d,
            (0.0..=65535.0).contains(&d),
            "[0, 65535] counts",
        )?;
        Ok(self)
    }

    /// How far beyond a crack's edge the finger feels it, mm: the fibre looks
    /// [`offset_mm`](Self::offset_mm) ahead of the tip over a spot [`spot_mm`](Self::spot_mm)
    /// wide, so it sees the crack that much before the tip's centre gets there. The tip itself,
    /// a sphere on a flat plate, touches the surface only under its centre.
    pub fn reach_mm(&self) -> f64 {
        self.offset_mm.abs() + self.spot_mm / 2.0
    }

    /// The relative intensity at distance `d_mm` from a surface of reflectivity 1.
    pub fn intensity(&self, d_mm: f64) -> f64 {
        intensity(d_mm, self.peak_mm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_curve_is_zero_at_contact_one_at_its_peak_and_falls_beyond() {
        let f = ProximityFibre::default();
        assert_eq!(f.intensity(0.0), 0.0);
        assert!((f.intensity(f.peak_mm) - 1.0).abs() < 1e-12);
        assert!(f.intensity(2.0 * f.peak_mm) < f.intensity(1.5 * f.peak_mm));
        // Far away it goes as 2/u².
        let u = 100.0;
        assert!((f.intensity(u * f.peak_mm) * u * u - 2.0).abs() < 1e-3);
    }

    #[test]
    fn settings_out_of_range_are_refused_naming_the_field() {
        for (fibre, field) in [
            (
                ProximityFibre {
                    peak_mm: 0.0,
                    ..Default::default()
                },
                "peak_mm",
            ),
            (
                ProximityFibre {
                    height_mm: f64::NAN,
                    ..Default::default()
                },
                "height_mm",
            ),
            (
                ProximityFibre {
                    spot_mm: -1.0,
                    ..Default::default()
                },
                "spot_mm",
            ),
            (
                ProximityFibre {
                    offset_mm: 25.0,
                    ..Default::default()
                },
                "offset_mm",
            ),
            (
                ProximityFibre {
                    dark_counts: f64::INFINITY,
                    ..Default::default()
                },
                "dark_counts",
            ),
            (
                ProximityFibre {
                    dark_counts: -3.0,
                    ..Default::default()
                },
                "dark_counts",
            ),
        ] {
            match fibre.checked() {
                Err(FibreError::Setting { field: f, .. }) => assert_eq!(f, field),
                other => panic!("{other:?}: not the setting {field}"),
            }
        }
        assert!(ProximityFibre {
            offset_mm: -1.8,
            ..Default::default()
        }
        .checked()
        .is_ok());
    }

    proptest! {
        #[test]
        fn the_curve_lies_in_zero_to_one_for_any_distance(d in -10.0f64..1e6, peak in 1e-3f64..20.0) {
            let v = intensity(d, peak);
            prop_assert!((0.0..=1.0 + 1e-12).contains(&v), "{v}");
        }
    }
}
