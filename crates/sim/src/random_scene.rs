//! Random scenes for detector data: a plate of a random material with random cracks, printed
//! decoys, screws, bumps and wavy patches, seen by a camera placed at random above it.
//!
//! [`random_scene`] draws one [`Scene`] from [`RandomSceneParams`], deterministic from its seed
//! (ChaCha8). Crack and decoy paths are random walks of a few straight segments that stay a margin
//! inside the plate; crack widths are log-uniform (as many thin cracks as wide ones); the camera
//! looks roughly down at a point near the plate's centre from a height at which the plate roughly
//! fills the image, slightly oblique and rolled. Features may overlap. Every scene returned passes
//! [`Scene::validate`].

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::camera::CameraSpec;
use crate::scene::{ManipulatorSpec, Material, PlateSpec};
use crate::surface::{Feature, Point};
use crate::{list, Scene, SensorParams, SimError};

/// The plate materials drawn from: name, sRGB colour (before a small random tint) and
/// reflectivity.
const MATERIALS: [(&str, [u8; 3], f64); 6] = [
    ("PLA light grey", [178, 176, 170], 1.0),
    ("PLA white", [214, 212, 206], 1.0),
    ("concrete grey", [146, 144, 138], 0.8),
    ("sandstone beige", [196, 181, 150], 0.9),
    ("aluminium", [166, 169, 174], 0.9),
    ("dark painted steel", [68, 70, 75], 0.5),
];

/// Radius of the cracks' rounded top edges, mm.
const EDGE_RADIUS_MM: f64 = 0.2;

/// How random scenes are drawn. Ranges `[lo, hi]` are inclusive; counts are drawn uniformly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RandomSceneParams {
    /// Plate size, mm `[x, y]`.
    pub plate_size_mm: [f64; 2],
    /// How far inside the plate's edges every crack and decoy point stays, mm.
    pub margin_mm: f64,
    /// Number of cracks.
    pub cracks: [u32; 2],
    /// Segments of a crack's or decoy's path.
    pub segments: [u32; 2],
    /// Length of a crack's or decoy's path, mm.
    pub length_mm: [f64; 2],
    /// Crack width, mm (log-uniform).
    pub crack_width_mm: [f64; 2],
    /// Crack depth, mm.
    pub crack_depth_mm: [f64; 2],
    /// Number of printed decoys.
    pub decoys: [u32; 2],
    /// Decoy width, mm (log-uniform).
    pub decoy_width_mm: [f64; 2],
    /// Decoy ink reflectivity (0 black .. 1 invisible).
    pub decoy_reflectivity: [f64; 2],
    /// Number of screws.
    pub screws: [u32; 2],
    /// Screw head diameter, mm.
    pub screw_diameter_mm: [f64; 2],
    /// Number of bumps.
    pub bumps: [u32; 2],
    /// Number of wavy patches.
    pub wavy: [u32; 2],
    /// Image size, pixels `[width, height]`.
    pub resolution: [u32; 2],
    /// Focal length, pixels (the same in x and y).
    pub focal_px: [f64; 2],
    /// Camera height above the plate, mm (raised where needed so the plate roughly fits).
    pub camera_height_mm: [f64; 2],
    /// The look-at point is the plate's centre moved by up to this much in x and y, mm.
    pub look_at_jitter_mm: f64,
    /// The camera sits above the look-at point moved by up to this much in x and y, mm.
    pub camera_offset_mm: f64,
    /// Roll about the optical axis is up to ± this, degrees.
    pub roll_deg: f64,
    /// Sensor noise, grey levels.
    pub noise_sigma: [f64; 2],
    /// Lighting variation between frames.
    pub lighting_variation: [f64; 2],
}

