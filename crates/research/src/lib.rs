//! The research side of crackbot: the online experiments of the visual-tactile paper in
//! simulation (Markdown + JSON tables), the trial scenes' scoring against their truth and the
//! geometry it needs. `crackbot-lab` runs them; the robot never links this crate.
//!
//!
//! * [`detection_trials`]: correct detections over trials on random scenes (real crack
//!   appearance 0.5–5 mm, printed decoys, bumps, screws, random camera pose), vision only against
//!   vision + tactile (paper: 46.66 % vs 92.85 %).
//! * [`exploration_times`]: time to explore a 200 × 100 mm plate, tactile only for several γ
//!   against vision + tactile (paper: 519.40 / 278.61 / 198.56 s vs 31.85 s).
//!
//! Every figure is a mission run by [`run_inspection`] on a generated scene: the same code path
//! as the robot's (link, PTY, online classification). Scenes come from a seed
//! ([`crackbot_sim::random_scene()`]); any valid scene file also runs.
//!
//! **Scoring.** A reported crack is *correct* when its position lies within
//! [`MATCH_MM`] of a true crack's centre line and no other report claimed that crack; it is a
//! false detection otherwise (a decoy, a screw, a duplicate). A true crack with no correct
//! report is missed. *Correct detections* = correct / (reports + missed): the share of the
//! mission's calls about cracks that are right, end to end. For vision only this is how the paper
//! counts (7 correct of 14 reports + 1 missed: 46.66 %). Localisation error: the distance of each
//! correct report from the crack's centre line.
//!
//! **The paper's vision + tactile count** ([`FingerBudget::right_calls`]). The paper's 92.85 % is
//! 13 of the 14 candidates vision gave the finger called right (cracks confirmed, printed decoys
//! rejected); the crack vision never proposed is left out of it. The trials give that figure
//! too, over every candidate the finger touched, beside the stricter end-to-end one above (which
//! also counts vision's misses, second reports of one crack and reports that land off the crack).
//!
//! **The finger's error budget** ([`FingerBudget`]): for each candidate the fused mission
//! touched, what its strokes crossed in the scene's truth (a crack, a printed decoy, a screw or
//! bump, nothing) against whether the finger confirmed it; and the cracks no stroke crossed,
//! which touch could never find. It separates what the finger gets wrong from what vision never
//! proposed.
//!
//! **Lines apart or in a tangle** ([`ClearanceSplit`]). The random scenes let features overlap;
//! the paper's plates hold one crack or print under the finger at a time. The trials split the
//! fused figure between scenes whose lines keep [`APART_MM`] from every other feature
//! ([`clearance_mm`]) and the rest, so a reader sees which kind of scene the errors come from.

#![expect(
    clippy::result_large_err,
    reason = "the missions' own error (crackbot_mission::MissionError) is returned as it is"
)]

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

pub use crackbot_sim::random_scene::{as_printed, trial_params};
use crackbot_sim::surface::distance_to_polyline;
use crackbot_sim::{random_scene, Feature, RandomSceneParams, Scene};
use serde::Serialize;

use crackbot_mission::inspect::{run_inspection, InspectConfig, InspectMode, InspectReport};
use crackbot_mission::MissionError;

/// A report within this distance of a true crack's centre line (plus half its width) matches it, mm.
pub const MATCH_MM: f64 = 5.0;

/// How one mission scored against its scene's truth.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Score {
    /// True cracks in the scene.
    pub cracks: usize,
    /// Reports that match a true crack.
    pub correct: usize,
    /// Reports that match none (decoys, screws, duplicates).
    pub false_reports: usize,
    /// True cracks without a correct report.
    pub missed: usize,
    /// Distance of each correct report from its crack's centre line, mm.
    pub localisation_mm: Vec<f64>,
    /// Reported width − true width of each correct report that carries a width, mm.
    pub width_error_mm: Vec<f64>,
    /// Length of the dip's extent (the localiser's width, calibrated on the real plates) − true
    /// width of each correct report that carries an extent, mm: a second width estimate, scored
    /// beside the model's.
    pub extent_width_error_mm: Vec<f64>,
}

impl Score {
    /// Correct / (reports + missed), 0–1 (1 when there was nothing to report and nothing was).
    pub fn correct_fraction(&self) -> f64 {
        let n = self.correct + self.false_reports + self.missed;
        if n == 0 {
            1.0
        } else {
            self.correct as f64 / n as f64
        }
    }
}

