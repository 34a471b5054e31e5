//! Plans: slides, the moves between them, and how long it all takes.

use serde::Serialize;

use crate::candidate::{Candidate, CandidateId};
use crate::geometry::{dist, Point, Workspace};
use crate::order::Order;
use crate::settings::{Overlap, Settings};

/// One slide: the finger down on the surface, from `start_mm` to `end_mm` and, for an even
/// number of passes, back.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Slide {
    /// The candidates this slide inspects (several when overlapping candidates were merged;
    /// empty for a row of the tactile-only scan).
    pub candidates: Vec<CandidateId>,
    /// The row of a tactile-only scan, from the first one.
    pub row: Option<usize>,
    /// Where the first pass starts, mm.
    pub start_mm: Point,
    /// Where the first pass ends, mm.
    pub end_mm: Point,
    /// `|end − start|`, mm.
    pub stroke_mm: f64,
    /// One-way passes (2: forth and back, the simulator's and the recordings' "slide").
    pub passes: u32,
    /// Sliding speed, mm/s.
    pub speed_mm_s: f64,
    /// [`slide_time_s`] of this slide, s (settling not included).
    pub duration_s: f64,
    /// For a candidate: the run on sound surface before the finger's reach meets the crack's
    /// edge, at the start side and at the end side, mm
    /// (`distance to the crack's edge − reach`, [`crate::Settings::reach_mm`]); `None` for scan
    /// rows.
    pub sound_run_mm: Option<[f64; 2]>,
    /// How far the slide was shifted along itself to stay inside the workspace, mm (0: centred
    /// on the crack).
    pub shifted_mm: f64,
    /// Whether the workspace made the stroke shorter than asked.
    pub clipped: bool,
    /// How far along the crack's axis the slide was moved because it did not fit where asked, mm
    /// (0: where asked).
    pub moved_along_mm: f64,
}

impl Slide {
    /// Where the finger is when the slide ends: its start after an even number of passes, its
    /// end after an odd one.
    pub fn exit_mm(&self) -> Point {
        if self.passes.is_multiple_of(2) {
            self.start_mm
        } else {
            self.end_mm
        }
    }

    /// Whether the slide is where and as long as asked.
    pub fn is_as_asked(&self) -> bool {
        self.shifted_mm == 0.0 && !self.clipped && self.moved_along_mm == 0.0
    }
}

/// A move with the finger lifted, in a straight line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Move {
    /// From, mm.
    pub from_mm: Point,
    /// To, mm.
    pub to_mm: Point,
    /// Length, mm.
    pub length_mm: f64,
    /// Cruise speed, mm/s.
    pub speed_mm_s: f64,
    /// [`travel_time_s`] of this move, s.
    pub duration_s: f64,
}

/// Where the time goes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TimeEstimate {
    /// Moves with the finger lifted, s.
    pub travel_s: f64,
    /// Sliding, s.
    pub slide_s: f64,
    /// Approach, settling and lift, [`Settings::settle_s`] per slide, s.
    pub settle_s: f64,
    /// Passes with the finger lifted ([`Settings::raised_pass`]), one per targeted slide: an
    /// upper bound, since the mission flies one only where the strokes read as a crack, s.
    pub raised_s: f64,
    /// The sum, s.
    pub total_s: f64,
}

/// A candidate (or merged group) that no slide could reach.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unreachable {
    /// The candidate(s).
    pub candidates: Vec<CandidateId>,
    /// Why.
    pub reason: String,
}

/// What kind of plan, with its own figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanKind {
    /// Slides across detected candidates.
    Targeted {
        /// Candidates asked for.
        candidates: usize,
        /// How the candidates were ordered.
        order: Order,
        /// What was done with overlapping candidates.
        overlap: Overlap,
    },
    /// The tactile-only boustrophedon scan of eq. 2.
    TactileScan {
        /// The design parameter γ.
        gamma: f64,
        /// `L̄`, mm.
        mean_length_mm: f64,
        /// `N_s`.
        rows: usize,
        /// Distance between rows, mm (`h / (N_s − 1)`; the workspace height for one row).
        row_spacing_mm: f64,
        /// Whether every straight crack of length `L̄` lying across the rows crosses one
        /// (`row_spacing_mm ≤ L̄` and, for a single row, `h / 2 ≤ L̄`).
        crossing_guaranteed: bool,
    },
}

