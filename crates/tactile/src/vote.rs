//! How a slide's verdict is voted from its windows: who votes ([`SlideVote`]) and the slide
//! means of the voters' window probabilities ([`slide_means`]), shared by the deployed model's
//! online classifier and the evaluation.

use serde::{Deserialize, Serialize};

/// Who decides a slide's verdict when the windows carry context features.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlideVote {
    /// The context forest and a forest on the paper's window features: their slide means are summed
    /// ([`crate::eval::test_classifier_with_slide_voters`]).
    #[default]
    Both,
    /// The context forest alone. Every context feature is relative to the slide's own baseline,
    /// so the verdict does not move with the offsets that the fibres' mounting puts on the
    /// channels; the paper's window features are absolute counts, and a forest on them learns
    /// each plate's offsets along with its surface.
    Context,
}

impl SlideVote {
    /// How the reports name it: `context+paper` or `context`.
    pub fn name(self) -> &'static str {
        match self {
            SlideVote::Both => "context+paper",
            SlideVote::Context => "context",
        }
    }
}

/// Summed per-class means over `m` windows of each `k`-column probability table, in the order of
/// the evaluation's slide verdicts (table by table, window by window, `f32` → `f64` / m).
pub(crate) fn slide_means(tables: &[&[f32]], m: usize, k: usize) -> Vec<f64> {
    let n = m as f64;
    let mut mean = vec![0f64; k];
    for table in tables {
        for j in 0..m {
            for (s, &v) in mean.iter_mut().zip(&table[j * k..(j + 1) * k]) {
                *s += f64::from(v) / n;
            }
        }
    }
    mean
}
