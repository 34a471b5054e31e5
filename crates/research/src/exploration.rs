//! The exploration times: a plate explored tactile only for several γ against vision + tactile
//! ([`exploration_times`]), and their table.

use crate::score::score;
use crate::trials::{run, ExperimentConfig};
use crackbot_mission::inspect::InspectMode;
use crackbot_mission::MissionError;
use crackbot_sim::Scene;
use serde::Serialize;

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