impl Default for RandomSceneParams {
    fn default() -> Self {
        RandomSceneParams {
            plate_size_mm: [200.0, 100.0],
            margin_mm: 5.0,
            cracks: [1, 5],
            segments: [2, 6],
            length_mm: [15.0, 90.0],
            crack_width_mm: [0.5, 10.0],
            crack_depth_mm: [0.5, 4.0],
            decoys: [0, 2],
            decoy_width_mm: [0.5, 4.0],
            decoy_reflectivity: [0.2, 0.6],
            screws: [0, 3],
            screw_diameter_mm: [5.0, 10.0],
            bumps: [0, 1],
            wavy: [0, 1],
            resolution: [640, 480],
            focal_px: [650.0, 750.0],
            camera_height_mm: [220.0, 320.0],
            look_at_jitter_mm: 15.0,
            camera_offset_mm: 20.0,
            roll_deg: 10.0,
            noise_sigma: [1.0, 4.0],
            lighting_variation: [0.05, 0.3],
        }
    }
}

/// `lo ≤ hi`, both finite, and `lo > 0` when `positive` (else `lo ≥ 0`).
fn check_range(name: &str, r: [f64; 2], positive: bool) -> Result<(), SimError> {
    let [lo, hi] = r;
    let lo_ok = if positive { lo > 0.0 } else { lo >= 0.0 };
    if !(lo.is_finite() && hi.is_finite() && lo_ok && lo <= hi) {
        let bound = if positive { "0 <" } else { "0 ≤" };
        return Err(SimError::setting(
            name,
            list(&r),
            format!("a range [lo, hi] with {bound} lo ≤ hi"),
        ));
    }
    Ok(())
}

fn check_count(name: &str, r: [u32; 2]) -> Result<(), SimError> {
    if r[0] > r[1] || r[1] > 100 {
        return Err(SimError::setting(
            name,
            list(&r),
            "a range [lo, hi] with lo ≤ hi ≤ 100",
        ));
    }
    Ok(())
}

fn check_non_negative(name: &str, v: f64) -> Result<(), SimError> {
    if !(v.is_finite() && v >= 0.0) {
        return Err(SimError::setting(name, v, "≥ 0"));
    }
    Ok(())
}

impl RandomSceneParams {
    /// Checks every range (finite, `lo ≤ hi`, positive where it must be), that the plate leaves
    /// room inside its margin, and that the camera is above the plate; names the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let [sx, sy] = self.plate_size_mm;
        if !(sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0) {
            return Err(SimError::setting(
                "plate_size_mm",
                list(&self.plate_size_mm),
                "> 0 mm in x and y",
            ));
        }
        check_non_negative("margin_mm", self.margin_mm)?;
        if 2.0 * self.margin_mm >= sx.min(sy) {
            return Err(SimError::setting(
                "margin_mm",
                self.margin_mm,
                format!(
                    "below {} mm, half the smaller side of the {sx} × {sy} mm plate (this one \
                     leaves no room)",
                    sx.min(sy) / 2.0
                ),
            ));
        }
        for (name, r) in [
            ("cracks", self.cracks),
            ("decoys", self.decoys),
            ("screws", self.screws),
            ("bumps", self.bumps),
            ("wavy", self.wavy),
        ] {
            check_count(name, r)?;
        }
        check_count("segments", self.segments)?;
        if self.segments[0] == 0 {
            return Err(SimError::setting(
                "segments",
                list(&self.segments),
                "a range [lo, hi] with 1 ≤ lo ≤ hi",
            ));
        }
        for (name, r, positive) in [
            ("length_mm", self.length_mm, true),
            ("crack_width_mm", self.crack_width_mm, true),
            ("crack_depth_mm", self.crack_depth_mm, true),
            ("decoy_width_mm", self.decoy_width_mm, true),
            ("decoy_reflectivity", self.decoy_reflectivity, false),
            ("screw_diameter_mm", self.screw_diameter_mm, true),
            ("focal_px", self.focal_px, true),
            ("camera_height_mm", self.camera_height_mm, true),
            ("noise_sigma", self.noise_sigma, false),
            ("lighting_variation", self.lighting_variation, false),
        ] {
            check_range(name, r, positive)?;
        }
        if self.decoy_reflectivity[1] > 1.0 {
            return Err(SimError::setting(
                "decoy_reflectivity",
                list(&self.decoy_reflectivity),
                "within [0, 1]",
            ));
        }
        if self.lighting_variation[1] > 1.0 {
            return Err(SimError::setting(
                "lighting_variation",
                list(&self.lighting_variation),
                "within [0, 1]",
            ));
        }
        if self.screw_diameter_mm[1] >= sx.min(sy) {
            return Err(SimError::setting(
                "screw_diameter_mm",
                list(&self.screw_diameter_mm),
                format!(
                    "below {} mm, the smaller side of the {sx} × {sy} mm plate (a screw must fit \
                     on it)",
                    sx.min(sy)
                ),
            ));
        }
        if self.resolution[0] == 0 || self.resolution[1] == 0 {
            return Err(SimError::setting(
                "resolution",
                list(&self.resolution),
                "> 0 in width and height",
            ));
        }
        for (name, v) in [
            ("look_at_jitter_mm", self.look_at_jitter_mm),
            ("camera_offset_mm", self.camera_offset_mm),
            ("roll_deg", self.roll_deg),
        ] {
            check_non_negative(name, v)?;
        }
        // Keep the camera looking at the plate and well above it, not edge-on.
        if self.camera_offset_mm > 0.5 * self.camera_height_mm[0] {
            return Err(SimError::setting(
                "camera_offset_mm",
                self.camera_offset_mm,
                format!(
                    "at most {} mm, half the lowest camera_height_mm {} (further off, the view is \
                     too oblique)",
                    0.5 * self.camera_height_mm[0],
                    self.camera_height_mm[0]
                ),
            ));
        }
        Ok(())
    }
}

