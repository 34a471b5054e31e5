//! The models from a session's recordings (pure: no rig): both trained with today's recipe
//! (`crackbot-lab tactile train`'s defaults: the recognition model on every plate, the width
//! plates read as no crack / crack, both forests voting; the width model's context forest
//! deciding), evaluated leave-one-repetition-out, and the shipped models measured on the same
//! recordings.

use std::path::{Path, PathBuf};

use crackbot_plates::ReferencePlate;
use crackbot_recording::{Experiment, Recording};
use crackbot_tactile::model::{TactileModel, TrainConfig};
use crackbot_tactile::vote::SlideVote;
use serde::{Deserialize, Serialize};

use super::error::CommissionError;
use super::settings::CommissionSettings;

/// One recording of a session: the plate, the repetition and what was read.
pub type SessionRecording = (ReferencePlate, u32, Recording);

/// Recordings labelled for one model, named for its header.
pub type Labelled = Vec<(PathBuf, Recording)>;

/// A model's figures on test recordings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Figures {
    /// Share of windows read right.
    pub window_accuracy: f64,
    /// Share of slides read right.
    pub slide_accuracy: f64,
    /// Test windows.
    pub windows: usize,
    /// Test slides.
    pub slides: u64,
    /// Width models: mean absolute error of the width regressed per slide, mm.
    pub slide_width_mae_mm: Option<f64>,
    /// Width models: mean absolute error of the width the robot reports per slide, mm.
    pub slide_width_reported_mae_mm: Option<f64>,
}

/// Both models' figures: the new ones left-one-repetition-out, the shipped ones on everything.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// The new recognition model, each repetition read by a model trained on the others.
    pub recognition: Figures,
    /// The new width model, the same way.
    pub width: Figures,
    /// The shipped recognition model on every recording.
    pub shipped_recognition: Figures,
    /// The shipped width model on every recording.
    pub shipped_width: Figures,
}

/// The recordings of both models: every plate for recognition (labelled by its class), the
/// width plates for width (labelled by their width). The flat plate's recordings go into the
/// recognition set twice, as in the authors' sets (the surface-type experiment's "no crack"
/// and the width experiment's 0 mm plate were both flat): five crack plates against one flat
/// one read 17 % of the flat plate's held-out windows as crack.
pub fn labelled(recordings: &[SessionRecording]) -> (Labelled, Labelled) {
    let name = |p: &ReferencePlate, rep: u32| PathBuf::from(format!("{}-rep{rep}.csv", p.name));
    let relabel = |r: &Recording, label: f64| {
        let mut r = r.clone();
        for row in &mut r.rows {
            row.label = label;
        }
        r
    };
    let mut recognition: Labelled = recordings
        .iter()
        .map(|(p, rep, r)| (name(p, *rep), relabel(r, f64::from(p.recognition_label))))
        .collect();
    recognition.extend(
        recordings
            .iter()
            .filter(|(p, _, _)| p.width_label_mm == Some(0.0))
            .map(|(p, rep, r)| {
                (
                    PathBuf::from(format!("{}-rep{rep}-as-0mm.csv", p.name)),
                    r.clone(),
                )
            }),
    );
    let width = recordings
        .iter()
        .filter_map(|(p, rep, r)| p.width_label_mm.map(|w| (name(p, *rep), relabel(r, w))))
        .collect();
    (recognition, width)
}

fn train_config(s: &CommissionSettings, experiment: Experiment) -> TrainConfig {
    TrainConfig {
        n_trees: s.trees,
        max_depth: s.max_depth,
        seed: s.seed,
        slide_vote: match experiment {
            Experiment::Recognition => SlideVote::Both,
            Experiment::Width => SlideVote::Context,
        },
    }
}

/// Trains the `experiment`'s model on `recordings`.
pub fn train(
    recordings: &Labelled,
    experiment: Experiment,
    s: &CommissionSettings,
) -> Result<TactileModel, CommissionError> {
    let mut quiet = |_: &'static str, _: usize, _: usize| {};
    Ok(TactileModel::train(
        recordings,
        Some(experiment),
        &train_config(s, experiment),
        &mut quiet,
    )?)
}

/// The figures of `model` on `test`.
pub fn figures(model: &TactileModel, test: &Labelled) -> Result<Figures, CommissionError> {
    let r = crackbot_tactile::evaluation::evaluate_model_recordings(model, test)?;
    Ok(Figures {
        window_accuracy: r.window_accuracy,
        slide_accuracy: r.slide_accuracy,
        windows: r.test_windows,
        slides: r.test_slides,
        slide_width_mae_mm: r.slide_width_mae_mm,
        slide_width_reported_mae_mm: r.slide_width_reported_mae_mm,
    })
}

