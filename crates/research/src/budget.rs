//! The finger's error budget ([`FingerBudget`]): what each touched candidate's strokes crossed in
//! the scene's truth against what the finger called, and the cracks no stroke crossed.

use crate::geometry::stroke_meets;
use crackbot_mission::inspect::InspectReport;
use crackbot_sim::{Feature, Scene};
use serde::Serialize;

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

    pub(crate) fn add(&mut self, other: &FingerBudget) {
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