/// Uniform in `[lo, hi]` (exactly `lo` when the range is empty).
fn uniform(rng: &mut ChaCha8Rng, r: [f64; 2]) -> f64 {
    if r[1] > r[0] {
        rng.random_range(r[0]..=r[1])
    } else {
        r[0]
    }
}

/// Log-uniform in `[lo, hi]`, `lo > 0`.
fn log_uniform(rng: &mut ChaCha8Rng, r: [f64; 2]) -> f64 {
    uniform(rng, [r[0].ln(), r[1].ln()]).exp().clamp(r[0], r[1])
}

fn count(rng: &mut ChaCha8Rng, r: [u32; 2]) -> u32 {
    rng.random_range(r[0]..=r[1])
}

/// A random walk of straight segments, all points at least `margin_mm` (and at least `half`,
/// the feature's half width, so its footprint stays on the plate) inside the plate.
fn random_path(rng: &mut ChaCha8Rng, p: &RandomSceneParams, half: f64) -> Vec<Point> {
    let [sx, sy] = p.plate_size_mm;
    let m = p.margin_mm.max(half).min(0.49 * sx.min(sy));
    let inside = |q: Point| q[0] >= m && q[0] <= sx - m && q[1] >= m && q[1] <= sy - m;
    let n = count(rng, p.segments) as usize;
    let mut length = uniform(rng, p.length_mm);
    let mut last = Vec::new();
    for attempt in 0..64 {
        // Long paths that do not fit after many tries are shortened.
        if attempt > 0 && attempt % 16 == 0 {
            length *= 0.7;
        }
        let start = [rng.random_range(m..=sx - m), rng.random_range(m..=sy - m)];
        let mut heading: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        let mut path = vec![start];
        let mut q = start;
        for _ in 0..n {
            heading += rng.random_range(-0.6..=0.6);
            let seg = length / n as f64 * rng.random_range(0.7..=1.3);
            q = [q[0] + seg * heading.cos(), q[1] + seg * heading.sin()];
            path.push(q);
        }
        if path.iter().all(|&q| inside(q)) {
            return path;
        }
        last = path;
    }
    // Still outside: clamp into the margin (may merge points; dedupe the repeats).
    let mut path: Vec<Point> = Vec::new();
    for q in last {
        let q = [q[0].clamp(m, sx - m), q[1].clamp(m, sy - m)];
        if path
            .last()
            .is_none_or(|l: &Point| (l[0] - q[0]).hypot(l[1] - q[1]) > 1e-6)
        {
            path.push(q);
        }
    }
    if path.len() < 2 {
        let c = [sx / 2.0, sy / 2.0];
        path = vec![[c[0] - 10.0, c[1]], [c[0] + 10.0, c[1]]];
    }
    path
}

