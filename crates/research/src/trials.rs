//! The detection trials: missions on random scenes, vision only against vision + tactile, run
//! several at a time, each scored and retried once where the link or the sensor failed
//! ([`detection_trials`]).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::budget::{finger_budget, FingerBudget};
use crate::geometry::clearance_mm;
use crate::score::score;
use crate::tables::{
    ClearanceSplit, RetriedMission, Spread, Totals, Trial, TrialsReport, EXPLORATION_GOAL_S,
};
use crackbot_mission::inspect::{run_inspection, InspectConfig, InspectMode, InspectReport};
use crackbot_mission::MissionError;
use crackbot_sim::random_scene::{as_printed, trial_params};
use crackbot_sim::{random_scene, Feature, RandomSceneParams, Scene};

/// Settings shared by the experiments.
#[derive(Debug, Clone)]
pub struct ExperimentConfig {
    /// Where each mission writes its folder.
    pub out_dir: PathBuf,
    /// Simulation speed-up.
    pub speedup: f64,
    /// The mission's settings other than scene, mode and folder.
    pub template: InspectConfig,
    /// Give the trial scenes' cracks the authors' printed cross-section ([`as_printed`]).
    pub printed_cracks: bool,
    /// Trials run at once ([`detection_trials`]). Each mission is a simulated robot in real
    /// time over the speed-up: leave it a core and a half, or its sensor stream looks stalled.
    pub jobs: usize,
}

pub(crate) fn run(
    base: &ExperimentConfig,
    scene: &Scene,
    mode: InspectMode,
    name: &str,
) -> Result<InspectReport, MissionError> {
    let mut c = base.template.clone();
    c.set_scene(scene.clone());
    c.mode = mode;
    c.rig.speedup = base.speedup;
    c.output.out_dir = base.out_dir.join(name);
    let stop = AtomicBool::new(false);
    run_inspection(&c.check()?, &stop, |_| {})
}

