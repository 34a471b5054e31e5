//! Candidate cracks in surface millimetres, from a detector box, a main axis or a centre-line
//! polyline (the camera side maps its pixels to millimetres first; this crate never sees an
//! image).

use serde::{Deserialize, Serialize};

use crate::error::PlanError;
use crate::geometry::{dot, OrientedRect, Point};
use crate::MAX_COORD_MM;

pub use crate::CandidateId;

/// A place where a crack may be: a rectangle along the crack's main axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Id, unique within one request.
    pub id: CandidateId,
    /// Centre of the crack, mm.
    pub centre_mm: Point,
    /// Direction of the crack's main axis, degrees from +x (any value; 0 and 180 are the same
    /// axis). The finger slides perpendicular to it.
    pub axis_deg: f64,
    /// Length along the axis, mm (0: a point-like or zero-length crack, still slid across).
    pub length_mm: f64,
    /// Extent across the axis, mm, when known (a crack's width, a box's short side); `None`:
    /// [`crate::Settings::assumed_width_mm`].
    pub width_mm: Option<f64>,
    /// The detector's score (carried into the report; not used to plan).
    pub score: f64,
}

impl Candidate {
    /// A candidate from the two ends of its main axis (e.g. `crackbot_vision`'s
    /// `CrackShape::axis` mapped to mm). Coincident ends give a zero-length candidate along x
    /// (slid along y).
    pub fn from_axis(id: CandidateId, ends: [Point; 2], width_mm: Option<f64>, score: f64) -> Self {
        let d = [ends[1][0] - ends[0][0], ends[1][1] - ends[0][1]];
        let length = d[0].hypot(d[1]);
        Candidate {
            id,
            centre_mm: [
                (ends[0][0] + ends[1][0]) / 2.0,
                (ends[0][1] + ends[1][1]) / 2.0,
            ],
            axis_deg: if length > 0.0 {
                d[1].atan2(d[0]).to_degrees()
            } else {
                0.0
            },
            length_mm: length,
            width_mm,
            score,
        }
    }

    /// A candidate from an axis-aligned detector box `[min, max]` mm: the main axis along the
    /// box's longer side, the whole shorter side as its width (the finger slides across the
    /// whole box). A square box is taken along x.
    pub fn from_box(id: CandidateId, min_mm: Point, max_mm: Point, score: f64) -> Self {
        let (w, h) = ((max_mm[0] - min_mm[0]).abs(), (max_mm[1] - min_mm[1]).abs());
        Candidate {
            id,
            centre_mm: [(min_mm[0] + max_mm[0]) / 2.0, (min_mm[1] + max_mm[1]) / 2.0],
            axis_deg: if h > w { 90.0 } else { 0.0 },
            length_mm: w.max(h),
            width_mm: Some(w.min(h)),
            score,
        }
    }

