//! Scenes: a plate with features, the camera looking at it, the manipulator and the sensor,
//! read from TOML files (kept in `crates/sim/scenes/`) and validated.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::camera::Camera;
pub use crate::camera::CameraSpec;
use crate::surface::{Feature, Point, Surface};
use crate::{list, SensorParams, SimError};

/// The text of the built-in default scene (`crates/sim/scenes/default.toml`).
pub const DEFAULT_SCENE_TOML: &str = include_str!("../scenes/default.toml");

/// The steepest view of the plate a camera may have: the angle between its optical axis and the
/// plate's downward normal, degrees (beyond it the camera looks at the plate edge-on).
pub const MAX_CAMERA_TILT_DEG: f64 = 75.0;

/// The plate's material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Name, for people (e.g. "PLA", "concrete").
    #[serde(default = "default_material_name")]
    pub name: String,
    /// Colour seen by the camera, sRGB.
    #[serde(default = "default_colour")]
    pub colour: [u8; 3],
    /// Reflectivity seen by the proximity fibre relative to the calibration plate (white PLA = 1).
    #[serde(default = "default_reflectivity")]
    pub reflectivity: f64,
}

fn default_material_name() -> String {
    "PLA".to_string()
}
fn default_colour() -> [u8; 3] {
    [178, 176, 170]
}
fn default_reflectivity() -> f64 {
    1.0
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: default_material_name(),
            colour: default_colour(),
            reflectivity: default_reflectivity(),
        }
    }
}

/// The plate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlateSpec {
    /// Size, mm `[x, y]` (the paper: 200 × 100 mm).
    #[serde(default = "default_plate_size")]
    pub size_mm: [f64; 2],
    /// Material.
    #[serde(default)]
    pub material: Material,
}

fn default_plate_size() -> [f64; 2] {
    [200.0, 100.0]
}

impl Default for PlateSpec {
    fn default() -> Self {
        PlateSpec {
            size_mm: default_plate_size(),
            material: Material::default(),
        }
    }
}

/// The manipulator that carries the finger.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManipulatorSpec {
    /// Reachable box in the plate's frame: lower corner, mm `[x, y, z]`.
    #[serde(default = "default_workspace_min")]
    pub workspace_min_mm: [f64; 3],
    /// Reachable box: upper corner, mm `[x, y, z]`.
    #[serde(default = "default_workspace_max")]
    pub workspace_max_mm: [f64; 3],
    /// Speed of a tactile slide, mm/s (the paper: about 3.89 mm/s).
    #[serde(default = "default_slide_speed")]
    pub slide_speed_mm_s: f64,
    /// Length of a slide stroke, mm (the paper: about 16 mm).
    #[serde(default = "default_stroke")]
    pub stroke_mm: f64,
    /// Speed of moves between slides (finger lifted), mm/s.
    #[serde(default = "default_travel_speed")]
    pub travel_speed_mm_s: f64,
}

fn default_workspace_min() -> [f64; 3] {
    [0.0, 0.0, -5.0]
}
fn default_workspace_max() -> [f64; 3] {
    [200.0, 100.0, 150.0]
}
fn default_slide_speed() -> f64 {
    3.89
}
fn default_stroke() -> f64 {
    16.0
}
fn default_travel_speed() -> f64 {
    50.0
}

impl Default for ManipulatorSpec {
    fn default() -> Self {
        ManipulatorSpec {
            workspace_min_mm: default_workspace_min(),
            workspace_max_mm: default_workspace_max(),
            slide_speed_mm_s: default_slide_speed(),
            stroke_mm: default_stroke(),
            travel_speed_mm_s: default_travel_speed(),
        }
    }
}

/// A summary of a scene ([`Scene::summary`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneSummary {
    /// The scene's name (may be empty).
    pub name: String,
    /// The plate's size, mm.
    pub plate_size_mm: [f64; 2],
    /// The plate's material.
    pub material: String,
    /// Every feature, in scene order.
    pub features: Vec<FeatureSummary>,
    /// The camera, if any.
    pub camera: Option<CameraSummary>,
}

