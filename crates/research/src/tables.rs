//! The trials' tables: one row per trial ([`Trial`]), totals and spreads, the split by clearance
//! and the report as Markdown and JSON ([`TrialsReport`]).

use crate::budget::FingerBudget;
use crate::geometry::APART_MM;
use crate::score::Score;
use crackbot_mission::inspect::InspectMode;
use serde::Serialize;

/// One trial: a scene, both modes.
#[derive(Debug, Clone, Serialize)]
pub struct Trial {
    /// The scene's seed.
    pub seed: u64,
    /// True cracks and decoys.
    pub cracks: usize,
    /// Printed decoys.
    pub decoys: usize,
    /// Vision only.
    pub vision: Score,
    /// Vision + tactile.
    pub fused: Score,
    /// Exploration time of the fused mission (robot time), s.
    pub fused_exploration_s: f64,
    /// What the fused mission's finger said about what it touched.
    pub finger: FingerBudget,
    /// How close the scene's lines come to other features, mm ([`clearance_mm`]; `None`: at
    /// most one line and nothing else).
    pub clearance_mm: Option<f64>,
}

/// The goal for a fused mission's exploration, s (the paper's vision + tactile trials:
/// 31.85 s).
pub const EXPLORATION_GOAL_S: f64 = 15.0;

/// Reports summed over trials.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Totals {
    /// Reports that match a true crack.
    pub correct: usize,
    /// Reports that match none.
    pub false_reports: usize,
    /// True cracks without a correct report.
    pub missed: usize,
}

impl Totals {
    pub(crate) fn of<'a>(scores: impl Iterator<Item = &'a Score>) -> Self {
        scores.fold(Totals::default(), |t, s| Totals {
            correct: t.correct + s.correct,
            false_reports: t.false_reports + s.false_reports,
            missed: t.missed + s.missed,
        })
    }
}

/// The fused score split at [`APART_MM`]: scenes whose lines stand apart from every other
/// feature (as on the paper's plates) against scenes where a line touches, crosses or runs
/// beside another line, a screw, a bump or a wavy patch.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ClearanceSplit {
    /// Scenes whose lines keep [`APART_MM`] from everything else (or one line alone).
    pub apart_scenes: usize,
    /// Their fused correct detections, the mean over those trials (`None`: no such scene).
    pub apart_correct: Option<f64>,
    /// Their fused reports.
    pub apart: Totals,
    /// The other scenes.
    pub close_scenes: usize,
    /// Their fused correct detections (`None`: no such scene).
    pub close_correct: Option<f64>,
    /// Their fused reports.
    pub close: Totals,
}

impl ClearanceSplit {
    /// The split of `trials`.
    pub fn of(trials: &[Trial]) -> Self {
        let apart = |t: &&Trial| t.clearance_mm.is_none_or(|c| c >= APART_MM);
        let group = |keep: &dyn Fn(&&Trial) -> bool| {
            let g: Vec<&Trial> = trials.iter().filter(keep).collect();
            let share = (!g.is_empty()).then(|| {
                g.iter().map(|t| t.fused.correct_fraction()).sum::<f64>() / g.len() as f64
            });
            (g.len(), share, Totals::of(g.iter().map(|t| &t.fused)))
        };
        let (apart_scenes, apart_correct, apart_totals) = group(&apart);
        let (close_scenes, close_correct, close_totals) = group(&|t| !apart(t));
        ClearanceSplit {
            apart_scenes,
            apart_correct,
            apart: apart_totals,
            close_scenes,
            close_correct,
            close: close_totals,
        }
    }
}