    /// A candidate from a crack's centre-line polyline: the main axis is the principal direction
    /// of the polyline (its segments weighted by length); length and width are its extents
    /// along and across that axis, the width plus `line_width_mm` (the crack's own width, 0 when
    /// unknown). A bent crack thus gets a width that covers its bend, so one slide across the
    /// centre still crosses it. Errors on an empty polyline or a non-finite point.
    pub fn from_polyline(
        id: CandidateId,
        points: &[Point],
        line_width_mm: f64,
        score: f64,
    ) -> Result<Self, PlanError> {
        if points.is_empty() {
            return Err(PlanError::EmptyPolyline { id });
        }
        for (k, p) in points.iter().enumerate() {
            for v in p {
                if !v.is_finite() || v.abs() > MAX_COORD_MM {
                    return Err(PlanError::InvalidCandidate {
                        id,
                        index: k,
                        field: "polyline point",
                        value: *v,
                        expected: "finite, within ±1e9 mm",
                    });
                }
            }
        }
        if !(line_width_mm.is_finite() && line_width_mm >= 0.0) {
            return Err(PlanError::InvalidCandidate {
                id,
                index: 0,
                field: "line_width_mm",
                value: line_width_mm,
                expected: "finite and ≥ 0",
            });
        }
        // Second moments of the polyline as a uniform line density (each segment's own
        // moments about the mean: length·(m·mᵀ + d·dᵀ/12)).
        let mut total = 0.0;
        let mut mean = [0.0, 0.0];
        for w in points.windows(2) {
            let l = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            total += l;
            mean[0] += l * (w[0][0] + w[1][0]) / 2.0;
            mean[1] += l * (w[0][1] + w[1][1]) / 2.0;
        }
        let axis = if total > 0.0 {
            mean = [mean[0] / total, mean[1] / total];
            let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
            for w in points.windows(2) {
                let l = (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
                let m = [
                    (w[0][0] + w[1][0]) / 2.0 - mean[0],
                    (w[0][1] + w[1][1]) / 2.0 - mean[1],
                ];
                let d = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
                sxx += l * (m[0] * m[0] + d[0] * d[0] / 12.0);
                sxy += l * (m[0] * m[1] + d[0] * d[1] / 12.0);
                syy += l * (m[1] * m[1] + d[1] * d[1] / 12.0);
            }
            0.5 * (2.0 * sxy).atan2(sxx - syy)
        } else {
            0.0
        };
        let a = [axis.cos(), axis.sin()];
        let n = [-a[1], a[0]];
        let (mut a_lo, mut a_hi, mut n_lo, mut n_hi) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for p in points {
            let (u, v) = (dot(*p, a), dot(*p, n));
            a_lo = a_lo.min(u);
            a_hi = a_hi.max(u);
            n_lo = n_lo.min(v);
            n_hi = n_hi.max(v);
        }
        let (cu, cv) = ((a_lo + a_hi) / 2.0, (n_lo + n_hi) / 2.0);
        Ok(Candidate {
            id,
            centre_mm: [cu * a[0] + cv * n[0], cu * a[1] + cv * n[1]],
            axis_deg: axis.to_degrees(),
            length_mm: a_hi - a_lo,
            width_mm: Some(n_hi - n_lo + line_width_mm),
            score,
        })
    }

    /// The main axis as a unit vector.
    pub fn axis(&self) -> Point {
        let r = self.axis_deg.to_radians();
        [r.cos(), r.sin()]
    }

    /// The ends of the candidate's segment: its centre ∓ half its length along its axis, mm.
    pub fn ends(&self) -> [Point; 2] {
        let u = self.axis();
        let h = self.length_mm / 2.0;
        let [x, y] = self.centre_mm;
        [[x - h * u[0], y - h * u[1]], [x + h * u[0], y + h * u[1]]]
    }

    /// Checks every field (`index`: the position in the request, for the message).
    pub(crate) fn validate(&self, index: usize) -> Result<(), PlanError> {
        let err = |field, value, expected| PlanError::InvalidCandidate {
            id: self.id,
            index,
            field,
            value,
            expected,
        };
        let coord = "finite, within ±1e9 mm";
        for (field, v) in [
            ("centre_mm[0]", self.centre_mm[0]),
            ("centre_mm[1]", self.centre_mm[1]),
        ] {
            if !(v.is_finite() && v.abs() <= MAX_COORD_MM) {
                return Err(err(field, v, coord));
            }
        }
        if !self.axis_deg.is_finite() {
            return Err(err("axis_deg", self.axis_deg, "finite degrees"));
        }
        if !(self.length_mm.is_finite() && (0.0..=MAX_COORD_MM).contains(&self.length_mm)) {
            return Err(err("length_mm", self.length_mm, "finite, 0 to 1e9 mm"));
        }
        if let Some(w) = self.width_mm {
            if !(w.is_finite() && (0.0..=MAX_COORD_MM).contains(&w)) {
                return Err(err("width_mm", w, "finite, 0 to 1e9 mm"));
            }
        }
        if !self.score.is_finite() {
            return Err(err("score", self.score, "finite"));
        }
        Ok(())
    }

    pub(crate) fn rect(&self, assumed_width_mm: f64) -> OrientedRect {
        OrientedRect {
            centre: self.centre_mm,
            axis: self.axis(),
            half_len: self.length_mm / 2.0,
            half_wid: self.width_mm.unwrap_or(assumed_width_mm) / 2.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constructors() {
        let c = Candidate::from_axis(3, [[10.0, 10.0], [10.0, 30.0]], Some(2.0), 0.9);
        assert_eq!(c.centre_mm, [10.0, 20.0]);
        assert!((c.axis_deg - 90.0).abs() < 1e-9);
        assert_eq!(c.length_mm, 20.0);
        let z = Candidate::from_axis(4, [[1.0, 1.0], [1.0, 1.0]], None, 0.5);
        assert_eq!((z.length_mm, z.axis_deg), (0.0, 0.0));
        let b = Candidate::from_box(5, [0.0, 0.0], [10.0, 40.0], 0.1);
        assert_eq!(
            (b.axis_deg, b.length_mm, b.width_mm),
            (90.0, 40.0, Some(10.0))
        );
    }

    #[test]
    fn a_bent_polyline_gets_a_width_covering_its_bend() {
        // The default scene's 2 mm crack: (20,50) → (45,62) → (75,52).
        let c = Candidate::from_polyline(1, &[[20.0, 50.0], [45.0, 62.0], [75.0, 52.0]], 2.0, 1.0)
            .unwrap();
        assert!(c.axis_deg.abs() < 20.0, "{c:?}");
        assert!((50.0..60.0).contains(&c.length_mm), "{c:?}");
        assert!(c.width_mm.unwrap() > 8.0, "{c:?}");
        // A straight one: its own axis, its line width.
        let s = Candidate::from_polyline(2, &[[0.0, 0.0], [30.0, 40.0]], 1.0, 1.0).unwrap();
        assert!((s.axis_deg - 53.130_102_354).abs() < 1e-6, "{s:?}");
        assert!((s.length_mm - 50.0).abs() < 1e-9 && (s.width_mm.unwrap() - 1.0).abs() < 1e-9);
        assert!((s.centre_mm[0] - 15.0).abs() < 1e-9 && (s.centre_mm[1] - 20.0).abs() < 1e-9);
        assert!(Candidate::from_polyline(3, &[], 1.0, 1.0).is_err());
        let e = Candidate::from_polyline(3, &[[0.0, f64::NAN]], 1.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("polyline point"), "{e}");
        let one = Candidate::from_polyline(4, &[[5.0, 6.0]], 0.0, 1.0).unwrap();
        assert_eq!((one.centre_mm, one.length_mm), ([5.0, 6.0], 0.0));
    }
}