/// A point uniformly inside the plate, at least `inset` from its edges.
fn point_inside(rng: &mut ChaCha8Rng, size: [f64; 2], inset: f64) -> Point {
    let ix = inset.min(size[0] / 2.0);
    let iy = inset.min(size[1] / 2.0);
    [
        rng.random_range(ix..=size[0] - ix),
        rng.random_range(iy..=size[1] - iy),
    ]
}

/// A random scene drawn from `params`, deterministic from `seed`; it passes
/// [`Scene::validate`]. Fails when `params` does not validate.
pub fn random_scene(params: &RandomSceneParams, seed: u64) -> Result<Scene, SimError> {
    params.validate()?;
    let p = params;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let size = p.plate_size_mm;

    let (name, colour, reflectivity) = MATERIALS[rng.random_range(0..MATERIALS.len())];
    let colour =
        colour.map(|c| (f64::from(c) + rng.random_range(-8.0..=8.0)).clamp(0.0, 255.0) as u8);
    let material = Material {
        name: name.to_string(),
        colour,
        reflectivity,
    };

    let mut features = Vec::new();
    for _ in 0..count(&mut rng, p.cracks) {
        let width_mm = log_uniform(&mut rng, p.crack_width_mm);
        let path = random_path(&mut rng, p, width_mm / 2.0 + EDGE_RADIUS_MM + 0.01);
        let depth_mm = uniform(&mut rng, p.crack_depth_mm);
        let wall_angle_deg = rng.random_range(45.0..=90.0);
        features.push(Feature::Crack {
            path,
            width_mm,
            depth_mm,
            edge_radius_mm: EDGE_RADIUS_MM,
            wall_angle_deg,
        });
    }
    for _ in 0..count(&mut rng, p.decoys) {
        let width_mm = log_uniform(&mut rng, p.decoy_width_mm);
        let path = random_path(&mut rng, p, width_mm / 2.0 + 0.01);
        features.push(Feature::Decoy {
            path,
            width_mm,
            reflectivity: uniform(&mut rng, p.decoy_reflectivity),
        });
    }
    for _ in 0..count(&mut rng, p.screws) {
        let head_diameter_mm = uniform(&mut rng, p.screw_diameter_mm);
        let centre = point_inside(&mut rng, size, head_diameter_mm / 2.0 + 1.0);
        features.push(Feature::Screw {
            centre,
            head_diameter_mm,
            height_mm: rng.random_range(2.0..=4.0),
        });
    }
    for _ in 0..count(&mut rng, p.bumps) {
        let radius_mm: f64 = rng.random_range(6.0..=15.0);
        let centre = point_inside(&mut rng, size, radius_mm);
        features.push(Feature::Bump {
            centre,
            radius_mm,
            height_mm: rng.random_range(0.5..=3.0),
        });
    }
    for _ in 0..count(&mut rng, p.wavy) {
        let half = [
            rng.random_range(10.0..=25.0f64).min(size[0] / 2.0),
            rng.random_range(10.0..=20.0f64).min(size[1] / 2.0),
        ];
        let c = point_inside(&mut rng, size, half[0].max(half[1]));
        features.push(Feature::Wavy {
            min: [(c[0] - half[0]).max(0.0), (c[1] - half[1]).max(0.0)],
            max: [(c[0] + half[0]).min(size[0]), (c[1] + half[1]).min(size[1])],
            amplitude_mm: rng.random_range(0.3..=1.5),
            period_mm: rng.random_range(3.0..=8.0),
            direction_deg: rng.random_range(0.0..180.0),
        });
    }

    let focal = uniform(&mut rng, p.focal_px);
    // Height at which the plate just fits the image, looking straight down.
    let [w, h] = p.resolution.map(f64::from);
    let fit = focal * (size[0] / w).max(size[1] / h);
    let [zlo, zhi] = p.camera_height_mm;
    let z = uniform(&mut rng, [fit.clamp(zlo, zhi), zhi]);
    let j = p.look_at_jitter_mm;
    let look_at = [
        (size[0] / 2.0 + uniform(&mut rng, [-j, j])).clamp(0.0, size[0]),
        (size[1] / 2.0 + uniform(&mut rng, [-j, j])).clamp(0.0, size[1]),
    ];
    let o = p.camera_offset_mm;
    let position = [
        look_at[0] + uniform(&mut rng, [-o, o]),
        look_at[1] + uniform(&mut rng, [-o, o]),
        z,
    ];
    let camera = CameraSpec {
        resolution: p.resolution,
        focal_px: [focal, focal],
        principal_px: None,
        position_mm: position,
        look_at_mm: look_at,
        roll_deg: uniform(&mut rng, [-p.roll_deg, p.roll_deg]),
        noise_sigma: uniform(&mut rng, p.noise_sigma),
        lighting_variation: uniform(&mut rng, p.lighting_variation),
        distortion: [0.0; 5],
    };

    let manipulator = ManipulatorSpec {
        workspace_min_mm: [0.0, 0.0, -5.0],
        workspace_max_mm: [size[0], size[1], 150.0],
        ..ManipulatorSpec::default()
    };
    let scene = Scene {
        name: format!("random scene {seed}: {name}"),
        plate: PlateSpec {
            size_mm: size,
            material,
        },
        features,
        camera: Some(camera),
        manipulator,
        sensor: SensorParams::default(),
    };
    scene.validate()?;
    Ok(scene)
}

