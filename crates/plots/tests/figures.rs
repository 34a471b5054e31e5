//! The PNG figures of every crate: valid files of the documented sizes, and clear errors on
//! unusable paths or empty results.

use std::path::{Path, PathBuf};

use crackbot_plots::sim::{compare_png, work_precision_png, WORK_PRECISION_SIZE};
use crackbot_plots::tactile::{
    accuracy_boxplot_png, confusion_png, paper_plots, plots_markdown, tradeoff_png, BOXPLOT_SIZE,
    CONFUSION_SIZE, TRADEOFF_SIZE,
};
use crackbot_plots::vision::{detector_tradeoff_png, DETECTOR_TRADEOFF_SIZE};
use crackbot_sim::recordings::{ClassSlides, Comparison};
use crackbot_sim::work_precision::WorkPrecisionRow;
use crackbot_tactile::dataset::Experiment;
use crackbot_tactile::metrics::ConfusionMatrix;
use crackbot_tactile::paper::{CellResult, PairResult, PaperTables};
use crackbot_tactile::tradeoff::{Tradeoff, TradeoffConfig, TradeoffRow as ForestRow};
use crackbot_vision::tradeoff::TradeoffRow;

/// A fresh, empty folder under Cargo's temporary folder for integration tests.
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("plots-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// Checks the PNG signature, the IHDR chunk (first, 13 bytes) and the final IEND chunk, and
/// returns (width, height).
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(bytes.len() > 45, "{}: too short for a PNG", path.display());
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "{}: PNG signature",
        path.display()
    );
    assert_eq!(&bytes[8..12], &13u32.to_be_bytes(), "IHDR length");
    assert_eq!(&bytes[12..16], b"IHDR", "first chunk is IHDR");
    assert_eq!(
        &bytes[bytes.len() - 8..bytes.len() - 4],
        b"IEND",
        "last chunk is IEND"
    );
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    (be(16), be(20))
}

fn matrix() -> ConfusionMatrix {
    let truth = [0, 0, 0, 0, 1, 1, 1, 2, 2, 3, 3, 3];
    let predicted = [0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 0];
    ConfusionMatrix::from_labels(4, &truth, &predicted).expect("matrix")
}

fn tables() -> PaperTables {
    let mut cells = Vec::new();
    for (ci, classifier) in ["RF", "QDA"].into_iter().enumerate() {
        for (si, set) in ["P", "D1D2D3", "D1D2D3+P", "D1D2+P"]
            .into_iter()
            .enumerate()
        {
            for (fi, feature) in ["RAW", "MAV", "RMS"].into_iter().enumerate() {
                let base = 0.6 + 0.08 * si as f64 + 0.02 * fi as f64 - 0.05 * ci as f64;
                let pairs: Vec<PairResult> = (0..6)
                    .map(|k| PairResult {
                        train_repetition: 1 + k / 2,
                        test_repetition: 1 + (k / 2 + 1 + k % 2) % 3,
                        window_accuracy: base + 0.01 * k as f64,
                        window_precision: base,
                        window_recall: base + 0.01 * k as f64,
                        slide_accuracy: base + 0.1,
                    })
                    .collect();
                cells.push(CellResult {
                    classifier: classifier.to_string(),
                    feature: feature.to_string(),
                    set: set.to_string(),
                    accuracy_mean: base + 0.025,
                    accuracy_std: 0.018,
                    precision_mean: base,
                    recall_mean: base + 0.025,
                    slide_accuracy_mean: base + 0.1,
                    pairs,
                    confusion: matrix(),
                });
            }
        }
    }
    PaperTables {
        experiment: Experiment::Recognition,
        classes: Experiment::Recognition
            .class_names()
            .iter()
            .map(std::string::ToString::to_string)
            .collect(),
        repetitions: vec![1, 2, 3],
        cells,
        kruskal_wallis_sets: Vec::new(),
    }
}

