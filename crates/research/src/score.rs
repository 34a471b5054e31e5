//! A mission's report scored against its scene's truth ([`Score`]): which reports are correct,
//! which false, which cracks missed, and how far the correct ones lie from their cracks.

use crackbot_mission::inspect::InspectReport;
use crackbot_sim::surface::distance_to_polyline;
use crackbot_sim::{Feature, Scene};
use serde::Serialize;

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