/// Runs `n` detection trials on the random scenes of seeds `first_seed..first_seed + n`,
/// `base.jobs` at a time (each trial's two missions one after the other), calling `progress`
/// as each trial ends. The table lists the trials by seed whatever order they ended in.
pub fn detection_trials(
    base: &ExperimentConfig,
    first_seed: u64,
    n: u64,
    mut progress: impl FnMut(u64, &Trial),
) -> Result<TrialsReport, MissionError> {
    if base.jobs == 0 {
        return Err(MissionError::Setting {
            field: "jobs",
            value: 0.0,
            allowed: "at least 1 trial at once",
        });
    }
    let params = trial_params();
    let mut trials: Vec<Trial> = Vec::new();
    let mut retried: Vec<RetriedMission> = Vec::new();
    let next = AtomicU64::new(first_seed);
    let failed = AtomicBool::new(false);
    let end = first_seed.saturating_add(n);
    let workers = (base.jobs as u64).min(n.max(1)) as usize;
    let mut first_error = None;
    std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::channel();
        for _ in 0..workers {
            let tx = tx.clone();
            let (next, failed, params) = (&next, &failed, &params);
            scope.spawn(move || {
                while !failed.load(Ordering::Relaxed) {
                    let seed = next.fetch_add(1, Ordering::Relaxed);
                    if seed >= end {
                        break;
                    }
                    let mut again = Vec::new();
                    let result = one_trial(base, params, seed, &mut again);
                    if result.is_err() {
                        failed.store(true, Ordering::Relaxed);
                    }
                    if tx.send((seed, result, again)).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        for (seed, result, again) in rx {
            retried.extend(again);
            match result {
                Ok(t) => {
                    progress(seed, &t);
                    trials.push(t);
                }
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
    });
    if let Some(e) = first_error {
        return Err(e);
    }
    trials.sort_by_key(|t| t.seed);
    retried.sort_by_key(|r| r.seed);
    let mean =
        |f: &dyn Fn(&Trial) -> f64| trials.iter().map(f).sum::<f64>() / trials.len().max(1) as f64;
    // Mean absolute value over every fused trial's list (`None` when all are empty).
    let mean_abs = |errors: &dyn Fn(&Trial) -> &[f64]| -> Option<f64> {
        let e: Vec<f64> = trials
            .iter()
            .flat_map(|t| errors(t).iter().map(|e| e.abs()))
            .collect();
        (!e.is_empty()).then(|| e.iter().sum::<f64>() / e.len() as f64)
    };
    let mut finger = FingerBudget::default();
    for t in &trials {
        finger.add(&t.finger);
    }
    let explored: Vec<f64> = trials.iter().map(|t| t.fused_exploration_s).collect();
    Ok(TrialsReport {
        fused_by_clearance: ClearanceSplit::of(&trials),
        finger,
        finger_right_calls: finger.right_call_share(),
        vision_totals: Totals::of(trials.iter().map(|t| &t.vision)),
        fused_totals: Totals::of(trials.iter().map(|t| &t.fused)),
        fused_exploration_s: Spread::of(&explored),
        fused_within_goal: explored
            .iter()
            .filter(|&&e| e <= EXPLORATION_GOAL_S)
            .count(),
        vision_correct: mean(&|t| t.vision.correct_fraction()),
        fused_correct: mean(&|t| t.fused.correct_fraction()),
        // Distances: their absolute values are themselves.
        fused_localisation_mm: mean_abs(&|t| &t.fused.localisation_mm),
        fused_width_mae_mm: mean_abs(&|t| &t.fused.width_error_mm),
        fused_extent_width_mae_mm: mean_abs(&|t| &t.fused.extent_width_error_mm),
        trials,
        retried,
        paper: [46.66, 92.85],
    })
}

/// One trial: the scene of `seed`, its vision-only and its fused mission, scored.
pub(crate) fn one_trial(
    base: &ExperimentConfig,
    params: &RandomSceneParams,
    seed: u64,
    retried: &mut Vec<RetriedMission>,
) -> Result<Trial, MissionError> {
    let mut scene = random_scene(params, seed)?;
    if base.printed_cracks {
        scene = as_printed(&scene);
    }
    let vision = run_retried(base, &scene, InspectMode::Vision, seed, retried)?;
    let fused = run_retried(base, &scene, InspectMode::Fused, seed, retried)?;
    let decoys = scene
        .features
        .iter()
        .filter(|f| matches!(f, Feature::Decoy { .. }))
        .count();
    Ok(Trial {
        seed,
        cracks: score(&scene, &vision).cracks,
        decoys,
        vision: score(&scene, &vision),
        fused: score(&scene, &fused),
        fused_exploration_s: fused.exploration_s,
        finger: finger_budget(&scene, &fused),
        clearance_mm: clearance_mm(&scene),
    })
}

/// [`run`] for one trial's mission, run once more from the start when the run itself failed
/// (a sensor stream that stalls twice in one slide on a loaded machine, say): the first
/// failure is kept in `retried` and its folder renamed `…-failed`. A second failure, or a
/// setting that cannot work, ends the trials with its error.
pub(crate) fn run_retried(
    base: &ExperimentConfig,
    scene: &Scene,
    mode: InspectMode,
    seed: u64,
    retried: &mut Vec<RetriedMission>,
) -> Result<InspectReport, MissionError> {
    let name = format!("trial-{seed}-{}", mode.as_str());
    retry_once(seed, mode, retried, |again| {
        let dir = base.out_dir.join(&name);
        if again && dir.exists() {
            let failed = base.out_dir.join(format!("{name}-failed"));
            let _ = std::fs::remove_dir_all(&failed);
            std::fs::rename(&dir, &failed).map_err(|source| MissionError::Io {
                path: dir.clone(),
                source,
            })?;
        }
        run(base, scene, mode, &name)
    })
}

/// Whether a mission that failed this way may go right the next time: the link, the sensor
/// stream or the controller failed, not a setting, a model or the scene.
pub(crate) fn worth_retrying(e: &MissionError) -> bool {
    matches!(
        e,
        MissionError::SensorStalled { .. }
            | MissionError::NoSamples { .. }
            | MissionError::SensorLost { .. }
            | MissionError::ControllerUnreachable { .. }
            | MissionError::ControllerRestarted
            | MissionError::Timeout { .. }
            | MissionError::Link { .. }
            | MissionError::Acquisition(_)
            | MissionError::Emulator(_)
    )
}

/// `attempt(false)`, then `attempt(true)` once if the first failed in a way
/// [`worth_retrying`], recording that failure in `retried`.
pub(crate) fn retry_once<T>(
    seed: u64,
    mode: InspectMode,
    retried: &mut Vec<RetriedMission>,
    mut attempt: impl FnMut(bool) -> Result<T, MissionError>,
) -> Result<T, MissionError> {
    match attempt(false) {
        Err(e) if worth_retrying(&e) => {
            tracing::warn!(
                "trial {seed}, {} mission: {e}; running it again",
                mode.as_str()
            );
            retried.push(RetriedMission {
                seed,
                mode,
                error: e.to_string(),
            });
            attempt(true)
        }
        other => other,
    }
}
