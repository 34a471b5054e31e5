//! Surface geometry: height and reflectivity of a flat plate carrying cracks, bumps, wavy
//! patches, printed decoys and screws.
//!
//! Coordinates are millimetres in the plate's frame: `x` along its length, `y` along its width,
//! origin at a corner, `z` up (0 is the plate's top face). Heights are millimetres (cracks are
//! negative). Reflectivity is the fraction of the plate material's own reflectivity seen by the
//! proximity fibre (1 = bare plate, below 1 darker).

use serde::{Deserialize, Serialize};

/// A point on the plate, mm.
pub type Point = [f64; 2];

/// One feature on the plate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Feature {
    /// A groove of constant width and depth along a polyline, flat-bottomed, with rounded edges.
    Crack {
        /// Polyline of the crack's centre line, mm (two points or more).
        path: Vec<Point>,
        /// Width at the top, mm (0: a closed hairline, invisible to touch).
        width_mm: f64,
        /// Depth, mm.
        depth_mm: f64,
        /// Radius of the rounded top edges, mm.
        #[serde(default = "default_edge_radius")]
        edge_radius_mm: f64,
        /// Angle of the walls from the plate's plane, degrees (90: vertical walls; the default
        /// 45° is a printed V/trapezoid groove, flat-bottomed where it reaches `depth_mm`).
        #[serde(default = "default_wall_angle")]
        wall_angle_deg: f64,
    },
    /// A smooth dome (raised cosine) of given base radius and height.
    Bump {
        /// Centre, mm.
        centre: Point,
        /// Radius of the base, mm.
        radius_mm: f64,
        /// Height of the top, mm.
        height_mm: f64,
    },
    /// A sinusoidal corrugation over a rectangle: ridges perpendicular to `direction_deg`.
    Wavy {
        /// Lower corner of the patch, mm.
        min: Point,
        /// Upper corner of the patch, mm.
        max: Point,
        /// Amplitude, mm (the paper: 1 mm).
        #[serde(default = "default_wave_amplitude")]
        amplitude_mm: f64,
        /// Period, mm (the paper: 5 mm).
        #[serde(default = "default_wave_period")]
        period_mm: f64,
        /// Direction of travel of the wave in the plate, degrees from +x.
        #[serde(default)]
        direction_deg: f64,
    },
    /// A crack printed on the surface: flat to the touch, darker to the proximity fibre and the
    /// camera.
    Decoy {
        /// Polyline of the printed line, mm.
        path: Vec<Point>,
        /// Width of the printed line, mm.
        width_mm: f64,
        /// Reflectivity of the ink relative to the plate (0 black .. 1 invisible).
        #[serde(default = "default_decoy_reflectivity")]
        reflectivity: f64,
    },
    /// A screw head: a low cylinder, an occluder for the camera and an obstacle for the finger.
    Screw {
        /// Centre, mm.
        centre: Point,
        /// Head diameter, mm.
        #[serde(default = "default_screw_diameter")]
        head_diameter_mm: f64,
        /// Head height, mm.
        #[serde(default = "default_screw_height")]
        height_mm: f64,
    },
}

fn default_edge_radius() -> f64 {
    0.2
}
fn default_wall_angle() -> f64 {
    45.0
}
fn default_wave_amplitude() -> f64 {
    1.0
}
fn default_wave_period() -> f64 {
    5.0
}
fn default_decoy_reflectivity() -> f64 {
    0.35
}
fn default_screw_diameter() -> f64 {
    8.0
}
fn default_screw_height() -> f64 {
    3.0
}

