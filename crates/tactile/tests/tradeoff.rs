//! The random forest's error against run time, on a few slides of the authors' recordings.

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::dataset::{build_windows, Experiment, PipelineConfig, WindowSet};
use crackbot_tactile::tradeoff::{median_latency, run_tradeoff, TradeoffConfig};

fn data(file: &str) -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::TACTILE_TYPE).join(file)
}

/// The first four slides of each of the four surfaces' recordings of one repetition.
fn windows(repetition: u32) -> WindowSet {
    let files: Vec<PathBuf> = ["nocrack", "crack", "bump", "pattern"]
        .iter()
        .map(|s| data(&format!("crack_{s}_complete_{repetition}.mat")))
        .collect();
    let mut recordings: Vec<(PathBuf, Recording)> =
        collect_recordings(&files).expect("the authors' recordings");
    for (_, rec) in &mut recordings {
        let slides = rec.slides();
        let end = slides.get(3).map_or(rec.rows.len(), |s| s.end);
        rec.rows.truncate(end);
    }
    let config = PipelineConfig::default();
    build_windows(&recordings, Experiment::Recognition, &config).expect("windows")
}

#[test]
fn grid_of_trees_and_depths_is_sane_and_tabulated() {
    let train = windows(1);
    let test = windows(2);
    let config = TradeoffConfig {
        n_trees: vec![1, 5],
        max_depths: vec![None, Some(4)],
        seed: 3,
        latency_batch: 200,
    };
    let mut seen = 0;
    let t = run_tradeoff(&train, &test, &config, |_| seen += 1).expect("grid");
    assert_eq!(seen, 4);
    assert_eq!(t.rows.len(), 4);
    assert_eq!(t.train_windows, train.n_rows());
    assert_eq!(t.test_windows, test.n_rows());
    assert_eq!(t.test_slides, 16);
    let row = |d: Option<usize>, n: usize| {
        t.rows
            .iter()
            .find(|r| r.max_depth == d && r.n_trees == n)
            .expect("row")
    };
    for d in [None, Some(4)] {
        // Tree i depends on (seed, i) only: five trees hold the first one, and more.
        assert!(row(d, 5).n_nodes > row(d, 1).n_nodes, "{d:?}");
        assert!(row(d, 5).model_bytes > row(d, 1).model_bytes, "{d:?}");
    }
    for n in [1, 5] {
        assert!(row(None, n).n_nodes > row(Some(4), n).n_nodes);
        assert!(row(Some(4), n).depth_reached <= 4);
        assert!(
            row(Some(4), n).n_nodes <= n * 31,
            "a depth-4 tree has at most 31 nodes"
        );
    }
    for r in &t.rows {
        assert!((0.0..=1.0).contains(&r.window_accuracy), "{r:?}");
        assert!((0.0..=1.0).contains(&r.slide_accuracy), "{r:?}");
        assert!(r.window_accuracy > 0.25, "better than chance: {r:?}");
        assert!(r.latency_seconds > 0.0 && r.latency_seconds < 1e-3, "{r:?}");
        assert!(
            r.train_seconds >= 0.0 && r.train_seconds.is_finite(),
            "{r:?}"
        );
    }
    let md = t.to_markdown();
    assert!(md.contains("| max depth | trees |"), "{md}");
    for prefix in ["| none | 1 |", "| none | 5 |", "| 4 | 1 |", "| 4 | 5 |"] {
        assert_eq!(
            md.lines().filter(|l| l.starts_with(prefix)).count(),
            1,
            "{prefix}\n{md}"
        );
    }
}

#[test]
fn bad_grids_and_batches_are_errors() {
    let train = windows(1);
    let bad = |config: TradeoffConfig| {
        run_tradeoff(&train, &train, &config, |_| {})
            .expect_err("bad grid")
            .to_string()
    };
    let base = TradeoffConfig {
        n_trees: vec![1],
        max_depths: vec![Some(2)],
        ..TradeoffConfig::default()
    };
    assert!(bad(TradeoffConfig {
        n_trees: vec![],
        ..base.clone()
    })
    .contains("at least one"));
    assert!(bad(TradeoffConfig {
        n_trees: vec![0],
        ..base.clone()
    })
    .contains("at least 1"));
    assert!(bad(TradeoffConfig {
        max_depths: vec![Some(0)],
        ..base.clone()
    })
    .contains("at least 1"));
    let forest = crackbot_forest::RandomForest::fit(
        &crackbot_forest::Dataset::with_classes(
            train.x.clone(),
            train.n_features,
            train.y.clone(),
            4,
        )
        .expect("data"),
        &crackbot_forest::ForestParams::classifier()
            .n_trees(1)
            .quiet(true),
    )
    .expect("forest");
    assert!(median_latency(&forest, &train, 0).is_err());
    assert!(median_latency(&forest, &train, 7).expect("latency") > 0.0);
}
