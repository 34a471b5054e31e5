//! Folders of recordings, real (the authors') or simulated (`crackbot sim dataset`): reading
//! them, keeping one repetition, and choosing the slides that the real-vs-simulated comparison
//! draws.

use std::path::Path;

use crackbot_recording::{collect_recordings, Recording};
use serde::Serialize;

use crate::experiment::Experiment;
use crate::SimError;

fn data_err(dir: &Path, message: String) -> SimError {
    SimError::Data {
        path: dir.display().to_string(),
        message,
    }
}

/// Every `.mat` and `.csv` recording in `dir`; an error when there is none.
pub fn load_recordings(dir: &Path) -> Result<Vec<Recording>, SimError> {
    let recs =
        collect_recordings(&[dir.to_path_buf()]).map_err(|source| SimError::ReadRecordings {
            dir: dir.display().to_string(),
            source,
        })?;
    if recs.is_empty() {
        return Err(data_err(dir, "no .mat or .csv recordings".into()));
    }
    Ok(recs.into_iter().map(|(_, r)| r).collect())
}

/// The recordings of repetition `repetition` in `dir`; an error when there is none.
pub fn recordings_of_repetition(dir: &Path, repetition: u32) -> Result<Vec<Recording>, SimError> {
    let recs: Vec<Recording> = load_recordings(dir)?
        .into_iter()
        .filter(|r| r.repetition() == Some(repetition))
        .collect();
    if recs.is_empty() {
        return Err(data_err(
            dir,
            format!("no recording of repetition {repetition}"),
        ));
    }
    Ok(recs)
}

/// The experiment recordings with these labels belong to: width when a label exceeds 3 (a crack
/// width in mm), else recognition (labels 0–3). Unlike [`Experiment::detect`] it always answers
/// (labels 0–2 alone are recognition), so that [`class_name`] can name labels of neither.
pub fn experiment_of(labels: &[f64]) -> Experiment {
    if labels.iter().any(|&l| l > 3.0) {
        Experiment::Width
    } else {
        Experiment::Recognition
    }
}

/// The name of a class ([`Experiment::class_names`]: `no crack`, `crack`, `bump`, `wavy`, or
/// `"2 mm"`); a label outside the experiment's classes is `label 4`, or `4 mm` for a width.
pub fn class_name(label: f64, experiment: Experiment) -> String {
    let known = experiment
        .class_of(label)
        .and_then(|c| experiment.class_names().get(c as usize));
    match (known, experiment) {
        (Some(name), _) => (*name).to_string(),
        (None, Experiment::Width) => format!("{label} mm"),
        (None, _) => format!("label {label}"),
    }
}

/// The channel values `[D1, D2, D3, P]` of one slide.
pub type SlideRows = Vec<[f64; 4]>;

/// One class of the comparison: the same slide of its first real and first simulated recording.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassSlides {
    /// The class label.
    pub label: f64,
    /// Its name ([`class_name`]).
    pub name: String,
    /// The slide's rows in the real recording of the lowest repetition (`None`: no such slide).
    pub real: Option<SlideRows>,
    /// The same in the simulated recordings.
    pub simulated: Option<SlideRows>,
}

/// What `crackbot sim compare` draws: per class of the real recordings (in label order), one
/// slide of the real and of the simulated data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// The experiment, recognised from the real labels ([`experiment_of`]).
    pub experiment: Experiment,
    /// The slide drawn (1-based).
    pub slide: u32,
    /// One entry per real class.
    pub classes: Vec<ClassSlides>,
}

/// Slide `slide` of the recording of `label` with the lowest repetition in `recs`.
fn pick(recs: &[Recording], label: f64, slide: u32) -> Option<SlideRows> {
    let rec = recs
        .iter()
        .filter(|r| r.label() == Some(label))
        .min_by_key(|r| r.repetition().unwrap_or(u32::MAX))?;
    let rows: SlideRows = rec
        .rows
        .iter()
        .filter(|row| row.slide == slide)
        .map(crackbot_recording::Row::channels)
        .collect();
    (!rows.is_empty()).then_some(rows)
}

/// Chooses what the real-vs-simulated comparison draws: for every class of `real`, slide
/// `slide` of its first real and first simulated recording.
pub fn compare_slides(real: &[Recording], simulated: &[Recording], slide: u32) -> Comparison {
    let mut labels: Vec<f64> = real
        .iter()
        .filter_map(crackbot_recording::Recording::label)
        .collect();
    labels.sort_by(f64::total_cmp);
    labels.dedup();
    let experiment = experiment_of(&labels);
    Comparison {
        experiment,
        slide,
        classes: labels
            .into_iter()
            .map(|label| ClassSlides {
                label,
                name: class_name(label, experiment),
                real: pick(real, label, slide),
                simulated: pick(simulated, label, slide),
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_recording::Row;

    fn rec(label: f64, repetition: u32, slides: &[u32]) -> Recording {
        Recording {
            rows: slides
                .iter()
                .map(|&slide| Row {
                    x_mm: 0.0,
                    d1: f64::from(repetition),
                    d2: 0.0,
                    d3: 0.0,
                    p: 0.0,
                    direction: 1,
                    slide,
                    label,
                    repetition,
                })
                .collect(),
            extra: None,
        }
    }

    #[test]
    fn the_comparison_takes_the_first_repetition_of_every_real_class() {
        let real = [
            rec(1.0, 2, &[1, 2]),
            rec(1.0, 1, &[2, 2]),
            rec(0.0, 1, &[1]),
        ];
        let sim = [rec(1.0, 3, &[2])];
        let c = compare_slides(&real, &sim, 2);
        assert_eq!(c.experiment, Experiment::Recognition);
        assert_eq!(c.classes.len(), 2);
        assert_eq!(c.classes[0].name, "no crack");
        assert_eq!(c.classes[0].real, None);
        assert_eq!(c.classes[1].name, "crack");
        assert_eq!(c.classes[1].real.as_ref().unwrap().len(), 2);
        assert_eq!(c.classes[1].real.as_ref().unwrap()[0][0], 1.0);
        assert_eq!(c.classes[1].simulated.as_ref().unwrap().len(), 1);
        assert_eq!(experiment_of(&[5.0]), Experiment::Width);
        assert_eq!(class_name(5.0, Experiment::Width), "5 mm");
    }

    #[test]
    fn empty_folders_and_missing_repetitions_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let err = load_recordings(dir.path()).unwrap_err();
        assert!(
            err.to_string().contains(&dir.path().display().to_string()),
            "{err}"
        );
        let err = load_recordings(&dir.path().join("missing")).unwrap_err();
        assert!(
            err.to_string().starts_with("reading recordings in"),
            "{err}"
        );
        crackbot_recording::write_recording(&dir.path().join("a_1.csv"), &rec(0.0, 1, &[1]))
            .unwrap();
        assert_eq!(recordings_of_repetition(dir.path(), 1).unwrap().len(), 1);
        let err = recordings_of_repetition(dir.path(), 2).unwrap_err();
        assert!(err.to_string().contains("repetition 2"), "{err}");
    }
}
