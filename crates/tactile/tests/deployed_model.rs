//! The deployed model: trained, written, read back; corrupt, truncated and mismatched files are
//! refused with a clear error; online classification (sample by sample) gives the offline slide
//! verdicts bit for bit on real recordings, under random chunking of the stream too, with either
//! slide vote; the context vote does not move with the fibres' offsets.

// Helpers shared by the tests unwrap too: a failure there is a failed test.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crackbot_forest::Classifier;
use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::dataset::{Experiment, WindowSet};
use crackbot_tactile::eval::test_classifier_with_slide_voters;
use crackbot_tactile::evaluation::{evaluate_model_recordings, SlideVote};
use crackbot_tactile::model::{TactileModel, TrainConfig, FORMAT_VERSION, MAGIC};
use crackbot_tactile::online::{classify_recording, OnlineClassifier};
use crackbot_tactile::TactileError;
use proptest::prelude::*;

fn type_recordings(rep: u32) -> Vec<(PathBuf, Recording)> {
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE_TYPE);
    collect_recordings(&[dir])
        .unwrap()
        .into_iter()
        .filter(|(p, _)| p.to_string_lossy().ends_with(&format!("_{rep}.mat")))
        .collect()
}

/// A small recognition model trained on repetition 1, voting with the context forest alone (the
/// default; shared by the tests).
fn model() -> &'static TactileModel {
    static MODEL: OnceLock<TactileModel> = OnceLock::new();
    MODEL.get_or_init(|| small_model(SlideVote::Context))
}

/// The same model with the window forest voting too.
fn model_voting_both() -> &'static TactileModel {
    static MODEL: OnceLock<TactileModel> = OnceLock::new();
    MODEL.get_or_init(|| small_model(SlideVote::Both))
}

fn small_model(slide_vote: SlideVote) -> TactileModel {
    let config = TrainConfig {
        n_trees: 12,
        max_depth: Some(10),
        seed: 3,
        slide_vote,
    };
    TactileModel::train(
        &type_recordings(1),
        Some(Experiment::Recognition),
        &config,
        &mut |_, _, _| {},
    )
    .unwrap()
}

/// `recordings` with a constant added to D1, D2 and D3 of each (as a remounted fibre shifts them).
fn shifted(recordings: &[(PathBuf, Recording)], by: [f64; 3]) -> Vec<(PathBuf, Recording)> {
    recordings
        .iter()
        .map(|(p, rec)| {
            let mut rec = rec.clone();
            rec.shift_deformation(by);
            (p.clone(), rec)
        })
        .collect()
}

