//! Pieces of one crack: confirmed candidates whose detections continue each other.
//!
//! The detector's crack map breaks a long, bent crack where it fades, and each piece becomes a
//! candidate of its own ([`super::CandidateSource::Cracks`]). When the finger confirms two
//! pieces, the report would name one crack twice. Confirmed candidates whose detected segments
//! come within [`PIECE_GAP_MM`] of each other and run within [`PIECE_ANGLE_DEG`] of the same
//! direction are reported as one crack: the most confident piece's entry, carrying the others'
//! slides and ids.
//!
//! The detections' straight segments miss pieces of one crack that the crack map split at a
//! crossing, where its centre line went on into a printed line or another crack; and they join
//! two cracks that happen to lie end to end. There the finger tells where the crack is: the
//! points where the strokes met it. With the detector's crack map ([`CrackTrace`]),
//! [`traced_between`] joins two confirmed pieces when the straight line between those points
//! runs along both pieces and over the map, and pieces that continue each other are joined only
//! where that line leaves the map for no longer than the gap between them (plus the same
//! tolerance).

use crackbot_imaging::geometry::distance_to_polyline;
use crackbot_planner::geometry::connected_groups;
use crackbot_planner::Candidate;
use serde::{Deserialize, Serialize};

use super::trace::{CrackTrace, TRACE_REACH_MM};
use crate::inspect::report::ReportedCrack;
use crate::MissionError;

/// Longest stretch of the line between two crossings that may run off the crack map for the
/// two pieces to be one crack, mm (see `traced_between`): two map cells. On the trial scenes
/// 4000–5119 (`examples/trace_pairs.rs`) the lines between crossings of one crack ran off the
/// map by 0–2.0 mm, those between two cracks along both pieces by 3.5 mm and more, but for
/// cracks that touch or cross (`crates/research/EXPERIMENTS.md`, "Pieces joined where the crack
/// map runs between their crossings").
pub const PIECE_TRACE_GAP_MM: f64 = 2.0;
/// Largest gap between two confirmed pieces of one crack by default, mm: a narrow crack's
/// pieces on either side of a wide one it crosses lie 8.9–11.5 mm apart end to end on the
/// simulated trial scenes (seeds 1000–1029, 2000–2029, 3000–3029; 10 mm before).
pub const PIECE_GAP_MM: f64 = 12.0;
/// Largest difference of direction between two pieces of one crack, degrees: the detector's own
/// rule for a crack that goes on ([`crackbot_vision::crack_map::CONTINUATION_DEG`]); pieces of
/// one bent crack met at 33–38° on the trial scenes above (30° before).
pub const PIECE_ANGLE_DEG: f64 = 40.0;
/// Pieces continue each other end to end: along the first one's direction they may overlap by
/// at most this much, mm (two cracks running side by side overlap by far more).
pub const PIECE_OVERLAP_MM: f64 = 2.0;

/// The angle between two undirected lines at `a` and `b` degrees from +x, in [0, 90].
pub fn turn_deg(a: f64, b: f64) -> f64 {
    let turn = (a - b).rem_euclid(180.0);
    turn.min(180.0 - turn)
}

/// The gap between two detected segments that continue each other (directions within
/// [`PIECE_ANGLE_DEG`], end to end rather than side by side: overlapping by at most
/// [`PIECE_OVERLAP_MM`] along the first one's direction), mm: how far an end of one lies from
/// the other. `None` when they do not continue each other.
pub(crate) fn continuation_gap(a: &Candidate, b: &Candidate) -> Option<f64> {
    let (ea, eb) = (a.ends(), b.ends());
    let gap = ea
        .iter()
        .map(|&p| distance_to_polyline(&eb, p))
        .chain(eb.iter().map(|&p| distance_to_polyline(&ea, p)))
        .fold(f64::INFINITY, f64::min);
    let (s, c) = a.axis_deg.to_radians().sin_cos();
    let along = |p: [f64; 2]| p[0] * c + p[1] * s;
    let span = |e: [[f64; 2]; 2]| {
        let (u, v) = (along(e[0]), along(e[1]));
        (u.min(v), u.max(v))
    };
    let ((a0, a1), (b0, b1)) = (span(ea), span(eb));
    let overlap = a1.min(b1) - a0.max(b0);
    (turn_deg(a.axis_deg, b.axis_deg) <= PIECE_ANGLE_DEG && overlap <= PIECE_OVERLAP_MM)
        .then_some(gap)
}