/// Scores a mission's report against its scene.
pub fn score(scene: &Scene, report: &InspectReport) -> Score {
    let cracks: Vec<(&[[f64; 2]], f64)> = scene
        .features
        .iter()
        .filter_map(|f| match f {
            Feature::Crack { path, width_mm, .. } => Some((path.as_slice(), *width_mm)),
            _ => None,
        })
        .collect();
    let mut claimed = vec![false; cracks.len()];
    let mut s = Score {
        cracks: cracks.len(),
        ..Score::default()
    };
    for r in &report.cracks {
        let best = cracks
            .iter()
            .enumerate()
            .filter(|(i, _)| !claimed[*i])
            .map(|(i, (path, w))| (i, distance_to_polyline(path, r.position_mm), *w))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match best {
            Some((i, d, w)) if d <= MATCH_MM + w / 2.0 => {
                claimed[i] = true;
                s.correct += 1;
                s.localisation_mm.push(d);
                if let Some(rw) = r.width_mm {
                    s.width_error_mm.push(rw - w);
                }
                if let Some([a, b]) = r.extent_mm {
                    s.extent_width_error_mm
                        .push((a[0] - b[0]).hypot(a[1] - b[1]) - w);
                }
            }
            _ => s.false_reports += 1,
        }
    }
    s.missed = claimed.iter().filter(|c| !**c).count();
    s
}

/// What the finger said about the candidates it touched, by what their strokes crossed in the
/// scene's truth: `[confirmed, rejected]` per kind. A candidate whose strokes crossed a crack
/// counts as a crack; else a decoy; else a screw, bump or wavy patch; else nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct FingerBudget {
    /// Strokes crossed a true crack.
    pub crack: [usize; 2],
    /// Strokes crossed a printed decoy (and no crack).
    pub decoy: [usize; 2],
    /// Strokes crossed a screw, bump or wavy patch (and no crack or decoy).
    pub relief: [usize; 2],
    /// Strokes crossed nothing of the scene's features.
    pub nothing: [usize; 2],
    /// True cracks that no stroke crossed.
    pub untouched_cracks: usize,
}

impl FingerBudget {
    /// The finger's right calls and the candidates it touched, as the paper counts its vision +
    /// tactile figure: a candidate whose strokes crossed a crack is right when confirmed, any
    /// other (a printed decoy, a screw, bump or wavy patch, bare plate) when rejected.
    pub fn right_calls(&self) -> (usize, usize) {
        let right = self.crack[0] + self.decoy[1] + self.relief[1] + self.nothing[1];
        let touched = [self.crack, self.decoy, self.relief, self.nothing]
            .iter()
            .map(|[c, r]| c + r)
            .sum();
        (right, touched)
    }

    /// [`Self::right_calls`] as a share, 0–1 (`None` when the finger touched nothing).
    pub fn right_call_share(&self) -> Option<f64> {
        let (right, touched) = self.right_calls();
        (touched > 0).then(|| right as f64 / touched as f64)
    }

    fn add(&mut self, other: &FingerBudget) {
        for (a, b) in [
            (&mut self.crack, other.crack),
            (&mut self.decoy, other.decoy),
            (&mut self.relief, other.relief),
            (&mut self.nothing, other.nothing),
        ] {
            a[0] += b[0];
            a[1] += b[1];
        }
        self.untouched_cracks += other.untouched_cracks;
    }
}