/// One feature of a [`SceneSummary`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FeatureSummary {
    /// Index in the scene's `features`.
    pub index: usize,
    /// Its kind (`crack`, `bump`, …).
    pub kind: &'static str,
    /// Lower corner of its footprint on the plate, mm.
    pub min_mm: Point,
    /// Upper corner of its footprint, mm.
    pub max_mm: Point,
}

/// The camera of a [`SceneSummary`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CameraSummary {
    /// Image size, pixels.
    pub resolution: [u32; 2],
    /// Optical centre, mm.
    pub position_mm: [f64; 3],
    /// Point looked at on the plate, mm.
    pub look_at_mm: [f64; 2],
}

/// A whole scene, as read from a TOML file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name, for people.
    #[serde(default)]
    pub name: String,
    /// The plate.
    #[serde(default)]
    pub plate: PlateSpec,
    /// Features on the plate (`[[features]]` tables with a `kind`).
    #[serde(default)]
    pub features: Vec<Feature>,
    /// The camera, if the scene has one: a scene without one never renders images.
    #[serde(default)]
    pub camera: Option<CameraSpec>,
    /// The manipulator.
    #[serde(default)]
    pub manipulator: ManipulatorSpec,
    /// The sensor's mechanics, optics and electronics.
    #[serde(default)]
    pub sensor: SensorParams,
}

impl Scene {
    /// Parses a scene from TOML text and validates it; `source` names the text in errors (a
    /// path, or e.g. `"<builtin>"`).
    pub fn from_toml_str(text: &str, source: &str) -> Result<Scene, SimError> {
        Scene::checked(toml::from_str(text).map_err(|e| e.to_string()), source)
    }

    /// A parsed scene, validated; errors name `source`.
    fn checked(parsed: Result<Scene, String>, source: &str) -> Result<Scene, SimError> {
        let scene = parsed.map_err(|message| SimError::Parse {
            path: source.to_string(),
            message,
        })?;
        scene.validate().map_err(|e| SimError::InScene {
            path: source.to_string(),
            source: Box::new(e),
        })?;
        Ok(scene)
    }

    /// Parses a scene from JSON text (the same fields as the TOML form, as
    /// `serde_json::to_string(&scene)` writes it) and validates it; `source` names the text in
    /// errors.
    pub fn from_json_str(text: &str, source: &str) -> Result<Scene, SimError> {
        Scene::checked(
            serde_json::from_str(text).map_err(|e| e.to_string()),
            source,
        )
    }

    /// Reads, parses and validates the scene file at `path`: JSON when its name ends in
    /// `.json` (as the trial scenes are written), TOML otherwise.
    pub fn load(path: &Path) -> Result<Scene, SimError> {
        let text = std::fs::read_to_string(path).map_err(SimError::io(path))?;
        let source = path.display().to_string();
        let json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        if json {
            Scene::from_json_str(&text, &source)
        } else {
            Scene::from_toml_str(&text, &source)
        }
    }

    /// The built-in default scene (`crates/sim/scenes/default.toml`, compiled in): a 200 × 100 mm
    /// PLA plate with cracks of several widths, a bump, a wavy patch, a printed decoy, two
    /// screws and a top-down camera.
    pub fn builtin_default() -> Scene {
        match Scene::from_toml_str(DEFAULT_SCENE_TOML, "<builtin default.toml>") {
            Ok(scene) => scene,
            // Unreachable: a unit test checks the built-in scene parses and validates.
            Err(_) => Scene {
                name: "bare plate".to_string(),
                plate: PlateSpec::default(),
                features: Vec::new(),
                camera: None,
                manipulator: ManipulatorSpec::default(),
                sensor: SensorParams::default(),
            },
        }
    }

    /// The scene file at `path`, or the [built-in default](Scene::builtin_default) when `None`.
    pub fn load_or_default(path: Option<&Path>) -> Result<Scene, SimError> {
        match path {
            Some(p) => Scene::load(p),
            None => Ok(Scene::builtin_default()),
        }
    }

