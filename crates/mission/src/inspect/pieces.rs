//! Pieces of one crack: confirmed candidates whose detections continue each other.
//!
//! The detector's crack map breaks a long, bent crack where it fades, and each piece becomes a
//! candidate of its own ([`super::CandidateSource::Cracks`]). When the finger confirms two
//! pieces, the report would name one crack twice. Confirmed candidates whose detected segments
//! come within [`PIECE_GAP_MM`] of each other and run within [`PIECE_ANGLE_DEG`] of the same
//! direction are reported as one crack: the most confident piece's entry, carrying the others'
//! slides and ids.

use crackbot_planner::geometry::connected_groups;
use crackbot_sim::surface::distance_to_polyline;

use super::{Candidate, ReportedCrack};

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

/// Whether two detected segments are pieces of one crack: an end of one within `gap_mm` of
/// the other, directions within [`PIECE_ANGLE_DEG`], and end to end rather than side by side
/// (overlapping by at most [`PIECE_OVERLAP_MM`] along the first one's direction).
pub(super) fn same_crack(a: &Candidate, b: &Candidate, gap_mm: f64) -> bool {
    let (ea, eb) = (a.ends(), b.ends());
    let gap = ea
        .iter()
        .map(|&p| distance_to_polyline(&eb, p))
        .chain(eb.iter().map(|&p| distance_to_polyline(&ea, p)))
        .fold(f64::INFINITY, f64::min);
    let turn = (a.axis_deg - b.axis_deg).rem_euclid(180.0);
    let (s, c) = a.axis_deg.to_radians().sin_cos();
    let along = |p: [f64; 2]| p[0] * c + p[1] * s;
    let span = |e: [[f64; 2]; 2]| {
        let (u, v) = (along(e[0]), along(e[1]));
        (u.min(v), u.max(v))
    };
    let ((a0, a1), (b0, b1)) = (span(ea), span(eb));
    let overlap = a1.min(b1) - a0.max(b0);
    gap <= gap_mm && turn.min(180.0 - turn) <= PIECE_ANGLE_DEG && overlap <= PIECE_OVERLAP_MM
}

/// Joins the confirmed reports whose candidates are pieces of one crack ([`same_crack`]): each
/// group becomes its most confident report, with the other pieces' slides added to its
/// evidence and their candidate ids in `evidence.pieces`. Reports without a candidate stay.
pub(super) fn join_pieces(
    cracks: Vec<ReportedCrack>,
    candidates: &[Candidate],
    gap_mm: f64,
) -> Vec<ReportedCrack> {
    let geometry = |r: &ReportedCrack| {
        r.candidate
            .and_then(|id| candidates.iter().find(|c| c.id == id))
    };
    let groups = connected_groups(cracks.len(), |i, j| {
        match (geometry(&cracks[i]), geometry(&cracks[j])) {
            (Some(a), Some(b)) => same_crack(a, b, gap_mm),
            _ => false,
        }
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
    use super::super::Evidence;
    use super::*;

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

    fn report(id: u64, conf: f64) -> ReportedCrack {
        ReportedCrack {
            candidate: Some(id),
            position_mm: [0.0, 0.0],
            extent_mm: None,
            class: "crack".into(),
            width_mm: None,
            width_std_mm: None,
            confidence: conf,
            evidence: Evidence {
                detector_score: Some(0.9),
                slides: vec![id as u32],
                votes: Vec::new(),
                doubts: Vec::new(),
                height_ratio: None,
                pieces: Vec::new(),
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
            PIECE_GAP_MM,
        );
        assert_eq!(joined.len(), 3);
        let one = joined.iter().find(|r| r.candidate == Some(2)).unwrap();
        assert_eq!(one.evidence.pieces, vec![1]);
        assert_eq!(one.evidence.slides, vec![2, 1]);
        // A gap of 0 joins only touching pieces.
        assert_eq!(
            join_pieces(vec![report(1, 0.6), report(2, 0.8)], &c, 0.0).len(),
            2
        );
    }
}
