//! What a commissioning does, checked once: which plates, how many repetitions and slides of
//! the papers' protocol, the stroke and its speed, the forests, and what the new models must
//! reach on held-out repetitions before they are installed.

use crackbot_plates::set::{RECOGNITION_CLASSES, WIDTHS_MM};
use crackbot_plates::{reference_set, ReferencePlate};
use serde::{Deserialize, Serialize};

use super::error::CommissionError;

/// Repetitions of each plate by default (the papers recorded five; three leave one out twice
/// over and fit the robot time).
pub const REPETITIONS: u32 = 3;
/// Slides per repetition by default, forth and back alternately (the papers: 12).
pub const SLIDES: u32 = 6;
/// Fewest repetitions: the evaluation leaves one out.
pub const MIN_REPETITIONS: u32 = 2;
/// Fewest slides per repetition: two each way.
pub const MIN_SLIDES: u32 = 4;
/// The papers' stroke, mm.
pub const STROKE_MM: f64 = 16.0;
/// The papers' average slide speed, mm/s.
pub const SPEED_MM_S: f64 = 3.89;

/// The settings of a commissioning (`session.toml` of its folder keeps them: a session resumes
/// only with the same ones).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CommissionSettings {
    /// The plates slid over, by name (`crackbot_plates::set`); every one by default.
    pub plates: Vec<String>,
    /// Repetitions of each plate (each a separate mounting on hardware).
    pub repetitions: u32,
    /// Slides per repetition, forth and back alternately.
    pub slides: u32,
    /// Length of a slide, mm.
    pub stroke_mm: f64,
    /// Slide speed, mm/s.
    pub speed_mm_s: f64,
    /// Seed of where each repetition's slides start and of the forests.
    pub seed: u64,
    /// Trees of each forest (the shipped models': 32).
    pub trees: usize,
    /// Depth limit of every tree (`None`: fully grown; the shipped models': 10, trained on
    /// far more slides). On a session's slides fully grown trees read 93.6 % of the held-out
    /// windows, depth 24 92.3 %, 16 88.4 %, 10 85.4 % (one commissioning on the simulator).
    pub max_depth: Option<usize>,
    /// Least window accuracy of the recognition model on held-out repetitions, 0–1. The
    /// thresholds are floors that catch a commissioning gone wrong, not the goal: on simulated
    /// fingers the held-out figures came out 0.87–0.93 (windows, slides) and 0.75–1.10 mm (width
    /// slide error) from run to run of the same settings, the shipped models' 0.82–0.86, 0.65–0.74
    /// and 2.2–3.8 mm.
    pub min_window_accuracy: f64,
    /// Least slide accuracy of the recognition model on held-out repetitions, 0–1.
    pub min_slide_accuracy: f64,
    /// Largest slide width error of the width model on held-out repetitions, mm.
    pub max_width_mae_mm: f64,
}

impl Default for CommissionSettings {
    fn default() -> Self {
        CommissionSettings {
            plates: reference_set().into_iter().map(|p| p.name).collect(),
            repetitions: REPETITIONS,
            slides: SLIDES,
            stroke_mm: STROKE_MM,
            speed_mm_s: SPEED_MM_S,
            seed: 1,
            trees: 32,
            max_depth: None,
            min_window_accuracy: 0.80,
            min_slide_accuracy: 0.80,
            max_width_mae_mm: 1.5,
        }
    }
}

impl CommissionSettings {
    /// Checks the settings; the plates they name, in the set's order.
    pub fn check(&self) -> Result<Vec<ReferencePlate>, CommissionError> {
        let set = reference_set();
        for name in &self.plates {
            if !set.iter().any(|p| &p.name == name) {
                return Err(CommissionError::UnknownPlate {
                    name: name.clone(),
                    known: set
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                });
            }
        }
        let plates: Vec<ReferencePlate> = set
            .into_iter()
            .filter(|p| self.plates.contains(&p.name))
            .collect();
        self.check_counts()?;
        self.check_ranges()?;
        check_classes(&plates)?;
        Ok(plates)
    }

    fn check_counts(&self) -> Result<(), CommissionError> {
        if self.repetitions < MIN_REPETITIONS {
            return Err(CommissionError::TooFewSlides {
                what: format!("{} repetition(s) of each plate", self.repetitions),
                least: MIN_REPETITIONS,
            });
        }
        if self.slides < MIN_SLIDES {
            return Err(CommissionError::TooFewSlides {
                what: format!("{} slides per repetition", self.slides),
                least: MIN_SLIDES,
            });
        }
        Ok(())
    }