/// The scenes of the detection trials: real crack appearance 0.5–5 mm wide, 1–3 cracks, 1–2
/// printed decoys, screws and bumps, random camera pose.
pub fn trial_params() -> RandomSceneParams {
    RandomSceneParams {
        cracks: [1, 3],
        crack_width_mm: [0.5, 5.0],
        decoys: [1, 2],
        screws: [0, 2],
        bumps: [0, 1],
        wavy: [0, 0],
        ..RandomSceneParams::default()
    }
}

/// `scene` with every crack given the cross-section of the authors' printed plates (depth and wall
/// angle as fitted to their recordings, `crate::plates::calibrated_samples`): the
/// profile the deployed tactile models know. Random scenes otherwise draw V-grooves whose depth
/// follows their width, which the models never felt (`crates/research/EXPERIMENTS.md`, "The same
/// scenes, cracks with the authors' printed profile").
pub fn as_printed(scene: &Scene) -> Scene {
    let s = crate::plates::calibrated_samples();
    let mut out = scene.clone();
    for f in &mut out.features {
        if let Feature::Crack {
            depth_mm,
            wall_angle_deg,
            ..
        } = f
        {
            *depth_mm = s.crack_depth_mm;
            *wall_angle_deg = s.crack_wall_angle_deg;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inside(p: &RandomSceneParams, path: &[Point]) -> bool {
        let m = p.margin_mm - 1e-9;
        let [sx, sy] = p.plate_size_mm;
        path.iter()
            .all(|q| q[0] >= m && q[0] <= sx - m && q[1] >= m && q[1] <= sy - m)
    }

    #[test]
    fn two_hundred_seeds_validate_and_keep_paths_inside() {
        let p = RandomSceneParams::default();
        for seed in 0..200 {
            let scene = random_scene(&p, seed).unwrap();
            scene.validate().unwrap();
            let cracks = scene
                .features
                .iter()
                .filter(|f| matches!(f, Feature::Crack { .. }))
                .count();
            assert!((1..=5).contains(&cracks), "seed {seed}: {cracks} cracks");
            for f in &scene.features {
                match f {
                    Feature::Crack { path, width_mm, .. } => {
                        assert!(inside(&p, path), "seed {seed}: {path:?}");
                        assert!((0.5..=10.0).contains(width_mm));
                        assert!(path.len() >= 2);
                    }
                    Feature::Decoy {
                        path,
                        width_mm,
                        reflectivity,
                    } => {
                        assert!(inside(&p, path), "seed {seed}: {path:?}");
                        assert!((0.5..=4.0).contains(width_mm));
                        assert!((0.2..=0.6).contains(reflectivity));
                    }
                    _ => {}
                }
            }
            let cam = scene.camera.as_ref().unwrap();
            assert_eq!(cam.resolution, [640, 480]);
            assert!((220.0..=320.0).contains(&cam.position_mm[2]));
        }
    }

    #[test]
    fn same_seed_same_scene_other_seed_other_scene() {
        let p = RandomSceneParams::default();
        assert_eq!(random_scene(&p, 7).unwrap(), random_scene(&p, 7).unwrap());
        assert_ne!(random_scene(&p, 7).unwrap(), random_scene(&p, 8).unwrap());
    }

    #[test]
    fn scenes_vary() {
        let p = RandomSceneParams::default();
        let mut widths = Vec::new();
        let mut counts = std::collections::BTreeSet::new();
        let mut materials = std::collections::BTreeSet::new();
        for seed in 0..200 {
            let scene = random_scene(&p, seed).unwrap();
            let mut n = 0;
            for f in &scene.features {
                if let Feature::Crack { width_mm, .. } = f {
                    widths.push(*width_mm);
                    n += 1;
                }
            }
            counts.insert(n);
            materials.insert(scene.plate.material.name.clone());
        }
        let lo = widths.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = widths.iter().copied().fold(0.0, f64::max);
        assert!(lo < 0.7 && hi > 8.0, "widths span [{lo}, {hi}]");
        // Log-uniform: about as many cracks under √(0.5·10) ≈ 2.2 mm as over it.
        let thin = widths.iter().filter(|&&w| w < 5f64.sqrt()).count() as f64;
        let share = thin / widths.len() as f64;
        assert!((0.35..0.65).contains(&share), "{share}");
        assert_eq!(counts.len(), 5, "{counts:?}");
        assert!(materials.len() >= 4, "{materials:?}");
    }

    #[test]
    fn bad_parameters_are_clear_errors() {
        let p = RandomSceneParams {
            crack_width_mm: [2.0, 1.0],
            ..RandomSceneParams::default()
        };
        let err = random_scene(&p, 0).unwrap_err();
        assert!(
            matches!(
                &err,
                SimError::Setting { field, value, allowed }
                    if field == "crack_width_mm"
                        && value == "[2, 1]"
                        && allowed == "a range [lo, hi] with 0 < lo ≤ hi"
            ),
            "{err:?}"
        );
        assert_eq!(
            err.to_string(),
            "invalid setting crack_width_mm = [2, 1]: it must be a range [lo, hi] with 0 < lo ≤ hi"
        );
        let field_of = |p: &RandomSceneParams| match p.validate() {
            Err(SimError::Setting { field, .. }) => field,
            other => panic!("expected SimError::Setting, got {other:?}"),
        };
        let p = RandomSceneParams {
            margin_mm: 60.0,
            ..RandomSceneParams::default()
        };
        assert_eq!(field_of(&p), "margin_mm");
        let p = RandomSceneParams {
            cracks: [3, 1],
            ..RandomSceneParams::default()
        };
        assert_eq!(field_of(&p), "cracks");
        let p = RandomSceneParams {
            decoy_reflectivity: [0.2, 1.5],
            ..RandomSceneParams::default()
        };
        assert_eq!(field_of(&p), "decoy_reflectivity");
        let p = RandomSceneParams {
            noise_sigma: [-1.0, 2.0],
            ..RandomSceneParams::default()
        };
        assert_eq!(field_of(&p), "noise_sigma");
    }
}