    /// What `crackbot sim scene` shows: the plate, every feature's footprint and the camera.
    pub fn summary(&self) -> SceneSummary {
        SceneSummary {
            name: self.name.clone(),
            plate_size_mm: self.plate.size_mm,
            material: self.plate.material.name.clone(),
            features: self
                .features
                .iter()
                .enumerate()
                .map(|(index, f)| {
                    let (min_mm, max_mm) = f.footprint();
                    FeatureSummary {
                        index,
                        kind: f.kind(),
                        min_mm,
                        max_mm,
                    }
                })
                .collect(),
            camera: self.camera.as_ref().map(|c| CameraSummary {
                resolution: c.resolution,
                position_mm: c.position_mm,
                look_at_mm: c.look_at_mm,
            }),
        }
    }

    /// The scene's camera, built from its spec (`None` for a scene without a camera).
    pub fn camera(&self) -> Option<Result<Camera, SimError>> {
        self.camera.as_ref().map(Camera::from_spec)
    }

    /// Checks the whole scene, naming the first bad field (and the feature by index and kind).
    pub fn validate(&self) -> Result<(), SimError> {
        let [sx, sy] = self.plate.size_mm;
        if !(sx.is_finite() && sx > 0.0 && sy.is_finite() && sy > 0.0) {
            return Err(SimError::setting(
                "plate.size_mm",
                list(&self.plate.size_mm),
                "> 0 mm in x and y",
            ));
        }
        let refl = self.plate.material.reflectivity;
        if !(0.0..=1.0).contains(&refl) {
            return Err(SimError::setting(
                "plate.material.reflectivity",
                refl,
                "in [0, 1]",
            ));
        }
        for (i, f) in self.features.iter().enumerate() {
            validate_feature(f, self.plate.size_mm).map_err(|e| match e {
                SimError::Setting {
                    field,
                    value,
                    allowed,
                } => SimError::Setting {
                    field: if field.is_empty() {
                        format!("features[{i}]")
                    } else {
                        format!("features[{i}].{field}")
                    },
                    value,
                    allowed: format!("{allowed} for a {}", f.kind()),
                },
                other => other,
            })?;
        }
        self.validate_manipulator()?;
        if let Some(spec) = &self.camera {
            self.validate_camera(spec)?;
        }
        self.sensor.finger.validate()?;
        self.sensor.optics.validate()?;
        Ok(())
    }