impl Feature {
    /// A short name of the feature's kind, for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Feature::Crack { .. } => "crack",
            Feature::Bump { .. } => "bump",
            Feature::Wavy { .. } => "wavy",
            Feature::Decoy { .. } => "decoy",
            Feature::Screw { .. } => "screw",
        }
    }

    /// Axis-aligned bounding box of the feature's footprint on the plate, `(min, max)`, mm.
    pub fn footprint(&self) -> (Point, Point) {
        let poly_box = |path: &[Point], half: f64| {
            let mut lo = [f64::INFINITY; 2];
            let mut hi = [f64::NEG_INFINITY; 2];
            for p in path {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k] - half);
                    hi[k] = hi[k].max(p[k] + half);
                }
            }
            (lo, hi)
        };
        match self {
            Feature::Crack {
                path,
                width_mm,
                edge_radius_mm,
                ..
            } => poly_box(path, width_mm / 2.0 + edge_radius_mm.max(0.0)),
            Feature::Decoy { path, width_mm, .. } => poly_box(path, width_mm / 2.0),
            Feature::Bump {
                centre, radius_mm, ..
            } => poly_box(&[*centre], *radius_mm),
            Feature::Screw {
                centre,
                head_diameter_mm,
                ..
            } => poly_box(&[*centre], head_diameter_mm / 2.0),
            Feature::Wavy { min, max, .. } => (*min, *max),
        }
    }

    /// Height contribution at `p`, mm (added to the plate's 0).
    pub fn height_mm(&self, p: Point) -> f64 {
        match self {
            Feature::Crack {
                path,
                width_mm,
                depth_mm,
                edge_radius_mm,
                wall_angle_deg,
            } => {
                // Written so that NaN counts as no groove (a scene file's validation refuses
                // it first; a surface built in code gets a flat plate, never NaN heights).
                if !(*width_mm > 0.0 && *depth_mm > 0.0) {
                    return 0.0;
                }
                let d = distance_to_polyline(path, p);
                if d >= width_mm / 2.0 + edge_radius_mm.max(0.0) {
                    return 0.0;
                }
                groove_height(
                    d,
                    width_mm / 2.0,
                    *depth_mm,
                    *edge_radius_mm,
                    *wall_angle_deg,
                )
            }
            Feature::Bump {
                centre,
                radius_mm,
                height_mm,
            } => {
                let r = dist(*centre, p);
                if r >= *radius_mm || *radius_mm <= 0.0 {
                    0.0
                } else {
                    height_mm * 0.5 * (1.0 + (std::f64::consts::PI * r / radius_mm).cos())
                }
            }
            Feature::Wavy {
                min,
                max,
                amplitude_mm,
                period_mm,
                direction_deg,
            } => {
                if p[0] < min[0] || p[0] > max[0] || p[1] < min[1] || p[1] > max[1] {
                    return 0.0;
                }
                if *period_mm <= 0.0 {
                    return 0.0;
                }
                let a = direction_deg.to_radians();
                let s = (p[0] - min[0]) * a.cos() + (p[1] - min[1]) * a.sin();
                // Starts at 0 height with the corrugation rising: no step at the patch's edge.
                amplitude_mm * (2.0 * std::f64::consts::PI * s / period_mm).sin()
            }
            Feature::Decoy { .. } => 0.0,
            Feature::Screw {
                centre,
                head_diameter_mm,
                height_mm,
            } => {
                let r = dist(*centre, p);
                let rad = head_diameter_mm / 2.0;
                if r >= rad {
                    0.0
                } else {
                    // A domed head: full height in the middle, 60 % at the rim.
                    height_mm * (1.0 - 0.4 * (r / rad).powi(2))
                }
            }
        }
    }

    /// Reflectivity factor at `p` (1 where the feature does not change the surface's colour).
    pub fn reflectivity(&self, p: Point) -> f64 {
        match self {
            Feature::Decoy {
                path,
                width_mm,
                reflectivity,
            } if distance_to_polyline(path, p) <= width_mm / 2.0 => *reflectivity,
            _ => 1.0,
        }
    }
}

/// Height of a groove of half-width `half` at the top, depth `depth`, walls at `angle_deg`
/// from the plate, at distance `d` from its centre line. The top edges are rounded by a
/// parabolic fillet over `±r` around the edge (tangent to the top face and to the wall), so the
/// profile's slope never exceeds the wall's.
fn groove_height(d: f64, half: f64, depth: f64, r: f64, angle_deg: f64) -> f64 {
    let slope = angle_deg.clamp(1.0, 90.0).to_radians().tan();
    let wall = |d: f64| -((half - d) * slope).clamp(0.0, depth);
    // A fillet no wider than half the wall's horizontal run or the half-width.
    let b = r.clamp(0.0, (0.5 * depth / slope).min(half));
    if b > 0.0 && (d - half).abs() < b {
        return -slope * (half + b - d).powi(2) / (4.0 * b);
    }
    wall(d)
}

fn dist(a: Point, b: Point) -> f64 {
    crackbot_imaging::geometry::distance(a, b)
}

pub use crackbot_imaging::geometry::distance_to_polyline;

/// A plate with its features: the finger's world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Surface {
    /// Size of the plate, mm (`[x, y]`).
    pub size_mm: [f64; 2],
    /// The features, in any order; heights add up and reflectivities multiply.
    pub features: Vec<Feature>,
}

impl Surface {
    /// A bare plate.
    pub fn flat(size_mm: [f64; 2]) -> Self {
        Surface {
            size_mm,
            features: Vec::new(),
        }
    }

    /// Height at `p`, mm.
    pub fn height_mm(&self, p: Point) -> f64 {
        self.features.iter().map(|f| f.height_mm(p)).sum()
    }

    /// Reflectivity factor at `p` (1 = bare plate).
    pub fn reflectivity(&self, p: Point) -> f64 {
        self.features.iter().map(|f| f.reflectivity(p)).product()
    }

    /// The height and reflectivity along the segment from `a` to `b`, sampled every `step_mm`.
    pub fn profile(&self, a: Point, b: Point, step_mm: f64) -> Profile {
        let len = dist(a, b);
        let n = ((len / step_mm.max(1e-6)).ceil() as usize).max(1) + 1;
        let step = len / (n - 1) as f64;
        let dir = if len > 0.0 {
            [(b[0] - a[0]) / len, (b[1] - a[1]) / len]
        } else {
            [1.0, 0.0]
        };
        let mut height = Vec::with_capacity(n);
        let mut reflectivity = Vec::with_capacity(n);
        for k in 0..n {
            let s = k as f64 * step;
            let p = [a[0] + s * dir[0], a[1] + s * dir[1]];
            height.push(self.height_mm(p));
            reflectivity.push(self.reflectivity(p));
        }
        Profile {
            step_mm: step.max(1e-9),
            height,
            reflectivity,
        }
    }
}