/// A plan: slides in order, the moves between them, and the time estimate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plan {
    /// Targeted or tactile-only.
    pub kind: PlanKind,
    /// The workspace everything lies in.
    pub workspace: Workspace,
    /// Where the finger starts, mm.
    pub start_mm: Point,
    /// Where it ends, mm.
    pub end_mm: Point,
    /// The slides, in order.
    pub slides: Vec<Slide>,
    /// The moves: `moves[k]` leads to `slides[k].start_mm`; with
    /// [`Settings::return_to_start`] one more leads back to the start.
    pub moves: Vec<Move>,
    /// The raised passes ([`Settings::raised_pass`]): for each targeted slide, the back-off and
    /// the pass, in the order of the slides; empty without them.
    pub raised: Vec<Move>,
    /// Sum of the moves, mm (the raised passes not included).
    pub travel_mm: f64,
    /// Distance slid (stroke × passes, summed), mm.
    pub slide_mm: f64,
    /// Where the time goes.
    pub time: TimeEstimate,
    /// `time.total_s`, s.
    pub estimated_s: f64,
    /// Candidates no slide could reach (with [`crate::OnUnreachable::Report`]).
    pub unreachable: Vec<Unreachable>,
    /// Groups of candidates whose rectangles overlap (merged into one slide set with
    /// [`Overlap::Merge`], slid one by one with [`Overlap::SlideBoth`]).
    pub overlapping: Vec<Vec<CandidateId>>,
}

/// Time of a move of `distance_mm` at cruise `speed_mm_s`: `d / v`, or with an acceleration
/// `a` a trapezoidal profile, `d / v + v / a` (`2·√(d / a)` when it never reaches `v`).
pub fn travel_time_s(distance_mm: f64, speed_mm_s: f64, accel_mm_s2: Option<f64>) -> f64 {
    if distance_mm <= 0.0 {
        return 0.0;
    }
    match accel_mm_s2 {
        None => distance_mm / speed_mm_s,
        Some(a) if distance_mm >= speed_mm_s * speed_mm_s / a => {
            distance_mm / speed_mm_s + speed_mm_s / a
        }
        Some(a) => 2.0 * (distance_mm / a).sqrt(),
    }
}

/// Time of a slide of `passes` one-way strokes of `stroke_mm` at `speed_mm_s`, each starting and
/// stopping over `reversal_s` (the simulator's arm: a raised-cosine ramp of that length at each
/// reversal, `stroke / v + ramp / 2` per stroke, the ramp no longer than `stroke / v`).
pub fn slide_time_s(stroke_mm: f64, speed_mm_s: f64, passes: u32, reversal_s: f64) -> f64 {
    let cruise = stroke_mm / speed_mm_s;
    let ramp = reversal_s.clamp(0.0, cruise);
    f64::from(passes) * (cruise + ramp / 2.0)
}

/// Where the raised pass over `slide` ([`Settings::raised_pass`]) begins and ends, mm: from
/// `overrun_mm` behind the end where the strokes leave the finger to `overrun_mm` beyond the
/// other end, both clamped to `workspace`. `None` without raised passes or for a scan row.
pub fn raised_pass(
    slide: &Slide,
    settings: &Settings,
    workspace: &Workspace,
) -> Option<[Point; 2]> {
    let r = settings.raised_pass?;
    if slide.candidates.is_empty() {
        return None;
    }
    let at = slide.exit_mm();
    let other = if slide.passes.is_multiple_of(2) {
        slide.end_mm
    } else {
        slide.start_mm
    };
    let d = dist(at, other);
    let u = if d > 0.0 {
        [(other[0] - at[0]) / d, (other[1] - at[1]) / d]
    } else {
        [0.0, 0.0]
    };
    Some([
        workspace.clamp([at[0] - r.overrun_mm * u[0], at[1] - r.overrun_mm * u[1]]),
        workspace.clamp([
            other[0] + r.overrun_mm * u[0],
            other[1] + r.overrun_mm * u[1],
        ]),
    ])
}