    fn validate_manipulator(&self) -> Result<(), SimError> {
        let m = &self.manipulator;
        for (name, v) in [
            ("manipulator.slide_speed_mm_s", m.slide_speed_mm_s),
            ("manipulator.stroke_mm", m.stroke_mm),
            ("manipulator.travel_speed_mm_s", m.travel_speed_mm_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(SimError::setting(name, v, "> 0"));
            }
        }
        let (lo, hi) = (m.workspace_min_mm, m.workspace_max_mm);
        for (name, v) in [
            ("manipulator.workspace_min_mm", lo),
            ("manipulator.workspace_max_mm", hi),
        ] {
            if !v.iter().all(|v| v.is_finite()) {
                return Err(SimError::setting(name, list(&v), "finite"));
            }
        }
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            if lo[k] >= hi[k] {
                return Err(SimError::setting(
                    "manipulator.workspace_min_mm",
                    list(&lo),
                    format!(
                        "below manipulator.workspace_max_mm {} in {axis} ({} ≥ {})",
                        list(&hi),
                        lo[k],
                        hi[k]
                    ),
                ));
            }
        }
        let size = self.plate.size_mm;
        for (k, axis) in ["x", "y"].iter().enumerate() {
            let cover = |bound: &str| {
                format!(
                    "{bound} in {axis}: the workspace must cover the plate [0, {}]",
                    size[k]
                )
            };
            if lo[k] > 0.0 {
                return Err(SimError::setting(
                    "manipulator.workspace_min_mm",
                    list(&lo),
                    cover("≤ 0"),
                ));
            }
            if hi[k] < size[k] {
                return Err(SimError::setting(
                    "manipulator.workspace_max_mm",
                    list(&hi),
                    cover(&format!("≥ {}", size[k])),
                ));
            }
        }
        Ok(())
    }

    fn validate_camera(&self, spec: &CameraSpec) -> Result<(), SimError> {
        if !(spec.noise_sigma.is_finite() && spec.noise_sigma >= 0.0) {
            return Err(SimError::setting(
                "camera.noise_sigma",
                spec.noise_sigma,
                "≥ 0",
            ));
        }
        if !(0.0..=1.0).contains(&spec.lighting_variation) {
            return Err(SimError::setting(
                "camera.lighting_variation",
                spec.lighting_variation,
                "in [0, 1]",
            ));
        }
        let z = spec.position_mm[2];
        if !(z.is_finite() && z > 0.0) {
            return Err(SimError::setting(
                "camera.position_mm",
                list(&spec.position_mm),
                "above the plate (z > 0)",
            ));
        }
        let [sx, sy] = self.plate.size_mm;
        let [lx, ly] = spec.look_at_mm;
        if !(lx >= 0.0 && lx <= sx && ly >= 0.0 && ly <= sy) {
            return Err(SimError::setting(
                "camera.look_at_mm",
                list(&spec.look_at_mm),
                format!("a point on the plate [0, {sx}] × [0, {sy}] (the camera looks away from the plate)"),
            ));
        }
        let cam = Camera::from_spec(spec)?;
        let tilt = (-cam.forward()[2]).clamp(-1.0, 1.0).acos().to_degrees();
        if tilt > MAX_CAMERA_TILT_DEG {
            return Err(SimError::setting(
                "camera.position_mm",
                list(&spec.position_mm),
                format!(
                    "a view at most {MAX_CAMERA_TILT_DEG}° from the vertical (this one is \
                     {tilt:.1}°: the camera looks at the plate edge-on)"
                ),
            ));
        }
        let probes = [
            [0.0, 0.0],
            [sx, 0.0],
            [0.0, sy],
            [sx, sy],
            [sx / 2.0, sy / 2.0],
            [lx, ly],
        ];
        let sees = probes.iter().any(|p| {
            cam.project([p[0], p[1], 0.0])
                .is_some_and(|uv| cam.in_image(uv))
        });
        if !sees {
            return Err(SimError::CameraMissesPlate);
        }
        Ok(())
    }

    /// The plate and its features, for the finger.
    pub fn surface(&self) -> Surface {
        Surface {
            size_mm: self.plate.size_mm,
            features: self.features.clone(),
        }
    }
}

fn check_positive(name: &str, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SimError::setting(name, v, "> 0"))
    }
}

fn check_non_negative(name: &str, v: f64) -> Result<(), SimError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(SimError::setting(name, v, "≥ 0"))
    }
}

fn check_point(name: &str, p: Point) -> Result<(), SimError> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SimError::setting(name, list(&p), "finite"))
    }
}

/// A path as written: `[[x, y], …]`.
fn path_list(path: &[Point]) -> String {
    list(&path.iter().map(|p| list(p)).collect::<Vec<_>>())
}

fn check_path(path: &[Point]) -> Result<(), SimError> {
    if path.len() < 2 {
        return Err(SimError::setting(
            "path",
            path_list(path),
            format!("a path of at least 2 points (it has {})", path.len()),
        ));
    }
    for (k, p) in path.iter().enumerate() {
        check_point(&format!("path[{k}]"), *p)?;
    }
    let length: f64 = path
        .windows(2)
        .map(|s| ((s[1][0] - s[0][0]).powi(2) + (s[1][1] - s[0][1]).powi(2)).sqrt())
        .sum();
    if length.is_nan() || length <= 1e-9 {
        return Err(SimError::setting(
            "path",
            path_list(path),
            format!(
                "a path of non-zero length (it has zero length: all {} points coincide)",
                path.len()
            ),
        ));
    }
    Ok(())
}