/// Which rules join confirmed pieces: `[pieces]` of the configuration file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PiecesConfig {
    /// Fused missions: confirmed candidates whose detections continue each other across a gap
    /// of at most this much (mm, within [`PIECE_ANGLE_DEG`] of one direction) are reported as
    /// one crack ([`continuation_gap`], [`PIECE_GAP_MM`]); `None` (0 in the file) reports every
    /// confirmed candidate.
    #[serde(with = "crate::inspect::off::at_zero")]
    pub gap_mm: Option<f64>,
    /// Fused missions: two confirmed candidates are also one crack when the straight line
    /// between the points where their strokes met it runs along both and over the detector's
    /// crack map, off it for at most this much (mm, [`traced_between`],
    /// [`PIECE_TRACE_GAP_MM`]); candidates joined by `gap_mm` must then also have that line on
    /// the map but for their gap plus this much. `None` (negative in the file) joins by the
    /// detections' geometry alone.
    #[serde(with = "crate::inspect::off::when_negative")]
    pub trace_gap_mm: Option<f64>,
}

impl Default for PiecesConfig {
    fn default() -> Self {
        PiecesConfig {
            gap_mm: Some(PIECE_GAP_MM),
            trace_gap_mm: Some(PIECE_TRACE_GAP_MM),
        }
    }
}

impl PiecesConfig {
    /// Refuses a setting out of range, naming it.
    pub fn check(&self) -> Result<(), MissionError> {
        for (field, value) in [
            ("pieces.gap_mm", self.gap_mm),
            ("pieces.trace_gap_mm", self.trace_gap_mm),
        ] {
            if let Some(v) = value.filter(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(MissionError::Setting {
                    field,
                    value: v,
                    allowed: "a number ≥ 0",
                });
            }
        }
        Ok(())
    }

    /// Whether any rule joins pieces.
    pub fn joins(&self) -> bool {
        self.gap_mm.is_some() || self.trace_gap_mm.is_some()
    }
}

/// Whether the strokes across two confirmed pieces met one crack that the camera traced: the
/// straight line between the points where they met it (the reports' positions) runs within
/// [`PIECE_ANGLE_DEG`] of both pieces' directions and over the crack map, leaving it (by more
/// than [`TRACE_REACH_MM`]) for at most `gap_mm`. Two cracks side by side, or crossing, put the
/// line across sound surface or across the pieces.
pub(crate) fn traced_between(
    a: (&ReportedCrack, &Candidate),
    b: (&ReportedCrack, &Candidate),
    trace: &CrackTrace,
    gap_mm: f64,
) -> bool {
    let (p, q) = (a.0.position_mm, b.0.position_mm);
    let line_deg = (q[1] - p[1]).atan2(q[0] - p[0]).to_degrees();
    let along = |c: &Candidate| turn_deg(line_deg, c.axis_deg) <= PIECE_ANGLE_DEG;
    along(a.1) && along(b.1) && trace.longest_gap_mm(p, q, TRACE_REACH_MM) <= gap_mm
}

