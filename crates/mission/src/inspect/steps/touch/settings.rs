//! The touch step's section of the configuration, `[touch]`: the deployed models, the shallowest
//! dip, when a stroke is made again beside its candidate, and when a stroke's dip is several.

use std::path::PathBuf;

use crackbot_tactile::stroke::SeparateDips;
use serde::{Deserialize, Serialize};

use crate::MissionError;

/// A candidate's stroke is made once more beside it when its two ends read this unlike each
/// other: the darker end's signal above the fibre's dark level is less than this share of the
/// brighter end's ([`ends_agree`]). A stroke is planned to start and end on sound surface;
/// on the simulated trial scenes 9000–9119 and 9180–9299, 30 of 839 candidate strokes did not
/// (another crack or a print beside the candidate, a bump's flank, a screw head, a crack wider
/// than its stroke), and half of those candidates ended as errors.
pub const UNEVEN_ENDS_SHARE: f64 = 0.6;
/// How far along the candidate the stroke is made again, mm: past a screw head's radius.
pub const RESTROKE_ALONG_MM: f64 = 5.0;
/// Least of the candidate left beyond the moved stroke, mm: it still crosses the candidate.
pub const RESTROKE_KEEP_MM: f64 = 1.0;

/// Shallowest proximity dip a confirmed crack needs by default, counts: the simulated 0.5–0.9 mm
/// cracks of the trial scenes dip 52–88 counts (the localiser's default of 100 rejected them),
/// flat surface read as a crack 14 (seeds 1000–1029, `EXPERIMENTS.md`, "Prints told by two
/// heights"); the authors' flat plate's proximity channel spans 18–22 counts in a slide.
pub const MIN_DIP_COUNTS: f64 = 40.0;

/// How the touch step strokes, reads and localises: `[touch]` of the configuration file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TouchConfig {
    /// The deployed recognition model.
    pub recognition_model: PathBuf,
    /// The deployed width model.
    pub width_model: PathBuf,
    /// Shallowest proximity dip that counts as one for the judge's `require_dip`, counts
    /// ([`crackbot_tactile::localise::LocaliseConfig::min_depth_counts`], 100 there). With the
    /// print check on, the gate needs to stop only surfaces that do not darken the fibre at
    /// all, so it is lower by default ([`MIN_DIP_COUNTS`]); without it, 100 keeps more faint
    /// prints out.
    pub min_dip_counts: f64,
    /// [`UNEVEN_ENDS_SHARE`].
    pub uneven_ends_share: f64,
    /// [`RESTROKE_ALONG_MM`].
    pub restroke_along_mm: f64,
    /// [`RESTROKE_KEEP_MM`].
    pub restroke_keep_mm: f64,
    /// When a stroke's dip is several ([`crackbot_tactile::stroke::own_dip`]).
    pub separate_dips: SeparateDips,
}

impl TouchConfig {
    /// The committed models and the measured defaults.
    pub fn new() -> Self {
        TouchConfig {
            recognition_model: crackbot_datasets::model_path("tactile/recognition.ctm"),
            width_model: crackbot_datasets::model_path("tactile/width.ctm"),
            min_dip_counts: MIN_DIP_COUNTS,
            uneven_ends_share: UNEVEN_ENDS_SHARE,
            restroke_along_mm: RESTROKE_ALONG_MM,
            restroke_keep_mm: RESTROKE_KEEP_MM,
            separate_dips: SeparateDips::default(),
        }
    }

    /// Refuses a setting out of range, naming it.
    pub fn check(&self) -> Result<(), MissionError> {
        let d = &self.separate_dips;
        for (field, value, ok, allowed) in [
            (
                "touch.min_dip_counts",
                self.min_dip_counts,
                self.min_dip_counts >= 0.0,
                "a number ≥ 0",
            ),
            (
                "touch.uneven_ends_share",
                self.uneven_ends_share,
                (0.0..=1.0).contains(&self.uneven_ends_share),
                "[0, 1]",
            ),
            (
                "touch.restroke_along_mm",
                self.restroke_along_mm,
                self.restroke_along_mm >= 0.0,
                "a number ≥ 0",
            ),
            (
                "touch.restroke_keep_mm",
                self.restroke_keep_mm,
                self.restroke_keep_mm >= 0.0,
                "a number ≥ 0",
            ),
            (
                "touch.separate_dips.excess_mm",
                d.excess_mm,
                d.excess_mm >= 0.0,
                "a number ≥ 0",
            ),
            (
                "touch.separate_dips.back_share",
                d.back_share,
                (0.0..=1.0).contains(&d.back_share),
                "[0, 1]",
            ),
            (
                "touch.separate_dips.gap_mm",
                d.gap_mm,
                d.gap_mm >= 0.0,
                "a number ≥ 0",
            ),
        ] {
            if !(value.is_finite() && ok) {
                return Err(MissionError::Setting {
                    field,
                    value,
                    allowed,
                });
            }
        }
        Ok(())
    }
}

impl Default for TouchConfig {
    fn default() -> Self {
        TouchConfig::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_pass_and_a_setting_out_of_range_is_named_by_its_key() {
        let good = TouchConfig::new();
        good.check().unwrap();
        assert_eq!(good.min_dip_counts, MIN_DIP_COUNTS);
        assert_eq!(good.uneven_ends_share, UNEVEN_ENDS_SHARE);
        let refused = |change: &dyn Fn(&mut TouchConfig)| {
            let mut c = good.clone();
            change(&mut c);
            match c.check() {
                Err(MissionError::Setting { field, .. }) => field,
                other => panic!("{other:?}"),
            }
        };
        assert_eq!(
            refused(&|c| c.min_dip_counts = -1.0),
            "touch.min_dip_counts"
        );
        assert_eq!(
            refused(&|c| c.uneven_ends_share = 1.5),
            "touch.uneven_ends_share"
        );
        assert_eq!(
            refused(&|c| c.restroke_along_mm = f64::NAN),
            "touch.restroke_along_mm"
        );
        assert_eq!(
            refused(&|c| c.separate_dips.back_share = -0.1),
            "touch.separate_dips.back_share"
        );
        assert_eq!(
            refused(&|c| c.separate_dips.gap_mm = f64::INFINITY),
            "touch.separate_dips.gap_mm"
        );
    }
}