/// Distance between segments `a`–`b` and `c`–`d` (0 when they cross), mm.
fn segment_distance(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
    };
    let (d1, d2) = (cross(a, b, c), cross(a, b, d));
    let (d3, d4) = (cross(c, d, a), cross(c, d, b));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    [
        distance_to_polyline(&[c, d], a),
        distance_to_polyline(&[c, d], b),
        distance_to_polyline(&[a, b], c),
        distance_to_polyline(&[a, b], d),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// Least distance between two polylines (0 where they cross), mm.
fn polyline_distance(p: &[[f64; 2]], q: &[[f64; 2]]) -> f64 {
    p.windows(2)
        .flat_map(|s| {
            q.windows(2)
                .map(move |t| segment_distance(s[0], s[1], t[0], t[1]))
        })
        .fold(f64::INFINITY, f64::min)
}

/// Whether `p` lies in the axis-aligned rectangle `min`–`max` (edges included).
fn in_rectangle(min: [f64; 2], max: [f64; 2], p: [f64; 2]) -> bool {
    (min[0]..=max[0]).contains(&p[0]) && (min[1]..=max[1]).contains(&p[1])
}

/// Lines kept at least this far, edge to edge, from every other feature of their scene stand
/// apart, mm: the paper's plates, a crack or a print alone under the finger. A stroke reaches
/// [`crackbot_mission::inspect::TOUCH_MARGIN_MM`] plus the finger's reach (2.4 mm) beyond the edge of the line
/// it crosses, so a feature beyond that cannot share its stroke; the crack map's detections join
/// lines within about twice its dilation (0.02 of the frame, 4 mm on the trial plates). 5 mm is
/// the first, rounded up; the trials split their score at it ([`ClearanceSplit`]).
pub const APART_MM: f64 = 5.0;

/// Edge-to-edge gap between a crack or printed decoy and another feature, mm (0 where they touch
/// or cross); `None` where neither is a line (a screw beside a bump matters to no stroke).
pub fn feature_gap_mm(a: &Feature, b: &Feature) -> Option<f64> {
    fn line(f: &Feature) -> Option<(&[[f64; 2]], f64)> {
        match f {
            Feature::Crack { path, width_mm, .. } | Feature::Decoy { path, width_mm, .. } => {
                Some((path.as_slice(), width_mm / 2.0))
            }
            _ => None,
        }
    }
    let (path, half, other) = match (line(a), line(b)) {
        (Some((pa, ha)), Some((pb, hb))) => {
            return Some((polyline_distance(pa, pb) - ha - hb).max(0.0));
        }
        (Some((p, h)), None) => (p, h, b),
        (None, Some((p, h))) => (p, h, a),
        (None, None) => return None,
    };
    let gap = match other {
        Feature::Bump {
            centre, radius_mm, ..
        } => distance_to_polyline(path, *centre) - radius_mm,
        Feature::Screw {
            centre,
            head_diameter_mm,
            ..
        } => distance_to_polyline(path, *centre) - head_diameter_mm / 2.0,
        Feature::Wavy { min, max, .. } => {
            if path.iter().any(|&p| in_rectangle(*min, *max, p)) {
                0.0
            } else {
                let outline = [*min, [max[0], min[1]], *max, [min[0], max[1]], *min];
                polyline_distance(path, &outline)
            }
        }
        // Two lines were measured above.
        Feature::Crack { .. } | Feature::Decoy { .. } => return None,
    };
    Some((gap - half).max(0.0))
}

/// The smallest [`feature_gap_mm`] of a scene: how close its lines come to anything else, mm;
/// `None` with at most one line and nothing else.
pub fn clearance_mm(scene: &Scene) -> Option<f64> {
    let f = &scene.features;
    (0..f.len())
        .flat_map(|i| (i + 1..f.len()).filter_map(move |j| feature_gap_mm(&f[i], &f[j])))
        .reduce(f64::min)
}

/// Whether the stroke `a`–`b` crosses (or touches) the feature `f`.
fn stroke_meets(a: [f64; 2], b: [f64; 2], f: &Feature) -> bool {
    let polyline = |path: &[[f64; 2]], half_width: f64| {
        path.windows(2)
            .any(|s| segment_distance(a, b, s[0], s[1]) <= half_width)
    };
    match f {
        Feature::Crack { path, width_mm, .. } | Feature::Decoy { path, width_mm, .. } => {
            polyline(path, width_mm / 2.0)
        }
        Feature::Bump {
            centre, radius_mm, ..
        } => distance_to_polyline(&[a, b], *centre) < *radius_mm,
        Feature::Screw {
            centre,
            head_diameter_mm,
            ..
        } => distance_to_polyline(&[a, b], *centre) < head_diameter_mm / 2.0,
        Feature::Wavy { min, max, .. } => {
            // Points every 0.5 mm along the stroke, inside the patch's rectangle.
            let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.5).ceil().max(1.0) as usize;
            (0..=n).any(|k| {
                let t = k as f64 / n as f64;
                in_rectangle(
                    *min,
                    *max,
                    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])],
                )
            })
        }
    }
}