/// Figures pooled over folds (weighted by windows and slides).
fn pooled(folds: &[Figures]) -> Figures {
    let windows: usize = folds.iter().map(|f| f.windows).sum();
    let slides: u64 = folds.iter().map(|f| f.slides).sum();
    let by_windows = |g: fn(&Figures) -> f64| {
        folds.iter().map(|f| g(f) * f.windows as f64).sum::<f64>() / windows.max(1) as f64
    };
    let by_slides = |g: fn(&Figures) -> Option<f64>| {
        let v: Vec<(f64, f64)> = folds
            .iter()
            .filter_map(|f| g(f).map(|m| (m, f.slides as f64)))
            .collect();
        let n: f64 = v.iter().map(|x| x.1).sum();
        (n > 0.0).then(|| v.iter().map(|x| x.0 * x.1).sum::<f64>() / n)
    };
    Figures {
        window_accuracy: by_windows(|f| f.window_accuracy),
        slide_accuracy: folds
            .iter()
            .map(|f| f.slide_accuracy * f.slides as f64)
            .sum::<f64>()
            / slides.max(1) as f64,
        windows,
        slides,
        slide_width_mae_mm: by_slides(|f| f.slide_width_mae_mm),
        slide_width_reported_mae_mm: by_slides(|f| f.slide_width_reported_mae_mm),
    }
}

/// Each repetition of `set` read by a model trained on the others, pooled; `fold` is told
/// each fold as it starts (1-based, of the repetitions).
pub fn leave_one_repetition_out(
    set: &Labelled,
    experiment: Experiment,
    s: &CommissionSettings,
    fold: &mut dyn FnMut(u32),
) -> Result<Figures, CommissionError> {
    let rep_of = |r: &Recording| r.rows.first().map_or(0, |row| row.repetition);
    let mut folds = Vec::new();
    for rep in 1..=s.repetitions {
        fold(rep);
        let (test, train_set): (Labelled, Labelled) =
            set.iter().cloned().partition(|(_, r)| rep_of(r) == rep);
        let model = train(&train_set, experiment, s)?;
        folds.push(figures(&model, &test)?);
    }
    Ok(pooled(&folds))
}

/// Refuses models whose held-out figures are below the settings' (`session` named).
pub fn judge(
    e: &Evaluation,
    s: &CommissionSettings,
    session: &Path,
) -> Result<(), CommissionError> {
    let fail = |what, value: f64, least: f64| CommissionError::FailsEvaluation {
        model: "recognition",
        what,
        value: 100.0 * value,
        least: 100.0 * least,
        session: session.to_path_buf(),
    };
    if e.recognition.window_accuracy < s.min_window_accuracy {
        return Err(fail(
            "windows",
            e.recognition.window_accuracy,
            s.min_window_accuracy,
        ));
    }
    if e.recognition.slide_accuracy < s.min_slide_accuracy {
        return Err(fail(
            "slides",
            e.recognition.slide_accuracy,
            s.min_slide_accuracy,
        ));
    }
    match e.width.slide_width_mae_mm {
        Some(v) if v <= s.max_width_mae_mm => Ok(()),
        v => Err(CommissionError::WidthError {
            value: v.unwrap_or(f64::INFINITY),
            most: s.max_width_mae_mm,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fig(w: f64, s: f64, windows: usize, slides: u64, mae: Option<f64>) -> Figures {
        Figures {
            window_accuracy: w,
            slide_accuracy: s,
            windows,
            slides,
            slide_width_mae_mm: mae,
            slide_width_reported_mae_mm: None,
        }
    }

    #[test]
    fn folds_pool_by_windows_and_slides_and_weak_models_are_refused() {
        let p = pooled(&[
            fig(1.0, 1.0, 300, 10, Some(0.2)),
            fig(0.7, 0.5, 100, 30, Some(1.0)),
        ]);
        assert!((p.window_accuracy - 0.925).abs() < 1e-12);
        assert!((p.slide_accuracy - 0.625).abs() < 1e-12);
        assert!((p.slide_width_mae_mm.unwrap() - 0.8).abs() < 1e-12);
        let s = CommissionSettings::default();
        let good = fig(0.97, 1.0, 10, 10, Some(0.3));
        let e = |recognition: Figures, width: Figures| Evaluation {
            recognition,
            width,
            shipped_recognition: good,
            shipped_width: good,
        };
        assert!(judge(&e(good, good), &s, Path::new("s")).is_ok());
        let msg = judge(&e(fig(0.97, 0.75, 10, 10, None), good), &s, Path::new("s"))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("slides 75.0 %") && msg.contains("80.0 %"),
            "{msg}"
        );
        let msg = judge(
            &e(good, fig(0.9, 0.9, 10, 10, Some(1.8))),
            &s,
            Path::new("s"),
        )
        .unwrap_err()
        .to_string();
        assert!(msg.contains("1.80 mm"), "{msg}");
    }
}
