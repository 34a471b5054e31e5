//! What the label column means: the paper's two experiments, their label values and class names.
//!
//! Column 8 of a recording ([`Row::label`](crate::Row::label)) holds a surface class id in the
//! surface-type experiment and a crack width in millimetres in the width experiment. This is the one place
//! that says which values exist, in which class order, and what they are called.

use serde::{Deserialize, Serialize};

/// Which of the paper's two experiments a set of recordings belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Experiment {
    /// Surface type: 0 flat (no crack), 1 crack, 2 bump, 3 wavy pattern.
    Recognition,
    /// Crack width: 0, 1, 2, 5, 8, 10 mm.
    Width,
}

/// Labels that do not tell the experiment ([`Experiment::detect`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExperimentError {
    /// Every label is a class of both experiments (only 0, 1, 2 occur).
    #[error(
        "labels {labels:?} fit both experiments (recognition 0–3, width 0/1/2/5/8/10 mm): name it with --experiment"
    )]
    Ambiguous {
        /// The labels found, sorted, each once.
        labels: Vec<f64>,
    },
    /// Some label is a class of neither experiment, or the labels mix them.
    #[error(
        "labels {labels:?} fit neither experiment (recognition: 0 flat, 1 crack, 2 bump, 3 wavy; width: 0, 1, 2, 5, 8, 10 mm)"
    )]
    Unknown {
        /// The labels found, sorted, each once.
        labels: Vec<f64>,
    },
}

impl Experiment {
    /// Both experiments.
    pub const ALL: [Experiment; 2] = [Experiment::Recognition, Experiment::Width];

    /// The label values of the experiment's classes, in class order.
    pub fn labels(self) -> &'static [f64] {
        match self {
            Experiment::Recognition => &[0.0, 1.0, 2.0, 3.0],
            Experiment::Width => &[0.0, 1.0, 2.0, 5.0, 8.0, 10.0],
        }
    }

    /// Human names of the classes.
    pub fn class_names(self) -> &'static [&'static str] {
        match self {
            Experiment::Recognition => &["no crack", "crack", "bump", "wavy"],
            Experiment::Width => &["0 mm", "1 mm", "2 mm", "5 mm", "8 mm", "10 mm"],
        }
    }

    /// Number of classes.
    pub fn n_classes(self) -> usize {
        self.labels().len()
    }

    /// Class index of a label value.
    pub fn class_of(self, label: f64) -> Option<u32> {
        self.labels()
            .iter()
            .position(|&l| l == label)
            .map(|i| i as u32)
    }

    /// `"recognition"` or `"width"`.
    pub fn name(self) -> &'static str {
        match self {
            Experiment::Recognition => "recognition",
            Experiment::Width => "width",
        }
    }

    /// The surface-type label of a crack-width label: 0 mm is flat (`0`, "no crack") and every
    /// other width of the width experiment is a crack (`1`). `None` for a label that is no width
    /// of the experiment.
    ///
    /// The surface-type experiment's only crack is one plate, so a recognition model trained on
    /// it alone calls the authors' own 1, 8 and 10 mm cracks "bump"; the width recordings, read
    /// this way, teach it what else a crack feels like.
    pub fn recognition_label_of_width(width_mm: f64) -> Option<f64> {
        Experiment::Width
            .class_of(width_mm)
            .map(|_| if width_mm == 0.0 { 0.0 } else { 1.0 })
    }

    /// Recognises the experiment from the labels found: widths 5, 8 or 10 mm mean the width
    /// experiment, a wavy pattern (3) means recognition; labels that fit both (only 0, 1, 2) or
    /// neither are an error that says so.
    pub fn detect(labels: &[f64]) -> Result<Experiment, ExperimentError> {
        let fits = |e: Experiment| labels.iter().all(|&l| e.class_of(l).is_some());
        match (fits(Experiment::Recognition), fits(Experiment::Width)) {
            (true, false) => Ok(Experiment::Recognition),
            (false, true) => Ok(Experiment::Width),
            (true, true) => Err(ExperimentError::Ambiguous {
                labels: labels.to_vec(),
            }),
            (false, false) => Err(ExperimentError::Unknown {
                labels: labels.to_vec(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_read_as_surface_types() {
        assert_eq!(Experiment::recognition_label_of_width(0.0), Some(0.0));
        for w in [1.0, 2.0, 5.0, 8.0, 10.0] {
            assert_eq!(Experiment::recognition_label_of_width(w), Some(1.0));
        }
        for w in [3.0, -1.0, 0.5, f64::NAN] {
            assert_eq!(Experiment::recognition_label_of_width(w), None);
        }
    }

    #[test]
    fn experiments_are_recognised_from_labels() {
        assert_eq!(
            Experiment::detect(&[0.0, 1.0, 2.0, 3.0]).unwrap(),
            Experiment::Recognition
        );
        assert_eq!(
            Experiment::detect(&[0.0, 1.0, 2.0, 5.0, 8.0, 10.0]).unwrap(),
            Experiment::Width
        );
        assert_eq!(Experiment::detect(&[3.0]).unwrap(), Experiment::Recognition);
        assert_eq!(Experiment::detect(&[10.0]).unwrap(), Experiment::Width);
        let both = Experiment::detect(&[0.0, 1.0]).unwrap_err();
        assert_eq!(
            both,
            ExperimentError::Ambiguous {
                labels: vec![0.0, 1.0]
            }
        );
        assert_eq!(
            both.to_string(),
            "labels [0.0, 1.0] fit both experiments (recognition 0–3, width 0/1/2/5/8/10 mm): name it with --experiment"
        );
        let neither = Experiment::detect(&[4.0]).unwrap_err().to_string();
        assert!(neither.contains("neither"), "{neither}");
        assert_eq!(Experiment::Width.class_of(5.0), Some(3));
        assert_eq!(Experiment::Width.class_of(3.0), None);
        for e in Experiment::ALL {
            assert_eq!(e.class_names().len(), e.n_classes());
        }
    }
}