/// `slide` moved `by` mm along `candidate`'s axis (the mission makes a stroke again beside its
/// candidate so), to the side where more of the candidate
/// lies beyond the slide (`by` is a distance; its sign is chosen here); `None` when less than
/// `by` plus `keep` mm of the candidate lies on that side, or either end would leave
/// `workspace`.
pub fn slide_along(
    slide: &Slide,
    candidate: &Candidate,
    workspace: &Workspace,
    by: f64,
    keep: f64,
) -> Option<Slide> {
    let u = candidate.axis();
    let mid = [
        (slide.start_mm[0] + slide.end_mm[0]) / 2.0,
        (slide.start_mm[1] + slide.end_mm[1]) / 2.0,
    ];
    let t = (mid[0] - candidate.centre_mm[0]) * u[0] + (mid[1] - candidate.centre_mm[1]) * u[1];
    let half = candidate.length_mm / 2.0;
    let (room, sign) = if half - t >= half + t {
        (half - t, 1.0)
    } else {
        (half + t, -1.0)
    };
    if room.is_nan() || room < by + keep {
        return None;
    }
    let shift = |p: [f64; 2]| [p[0] + sign * by * u[0], p[1] + sign * by * u[1]];
    let (start, end) = (shift(slide.start_mm), shift(slide.end_mm));
    (workspace.contains(start) && workspace.contains(end)).then(|| Slide {
        start_mm: start,
        end_mm: end,
        moved_along_mm: slide.moved_along_mm + sign * by,
        ..slide.clone()
    })
}

/// Where the finger is once `slide` is done: the end of its raised pass, if it has one, else
/// [`Slide::exit_mm`].
pub(crate) fn leaves_at(slide: &Slide, settings: &Settings, workspace: &Workspace) -> Point {
    raised_pass(slide, settings, workspace).map_or(slide.exit_mm(), |[_, to]| to)
}