/// Checks one feature's parameters and that it lies on a plate of `size`; a
/// [`SimError::Setting`] names the feature's field (empty for the whole feature; the caller
/// prefixes the feature's index and adds its kind).
fn validate_feature(f: &Feature, size: [f64; 2]) -> Result<(), SimError> {
    match f {
        Feature::Crack {
            path,
            width_mm,
            depth_mm,
            edge_radius_mm,
            wall_angle_deg,
        } => {
            check_path(path)?;
            check_non_negative("width_mm", *width_mm)?;
            check_positive("depth_mm", *depth_mm)?;
            check_non_negative("edge_radius_mm", *edge_radius_mm)?;
            if !(*wall_angle_deg > 0.0 && *wall_angle_deg <= 90.0) {
                return Err(SimError::setting(
                    "wall_angle_deg",
                    wall_angle_deg,
                    "in (0, 90]",
                ));
            }
        }
        Feature::Bump {
            centre,
            radius_mm,
            height_mm,
        } => {
            check_point("centre", *centre)?;
            check_positive("radius_mm", *radius_mm)?;
            check_positive("height_mm", *height_mm)?;
        }
        Feature::Wavy {
            min,
            max,
            amplitude_mm,
            period_mm,
            direction_deg,
        } => {
            check_point("min", *min)?;
            check_point("max", *max)?;
            if !(min[0] < max[0] && min[1] < max[1]) {
                return Err(SimError::setting(
                    "min",
                    list(min),
                    format!("below max = {} in x and y", list(max)),
                ));
            }
            check_non_negative("amplitude_mm", *amplitude_mm)?;
            check_positive("period_mm", *period_mm)?;
            if !direction_deg.is_finite() {
                return Err(SimError::setting("direction_deg", direction_deg, "finite"));
            }
        }
        Feature::Decoy {
            path,
            width_mm,
            reflectivity,
        } => {
            check_path(path)?;
            check_non_negative("width_mm", *width_mm)?;
            if !(0.0..=1.0).contains(reflectivity) {
                return Err(SimError::setting("reflectivity", reflectivity, "in [0, 1]"));
            }
        }
        Feature::Screw {
            centre,
            head_diameter_mm,
            height_mm,
        } => {
            check_point("centre", *centre)?;
            check_positive("head_diameter_mm", *head_diameter_mm)?;
            check_positive("height_mm", *height_mm)?;
        }
    }
    let (lo, hi) = f.footprint();
    let eps = 1e-9;
    if !(lo[0] >= -eps && lo[1] >= -eps && hi[0] <= size[0] + eps && hi[1] <= size[1] + eps) {
        return Err(SimError::setting(
            "",
            format!("a footprint {}–{} mm", list(&lo), list(&hi)),
            format!(
                "inside the plate [0, {}] × [0, {}] (this one is outside the plate)",
                size[0], size[1]
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_default_parses_and_validates() {
        let scene = Scene::from_toml_str(DEFAULT_SCENE_TOML, "default.toml");
        assert!(scene.is_ok(), "{scene:?}");
        let scene = Scene::builtin_default();
        assert!(scene.camera.is_some());
        assert!(scene.features.len() >= 6);
        assert!(scene.validate().is_ok());
    }

    #[test]
    fn a_scene_loads_from_json_as_from_toml_and_errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let scene = Scene::builtin_default();
        let json = dir.path().join("scene.JSON");
        std::fs::write(&json, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
        assert_eq!(Scene::load(&json).unwrap(), scene);
        // JSON in a file named .toml is read as TOML, and the error names the file.
        let toml = dir.path().join("scene.toml");
        std::fs::copy(&json, &toml).unwrap();
        let e = Scene::load(&toml).unwrap_err().to_string();
        assert!(e.contains("scene.toml"), "{e}");
        // A malformed or invalid JSON scene: errors naming the file, no panic.
        std::fs::write(&json, "{\"name\": ").unwrap();
        let e = Scene::load(&json).unwrap_err().to_string();
        assert!(e.contains("scene.JSON"), "{e}");
        let mut bad = serde_json::to_value(&scene).unwrap();
        bad["plate"]["size_mm"] = serde_json::json!([-5.0, 100.0]);
        std::fs::write(&json, bad.to_string()).unwrap();
        let err = Scene::load(&json).unwrap_err();
        assert!(
            matches!(
                &err,
                SimError::InScene { path, source }
                    if path.ends_with("scene.JSON")
                        && matches!(
                            source.as_ref(),
                            SimError::Setting { field, .. } if field == "plate.size_mm"
                        )
            ),
            "{err:?}"
        );
        let e = err.to_string();
        assert!(
            e.contains("scene.JSON") && e.contains("plate.size_mm = [-5, 100]"),
            "{e}"
        );
    }
}
