//! The paper's grid on the authors' real recordings (two repetitions, QDA, to stay fast).

use std::path::PathBuf;

use crackbot_recording::collect_recordings;
use crackbot_tactile::dataset::{detect_experiment, Experiment, PipelineConfig};
use crackbot_tactile::eval::ClassifierKind;
use crackbot_tactile::paper::{by_repetition, run_grid};

fn data(experiment: &str) -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::TACTILE).join(experiment)
}

#[test]
fn grid_on_two_repetitions_of_the_recognition_experiment() {
    let mut recordings = collect_recordings(&[data("type")]).expect("the authors' recordings");
    recordings.retain(|(_, r)| r.repetition() != Some(3));
    assert_eq!(recordings.len(), 8);
    let experiment = detect_experiment(&recordings).expect("experiment");
    assert_eq!(experiment, Experiment::Recognition);
    let reps = by_repetition(recordings).expect("repetitions");
    assert_eq!(
        reps.iter().map(|(r, v)| (*r, v.len())).collect::<Vec<_>>(),
        vec![(1, 4), (2, 4)]
    );
    let base = PipelineConfig::default();
    let mut seen = 0;
    let tables = run_grid(experiment, &reps, &[ClassifierKind::Qda], &base, 1, |_| {
        seen += 1;
    })
    .expect("grid");
    assert_eq!(seen, 12);
    assert_eq!(tables.cells.len(), 12);
    for cell in &tables.cells {
        assert_eq!(cell.pairs.len(), 2, "train 1 → test 2 and train 2 → test 1");
        assert!(cell
            .pairs
            .iter()
            .all(|p| p.train_repetition != p.test_repetition));
        assert!(
            (0.25..=1.0).contains(&cell.accuracy_mean),
            "{} {}: {}",
            cell.feature,
            cell.set,
            cell.accuracy_mean
        );
        assert!(
            (cell.recall_mean - cell.accuracy_mean).abs() < 1e-9,
            "weighted recall equals accuracy"
        );
        assert_eq!(cell.confusion.n_classes(), 4);
    }
    // Deformation and proximity together beat proximity alone, as in the paper.
    let acc = |f: &str, s: &str| {
        tables
            .cells
            .iter()
            .find(|c| c.feature == f && c.set == s)
            .expect("cell")
            .accuracy_mean
    };
    assert!(acc("MAV", "D1D2+P") > acc("MAV", "P"));
    assert_eq!(tables.kruskal_wallis_sets.len(), 3);
    let md = tables.to_markdown();
    assert!(
        md.contains("| MAV — D1D2+P |") && md.contains("95.17"),
        "{md}"
    );
}

#[test]
fn one_repetition_is_not_enough_for_intersession() {
    let mut recordings = collect_recordings(&[data("width")]).expect("the authors' recordings");
    recordings.retain(|(_, r)| r.repetition() == Some(1));
    let err = by_repetition(recordings)
        .expect_err("needs two repetitions")
        .to_string();
    assert!(err.contains("at least two repetitions"), "{err}");
}
