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

mod budget;
mod exploration;
mod geometry;
mod score;
mod tables;
mod trials;

pub use budget::{finger_budget, FingerBudget};
pub use crackbot_sim::random_scene::{as_printed, trial_params};
pub use exploration::{exploration_markdown, exploration_times, ExplorationRow};
pub use geometry::{clearance_mm, feature_gap_mm, APART_MM};
pub use score::{score, Score, MATCH_MM};
pub use tables::{
    ClearanceSplit, RetriedMission, Spread, Totals, Trial, TrialsReport, EXPLORATION_GOAL_S,
};
pub use trials::{detection_trials, ExperimentConfig};

#[cfg(test)]
mod tests;
