//! What a plan is made with ([`Settings`]): speeds, strokes, margins, the finger's reach, how
//! overlapping candidates are treated, the order, and the print check's raised pass. The
//! planner checks them once against the workspace and limits (`planner.rs`).

use serde::{Deserialize, Serialize};

use crate::geometry::Point;
use crate::order::Order;

/// What to do with candidates whose rectangles overlap or touch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Overlap {
    /// Slide across each candidate on its own (the default: every candidate gets its own
    /// verdict, and ids map one to one to slides). The plan lists the overlapping groups.
    #[default]
    SlideBoth,
    /// Merge each group of overlapping candidates (transitively) into one rectangle along the
    /// longest member's axis, covering every member, and slide across that once (for detectors
    /// that label one crack as a chain of overlapping boxes).
    Merge,
}

/// What to do with a candidate that no slide can reach.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OnUnreachable {
    /// Plan the others and list it in [`Plan::unreachable`] with the reason (the default).
    #[default]
    Report,
    /// Refuse the whole plan with [`PlanError::Unreachable`].
    Error,
}

/// How the finger moves and how slides are laid out. Defaults: the paper's slide speed and
/// stroke, the simulator's travel speed and fitted tip radius (as the finger's reach).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Sliding speed, mm/s (the papers: "the average sliding velocity was 3.89 mm/s"; the
    /// simulator's fit to the recordings' sample counts is 4.6 mm/s).
    pub slide_speed_mm_s: f64,
    /// Speed of moves with the finger lifted, mm/s (the simulator's scene default, 50).
    pub travel_speed_mm_s: f64,
    /// Acceleration of moves, mm/s² (`None`: moves at constant speed).
    pub travel_accel_mm_s2: Option<f64>,
    /// Per slide: lowering the finger onto the surface, settling, lifting it, s. An assumption
    /// (nothing in the papers or the simulator measures it).
    pub settle_s: f64,
    /// Length of each start/stop ramp of a stroke, s (the simulator's arm: 0.05).
    pub reversal_s: f64,
    /// One-way passes per targeted slide (2: forth and back, as the simulator's slide and the
    /// recordings' periodic sliding).
    pub passes: u32,
    /// One-way passes per row of the tactile-only scan (1: a boustrophedon sweep).
    pub scan_passes: u32,
    /// Sound surface wanted beyond the crack's edge and the finger's reach on each side of a
    /// targeted slide, mm.
    pub margin_mm: f64,
    /// The least sound surface accepted there when the workspace cuts a slide short, mm.
    pub min_margin_mm: f64,
    /// How far beyond a crack's edge the finger still feels it, mm: a targeted slide starts and
    /// ends this far plus the margin beyond the edge. The default is the simulator's fitted tip
    /// radius (4.4), which keeps the whole tip on sound surface; the proximity fibre, which
    /// looks 1.8 mm ahead of the tip over a 1.13 mm spot, reaches 2.4 mm
    /// (`crackbot_mission`'s missions use that). Files written before 2026-11-26 call it
    /// `tip_radius_mm`.
    #[serde(alias = "tip_radius_mm")]
    pub reach_mm: f64,
    /// Shortest targeted stroke, mm (the paper's periodic slide: 16 mm).
    pub min_stroke_mm: f64,
    /// Width assumed for a candidate that gives none, mm (the widest crack of the paper's
    /// plates: 10 mm).
    pub assumed_width_mm: f64,
    /// Spacing of slides along a crack, mm: `ceil(length / spacing)` slides spread evenly along
    /// it (at most [`MAX_SLIDES_PER_CANDIDATE`]); `None`: one slide across its centre.
    pub along_spacing_mm: Option<f64>,
    /// Overlapping candidates: slide each, or merge.
    pub overlap: Overlap,
    /// How candidates are ordered.
    pub order: Order,
    /// Candidates no slide can reach: report or refuse.
    pub on_unreachable: OnUnreachable,
    /// Where the finger starts, mm (`None`: the workspace's `(x_min, y_min)` corner).
    pub start_mm: Option<Point>,
    /// Whether the plan ends back at the start.
    pub return_to_start: bool,
    /// A pass with the finger lifted over each targeted slide after its strokes (the mission's
    /// print check); `None`: none. Scan rows get none.
    pub raised_pass: Option<RaisedPass>,
}

/// A pass with the finger lifted over a targeted slide, flown after its strokes: the finger
/// backs off `overrun_mm` beyond the end where the strokes left it, then flies level to
/// `overrun_mm` beyond the other end (both clamped to the workspace), where the next move
/// starts. The mission flies it only where the strokes read as a crack, so the plan's time,
/// which counts one for every targeted slide, is an upper bound.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RaisedPass {
    /// How far beyond each end of the slide the pass reaches, mm.
    pub overrun_mm: f64,
    /// Speed, mm/s (at most the travel speed limit).
    pub speed_mm_s: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            slide_speed_mm_s: crate::PAPER_SLIDE_SPEED_MM_S,
            travel_speed_mm_s: 50.0,
            travel_accel_mm_s2: None,
            settle_s: 1.0,
            reversal_s: 0.05,
            passes: 2,
            scan_passes: 1,
            margin_mm: 10.0,
            min_margin_mm: 2.0,
            reach_mm: 4.4,
            min_stroke_mm: crate::PAPER_STROKE_MM,
            assumed_width_mm: 10.0,
            along_spacing_mm: None,
            overlap: Overlap::default(),
            order: Order::default(),
            on_unreachable: OnUnreachable::default(),
            start_mm: None,
            return_to_start: false,
            raised_pass: None,
        }
    }
}