/// A surface sampled along a line: what the finger meets on one slide.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// Spacing of the samples, mm.
    pub step_mm: f64,
    /// Height at each sample, mm.
    pub height: Vec<f64>,
    /// Reflectivity at each sample.
    pub reflectivity: Vec<f64>,
}

impl Profile {
    /// Length of the line, mm.
    pub fn length_mm(&self) -> f64 {
        self.step_mm * (self.height.len().saturating_sub(1)) as f64
    }

    /// Linear interpolation of `values`, tabulated every `step`, at `s` (same unit as `step`),
    /// clamped at the ends; 0 for an empty table.
    #[inline]
    pub fn sample(values: &[f64], step: f64, s: f64) -> f64 {
        let Some(last) = values.len().checked_sub(1) else {
            return 0.0;
        };
        if last == 0 {
            return values[0];
        }
        let u = (s / step).clamp(0.0, last as f64);
        let k = (u as usize).min(last - 1);
        let f = u - k as f64;
        values[k] + (values[k + 1] - values[k]) * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crack(width: f64, depth: f64) -> Feature {
        Feature::Crack {
            path: vec![[50.0, 0.0], [50.0, 100.0]],
            width_mm: width,
            depth_mm: depth,
            edge_radius_mm: 0.2,
            wall_angle_deg: 60.0,
        }
    }

    #[test]
    fn crack_is_a_flat_bottomed_groove_with_rounded_edges() {
        let s = Surface {
            size_mm: [200.0, 100.0],
            features: vec![crack(4.0, 3.0)],
        };
        assert_eq!(s.height_mm([50.0, 40.0]), -3.0);
        assert_eq!(s.height_mm([52.5, 40.0]), 0.0);
        let edge = s.height_mm([51.95, 40.0]);
        assert!(edge < 0.0 && edge > -0.2, "{edge}");
        // The fillet is tangent to the top face: nothing beyond the edge plus its radius.
        assert_eq!(s.height_mm([52.21, 40.0]), 0.0);
        // Zero-width cracks are invisible to touch.
        let closed = Surface {
            size_mm: [200.0, 100.0],
            features: vec![crack(0.0, 3.0)],
        };
        assert_eq!(closed.height_mm([50.0, 40.0]), 0.0);
    }

    #[test]
    fn a_crack_with_nan_dimensions_leaves_the_plate_flat_not_nan() {
        for (width, depth) in [(4.0, f64::NAN), (f64::NAN, 3.0), (4.0, -1.0)] {
            let s = Surface {
                size_mm: [200.0, 100.0],
                features: vec![crack(width, depth)],
            };
            for x in [49.0, 50.0, 51.9, 60.0] {
                assert_eq!(
                    s.height_mm([x, 40.0]),
                    0.0,
                    "width {width}, depth {depth}, x {x}"
                );
            }
        }
    }

    #[test]
    fn decoy_is_flat_and_dark() {
        let s = Surface {
            size_mm: [200.0, 100.0],
            features: vec![Feature::Decoy {
                path: vec![[10.0, 10.0], [90.0, 10.0]],
                width_mm: 2.0,
                reflectivity: 0.3,
            }],
        };
        assert_eq!(s.height_mm([50.0, 10.0]), 0.0);
        assert_eq!(s.reflectivity([50.0, 10.0]), 0.3);
        assert_eq!(s.reflectivity([50.0, 12.0]), 1.0);
    }

    #[test]
    fn bump_and_wave_have_the_given_heights() {
        let bump = Feature::Bump {
            centre: [20.0, 20.0],
            radius_mm: 5.0,
            height_mm: 2.0,
        };
        assert!((bump.height_mm([20.0, 20.0]) - 2.0).abs() < 1e-12);
        assert_eq!(bump.height_mm([26.0, 20.0]), 0.0);
        let wave = Feature::Wavy {
            min: [0.0, 0.0],
            max: [50.0, 50.0],
            amplitude_mm: 1.0,
            period_mm: 5.0,
            direction_deg: 0.0,
        };
        assert!((wave.height_mm([1.25, 3.0]) - 1.0).abs() < 1e-12);
        assert!((wave.height_mm([3.75, 3.0]) + 1.0).abs() < 1e-12);
        assert_eq!(wave.height_mm([60.0, 3.0]), 0.0);
    }

    #[test]
    fn profile_samples_the_line() {
        let s = Surface {
            size_mm: [200.0, 100.0],
            features: vec![crack(4.0, 3.0)],
        };
        let p = s.profile([40.0, 50.0], [60.0, 50.0], 0.01);
        assert!((p.length_mm() - 20.0).abs() < 1e-9);
        assert_eq!(Profile::sample(&p.height, p.step_mm, 10.0), -3.0);
        assert_eq!(Profile::sample(&p.height, p.step_mm, 0.0), 0.0);
    }
}
