//! A quick probe of how well the simulated finger transfers, for trying simulator parameters:
//! for each parameter file (none: the committed simulator) it simulates the recognition plates
//! and reports
//! - real → sim: slides of the simulation read right by a recognition model trained on real
//!   repetition 1 (`--fit-model`, the repetition the simulator is fitted on) and by the deployed
//!   model (`models/tactile/recognition.ctm`, repetitions 1–3: a held-out figure);
//! - sim → real: a small deployed-configuration forest trained on the simulation, tested on real
//!   repetition 1 (fitting) and on repetitions 2 and 3 (held out).
//!
//! ```sh
//! CRACKBOT_DATA_DIR=../shared/data cargo run --release -p crackbot-research --example transfer_probe -- \
//!     --fit-model fold1/recognition.ctm [--fit-width-model fold1w/width.ctm] [--seed 7] \
//!     [--recordings 5] [--width-only] [PARAMS.toml …]
//! ```
//! Run from the repository root (it reads `models/tactile/*.ctm`). The repetition-1 models:
//! ```sh
//! crackbot tactile convert --width-as-recognition ../shared/data/tactile/width/*_1.mat --out wlab
//! crackbot tactile train --recognition ../shared/data/tactile/type/*_1.mat wlab/*_1.csv \
//!     --out fold1 --trees 32 --max-depth 10
//! crackbot tactile train --width ../shared/data/tactile/width/*_1.mat --out fold1w --trees 32 --max-depth 10
//! ```
//! Data: the authors' repetitions 1–3 only. Used to choose the wavy plate's amplitude
//! (`crates/sim/docs/calibration.md`, "The wavy plate's amplitude").

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use crackbot_recording::{collect_recordings, Recording};
use crackbot_sim::experiment::{generate, Experiment, ExperimentConfig};
use crackbot_tactile::evaluation::evaluate_model_recordings;
use crackbot_tactile::model::{TactileModel, TrainConfig};

type Recs = Vec<(PathBuf, Recording)>;

/// Simulates `experiment` (seed `seed`, parameters `params` over the calibrated ones, `recordings`
/// per plate when given) and reads the recordings back.
fn simulate(
    experiment: Experiment,
    seed: u64,
    params: Option<&str>,
    recordings: Option<u32>,
) -> Result<Recs> {
    let mut config = ExperimentConfig::paper(experiment, seed);
    if let Some(text) = params {
        config.apply_params_toml(text)?;
    }
    if let Some(n) = recordings {
        config.recordings = n;
    }
    let dir = tempfile::tempdir()?;
    generate(&config, dir.path(), "csv", |_, _| {})?;
    Ok(collect_recordings(&[dir.path().to_path_buf()])?)
}

/// The recordings of `all` whose repetition column is one of `reps`.
fn pick(all: &Recs, reps: &[u32]) -> Recs {
    all.iter()
        .filter(|(_, r)| r.repetition().is_some_and(|r| reps.contains(&r)))
        .cloned()
        .collect()
}