/// The finger's error budget of a fused mission's report against its scene.
pub fn finger_budget(scene: &Scene, report: &InspectReport) -> FingerBudget {
    let mut b = FingerBudget::default();
    let mut touched = vec![false; scene.features.len()];
    let mut ids: Vec<u64> = report.passes.iter().filter_map(|p| p.candidate).collect();
    ids.sort_unstable();
    ids.dedup();
    for id in ids {
        let mut met = [false; 4];
        for p in report.passes.iter().filter(|p| p.candidate == Some(id)) {
            for (k, f) in scene.features.iter().enumerate() {
                if stroke_meets(p.start_mm, p.end_mm, f) {
                    touched[k] = true;
                    let kind = match f {
                        Feature::Crack { .. } => 0,
                        Feature::Decoy { .. } => 1,
                        _ => 2,
                    };
                    met[kind] = true;
                }
            }
        }
        met[3] = !met[..3].iter().any(|&m| m);
        // A piece joined to another confirmed piece of its crack was confirmed too.
        let confirmed = report
            .cracks
            .iter()
            .any(|c| c.candidate == Some(id) || c.evidence.pieces.contains(&id));
        let slot = match met.iter().position(|&m| m) {
            Some(0) => &mut b.crack,
            Some(1) => &mut b.decoy,
            Some(2) => &mut b.relief,
            _ => &mut b.nothing,
        };
        slot[usize::from(!confirmed)] += 1;
    }
    b.untouched_cracks = scene
        .features
        .iter()
        .zip(&touched)
        .filter(|(f, t)| matches!(f, Feature::Crack { .. }) && !**t)
        .count();
    b
}

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
    fn of<'a>(scores: impl Iterator<Item = &'a Score>) -> Self {
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

fn run(
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
fn one_trial(
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

/// [`run`] for one trial's mission, run once more from the start when the run itself failed
/// (a sensor stream that stalls twice in one slide on a loaded machine, say): the first
/// failure is kept in `retried` and its folder renamed `…-failed`. A second failure, or a
/// setting that cannot work, ends the trials with its error.
fn run_retried(
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
fn worth_retrying(e: &MissionError) -> bool {
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
fn retry_once<T>(
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

/// One row of the exploration-time table.
#[derive(Debug, Clone, Serialize)]
pub struct ExplorationRow {
    /// `tactile` or `fused`.
    pub mode: InspectMode,
    /// γ of the tactile scan.
    pub gamma: Option<f64>,
    /// Slides (passes) made.
    pub passes: usize,
    /// Exploration time, robot time, s.
    pub exploration_s: f64,
    /// The planner's estimate, s.
    pub estimated_s: f64,
    /// Cracks found / in the scene.
    pub found: usize,
    /// Cracks in the scene.
    pub cracks: usize,
    /// The paper's time, s.
    pub paper_s: f64,
}

/// Exploration time on `scene`: tactile only for each γ, then fused.
pub fn exploration_times(
    base: &ExperimentConfig,
    scene: &Scene,
    gammas: &[f64],
    mut progress: impl FnMut(&ExplorationRow),
) -> Result<Vec<ExplorationRow>, MissionError> {
    let paper = |g: f64| {
        if (g - 0.25).abs() < 1e-9 {
            519.40
        } else if (g - 0.5).abs() < 1e-9 {
            278.61
        } else if (g - 0.75).abs() < 1e-9 {
            198.56
        } else {
            f64::NAN
        }
    };
    let mut rows = Vec::new();
    for &g in gammas {
        let mut b = base.clone();
        b.template.plan.gamma = g;
        let r = run(
            &b,
            scene,
            InspectMode::Tactile,
            &format!("explore-tactile-{g}"),
        )?;
        let s = score(scene, &r);
        let row = ExplorationRow {
            mode: InspectMode::Tactile,
            gamma: Some(g),
            passes: r.passes.len(),
            exploration_s: r.exploration_s,
            estimated_s: r.plan.as_ref().map_or(f64::NAN, |p| p.estimated_s),
            found: s.correct,
            cracks: s.cracks,
            paper_s: paper(g),
        };
        progress(&row);
        rows.push(row);
    }
    let r = run(base, scene, InspectMode::Fused, "explore-fused")?;
    let s = score(scene, &r);
    let row = ExplorationRow {
        mode: InspectMode::Fused,
        gamma: None,
        passes: r.passes.len(),
        exploration_s: r.exploration_s,
        estimated_s: r.plan.as_ref().map_or(f64::NAN, |p| p.estimated_s),
        found: s.correct,
        cracks: s.cracks,
        paper_s: 31.85,
    };
    progress(&row);
    rows.push(row);
    Ok(rows)
}

/// The exploration table in Markdown.
pub fn exploration_markdown(rows: &[ExplorationRow]) -> String {
    let mut out = String::from(
        "| modality | γ | passes | exploration, s (robot time) | planner's estimate, s | cracks found | the paper, s |\n|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        out += &format!(
            "| {} | {} | {} | {:.1} | {:.1} | {}/{} | {:.2} |\n",
            match r.mode {
                InspectMode::Tactile => "tactile only",
                InspectMode::Fused => "vision + tactile",
                InspectMode::Vision => "vision only",
            },
            r.gamma.map_or("–".into(), |g| format!("{g}")),
            r.passes,
            r.exploration_s,
            r.estimated_s,
            r.found,
            r.cracks,
            r.paper_s
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_mission::inspect::{Evidence, PassRecord, ReportedCrack};

    /// A table of no trials with these means and finger budget.
    fn empty_report(vision_correct: f64, fused_correct: f64, finger: FingerBudget) -> TrialsReport {
        TrialsReport {
            trials: Vec::new(),
            vision_correct,
            fused_correct,
            fused_localisation_mm: None,
            fused_width_mae_mm: None,
            fused_extent_width_mae_mm: None,
            paper: [46.66, 92.85],
            finger,
            finger_right_calls: finger.right_call_share(),
            vision_totals: Totals::default(),
            fused_totals: Totals::default(),
            fused_exploration_s: None,
            fused_within_goal: 0,
            fused_by_clearance: ClearanceSplit::default(),
            retried: Vec::new(),
        }
    }

    #[test]
    fn a_mission_that_failed_in_its_link_runs_once_more_and_a_bad_setting_does_not() {
        let stalled = || MissionError::SensorStalled {
            port: "/dev/pts/9".into(),
            detail: "610 samples of the stroke, 832 expected".into(),
        };
        let mut retried = Vec::new();
        let mut calls = Vec::new();
        let ok = retry_once(7, InspectMode::Fused, &mut retried, |again| {
            calls.push(again);
            if again {
                Ok(3)
            } else {
                Err(stalled())
            }
        });
        assert_eq!(ok.unwrap(), 3);
        assert_eq!(calls, vec![false, true]);
        assert_eq!(retried.len(), 1);
        assert_eq!((retried[0].seed, retried[0].mode), (7, InspectMode::Fused));
        assert!(
            retried[0].error.contains("stalled mid-slide"),
            "{retried:?}"
        );
        // Failing twice ends with the second error; a bad setting is not tried again.
        let twice = retry_once(8, InspectMode::Vision, &mut retried, |_| -> Result<(), _> {
            Err(stalled())
        });
        assert!(matches!(twice, Err(MissionError::SensorStalled { .. })));
        assert_eq!(retried.len(), 2);
        let mut n = 0;
        let bad = retry_once(9, InspectMode::Fused, &mut retried, |_| -> Result<(), _> {
            n += 1;
            Err(MissionError::Setting {
                field: "speedup",
                value: 0.0,
                allowed: "> 0",
            })
        });
        assert!(matches!(bad, Err(MissionError::Setting { .. })));
        assert_eq!((n, retried.len()), (1, 2));
        // The table lists what was run again.
        let mut t = empty_report(0.0, 0.0, FingerBudget::default());
        assert!(!t.markdown().contains("run again"));
        t.retried = retried;
        let md = t.markdown();
        assert!(md.contains("run again from the start (2)"), "{md}");
        assert!(md.contains("- trial 7, fused: the sensor stream"), "{md}");
    }

    #[test]
    fn a_table_without_confirmed_cracks_says_so_instead_of_nan() {
        let mut t = empty_report(0.5, 0.0, FingerBudget::default());
        let md = t.markdown();
        assert!(
            md.contains("– (no crack confirmed)") && !md.contains("NaN"),
            "{md}"
        );
        t.fused_localisation_mm = Some(1.234);
        assert!(t.markdown().contains("| 1.23 mm |"));
        assert!(t.markdown().contains("– (no width reported)"));
        t.fused_width_mae_mm = Some(0.75);
        assert!(t.markdown().contains("(mean absolute) | – | 0.75 mm |"));
        assert!(t.markdown().contains("– (no extent reported)"));
        t.fused_extent_width_mae_mm = Some(0.5);
        assert!(t
            .markdown()
            .contains("the dip's extent taken as the width | – | 0.50 mm |"));
        assert!(t
            .markdown()
            .contains("| exploration, mean ± sd (range) | – | – |"));
        t.fused_exploration_s = Spread::of(&[10.0, 14.0, 24.0]);
        t.fused_within_goal = 2;
        t.fused_totals = Totals {
            correct: 5,
            false_reports: 2,
            missed: 1,
        };
        let md = t.markdown();
        assert!(md.contains("| – | 16.0 ± 7.2 s (10.0–24.0) |"), "{md}");
        assert!(
            md.contains("| trials explored within 15 s | – | 2 of 0 |"),
            "{md}"
        );
        assert!(md.contains("| 0 / 0 / 0 | 5 / 2 / 1 |"), "{md}");
    }

    #[test]
    fn spreads_and_totals_add_up() {
        assert_eq!(Spread::of(&[]), None);
        let one = Spread::of(&[3.0]).unwrap();
        assert_eq!((one.mean, one.sd, one.min, one.max), (3.0, 0.0, 3.0, 3.0));
        let s = Spread::of(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert!((s.sd - 1.2909944487358056).abs() < 1e-12, "{s:?}");
        let score = |c, f, m| Score {
            correct: c,
            false_reports: f,
            missed: m,
            ..Score::default()
        };
        let scores = [score(1, 2, 3), score(4, 0, 1)];
        assert_eq!(
            Totals::of(scores.iter()),
            Totals {
                correct: 5,
                false_reports: 2,
                missed: 4
            }
        );
    }

    fn report_with(positions: &[[f64; 2]]) -> InspectReport {
        let scene = Scene::builtin_default();
        let mut r = InspectReport {
            mode: InspectMode::Fused,
            scene: scene.name.clone(),
            cracks: Vec::new(),
            rejected: Vec::new(),
            candidates: Vec::new(),
            frame: None,
            passes: Vec::new(),
            plan: None,
            elapsed_s: 0.0,
            exploration_s: 0.0,
            stages: Default::default(),
            sensor_clock: None,
            controller_clock: None,
            link: Default::default(),
            out_dir: String::new(),
        };
        for &p in positions {
            r.cracks.push(ReportedCrack {
                candidate: None,
                position_mm: p,
                extent_mm: None,
                class: "crack".into(),
                width_mm: None,
                width_range_mm: None,
                confidence: 1.0,
                evidence: Evidence {
                    detector_score: None,
                    ..Evidence::default()
                },
            });
        }
        r
    }

    #[test]
    fn printed_cracks_take_the_fitted_profile_and_nothing_else_changes() {
        let scene = Scene::builtin_default();
        let printed = as_printed(&scene);
        let fitted = crackbot_sim::plates::calibrated_samples();
        assert_eq!(printed.features.len(), scene.features.len());
        let mut cracks = 0;
        for (a, b) in scene.features.iter().zip(&printed.features) {
            match (a, b) {
                (
                    Feature::Crack {
                        path: p0,
                        width_mm: w0,
                        ..
                    },
                    Feature::Crack {
                        path: p1,
                        width_mm: w1,
                        depth_mm,
                        wall_angle_deg,
                        ..
                    },
                ) => {
                    cracks += 1;
                    assert_eq!((p0, w0), (p1, w1));
                    assert_eq!(*depth_mm, fitted.crack_depth_mm);
                    assert_eq!(*wall_angle_deg, fitted.crack_wall_angle_deg);
                }
                _ => assert_eq!(a, b),
            }
        }
        assert_eq!(cracks, 4);
        printed.validate().unwrap();
    }

    #[test]
    fn the_finger_budget_sorts_candidates_by_what_their_strokes_crossed() {
        let scene = Scene::builtin_default();
        // Candidate 1 across the 1 mm crack and candidate 2 across the decoy, both confirmed;
        // candidate 3 over a screw and candidate 4 over bare plate, both rejected. Candidate 2
        // is touched twice (forth and back).
        let mut r = report_with(&[[37.5, 30.0], [40.0, 84.0]]);
        r.cracks[0].candidate = Some(1);
        r.cracks[1].candidate = Some(2);
        let strokes = [
            (1, [37.5, 22.0], [37.5, 38.0]),
            (2, [40.0, 76.0], [40.0, 92.0]),
            (2, [40.0, 92.0], [40.0, 76.0]),
            (3, [184.0, 92.0], [200.0, 92.0]),
            (4, [100.0, 20.0], [100.0, 35.0]),
        ];
        for (k, (candidate, a, b)) in strokes.into_iter().enumerate() {
            r.passes.push(PassRecord {
                id: k as u32 + 1,
                candidate: Some(candidate),
                start_mm: a,
                end_mm: b,
                samples: 1400,
                class: None,
                confidence: 0.0,
                width_mm: None,
                doubt: None,
                dip: None,
                recording: String::new(),
                attempts: 1,
            });
        }
        let b = finger_budget(&scene, &r);
        assert_eq!(
            b,
            FingerBudget {
                crack: [1, 0],
                decoy: [1, 0],
                relief: [0, 1],
                nothing: [0, 1],
                // The 2, 5 and 10 mm cracks.
                untouched_cracks: 3,
            }
        );
        // Candidate 3 joined to candidate 1 as a piece of its crack counts as confirmed.
        r.cracks[0].evidence.pieces.push(3);
        assert_eq!(finger_budget(&scene, &r).relief, [1, 0]);
        // The 5 mm crack's centre line crosses x = 100 mm at y = 64.9 mm. A stroke that ends
        // 3.4 mm before it (perpendicular 3.3 mm) does not touch it; one that ends 1.9 mm before
        // it (inside its 2.5 mm half width) does.
        let crack5 = &scene.features[2];
        assert!(!stroke_meets([100.0, 50.0], [100.0, 61.5], crack5));
        assert!(stroke_meets([100.0, 50.0], [100.0, 63.0], crack5));
        // The paper's count: the crack confirmed, the screw and the bare plate rejected are
        // right; the decoy confirmed is wrong.
        assert_eq!(b.right_calls(), (3, 4));
        assert_eq!(b.right_call_share(), Some(0.75));
        assert_eq!(FingerBudget::default().right_call_share(), None);
        let mut t = empty_report(0.5, 0.5, b);
        assert!(
            t.markdown()
                .contains("on the candidates it touched (how the paper counts its 92.85 %: 13 of 14) | – | 3 of 4, 75.0 % |"),
            "{}",
            t.markdown()
        );
        t.finger.add(&b);
        assert_eq!(t.finger.crack, [2, 0]);
        assert!(
            t.markdown().contains("| a printed decoy | 2 | 0 |"),
            "{}",
            t.markdown()
        );
        assert!(empty_report(0.5, 0.5, FingerBudget::default())
            .markdown()
            .contains("| – (nothing touched) |"));
    }

    #[test]
    fn scoring_matches_reports_to_cracks_once_and_counts_decoys_and_misses() {
        let scene = Scene::builtin_default();
        // The default scene: four cracks; a report on the 1 mm crack, a duplicate of it, one on
        // the decoy.
        let r = report_with(&[[37.5, 30.0], [38.0, 30.2], [40.0, 84.0]]);
        let s = score(&scene, &r);
        assert_eq!(s.cracks, 4);
        assert_eq!((s.correct, s.false_reports, s.missed), (1, 2, 3), "{s:?}");
        assert!(s.localisation_mm[0] < 0.5, "{s:?}");
        assert!(s.width_error_mm.is_empty(), "no report carried a width");
        assert!((s.correct_fraction() - 1.0 / 6.0).abs() < 1e-12);
        // A width reported on the 1 mm crack is scored against it; one on the decoy is not.
        let mut r = report_with(&[[37.5, 30.0], [40.0, 84.0]]);
        for c in &mut r.cracks {
            c.width_mm = Some(2.0);
        }
        // An extent 1.5 mm long on the 1 mm crack scores +0.5 mm; the decoy's is not scored.
        for c in &mut r.cracks {
            let [x, y] = c.position_mm;
            c.extent_mm = Some([[x, y - 0.75], [x, y + 0.75]]);
        }
        let s = score(&scene, &r);
        assert_eq!(s.width_error_mm, vec![1.0], "{s:?}");
        assert_eq!(s.extent_width_error_mm.len(), 1, "{s:?}");
        assert!((s.extent_width_error_mm[0] - 0.5).abs() < 1e-12, "{s:?}");
        let none = score(&scene, &report_with(&[]));
        assert_eq!((none.correct, none.missed), (0, 4));
        assert_eq!(none.correct_fraction(), 0.0);
    }

    #[test]
    fn scenes_split_by_how_close_their_lines_come_to_other_features() {
        let crack = |path: Vec<[f64; 2]>, width_mm: f64| Feature::Crack {
            path,
            width_mm,
            depth_mm: 1.0,
            edge_radius_mm: 0.2,
            wall_angle_deg: 90.0,
        };
        let decoy = |path: Vec<[f64; 2]>, width_mm: f64| Feature::Decoy {
            path,
            width_mm,
            reflectivity: 0.4,
        };
        let a = crack(vec![[10.0, 10.0], [50.0, 10.0]], 2.0);
        // Parallel 8 mm higher, 1 mm wide: 8 - 1 - 0.5 = 6.5 mm edge to edge.
        let b = decoy(vec![[10.0, 18.0], [50.0, 18.0]], 1.0);
        assert!((feature_gap_mm(&a, &b).unwrap() - 6.5).abs() < 1e-9);
        // Crossing: 0; the order of the pair does not matter.
        let c = crack(vec![[30.0, 0.0], [30.0, 30.0]], 0.5);
        assert_eq!(feature_gap_mm(&a, &c), Some(0.0));
        assert_eq!(feature_gap_mm(&c, &a), Some(0.0));
        // A screw 10 mm below the crack's line, head 6 mm: 10 - 3 - 1 = 6 mm.
        let screw = Feature::Screw {
            centre: [30.0, 0.0],
            head_diameter_mm: 6.0,
            height_mm: 2.0,
        };
        assert!((feature_gap_mm(&screw, &a).unwrap() - 6.0).abs() < 1e-9);
        // A bump overlapping the line: 0, not negative.
        let bump = Feature::Bump {
            centre: [30.0, 12.0],
            radius_mm: 5.0,
            height_mm: 1.0,
        };
        assert_eq!(feature_gap_mm(&a, &bump), Some(0.0));
        assert_eq!(feature_gap_mm(&screw, &bump), None, "neither is a line");
        // A wavy patch 4 mm below the line (edge 3 mm), and one the line runs through.
        let wavy = |min: [f64; 2], max: [f64; 2]| Feature::Wavy {
            min,
            max,
            amplitude_mm: 0.5,
            period_mm: 5.0,
            direction_deg: 0.0,
        };
        assert!(
            (feature_gap_mm(&a, &wavy([20.0, -10.0], [40.0, 6.0])).unwrap() - 3.0).abs() < 1e-9
        );
        assert_eq!(
            feature_gap_mm(&a, &wavy([0.0, 0.0], [20.0, 20.0])),
            Some(0.0)
        );
        // A scene's clearance is its smallest gap; one line alone has none.
        let mut scene = Scene::builtin_default();
        scene.features = vec![a.clone()];
        assert_eq!(clearance_mm(&scene), None);
        scene.features = vec![a.clone(), b.clone(), screw.clone()];
        assert!((clearance_mm(&scene).unwrap() - 6.0).abs() < 1e-9);
        scene.features.push(c);
        assert_eq!(clearance_mm(&scene), Some(0.0));
        // Trials split at APART_MM, each group's share the mean over its trials.
        let trial = |seed, clearance_mm, correct, missed| Trial {
            seed,
            cracks: correct + missed,
            decoys: 0,
            vision: Score::default(),
            fused: Score {
                cracks: correct + missed,
                correct,
                missed,
                ..Score::default()
            },
            fused_exploration_s: 10.0,
            finger: FingerBudget::default(),
            clearance_mm,
        };
        let trials = [
            trial(1, None, 1, 0),
            trial(2, Some(APART_MM), 2, 0),
            trial(3, Some(0.0), 1, 1),
            trial(4, Some(4.9), 0, 2),
        ];
        let split = ClearanceSplit::of(&trials);
        assert_eq!((split.apart_scenes, split.close_scenes), (2, 2));
        assert_eq!(split.apart_correct, Some(1.0));
        assert_eq!(split.close_correct, Some(0.25));
        assert_eq!((split.close.correct, split.close.missed), (1, 3));
        let mut t = empty_report(0.5, 0.5, FingerBudget::default());
        assert!(
            t.markdown()
                .contains("(0 of 0 scenes; correct / false / missed) | – | – (no such scene) |"),
            "{}",
            t.markdown()
        );
        t.fused_by_clearance = split;
        assert!(
            t.markdown().contains("| – | 25.0 % (1 / 0 / 3) |"),
            "{}",
            t.markdown()
        );
    }
}
