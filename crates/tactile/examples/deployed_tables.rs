//! The deployed configuration's accuracy tables for the model card: leave-one-repetition-out and
//! intersession (train on one repetition, test on another), recognition and width, with the width
//! estimators side by side (posterior mean, posterior mode, regressor median). Recognition is
//! trained as `crackbot tactile train` trains the deployed model: on the surface-type recordings
//! and the width recordings read as surface types (0 mm "no crack", every other width "crack"),
//! and tested on the held-out repetition of both.
//!
//! ```sh
//! CRACKBOT_DATA_DIR=../shared/data cargo run --release -p crackbot-tactile --example deployed_tables
//! ```
//! Data: the authors' repetitions 1–3 only.

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::dataset::Experiment;
use crackbot_tactile::evaluation::evaluate_model_recordings;
use crackbot_tactile::model::{TactileModel, TrainConfig};
use crackbot_tactile::online::classify_recording;

type Recs = Vec<(PathBuf, Recording)>;

/// The recordings of `all` whose repetition column is one of `reps`.
fn pick(all: &Recs, reps: &[u32]) -> Recs {
    all.iter()
        .filter(|(_, r)| r.repetition().is_some_and(|r| reps.contains(&r)))
        .cloned()
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let only = std::env::args().nth(1);
    let config = TrainConfig {
        n_trees: 32,
        max_depth: Some(10),
        seed: 1,
    };
    let mut folds: Vec<(Vec<u32>, u32)> = vec![(vec![2, 3], 1), (vec![1, 3], 2), (vec![1, 2], 3)];
    for a in 1..=3 {
        for b in 1..=3 {
            if a != b {
                folds.push((vec![a], b));
            }
        }
    }
    for (experiment, dir) in [
        (Experiment::Recognition, crackbot_datasets::TACTILE_TYPE),
        (Experiment::Width, crackbot_datasets::TACTILE_WIDTH),
    ] {
        if only
            .as_deref()
            .is_some_and(|o| o != format!("{experiment:?}").to_lowercase())
        {
            continue;
        }
        let dir = crackbot_datasets::require(dir);
        let all = collect_recordings(&[dir])?;
        // The width plates read as surface types: pooled into recognition's training, and a
        // second test set for it.
        let width_plates: Recs = if experiment == Experiment::Recognition {
            let dir = crackbot_datasets::require(crackbot_datasets::TACTILE_WIDTH);
            collect_recordings(&[dir])?
                .into_iter()
                .map(|(p, r)| r.width_as_recognition().map(|r| (p, r)))
                .collect::<Result<_, _>>()?
        } else {
            Vec::new()
        };
        println!("| {experiment:?}: train → test | windows | slides | width plates: windows / slides | width MAE posterior mean / mode / regressor (slides), mm |");
        println!("|---|---|---|---|---|");
        for (train_reps, test_rep) in &folds {
            let mut train = pick(&all, train_reps);
            train.extend(pick(&width_plates, train_reps));
            let test = pick(&all, &[*test_rep]);
            let model = TactileModel::train(&train, Some(experiment), &config, &mut |_, _, _| {})?;
            let report = evaluate_model_recordings(&model, &test)?;
            let mut plates = String::from("–");
            if !width_plates.is_empty() {
                let r = evaluate_model_recordings(&model, &pick(&width_plates, &[*test_rep]))?;
                plates = format!(
                    "{:.1} % / {:.1} %",
                    100.0 * r.window_accuracy,
                    100.0 * r.slide_accuracy
                );
            }
            let mut width = String::from("–");
            if experiment == Experiment::Width {
                let (mut n, mut mean, mut mode, mut reg) = (0usize, 0.0, 0.0, 0.0);
                for (_, rec) in &test {
                    let truth = rec.label().unwrap_or(f64::NAN);
                    for v in classify_recording(&model, rec)?.into_iter().flatten() {
                        let Some(w) = v.width else { continue };
                        n += 1;
                        mean += (w.posterior_mean_mm - truth).abs();
                        mode += (v.label - truth).abs();
                        reg += (w.regressor_mm - truth).abs();
                    }
                }
                let n = n.max(1) as f64;
                width = format!("{:.2} / {:.2} / {:.2}", mean / n, mode / n, reg / n);
            }
            println!(
                "| {:?} → {} | {:.1} % | {:.1} % | {} | {} |",
                train_reps,
                test_rep,
                100.0 * report.window_accuracy,
                100.0 * report.slide_accuracy,
                plates,
                width
            );
        }
    }
    Ok(())
}