fn slides_right(model: &TactileModel, test: &Recs) -> Result<(f64, Vec<Vec<u64>>)> {
    let r = evaluate_model_recordings(model, test)?;
    Ok((r.slide_accuracy, r.slide_confusion))
}

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut fit_model, mut fit_width, mut seed, mut recordings, mut params) =
        (None, None, 7u64, None, Vec::new());
    let mut width_only = false;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--fit-model" => fit_model = args.next().map(PathBuf::from),
            "--fit-width-model" => fit_width = args.next().map(PathBuf::from),
            "--width-only" => width_only = true,
            "--seed" => seed = args.next().context("--seed needs a value")?.parse()?,
            "--recordings" => {
                recordings = Some(args.next().context("--recordings needs a value")?.parse()?);
            }
            _ => params.push(PathBuf::from(a)),
        }
    }
    let Some(fit_model) = fit_model else {
        bail!("--fit-model FILE (a recognition model trained on repetition 1) is required")
    };
    if width_only && fit_width.is_none() {
        bail!("--width-only needs --fit-width-model FILE (a width model trained on repetition 1)")
    }
    let fit_model = TactileModel::load(&fit_model)?;
    let deployed = TactileModel::load(Path::new("models/tactile/recognition.ctm"))?;
    let width_models = match &fit_width {
        Some(p) => Some((
            TactileModel::load(p)?,
            TactileModel::load(Path::new("models/tactile/width.ctm"))?,
        )),
        None => None,
    };
    let real = collect_recordings(&[crackbot_datasets::require(crackbot_datasets::TACTILE_TYPE)])?;
    let (real1, real23) = (pick(&real, &[1]), pick(&real, &[2, 3]));
    let real_width =
        collect_recordings(&[crackbot_datasets::require(crackbot_datasets::TACTILE_WIDTH)])?;
    let (real_width1, real_width23) = (pick(&real_width, &[1]), pick(&real_width, &[2, 3]));
    let train = TrainConfig {
        n_trees: 16,
        max_depth: Some(10),
        seed: 1,
        ..TrainConfig::default()
    };
    println!("| params | seed | real→sim, rep-1 model: slides | real→sim, deployed: slides | sim→real 1: windows / slides | sim→real 2, 3: windows / slides | s |");
    println!("|---|---|---|---|---|---|---|");
    let runs: Vec<Option<PathBuf>> = if params.is_empty() {
        vec![None]
    } else {
        params.into_iter().map(Some).collect()
    };
    for p in runs {
        let t = Instant::now();
        let text = match &p {
            Some(p) => Some(std::fs::read_to_string(p).with_context(|| p.display().to_string())?),
            None => None,
        };
        let name = p.map_or("committed".into(), |p| p.display().to_string());
        if !width_only {
            let sim = simulate(Experiment::Recognition, seed, text.as_deref(), recordings)?;
            let (r1, c1) = slides_right(&fit_model, &sim)?;
            let (rd, cd) = slides_right(&deployed, &sim)?;
            let model = TactileModel::train(
                &sim,
                Some(Experiment::Recognition),
                &train,
                &mut |_, _, _| {},
            )?;
            let s1 = evaluate_model_recordings(&model, &real1)?;
            let s23 = evaluate_model_recordings(&model, &real23)?;
            println!(
                "| {name} | {seed} | {:.1} % | {:.1} % | {:.1} % / {:.1} % | {:.1} % / {:.1} % | {:.0} |",
                100.0 * r1,
                100.0 * rd,
                100.0 * s1.window_accuracy,
                100.0 * s1.slide_accuracy,
                100.0 * s23.window_accuracy,
                100.0 * s23.slide_accuracy,
                t.elapsed().as_secs_f64()
            );
            eprintln!(
                "{name}: rep-1 model {c1:?}; deployed {cd:?}; s2r1 {:?}",
                s1.slide_confusion
            );
        }
        if let Some((fit_w, deployed_w)) = &width_models {
            let sim = simulate(Experiment::Width, seed, text.as_deref(), recordings)?;
            let a = evaluate_model_recordings(fit_w, &sim)?;
            let b = evaluate_model_recordings(deployed_w, &sim)?;
            let model =
                TactileModel::train(&sim, Some(Experiment::Width), &train, &mut |_, _, _| {})?;
            let w1 = evaluate_model_recordings(&model, &real_width1)?;
            let w23 = evaluate_model_recordings(&model, &real_width23)?;
            println!(
                "| {name} width | {seed} | {:.1} % (MAE {:.2} mm) | {:.1} % (MAE {:.2} mm) | {:.1} % / {:.1} % | {:.1} % / {:.1} % | |",
                100.0 * a.slide_accuracy,
                a.slide_width_reported_mae_mm.unwrap_or(f64::NAN),
                100.0 * b.slide_accuracy,
                b.slide_width_reported_mae_mm.unwrap_or(f64::NAN),
                100.0 * w1.window_accuracy,
                100.0 * w1.slide_accuracy,
                100.0 * w23.window_accuracy,
                100.0 * w23.slide_accuracy,
            );
            eprintln!(
                "{name} width: rep-1 model {:?}; deployed {:?}",
                a.slide_confusion, b.slide_confusion
            );
        }
    }
    Ok(())
}