    fn check_ranges(&self) -> Result<(), CommissionError> {
        let checks: [(&'static str, f64, bool, &'static str); 7] = [
            (
                "max_depth",
                self.max_depth.map_or(1.0, |d| d as f64),
                self.max_depth.is_none_or(|d| (1..=64).contains(&d)),
                "1–64 (or none: fully grown)",
            ),
            (
                "stroke_mm",
                self.stroke_mm,
                (4.0..=40.0).contains(&self.stroke_mm),
                "4–40 mm",
            ),
            (
                "speed_mm_s",
                self.speed_mm_s,
                (0.5..=20.0).contains(&self.speed_mm_s),
                "0.5–20 mm/s",
            ),
            (
                "trees",
                self.trees as f64,
                (1..=1000).contains(&self.trees),
                "1–1000",
            ),
            (
                "min_window_accuracy",
                self.min_window_accuracy,
                (0.0..=1.0).contains(&self.min_window_accuracy),
                "0–1",
            ),
            (
                "min_slide_accuracy",
                self.min_slide_accuracy,
                (0.0..=1.0).contains(&self.min_slide_accuracy),
                "0–1",
            ),
            (
                "max_width_mae_mm",
                self.max_width_mae_mm,
                self.max_width_mae_mm > 0.0,
                "> 0 mm",
            ),
        ];
        match checks.into_iter().find(|c| !c.2) {
            Some((field, value, _, allowed)) => Err(CommissionError::Setting {
                field,
                value,
                allowed,
            }),
            None => Ok(()),
        }
    }

    /// Robot time of the slides alone at this speed, s.
    pub fn slide_time_s(&self, plates: usize) -> f64 {
        plates as f64 * f64::from(self.repetitions * self.slides) * self.stroke_mm / self.speed_mm_s
    }
}

/// Every class of both models has a plate among `plates`.
fn check_classes(plates: &[ReferencePlate]) -> Result<(), CommissionError> {
    let set = reference_set();
    for (k, class) in RECOGNITION_CLASSES.iter().enumerate() {
        if !plates.iter().any(|p| usize::from(p.recognition_label) == k) {
            let wanted: Vec<&str> = set
                .iter()
                .filter(|p| usize::from(p.recognition_label) == k)
                .map(|p| p.name.as_str())
                .collect();
            return Err(CommissionError::MissingClass {
                model: "recognition",
                class: (*class).to_string(),
                wanted: wanted.join(" or "),
            });
        }
    }
    for w in WIDTHS_MM {
        if !plates.iter().any(|p| p.width_label_mm == Some(w)) {
            let wanted = set
                .iter()
                .find(|p| p.width_label_mm == Some(w))
                .map_or_else(String::new, |p| p.name.clone());
            return Err(CommissionError::MissingClass {
                model: "width",
                class: format!("{w} mm"),
                wanted,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_take_every_plate_and_bad_settings_are_named() {
        let s = CommissionSettings::default();
        assert_eq!(s.check().unwrap().len(), 8);
        // 8 plates × 3 × 6 slides of 16 mm at 3.89 mm/s: under ten minutes of sliding.
        assert!(
            (s.slide_time_s(8) - 592.3).abs() < 1.0,
            "{}",
            s.slide_time_s(8)
        );
        let refused = |f: &dyn Fn(&mut CommissionSettings)| {
            let mut s = CommissionSettings::default();
            f(&mut s);
            s.check().unwrap_err().to_string()
        };
        let e = refused(&|s| s.plates.retain(|p| p != "bump"));
        assert!(e.contains("\"bump\"") && e.contains("mount bump"), "{e}");
        let e = refused(&|s| s.plates.retain(|p| p != "crack-8mm"));
        assert!(
            e.contains("width") && e.contains("8 mm") && e.contains("crack-8mm"),
            "{e}"
        );
        assert!(refused(&|s| s.plates.push("crack-3mm".into())).contains("crack-3mm"));
        assert!(refused(&|s| s.repetitions = 1).contains("at least 2"));
        assert!(refused(&|s| s.slides = 2).contains("at least 4"));
        assert!(refused(&|s| s.speed_mm_s = 0.0).contains("speed_mm_s"));
    }
}