/// Mean, sample standard deviation and range of some values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one value).
    pub sd: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Spread {
    /// `None` for no values.
    pub fn of(values: &[f64]) -> Option<Self> {
        if values.is_empty() {
            return None;
        }
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = if values.len() > 1 {
            values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        Some(Spread {
            mean,
            sd: var.sqrt(),
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        })
    }
}

/// The trials' table.
#[derive(Debug, Clone, Serialize)]
pub struct TrialsReport {
    /// Every trial.
    pub trials: Vec<Trial>,
    /// Mean correct detections, vision only, 0–1.
    pub vision_correct: f64,
    /// Mean correct detections, vision + tactile, 0–1.
    pub fused_correct: f64,
    /// Mean localisation error of the fused mission's correct reports, mm (`None` when it made
    /// none).
    pub fused_localisation_mm: Option<f64>,
    /// Mean absolute width error of the fused mission's correct reports, mm (`None` when none
    /// carried a width).
    pub fused_width_mae_mm: Option<f64>,
    /// Mean absolute error of the dip's extent taken as the width, over the fused mission's
    /// correct reports that carry one, mm (`None` when none did).
    pub fused_extent_width_mae_mm: Option<f64>,
    /// The paper's figures: vision only, vision + tactile.
    pub paper: [f64; 2],
    /// The finger's error budget over every trial.
    pub finger: FingerBudget,
    /// The finger's right calls over every candidate it touched, 0–1, the paper's count for
    /// vision + tactile ([`FingerBudget::right_calls`]; `None` when it touched none).
    pub finger_right_calls: Option<f64>,
    /// Vision only: reports and misses summed over the trials.
    pub vision_totals: Totals,
    /// Vision + tactile: reports and misses summed over the trials.
    pub fused_totals: Totals,
    /// The fused missions' exploration times, s (`None` without trials).
    pub fused_exploration_s: Option<Spread>,
    /// Fused missions that explored within [`EXPLORATION_GOAL_S`].
    pub fused_within_goal: usize,
    /// The fused score of scenes whose lines stand apart against the others.
    pub fused_by_clearance: ClearanceSplit,
    /// Missions that failed once and were run again (their failed folders end in `-failed`).
    pub retried: Vec<RetriedMission>,
}

impl TrialsReport {
    /// The table in Markdown.
    pub fn markdown(&self) -> String {
        let mut out = String::from(
            "| trial (seed) | cracks | decoys | vision only: correct / false / missed | vision + tactile: correct / false / missed | fused exploration, s |\n|---|---|---|---|---|---|\n",
        );
        for t in &self.trials {
            out += &format!(
                "| {} | {} | {} | {} / {} / {} | {} / {} / {} | {:.1} |\n",
                t.seed,
                t.cracks,
                t.decoys,
                t.vision.correct,
                t.vision.false_reports,
                t.vision.missed,
                t.fused.correct,
                t.fused.false_reports,
                t.fused.missed,
                t.fused_exploration_s
            );
        }
        out += &format!(
            "\n| | vision only | vision + tactile |\n|---|---|---|\n| correct detections (this run) | {:.1} % | {:.1} % |\n| the paper | {:.2} % | {:.2} % |\n| localisation error of confirmed cracks | – | {} |\n| width error of confirmed cracks (mean absolute) | – | {} |\n| the same, the dip's extent taken as the width | – | {} |\n| correct / false / missed, all trials | {} / {} / {} | {} / {} / {} |\n| exploration, mean ± sd (range) | – | {} |\n| trials explored within {} s | – | {} of {} |\n",
            100.0 * self.vision_correct,
            100.0 * self.fused_correct,
            self.paper[0],
            self.paper[1],
            self.fused_localisation_mm
                .map_or_else(|| "– (no crack confirmed)".to_string(), |v| format!("{v:.2} mm")),
            self.fused_width_mae_mm
                .map_or_else(|| "– (no width reported)".to_string(), |v| format!("{v:.2} mm")),
            self.fused_extent_width_mae_mm
                .map_or_else(|| "– (no extent reported)".to_string(), |v| format!("{v:.2} mm")),
            self.vision_totals.correct,
            self.vision_totals.false_reports,
            self.vision_totals.missed,
            self.fused_totals.correct,
            self.fused_totals.false_reports,
            self.fused_totals.missed,
            self.fused_exploration_s.map_or_else(
                || "–".to_string(),
                |e| format!("{:.1} ± {:.1} s ({:.1}–{:.1})", e.mean, e.sd, e.min, e.max)
            ),
            EXPLORATION_GOAL_S,
            self.fused_within_goal,
            self.trials.len()
        );
        let (right, touched) = self.finger.right_calls();
        out += &format!(
            "| the finger's right calls on the candidates it touched (how the paper counts its {:.2} %: 13 of 14) | – | {} |\n",
            self.paper[1],
            self.finger.right_call_share().map_or_else(
                || "– (nothing touched)".to_string(),
                |v| format!("{right} of {touched}, {:.1} %", 100.0 * v)
            )
        );
        let split = &self.fused_by_clearance;
        let share = |correct: Option<f64>, t: &Totals| {
            correct.map_or_else(
                || "– (no such scene)".to_string(),
                |v| {
                    format!(
                        "{:.1} % ({} / {} / {})",
                        100.0 * v,
                        t.correct,
                        t.false_reports,
                        t.missed
                    )
                },
            )
        };
        out += &format!(
            "| correct detections where every line keeps {APART_MM} mm from every other feature, as on the paper's plates ({} of {} scenes; correct / false / missed) | – | {} |\n| correct detections where a line touches, crosses or runs within {APART_MM} mm of another feature ({} scenes) | – | {} |\n",
            split.apart_scenes,
            self.trials.len(),
            share(split.apart_correct, &split.apart),
            split.close_scenes,
            share(split.close_correct, &split.close),
        );
        let f = &self.finger;
        let cracks: usize = self.trials.iter().map(|t| t.cracks).sum();
        out += &format!(
            "\nWhat the finger said about the candidates it touched, by what their strokes crossed (fused missions, every trial):\n\n| strokes crossed | confirmed | rejected |\n|---|---|---|\n| a crack | {} | {} |\n| a printed decoy | {} | {} |\n| a screw, bump or wavy patch | {} | {} |\n| nothing | {} | {} |\n\nCracks no stroke crossed (never proposed by vision, or the stroke missed them): {} of {}.\n",
            f.crack[0],
            f.crack[1],
            f.decoy[0],
            f.decoy[1],
            f.relief[0],
            f.relief[1],
            f.nothing[0],
            f.nothing[1],
            f.untouched_cracks,
            cracks
        );
        if !self.retried.is_empty() {
            out += &format!(
                "\nMissions that failed once and were run again from the start ({}):\n\n",
                self.retried.len()
            );
            for r in &self.retried {
                out += &format!("- trial {}, {}: {}\n", r.seed, r.mode.as_str(), r.error);
            }
        }
        out
    }
}

/// A trial's mission that failed once and was run again from the start (its folder holds the
/// second run).
#[derive(Debug, Clone, Serialize)]
pub struct RetriedMission {
    /// The trial's seed.
    pub seed: u64,
    /// Which of its missions.
    pub mode: InspectMode,
    /// Why the first run failed.
    pub error: String,
}