/// Joins the confirmed reports whose candidates are pieces of one crack: they continue each
/// other ([`continuation_gap`]) or, with a crack map, [`traced_between`] joins them, as `rule`
/// enables each. With the map and the trace rule on, pieces that continue each other must also
/// have the line between their crossings on the map but for their gap plus `trace_gap_mm`.
/// Each group becomes its most confident report, with the other pieces' slides added to its
/// evidence and their candidate ids in `evidence.pieces`. Reports without a candidate stay.
pub(crate) fn join_pieces(
    cracks: Vec<ReportedCrack>,
    candidates: &[Candidate],
    trace: Option<&CrackTrace>,
    rule: &PiecesConfig,
) -> Vec<ReportedCrack> {
    let geometry = |r: &ReportedCrack| {
        r.candidate
            .and_then(|id| candidates.iter().find(|c| c.id == id))
    };
    let groups = connected_groups(cracks.len(), |i, j| {
        let (a, b) = (&cracks[i], &cracks[j]);
        // With the crack map, pieces that continue each other must also have their crossings
        // joined by it, but for a stretch as long as the gap between them (where the crack
        // faded) and the trace's own tolerance: two cracks end to end put theirs far apart.
        let by_gap = match (rule.gap_mm, geometry(a), geometry(b)) {
            (Some(max), Some(ga), Some(gb)) => continuation_gap(ga, gb).is_some_and(|g| {
                g <= max
                    && match (rule.trace_gap_mm, trace) {
                        (Some(tolerance), Some(t)) => {
                            t.longest_gap_mm(a.position_mm, b.position_mm, TRACE_REACH_MM)
                                <= g + tolerance
                        }
                        _ => true,
                    }
            }),
            _ => false,
        };
        let by_trace = match (rule.trace_gap_mm, trace, geometry(a), geometry(b)) {
            (Some(gap), Some(t), Some(ga), Some(gb)) => traced_between((a, ga), (b, gb), t, gap),
            _ => false,
        };
        by_gap || by_trace
    });
    let mut cracks: Vec<Option<ReportedCrack>> = cracks.into_iter().map(Some).collect();
    let members: Vec<Vec<ReportedCrack>> = groups
        .iter()
        .map(|g| g.iter().filter_map(|&i| cracks[i].take()).collect())
        .collect();
    members
        .into_iter()
        .filter(|m| !m.is_empty())
        .map(|mut m| {
            m.sort_by(|a, b| b.confidence.total_cmp(&a.confidence));
            let mut best = m.remove(0);
            for other in m {
                best.evidence.slides.extend(other.evidence.slides);
                best.evidence.pieces.extend(other.candidate);
            }
            best
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::trace::trace_of;
    use super::*;
    use crate::inspect::report::Evidence;

    /// Whether two detected segments are pieces of one crack by their geometry alone: they
    /// continue each other across at most `gap_mm`.
    fn same_crack(a: &Candidate, b: &Candidate, gap_mm: f64) -> bool {
        continuation_gap(a, b).is_some_and(|g| g <= gap_mm)
    }

    fn cand(id: u64, centre: [f64; 2], axis: f64, len: f64) -> Candidate {
        Candidate {
            id,
            centre_mm: centre,
            axis_deg: axis,
            length_mm: len,
            width_mm: None,
            score: 0.9,
        }
    }

    fn gap_only(gap_mm: f64) -> PiecesConfig {
        PiecesConfig {
            gap_mm: Some(gap_mm),
            trace_gap_mm: None,
        }
    }

    fn report(id: u64, conf: f64) -> ReportedCrack {
        ReportedCrack {
            candidate: Some(id),
            position_mm: [0.0, 0.0],
            extent_mm: None,
            class: "crack".into(),
            width_mm: None,
            width_range_mm: None,
            confidence: conf,
            evidence: Evidence {
                detector_score: Some(0.9),
                slides: vec![id as u32],
                ..Evidence::default()
            },
        }
    }

    #[test]
    fn pieces_that_continue_each_other_are_one_crack_and_others_stay_apart() {
        let c = [
            // 1 and 2: one crack along x, broken by an 8 mm gap, the second bent by 20°.
            cand(1, [20.0, 50.0], 0.0, 20.0),
            cand(2, [47.0, 50.0 + 5.0], 20.0, 20.0),
            // 3: parallel to 1 but 15 mm away; 4: close to 1's end but across it.
            cand(3, [20.0, 65.0], 0.0, 20.0),
            cand(4, [34.0, 50.0], 90.0, 6.0),
        ];
        assert!(same_crack(&c[0], &c[1], PIECE_GAP_MM));
        assert!(!same_crack(&c[0], &c[2], PIECE_GAP_MM));
        assert!(!same_crack(&c[0], &c[3], PIECE_GAP_MM));
        // Two cracks side by side, 5 mm apart and overlapping along their length: not one.
        assert!(!same_crack(
            &c[0],
            &cand(7, [25.0, 55.0], 5.0, 20.0),
            PIECE_GAP_MM
        ));
        // Direction wraps at 180°: 175° and 5° differ by 10°.
        assert!(same_crack(
            &cand(5, [0.0, 0.0], 175.0, 10.0),
            &cand(6, [12.0, 0.0], 5.0, 10.0),
            PIECE_GAP_MM
        ));
        // A narrow crack's two pieces either side of a wide crack it crosses: 11 mm apart end to
        // end, bent by 36° at the crossing. One crack; bent by 45°, or 13 mm apart, two.
        let bent = |deg: f64, gap: f64| {
            let (s, c) = deg.to_radians().sin_cos();
            cand(9, [30.0 + gap + 10.0 * c, 50.0 + 10.0 * s], deg, 20.0)
        };
        assert!(same_crack(&c[0], &bent(36.0, 11.0), PIECE_GAP_MM));
        assert!(!same_crack(&c[0], &bent(45.0, 11.0), PIECE_GAP_MM));
        assert!(!same_crack(&c[0], &bent(20.0, 13.0), PIECE_GAP_MM));
        let joined = join_pieces(
            vec![
                report(1, 0.6),
                report(2, 0.8),
                report(3, 0.7),
                report(4, 0.5),
            ],
            &c,
            None,
            &gap_only(PIECE_GAP_MM),
        );
        assert_eq!(joined.len(), 3);
        let one = joined.iter().find(|r| r.candidate == Some(2)).unwrap();
        assert_eq!(one.evidence.pieces, vec![1]);
        assert_eq!(one.evidence.slides, vec![2, 1]);
        // A gap of 0 joins only touching pieces.
        assert_eq!(
            join_pieces(
                vec![report(1, 0.6), report(2, 0.8)],
                &c,
                None,
                &gap_only(0.0)
            )
            .len(),
            2
        );
    }

    #[test]
    fn crossings_joined_by_the_crack_map_are_one_crack_and_side_by_side_ones_are_not() {
        let row = |r: usize, cols: &mut dyn Iterator<Item = usize>| -> Vec<(usize, usize)> {
            cols.map(|c| (r, c)).collect()
        };
        let mut cells = Vec::new();
        // y = 25: a crack faded for 2 mm at x = 40; y = 30: a second crack 5 mm beside it;
        // y = 70: a crack faded for 6 mm; x = 60: a crack across the first, y 40-90.
        cells.extend(row(25, &mut (10..40).chain(42..90)));
        cells.extend(row(30, &mut (10..90)));
        cells.extend(row(70, &mut (10..40).chain(46..90)));
        cells.extend((40..90).map(|r| (r, 60)));
        let trace = trace_of(&cells);
        assert!(trace.near_crack([20.0, 25.5], TRACE_REACH_MM));
        assert!(!trace.near_crack([20.0, 27.8], TRACE_REACH_MM));
        assert!(
            !trace.near_crack([-50.0, 25.0], TRACE_REACH_MM),
            "outside the frame"
        );
        assert!(trace.longest_gap_mm([20.0, 25.4], [70.0, 25.3], TRACE_REACH_MM) <= 0.5);
        let gap = trace.longest_gap_mm([20.0, 70.4], [70.0, 70.4], TRACE_REACH_MM);
        assert!((3.0..=5.0).contains(&gap), "{gap}");
        // Ends off the plate, huge or not numbers: an answer, at once, that joins nothing.
        let far = trace.longest_gap_mm([20.0, 25.4], [1e300, 25.4], TRACE_REACH_MM);
        assert!(far > 1e290, "{far}");
        assert!(trace
            .longest_gap_mm([f64::NAN, 25.4], [70.0, 25.3], 1.0)
            .is_nan());
        assert!(trace
            .longest_gap_mm([20.0, 25.4], [f64::INFINITY, 0.0], 1.0)
            .is_nan());
        assert_eq!(trace.longest_gap_mm([20.0, 25.4], [20.0, 25.4], 1.0), 0.0);

        let along_x = |id: u64, x: f64| cand(id, [x, 0.0], 0.0, 20.0);
        let felt = |id: u64, p: [f64; 2]| {
            let mut r = report(id, 0.5);
            r.position_mm = p;
            r
        };
        let (ca, cb) = (along_x(1, 20.0), along_x(2, 70.0));
        let joined = |p: [f64; 2], q: [f64; 2], cb: &Candidate| {
            traced_between(
                (&felt(1, p), &ca),
                (&felt(2, q), cb),
                &trace,
                PIECE_TRACE_GAP_MM,
            )
        };
        // One crack, across its faded 2 mm.
        assert!(joined([20.0, 25.4], [70.0, 25.3], &cb));
        // Its neighbour 5 mm away: the line between the crossings leaves both.
        assert!(!joined([20.0, 25.4], [70.0, 30.4], &cb));
        // Faded for 6 mm: more than the gap allowed.
        assert!(!joined([20.0, 70.4], [70.0, 70.4], &cb));
        // The crack across at x = 60, felt by a piece along y: the line runs across that piece.
        assert!(!joined(
            [60.4, 25.4],
            [60.4, 60.0],
            &cand(2, [60.0, 60.0], 90.0, 20.0)
        ));
        // Both along it, the line runs along the crack map (the cells at x = 60 reach y = 40).
        let up = cand(1, [60.0, 50.0], 90.0, 20.0);
        assert!(traced_between(
            (&felt(1, [60.4, 45.0]), &up),
            (&felt(2, [60.4, 80.0]), &cand(2, [60.0, 80.0], 90.0, 20.0)),
            &trace,
            PIECE_TRACE_GAP_MM
        ));

        // In the join: without a trace, or with the rule off, the pieces stay two.
        let both = PiecesConfig {
            gap_mm: Some(PIECE_GAP_MM),
            trace_gap_mm: Some(PIECE_TRACE_GAP_MM),
        };
        let reports = || vec![felt(1, [20.0, 25.4]), felt(2, [70.0, 25.3])];
        let c = [ca, cb];
        assert!(
            !same_crack(&c[0], &c[1], PIECE_GAP_MM),
            "30 mm apart end to end"
        );
        let one = join_pieces(reports(), &c, Some(&trace), &both);
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].evidence.pieces.len(), 1);
        assert_eq!(join_pieces(reports(), &c, None, &both).len(), 2);

        // Pieces end to end (the gap rule's pairs), with the map on: joined where the map runs
        // between their crossings but for the faded stretch (y = 70: detections 9 mm apart,
        // the crack faded for 6 mm); not where the crossings lie on two cracks (y = 25 and 30).
        let (left, right) = (
            cand(1, [25.0, 70.0], 0.0, 28.0),
            cand(2, [68.0, 70.0], 0.0, 40.0),
        );
        assert!(same_crack(&left, &right, PIECE_GAP_MM));
        let pair = || vec![felt(1, [20.0, 70.4]), felt(2, [70.0, 70.4])];
        let faded = [left, right];
        assert!(!traced_between(
            (&pair()[0], &faded[0]),
            (&pair()[1], &faded[1]),
            &trace,
            PIECE_TRACE_GAP_MM
        ));
        assert_eq!(join_pieces(pair(), &faded, Some(&trace), &both).len(), 1);
        let (lower, upper) = (
            cand(1, [25.0, 25.0], 0.0, 28.0),
            cand(2, [55.0, 30.0], 0.0, 20.0),
        );
        assert!(same_crack(&lower, &upper, PIECE_GAP_MM));
        let two = || vec![felt(1, [20.0, 25.4]), felt(2, [55.0, 30.4])];
        let apart = [lower, upper];
        assert_eq!(join_pieces(two(), &apart, Some(&trace), &both).len(), 2);
        // Without the map, or with the trace rule off, the geometry alone joins them.
        assert_eq!(join_pieces(two(), &apart, None, &both).len(), 1);
        assert_eq!(
            join_pieces(two(), &apart, Some(&trace), &gap_only(PIECE_GAP_MM)).len(),
            1
        );
        assert_eq!(
            join_pieces(reports(), &c, Some(&trace), &gap_only(PIECE_GAP_MM)).len(),
            2
        );
    }
}