#[test]
fn confusion_matrix_is_a_png_of_the_documented_size() {
    let dir = scratch("confusion");
    let path = dir.join("confusion.png");
    confusion_png(
        &path,
        &matrix(),
        Experiment::Recognition.class_names(),
        "test matrix",
    )
    .expect("drawn");
    assert_eq!(png_size(&path), CONFUSION_SIZE);
    let wrong = confusion_png(&dir.join("x.png"), &matrix(), &["a", "b"], "t")
        .expect_err("two names for four classes")
        .to_string();
    assert!(wrong.contains("2 class names"), "{wrong}");
}

#[test]
fn accuracy_boxplots_and_the_paper_figures_are_written_and_listed() {
    let dir = scratch("paper");
    let tables = tables();
    let path = dir.join("box.png");
    accuracy_boxplot_png(&path, &tables, "QDA").expect("drawn");
    assert_eq!(png_size(&path), BOXPLOT_SIZE);
    let missing = accuracy_boxplot_png(&dir.join("knn.png"), &tables, "KNN")
        .expect_err("no KNN cell")
        .to_string();
    assert!(missing.contains("KNN"), "{missing}");

    let files = paper_plots(&dir, &tables).expect("figures");
    let names: Vec<String> = files
        .iter()
        .map(|f| {
            f.path
                .file_name()
                .expect("file name")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    // RF MAV D1D2+P, the best RF cell (RMS D1D2+P), the best QDA cell, two box plots.
    assert_eq!(
        names,
        [
            "confusion-recognition-rf-mav-d1d2p.png",
            "confusion-recognition-rf-rms-d1d2p.png",
            "confusion-recognition-qda-rms-d1d2p.png",
            "accuracy-recognition-rf.png",
            "accuracy-recognition-qda.png",
        ]
    );
    for f in &files {
        let expected = if f.path.to_string_lossy().contains("confusion-") {
            CONFUSION_SIZE
        } else {
            BOXPLOT_SIZE
        };
        assert_eq!(png_size(&f.path), expected, "{}", f.path.display());
    }
    let md = plots_markdown(&files, &dir);
    for n in &names {
        assert!(md.contains(&format!("]({n})")), "{md}");
    }
}

#[test]
fn tradeoff_plot_is_a_png_of_the_documented_size() {
    let dir = scratch("tradeoff");
    let mut rows = Vec::new();
    for (di, max_depth) in [None, Some(8)].into_iter().enumerate() {
        for (ti, n_trees) in [1usize, 10, 100].into_iter().enumerate() {
            rows.push(ForestRow {
                n_trees,
                max_depth,
                depth_reached: max_depth.unwrap_or(25),
                n_nodes: 1000 * n_trees,
                model_bytes: 12_000 * n_trees,
                train_seconds: 0.01 * n_trees as f64,
                latency_seconds: 1e-7 * n_trees as f64,
                window_accuracy: 0.7 + 0.05 * ti as f64 - 0.03 * di as f64,
                slide_accuracy: 0.9 + 0.03 * ti as f64,
            });
        }
    }
    let tradeoff = Tradeoff {
        experiment: Experiment::Width,
        train_windows: 1000,
        test_windows: 900,
        test_slides: 12,
        n_features: 3,
        train_threads: 2,
        config: TradeoffConfig::default(),
        rows,
    };
    let path = dir.join("tradeoff.png");
    tradeoff_png(&path, &tradeoff).expect("drawn");
    assert_eq!(png_size(&path), TRADEOFF_SIZE);
}

#[test]
fn unwritable_targets_are_clear_errors() {
    let dir = scratch("errors");
    let m = matrix();
    let names = Experiment::Recognition.class_names();

    let missing = dir.join("no-such-folder").join("m.png");
    let e = confusion_png(&missing, &m, names, "t")
        .expect_err("missing folder")
        .to_string();
    assert!(e.contains("m.png") && e.contains("does not exist"), "{e}");
    assert!(!missing.exists());

    let file = dir.join("a-file");
    std::fs::write(&file, b"not a folder").expect("file");
    let under_file = file.join("m.png");
    let e = confusion_png(&under_file, &m, names, "t")
        .expect_err("parent is a file")
        .to_string();
    assert!(e.contains("m.png"), "{e}");

    let e = confusion_png(&dir.join("m.jpg"), &m, names, "t")
        .expect_err("not .png")
        .to_string();
    assert!(e.contains(".png"), "{e}");

    // A folder where the file should be: the encoder's error, naming the path.
    let taken = dir.join("taken.png");
    std::fs::create_dir_all(&taken).expect("folder");
    let e = confusion_png(&taken, &m, names, "t")
        .expect_err("a folder")
        .to_string();
    assert!(
        e.contains("taken.png") && e.contains("could not write"),
        "{e}"
    );
}

fn wp_row(method: &str, family: &str, rms: Option<f64>, ms: f64) -> WorkPrecisionRow {
    WorkPrecisionRow {
        method: method.into(),
        family: family.into(),
        rms_error_counts: rms,
        max_error_counts: rms.map(|r| 10.0 * r),
        ms_per_sim_second: ms,
        real_time_factor: 1000.0 / ms,
        rhs_per_sim_second: 800.0,
        failure: rms.is_none().then(|| "blew up".to_string()),
    }
}

#[test]
fn the_simulator_and_detector_figures_are_pngs_of_their_sizes() {
    let dir = scratch("sim-vision");
    let rows = vec![
        wp_row("sdirk2 x1", "sdirk2", Some(0.013), 0.66),
        wp_row("sdirk2 x8", "sdirk2", Some(0.0019), 2.67),
        wp_row("dopri5 1e-6", "dopri5", Some(8e-5), 17.2),
        wp_row("symplectic x1", "symplectic-euler", None, 0.2),
    ];
    let wp = dir.join("work_precision.png");
    work_precision_png(&wp, &rows).unwrap();
    assert_eq!(png_size(&wp), WORK_PRECISION_SIZE);

    let tradeoff = [
        (Some(256), 0.25, 6.0),
        (Some(320), 0.31, 9.5),
        (None, 0.05, 30.0),
    ]
    .map(|(size, map50, ms)| TradeoffRow {
        detector: size.map_or("classical".into(), |s| format!("onnx-{s}")),
        input_size: size,
        map: map50 / 2.0,
        map50,
        ar100: map50,
        ms_per_frame: ms,
    });
    let png = dir.join("tradeoff.png");
    detector_tradeoff_png(&png, &tradeoff).unwrap();
    assert_eq!(png_size(&png), DETECTOR_TRADEOFF_SIZE);

    let slide = |level: f64| {
        Some(
            (0..400)
                .map(|k| [level, 430.0, 700.0, 500.0 - (k % 50) as f64])
                .collect(),
        )
    };
    let comparison = Comparison {
        experiment: Experiment::Recognition,
        slide: 3,
        classes: vec![
            ClassSlides {
                label: 0.0,
                name: "no crack".into(),
                real: slide(650.0),
                simulated: slide(652.0),
            },
            ClassSlides {
                label: 1.0,
                name: "crack".into(),
                real: slide(660.0),
                simulated: None,
            },
        ],
    };
    let cmp = dir.join("compare.png");
    compare_png(&cmp, &comparison).unwrap();
    assert_eq!(png_size(&cmp), (1600, 2 * 260 + 60));
}

#[test]
fn figures_with_nothing_to_draw_or_a_bad_target_are_clear_errors() {
    let dir = scratch("sim-vision-errors");
    let failed = vec![wp_row("symplectic x1", "symplectic-euler", None, 0.2)];
    let err = work_precision_png(&dir.join("wp.png"), &failed).unwrap_err();
    assert!(err.to_string().contains("no integrator finished"), "{err}");
    let err = detector_tradeoff_png(&dir.join("tradeoff.jpg"), &[]).unwrap_err();
    assert!(err.to_string().contains("must end in .png"), "{err}");
    let err = detector_tradeoff_png(&dir.join("no/such/folder/t.png"), &[]).unwrap_err();
    assert!(err.to_string().contains("does not exist"), "{err}");
}
