//! The deployed configuration's accuracy tables for the model card: leave-one-repetition-out and
//! intersession (train on one repetition, test on another), recognition and width, with the width
//! estimators side by side (posterior mean, posterior mode, regressor median). Recognition is
//! trained as `crackbot tactile train` trains the deployed model: on the surface-type recordings
//! and the width recordings read as surface types (0 mm "no crack", every other width "crack"),
//! and tested on the held-out repetition of both.
//!
//! Each model votes as the committed one of its experiment does (recognition: both forests;
//! width: the context forest alone; `CRACKBOT_SLIDE_VOTE=both|context` sets both). The column
//! "offsets moved" tests the same model on the held-out recordings with D1, D2 and D3 each shifted
//! by a whole 5–12 counts, up or down, fixed per recording (what remounting the fibres does;
//! between the authors' two sessions the flat levels moved by about 10 counts).
//!
//! `CRACKBOT_WIDTH_SIM_SEEDS=8,9` adds the simulator's width plates of those seeds to every width
//! fold's training, as `crackbot tactile train --width-sim-seeds 8 9` does, and a column with the
//! slides right on simulated width plates of seeds the training never saw (7, 12, 13).
//! `CRACKBOT_RECOGNITION_SIM_SEEDS=8,9` does the same for recognition (`--recognition-sim-seeds`),
//! tested on the simulated surface-type plates of seeds 23–26.
//!
//! ```sh
//! CRACKBOT_DATA_DIR=../shared/data cargo run --release -p crackbot-research --example deployed_tables [recognition|width]
//! ```
//! Data: the authors' repetitions 1–3, and simulated plates where asked.

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::dataset::Experiment;
use crackbot_tactile::evaluation::{evaluate_model_recordings, SlideVote};
use crackbot_tactile::model::{TactileModel, TrainConfig};
use crackbot_tactile::online::classify_recording;

type Recs = Vec<(PathBuf, Recording)>;

/// Seeds of the simulated plates every model of `experiment` is tested on; never trained on.
fn held_out_sim_seeds(experiment: Experiment) -> &'static [u64] {
    match experiment {
        Experiment::Recognition => &[23, 24, 25, 26],
        Experiment::Width => &[7, 12, 13],
    }
}

/// The simulator's plates of `experiment` for `seed`, in memory.
fn simulated(experiment: Experiment, seed: u64) -> Result<Recs, Box<dyn std::error::Error>> {
    use crackbot_sim::experiment::{simulate_named, ExperimentConfig};
    Ok(simulate_named(
        &ExperimentConfig::paper(experiment, seed),
        |_, _| {},
    )?)
}

/// The simulated seeds to train `experiment`'s folds on, from its environment variable.
fn training_sim_seeds(experiment: Experiment) -> Result<Vec<u64>, Box<dyn std::error::Error>> {
    let name = match experiment {
        Experiment::Recognition => "CRACKBOT_RECOGNITION_SIM_SEEDS",
        Experiment::Width => "CRACKBOT_WIDTH_SIM_SEEDS",
    };
    let seeds: Vec<u64> = match std::env::var(name) {
        Ok(v) => v
            .split(',')
            .map(|s| s.trim().parse())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("{name} must be seeds, e.g. 8,9: {e}"))?,
        Err(_) => Vec::new(),
    };
    let held_out = held_out_sim_seeds(experiment);
    if let Some(s) = seeds.iter().find(|s| held_out.contains(s)) {
        return Err(format!("{name}: simulated seed {s} is a test seed ({held_out:?})").into());
    }
    Ok(seeds)
}

/// The recordings of `all` whose repetition column is one of `reps`.
fn pick(all: &Recs, reps: &[u32]) -> Recs {
    all.iter()
        .filter(|(_, r)| r.repetition().is_some_and(|r| reps.contains(&r)))
        .cloned()
        .collect()
}

/// `recs` with D1, D2 and D3 of each recording shifted by a whole 5–12 counts, up or down (a
/// fixed pseudo-random draw per recording and channel).
fn offsets_moved(recs: &Recs) -> Recs {
    recs.iter()
        .enumerate()
        .map(|(i, (p, r))| {
            let mut r = r.clone();
            let by: [f64; 3] = std::array::from_fn(|c| {
                let h = (i as u64 * 3 + c as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
                let size = 5.0 + (h % 8) as f64;
                if (h >> 8).is_multiple_of(2) {
                    size
                } else {
                    -size
                }
            });
            r.shift_deformation(by);
            (p.clone(), r)
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let only = std::env::args().nth(1);
    let forced = match std::env::var("CRACKBOT_SLIDE_VOTE").as_deref() {
        Ok("both") => Some(SlideVote::Both),
        Ok("context") => Some(SlideVote::Context),
        Ok(other) => {
            return Err(format!("CRACKBOT_SLIDE_VOTE must be both or context, got {other}").into())
        }
        Err(_) => None,
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
        // Simulated plates: trained on (the seeds asked for), tested on (the held-out ones).
        let sim_seeds = training_sim_seeds(experiment)?;
        let held_out = held_out_sim_seeds(experiment);
        let mut sim_train = Recs::new();
        for &seed in &sim_seeds {
            sim_train.extend(simulated(experiment, seed)?);
        }
        let sim_test = held_out
            .iter()
            .map(|&seed| simulated(experiment, seed))
            .collect::<Result<Vec<_>, _>>()?;
        let config = TrainConfig {
            n_trees: 32,
            max_depth: Some(10),
            seed: 1,
            slide_vote: forced.unwrap_or(match experiment {
                Experiment::Recognition => SlideVote::Both,
                Experiment::Width => SlideVote::Context,
            }),
        };
        println!(
            "{experiment:?}, slide vote {}{}:",
            config.slide_vote.name(),
            if sim_train.is_empty() {
                String::new()
            } else {
                format!(", with the simulated plates of seeds {sim_seeds:?}")
            }
        );
        println!("| {experiment:?}: train → test | windows | slides | offsets moved: windows / slides | width plates: windows / slides | width MAE posterior mean / mode / regressor (slides), mm | simulated plates, seeds {held_out:?}: slides |");
        println!("|---|---|---|---|---|---|---|");
        for (train_reps, test_rep) in &folds {
            let mut train = pick(&all, train_reps);
            train.extend(pick(&width_plates, train_reps));
            train.extend(sim_train.iter().cloned());
            let test = pick(&all, &[*test_rep]);
            let model = TactileModel::train(&train, Some(experiment), &config, &mut |_, _, _| {})?;
            let report = evaluate_model_recordings(&model, &test)?;
            let moved = evaluate_model_recordings(&model, &offsets_moved(&test))?;
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
            let simulated = sim_test
                .iter()
                .map(|t| evaluate_model_recordings(&model, t))
                .map(|r| r.map(|r| format!("{:.1} %", 100.0 * r.slide_accuracy)))
                .collect::<Result<Vec<_>, _>>()?
                .join(" / ");
            println!(
                "| {:?} → {} | {:.1} % | {:.1} % | {:.1} % / {:.1} % | {} | {} | {} |",
                train_reps,
                test_rep,
                100.0 * report.window_accuracy,
                100.0 * report.slide_accuracy,
                100.0 * moved.window_accuracy,
                100.0 * moved.slide_accuracy,
                plates,
                width,
                simulated
            );
        }
    }
    Ok(())
}
