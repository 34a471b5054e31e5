//! Scenes: a plate with features, the camera looking at it, the manipulator and the sensor,
//! read from TOML files (kept in `crates/sim/scenes/`) and validated.

use serde::{Deserialize, Serialize};

use crate::surface::{Feature, Surface};
use crate::SensorParams;

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

/// A pinhole camera above the plate.
///
/// The camera frame is the usual one (x right, y down in the image, z forward). Its pose is
/// given as the position of the optical centre in the plate's frame (mm, z up, plate top at 0)
/// and the point it looks at on the plate, plus a roll about the optical axis. With `look_at`
/// straight below `position_mm` and `roll_deg = 0`, image x runs along plate +x and image y
/// along plate −y (the plate is seen from above as drawn on paper).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Image size in pixels `[width, height]`.
    pub resolution: [u32; 2],
    /// Focal lengths in pixels `[fx, fy]`.
    pub focal_px: [f64; 2],
    /// Principal point in pixels `[cx, cy]` (default: image centre).
    #[serde(default)]
    pub principal_px: Option<[f64; 2]>,
    /// Optical centre in the plate's frame, mm `[x, y, z]`.
    pub position_mm: [f64; 3],
    /// Point on the plate (z = 0) the optical axis passes through, mm `[x, y]`.
    pub look_at_mm: [f64; 2],
    /// Rotation about the optical axis, degrees.
    #[serde(default)]
    pub roll_deg: f64,
    /// Standard deviation of the sensor's noise, in 8-bit grey levels.
    #[serde(default = "default_image_noise")]
    pub noise_sigma: f64,
    /// Relative spread of the lighting between frames (0: identical lighting).
    #[serde(default = "default_lighting_variation")]
    pub lighting_variation: f64,
}

fn default_image_noise() -> f64 {
    2.0
}
fn default_lighting_variation() -> f64 {
    0.15
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
    /// The plate and its features, for the finger.
    pub fn surface(&self) -> Surface {
        Surface {
            size_mm: self.plate.size_mm,
            features: self.features.clone(),
        }
    }
}