impl Plan {
    /// Puts slides in order into a plan: the moves between them, totals and times.
    pub(crate) fn assemble(
        kind: PlanKind,
        workspace: Workspace,
        start: Point,
        slides: Vec<Slide>,
        settings: &Settings,
        unreachable: Vec<Unreachable>,
        overlapping: Vec<Vec<CandidateId>>,
    ) -> Plan {
        let mut moves = Vec::with_capacity(slides.len() + 1);
        let mut raised = Vec::new();
        let mut at = start;
        let mv = |from: Point, to: Point, speed: f64| {
            let length = dist(from, to);
            Move {
                from_mm: from,
                to_mm: to,
                length_mm: length,
                speed_mm_s: speed,
                duration_s: travel_time_s(length, speed, settings.travel_accel_mm_s2),
            }
        };
        for s in &slides {
            moves.push(mv(at, s.start_mm, settings.travel_speed_mm_s));
            at = s.exit_mm();
            if let (Some([from, to]), Some(r)) =
                (raised_pass(s, settings, &workspace), settings.raised_pass)
            {
                raised.push(mv(at, from, r.speed_mm_s));
                raised.push(mv(from, to, r.speed_mm_s));
                at = to;
            }
        }
        if settings.return_to_start && !slides.is_empty() {
            moves.push(mv(at, start, settings.travel_speed_mm_s));
            at = start;
        }
        let travel_s = moves.iter().map(|m| m.duration_s).sum();
        let slide_s = slides.iter().map(|s| s.duration_s).sum();
        let settle_s = settings.settle_s * slides.len() as f64;
        let raised_s = raised.iter().fold(0.0, |a, m| a + m.duration_s);
        let total = travel_s + slide_s + settle_s + raised_s;
        Plan {
            kind,
            workspace,
            start_mm: start,
            end_mm: at,
            travel_mm: moves.iter().map(|m| m.length_mm).sum(),
            slide_mm: slides
                .iter()
                .map(|s| s.stroke_mm * f64::from(s.passes))
                .sum(),
            slides,
            moves,
            raised,
            time: TimeEstimate {
                travel_s,
                slide_s,
                settle_s,
                raised_s,
                total_s: total,
            },
            estimated_s: total,
            unreachable,
            overlapping,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times() {
        assert_eq!(travel_time_s(100.0, 50.0, None), 2.0);
        assert_eq!(travel_time_s(0.0, 50.0, Some(10.0)), 0.0);
        // Reaches 50 mm/s after 25 mm (v²/a = 25 at a = 100): 100/50 + 50/100.
        assert!((travel_time_s(100.0, 50.0, Some(100.0)) - 2.5).abs() < 1e-12);
        // Never reaches it: 2·√(16/100).
        assert!((travel_time_s(16.0, 50.0, Some(100.0)) - 0.8).abs() < 1e-12);
        // Continuous at d = v²/a.
        let d = 25.0;
        assert!((travel_time_s(d, 50.0, Some(100.0)) - 2.0 * (d / 100.0f64).sqrt()).abs() < 1e-12);
        // The simulator's slide: 2·(16/4.6 + 0.05/2).
        assert!((slide_time_s(16.0, 4.6, 2, 0.05) - (2.0 * 16.0 / 4.6 + 0.05)).abs() < 1e-12);
        // A ramp longer than the stroke takes is cut to it.
        assert!((slide_time_s(0.1, 4.6, 1, 1.0) - 1.5 * 0.1 / 4.6).abs() < 1e-12);
    }

    #[test]
    fn a_slide_moves_along_its_candidate_to_the_longer_side_and_stays_inside() {
        let ws = Workspace::new(0.0, 200.0, 0.0, 100.0).expect("workspace");
        // A crack along x from 40 to 80 mm at y = 50, slid across at x = 50 (10 mm from its
        // start, 30 from its end).
        let cand = Candidate::from_axis(7, [[40.0, 50.0], [80.0, 50.0]], Some(1.0), 0.9);
        let slide = Slide {
            candidates: vec![7],
            row: None,
            start_mm: [50.0, 40.0],
            end_mm: [50.0, 60.0],
            stroke_mm: 20.0,
            passes: 1,
            speed_mm_s: 4.6,
            duration_s: 4.3,
            sound_run_mm: Some([5.0, 5.0]),
            shifted_mm: 0.0,
            clipped: false,
            moved_along_mm: 0.0,
        };
        let moved = slide_along(&slide, &cand, &ws, 4.0, 1.0).expect("room on the far side");
        assert_eq!(moved.start_mm, [54.0, 40.0]);
        assert_eq!(moved.end_mm, [54.0, 60.0]);
        assert_eq!(moved.moved_along_mm, 4.0);
        assert_eq!(moved.stroke_mm, 20.0);
        // Slid across near its far end: it moves back towards the start.
        let near_end = Slide {
            start_mm: [78.0, 40.0],
            end_mm: [78.0, 60.0],
            ..slide.clone()
        };
        let back = slide_along(&near_end, &cand, &ws, 4.0, 1.0).expect("room behind");
        assert_eq!(back.start_mm, [74.0, 40.0]);
        // A short candidate has no room; nor has a slide at the workspace's edge.
        let short = Candidate::from_axis(8, [[48.0, 50.0], [52.0, 50.0]], None, 0.9);
        assert!(slide_along(&slide, &short, &ws, 4.0, 1.0).is_none());
        let edge = Slide {
            start_mm: [50.0, 0.0],
            end_mm: [50.0, 20.0],
            ..slide.clone()
        };
        let along_y = Candidate::from_axis(9, [[50.0, 10.0], [50.0, 12.0]], None, 0.9);
        assert!(slide_along(&edge, &along_y, &ws, 4.0, 1.0).is_none());
    }
}
