//! The plan step: where the finger slides, in what order and how long it takes
//! (`crackbot-planner`), within the site's workspace and speeds; its section of the
//! configuration ([`PlanConfig`]).

use crackbot_planner::{Candidate, Limits, Plan, Planner, RaisedPass, Settings, Workspace};
use serde::{Deserialize, Serialize};

use crate::inspect::report::InspectMode;
use crate::inspect::rig::site::Site;
use crate::MissionError;

/// Shortest stroke across a candidate by default, mm (or the site's manipulator stroke, if
/// shorter).
pub const TOUCH_MIN_STROKE_MM: f64 = 6.0;
/// Sound surface beyond a candidate's edge and the finger's reach on each side of its stroke by
/// default, mm.
pub const TOUCH_MARGIN_MM: f64 = 0.5;

/// How the plan is made: `[plan]` of the configuration file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanConfig {
    /// The planner's settings (slide speed, margins, passes…): `[plan.planner]`.
    pub planner: Settings,
    /// γ of the tactile-only scan (the paper's eq. 2).
    pub gamma: f64,
    /// Mean crack length of the tactile-only scan, mm (the paper's eq. 1 on real masks).
    pub mean_crack_length_mm: f64,
}

impl PlanConfig {
    /// The plan at `site`: its arm's speeds and stroke, its finger's reach.
    pub fn at(site: &Site) -> Self {
        let planner = Settings {
            travel_speed_mm_s: site.arm.travel_speed_mm_s,
            // Strokes across the crack at the speed of the authors' recordings the tactile
            // models were trained on (4.6 mm/s, the simulator's fit to them:
            // crates/sim/docs/calibration.md). One stroke per candidate: on the simulated
            // trials it was as accurate as the authors' four (forth and back, twice) at a third
            // of the time. Each stroke starts and ends 0.5 mm beyond what the finger can feel of
            // the crack (its proximity fibre's reach, 2.4 mm past the crack's edge; was the
            // tip's 4.4 mm radius), at least 6 mm in all (not the paper's 16 mm): on 60 trial
            // scenes more cracks confirmed and 19-23 % faster (EXPERIMENTS.md, "Strokes as long
            // as the finger's reach").
            slide_speed_mm_s: crackbot_planner::SIM_SLIDE_SPEED_MM_S,
            passes: 1,
            margin_mm: TOUCH_MARGIN_MM,
            min_margin_mm: TOUCH_MARGIN_MM,
            assumed_width_mm: 2.0,
            min_stroke_mm: TOUCH_MIN_STROKE_MM.min(site.arm.stroke_mm),
            reach_mm: site.fibre.reach_mm(),
            settle_s: 0.1,
            ..Settings::default()
        };
        PlanConfig {
            planner,
            gamma: 0.5,
            mean_crack_length_mm: crackbot_planner::paper_mean_length_mm(148.06, 480.0, 100.0),
        }
    }

    /// Refuses a setting out of range, naming it (the planner checks its own settings).
    pub fn check(&self) -> Result<(), MissionError> {
        if !(self.gamma > 0.0 && self.gamma < 1.0) {
            return Err(MissionError::Setting {
                field: "plan.gamma",
                value: self.gamma,
                allowed: "(0, 1)",
            });
        }
        if !(self.mean_crack_length_mm.is_finite() && self.mean_crack_length_mm > 0.0) {
            return Err(MissionError::Setting {
                field: "plan.mean_crack_length_mm",
                value: self.mean_crack_length_mm,
                allowed: "a number > 0",
            });
        }
        Ok(())
    }
}

/// The plan step: the site's workspace and speed limits, the planner with the print check's
/// raised passes (`raised`: the default overrun and speed, `None` without the check; the
/// settings' own raised pass replaces them, the speed kept under the travel limit), and the
/// plan: boustrophedon rows (a tactile mission) or a slide across every candidate.
pub(crate) fn plan(
    (config, mode): (&PlanConfig, InspectMode),
    site: &Site,
    raised: Option<(f64, f64)>,
    candidates: &[Candidate],
) -> Result<(Planner, Workspace, Plan), MissionError> {
    let m = &site.arm;
    let workspace = Workspace {
        x_min_mm: m.workspace_min_mm[0],
        x_max_mm: m.workspace_max_mm[0],
        y_min_mm: m.workspace_min_mm[1],
        y_max_mm: m.workspace_max_mm[1],
    };
    let limits = Limits {
        max_slide_speed_mm_s: 4.0 * m.slide_speed_mm_s,
        max_travel_speed_mm_s: 2.0 * m.travel_speed_mm_s,
    };
    let settings = Settings {
        raised_pass: raised.map(|(overrun_mm, speed_mm_s)| {
            config.planner.raised_pass.unwrap_or(RaisedPass {
                overrun_mm,
                speed_mm_s: speed_mm_s.min(limits.max_travel_speed_mm_s),
            })
        }),
        ..config.planner.clone()
    };
    let planner = Planner::new(workspace, limits, settings)?;
    let plan = match mode {
        InspectMode::Tactile => planner.tactile_scan(config.gamma, config.mean_crack_length_mm)?,
        _ => planner.targeted(candidates)?,
    };
    Ok((planner, workspace, plan))
}