#[test]
fn a_model_round_trips_and_bad_files_are_refused_by_name() {
    let m = model();
    let bytes = m.to_bytes().unwrap();
    assert_eq!(&bytes[..8], &MAGIC);
    let back = TactileModel::from_bytes(&bytes, Path::new("m.ctm")).unwrap();
    assert_eq!(back.header, {
        let mut h = m.header.clone();
        h.sections = back.header.sections.clone();
        h
    });
    assert_eq!(back.context_forest, m.context_forest);
    assert_eq!(back.window_forest, m.window_forest);
    let err = |b: &[u8]| {
        TactileModel::from_bytes(b, Path::new("bad.ctm"))
            .unwrap_err()
            .to_string()
    };
    let e = err(b"CRKFORST whatever");
    assert!(
        e.starts_with("bad.ctm: not a crackbot tactile model"),
        "{e}"
    );
    let e = err(&bytes[..bytes.len() / 2]);
    assert!(e.contains("truncated"), "{e}");
    let e = err(&bytes[..12]);
    assert!(e.contains("truncated"), "{e}");
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(err(&longer).contains("trailing"));
    // A flipped byte in a forest (after the header) and one in the header.
    let mut flipped = bytes.clone();
    let at = bytes.len() - 100;
    flipped[at] ^= 0x40;
    let e = err(&flipped);
    assert!(e.contains("corrupt") && e.contains("checksum"), "{e}");
    let mut version = bytes.clone();
    version[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    let e = err(&version);
    assert!(e.contains("format version 2"), "{e}");
    // Parts that do not fit: a window forest where the context forest belongs.
    let mut swapped = m.clone();
    swapped.context_forest = m.window_forest.clone();
    let e = err(&swapped.to_bytes().unwrap());
    assert!(e.contains("context forest takes 3 features"), "{e}");
    // A recognition model given width recordings.
    let width_dir = crackbot_datasets::require(crackbot_datasets::TACTILE_WIDTH);
    let width: Vec<_> = collect_recordings(&[width_dir])
        .unwrap()
        .into_iter()
        .filter(|(p, _)| p.to_string_lossy().contains("mm10"))
        .collect();
    let e = evaluate_model_recordings(m, &width).unwrap_err();
    assert!(matches!(e, TactileError::ExperimentMismatch { .. }), "{e}");
    // Missing file.
    let e = TactileModel::load(Path::new("/nonexistent/model.ctm"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/model.ctm"), "{e}");
}

#[test]
fn online_slide_verdicts_equal_the_offline_ones_bit_for_bit() {
    for m in [model(), model_voting_both()] {
        online_equals_offline(m);
    }
}

fn online_equals_offline(m: &TactileModel) {
    let test = type_recordings(2);
    let pipeline = m.pipeline().unwrap();
    let ctx = pipeline
        .build_windows(&test, Experiment::Recognition)
        .unwrap();
    let win = pipeline
        .without_context()
        .build_windows(&test, Experiment::Recognition)
        .unwrap();
    let voters: &[(&(dyn Classifier + Send + Sync), &WindowSet)] = match m.header.slide_vote {
        SlideVote::Both => &[(&m.window_forest, &win)],
        SlideVote::Context => &[],
    };
    let offline = test_classifier_with_slide_voters(&m.context_forest, &ctx, voters).unwrap();
    let report = evaluate_model_recordings(m, &test).unwrap();
    assert_eq!(report.slide_vote, m.header.slide_vote.name());
    assert_eq!(report.slide_confusion, offline.slides.rows());
    // Online: every classified slide's verdict is the offline one.
    let mut online_confusion = vec![vec![0u64; 4]; 4];
    let mut compared = 0;
    for (ri, (_, rec)) in test.iter().enumerate() {
        let verdicts = classify_recording(m, rec).unwrap();
        let slides: Vec<_> = ctx.slides.iter().filter(|s| s.recording == ri).collect();
        let classified: Vec<_> = verdicts.iter().flatten().filter(|v| v.segmented).collect();
        assert_eq!(
            classified.len(),
            slides.iter().filter(|s| !s.windows.is_empty()).count()
        );
        for (v, s) in classified
            .iter()
            .zip(slides.iter().filter(|s| !s.windows.is_empty()))
        {
            assert_eq!(v.windows, s.windows.len(), "slide {}", s.slide);
            online_confusion[s.class as usize][v.class as usize] += 1;
            compared += 1;
        }
    }
    assert_eq!(online_confusion, offline.slides.rows());
    assert!(compared >= 40, "{compared}");
}

/// Every context feature is relative to the slide's baseline: a model voting with the context
/// forest alone gives the same votes, bit for bit, when the deformation channels are shifted by
/// whole counts (a remounted fibre). The window forest's absolute features do not: the model
/// voting with both changes its votes.
#[test]
fn context_votes_do_not_move_with_the_fibres_offsets() {
    let test = type_recordings(2);
    let moved = shifted(&test, [11.0, -9.0, 7.0]);
    let votes = |m: &TactileModel, set: &[(PathBuf, Recording)]| -> Vec<Vec<f64>> {
        set.iter()
            .flat_map(|(_, rec)| classify_recording(m, rec).unwrap())
            .flatten()
            .map(|v| v.votes)
            .collect()
    };
    let before = votes(model(), &test);
    assert!(before.len() >= 40, "{}", before.len());
    assert_eq!(votes(model(), &moved), before);
    assert_ne!(
        votes(model_voting_both(), &moved),
        votes(model_voting_both(), &test)
    );
}

#[test]
fn running_verdicts_come_every_step_and_bad_samples_are_refused() {
    let m = model();
    let test = type_recordings(3);
    let (_, rec) = test
        .iter()
        .find(|(p, _)| p.to_string_lossy().contains("crack_crack"))
        .unwrap();
    let slide = rec.slides()[2].clone();
    let mut online = OnlineClassifier::new(m).unwrap();
    online.begin_slide();
    let mut running = 0;
    for (i, r) in rec.rows[slide.clone()].iter().enumerate() {
        let v = online.push(r.channels(), r.direction, r.x_mm).unwrap();
        assert_eq!(v.is_some(), i >= 9 && (i - 9) % 2 == 0, "sample {i}");
        if let Some(v) = v {
            assert!((0.0..=1.0).contains(&v.confidence));
            running += 1;
        }
    }
    assert_eq!(running, (slide.len() - 10) / 2 + 1);
    let err = online
        .push([f64::INFINITY, 400.0, 700.0, 500.0], 0, 10.0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("D1"), "{err}");
    let v = online.end_slide().unwrap().unwrap();
    assert_eq!(v.samples, slide.len(), "the refused sample was not kept");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    /// Chunks of random sizes (as the acquisition delivers them) give the same verdicts as one
    /// sample at a time.
    #[test]
    fn random_chunking_gives_the_same_verdicts(chunks in prop::collection::vec(1usize..700, 1..40)) {
        let m = model();
        let test = type_recordings(2);
        let (_, rec) = &test[0];
        let whole = classify_recording(m, rec).unwrap();
        let mut online = OnlineClassifier::new(m).unwrap();
        let mut got = Vec::new();
        for range in rec.slides() {
            online.begin_slide();
            let rows = &rec.rows[range];
            let mut at = 0;
            let mut c = 0;
            while at < rows.len() {
                let n = chunks[c % chunks.len()].min(rows.len() - at);
                for r in &rows[at..at + n] {
                    online.push(r.channels(), r.direction, r.x_mm).unwrap();
                }
                at += n;
                c += 1;
            }
            got.push(online.end_slide().unwrap());
        }
        prop_assert_eq!(got, whole);
    }
}

/// Width on a repetition the model never saw (trained on 1 and 2, tested on 3): the slide's
/// estimate (the vote's mode), the posterior mean and the regressor's, against the plate's width.
#[test]
fn width_of_an_unseen_repetition_is_measured_with_a_covering_uncertainty() {
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE_WIDTH);
    let all = collect_recordings(&[dir]).unwrap();
    let (train, test): (Vec<_>, Vec<_>) = all
        .into_iter()
        .filter(|(p, _)| !p.to_string_lossy().ends_with("_4.mat"))
        .partition(|(p, _)| !p.to_string_lossy().ends_with("_3.mat"));
    let config = TrainConfig {
        n_trees: 32,
        max_depth: Some(10),
        seed: 1,
        ..TrainConfig::default()
    };
    let m =
        TactileModel::train(&train, Some(Experiment::Width), &config, &mut |_, _, _| {}).unwrap();
    let (mut n, mut posterior, mut regressor, mut covered) = (0usize, 0.0, 0.0, 0usize);
    let mut estimate = 0.0;
    for (_, rec) in &test {
        let truth = rec.label().unwrap();
        for v in classify_recording(&m, rec).unwrap().into_iter().flatten() {
            let w = v.width.unwrap();
            n += 1;
            estimate += (w.mm - truth).abs();
            posterior += (w.posterior_mean_mm - truth).abs();
            regressor += (w.regressor_mm - truth).abs();
            covered += usize::from((w.mm - truth).abs() <= 2.0 * w.std_mm + 0.25);
        }
    }
    let (posterior, regressor) = (posterior / n as f64, regressor / n as f64);
    let estimate = estimate / n as f64;
    println!(
        "width, repetition 3 ({n} slides): estimate (mode) MAE {estimate:.3} mm, posterior mean MAE {posterior:.3} mm, regressor MAE {regressor:.3} mm, within 2 std (+0.25 mm) {covered}/{n}"
    );
    // Measured 2026-11-24: estimate 0.00 mm, posterior mean 1.34 mm, regressor 1.00 mm. The
    // issue's goal is MAE ≤ 0.3 mm.
    assert!(estimate <= 0.3, "estimate MAE {estimate}");
    assert!(n >= 60, "{n}");
    assert!(posterior <= 1.5, "posterior MAE {posterior}");
    assert!(regressor <= 1.2, "regressor MAE {regressor}");
    assert!(covered * 10 >= n * 9, "{covered}/{n} within 2 std");
}

/// Model headers are JSON, compared exactly after a round trip. serde_json's default parser
/// missed a training time of 7.396451812 s by one ulp (this test failed once in CI), so the
/// time is kept to the millisecond: every such value reads back exactly.
#[test]
fn training_times_to_the_millisecond_read_back_exactly() {
    for ms in (0..5_000_000u64).step_by(997) {
        let x = (ms as f64 / 1e3 * 1e3).round() / 1e3;
        let back: f64 =
            serde_json::from_str(&serde_json::to_string(&x).expect("json")).expect("a number");
        assert_eq!(back.to_bits(), x.to_bits(), "{x}");
    }
}

/// The committed models: recognition votes with both forests, width with the context forest
/// alone (models/tactile/MODEL_CARD.md, "Who votes").
#[test]
fn the_committed_models_vote_as_their_card_says() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/tactile");
    let recognition = TactileModel::load(&dir.join("recognition.ctm")).unwrap();
    assert_eq!(recognition.header.slide_vote, SlideVote::Both);
    let width = TactileModel::load(&dir.join("width.ctm")).unwrap();
    assert_eq!(width.header.slide_vote, SlideVote::Context);
    assert_eq!(width.header.training.config.slide_vote, SlideVote::Context);
}

/// The committed model `file` learned `real` real recordings and the simulator's plates of seeds
/// 8 and 9 (`per_seed` recordings each), and reads at least `goal` of the slides (and
/// `window_goal` of the windows, where given) of the simulated plates of `seed`, which it never
/// saw.
fn reads_simulated_plates_it_never_saw(
    file: &str,
    real: usize,
    per_seed: usize,
    seed: u64,
    goal: f64,
    window_goal: Option<f64>,
) {
    use crackbot_sim::experiment::{simulate_named, ExperimentConfig};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/tactile");
    let model = TactileModel::load(&dir.join(file)).unwrap();
    let names = &model.header.training.recordings;
    let count = |prefix: &str| names.iter().filter(|n| n.starts_with(prefix)).count();
    assert_eq!(
        (
            count("sim-seed8-"),
            count("sim-seed9-"),
            names.len() - count("sim-")
        ),
        (per_seed, per_seed, real),
        "{names:?}"
    );
    let experiment = model.header.experiment;
    let recordings = simulate_named(&ExperimentConfig::paper(experiment, seed), |_, _| {}).unwrap();
    let report = evaluate_model_recordings(&model, &recordings).unwrap();
    assert!(
        report.slide_accuracy >= goal,
        "{file}, seed {seed}: {} of the simulated slides right",
        report.slide_accuracy
    );
    if let Some(window_goal) = window_goal {
        assert!(
            report.window_accuracy >= window_goal,
            "{file}, seed {seed}: {} of the simulated windows right",
            report.window_accuracy
        );
    }
}

/// Issue 12's goal for width: ≥ 90 % of simulated width slides (96.4–100 % on seeds 7, 12, 13,
/// 20–22 when committed; a model of the real finger alone reads 35.6–46.1 %; MODEL_CARD.md, "A
/// darker proximity floor").
#[test]
fn the_committed_width_model_reads_simulated_plates_it_never_saw() {
    reads_simulated_plates_it_never_saw("width.ctm", 18, 30, 12, 0.9, None);
}

/// Issue 12's goal for recognition: ≥ 95 % of simulated surface-type slides (100 % on seeds
/// 23–28 when committed). Since the strokes start 6–7.4 mm before the feature the model of the
/// real finger alone reads 97.1–99.2 % of those slides too, so the windows say more: the committed
/// model reads 90.5–99.1 % of them (seed 23: 99.0 %), the real finger's model 66.1–80.2 % (seed
/// 23: 70.9 %; MODEL_CARD.md, "A darker proximity floor"). The real recordings: 12 surface-type
/// and 18 width plates.
#[test]
fn the_committed_recognition_model_reads_simulated_plates_it_never_saw() {
    reads_simulated_plates_it_never_saw("recognition.ctm", 30, 20, 23, 0.95, Some(0.9));
}
