//! `features.json`: every ground-truth feature of every rendered frame of a detector set
//! (`crackbot-lab sim detector-set` writes it beside its COCO file; `crackbot eval-detector` reads
//! it to count the cracks found and the decoys proposed). One type for both sides, like the COCO
//! types of [`crate::coco`].

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::ImagingError;

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneTruth {
    /// What the file holds, for people.
    #[serde(default)]
    pub description: String,
    /// Per frame.
    pub images: Vec<FrameTruth>,
}

/// One frame's features.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameTruth {
    /// The image, as in the COCO file.
    pub file_name: String,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// The frame's render seed.
    pub seed: u64,
    /// The seed its scene was drawn with.
    pub scene_seed: u64,
    /// The plate's material.
    pub material: String,
    /// Plate (mm, z = 0) → image (px) homography, row-major.
    pub plate_to_image: [[f64; 3]; 3],
    /// Cracks, decoys and screws.
    pub boxes: Vec<FeatureTruth>,
}

/// One visible feature of a frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeatureTruth {
    /// `crack`, `decoy` or `screw`.
    pub kind: String,
    /// Index of the feature in its scene.
    pub feature_index: usize,
    /// `[x, y, w, h]` of its visible pixels.
    pub bbox: [f64; 4],
    /// Visible pixels.
    pub pixels: u64,
    /// Width on the plate, mm (cracks and decoys).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width_mm: Option<f64>,
    /// The centre line in pixels (cracks and decoys); `None` for a point behind the camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_px: Option<Vec<Option<[f64; 2]>>>,
    /// The centre line on the plate, mm (cracks and decoys).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path_mm: Option<Vec<[f64; 2]>>,
    /// The centre on the plate, mm (screws).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centre_mm: Option<[f64; 2]>,
}

impl SceneTruth {
    /// Reads a features file, naming it in errors.
    pub fn load(path: &Path) -> Result<Self, ImagingError> {
        let text = std::fs::read_to_string(path).map_err(ImagingError::io(path))?;
        serde_json::from_str(&text).map_err(|e| ImagingError::Json {
            path: path.to_path_buf(),
            message: format!("not a features file: {e}"),
        })
    }

    /// Writes the file as pretty JSON.
    pub fn save(&self, path: &Path) -> Result<(), ImagingError> {
        let text = serde_json::to_string_pretty(self).map_err(|e| ImagingError::Json {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        std::fs::write(path, text).map_err(ImagingError::io(path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_names_a_bad_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("features.json");
        let truth = SceneTruth {
            description: "test".into(),
            images: vec![FrameTruth {
                file_name: "images/a.png".into(),
                width: 640,
                height: 480,
                seed: 1,
                scene_seed: 2,
                material: "PLA".into(),
                plate_to_image: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                boxes: vec![FeatureTruth {
                    kind: "crack".into(),
                    feature_index: 0,
                    bbox: [1.0, 2.0, 3.0, 4.0],
                    pixels: 5,
                    width_mm: Some(0.5),
                    path_px: Some(vec![Some([1.0, 2.0]), None]),
                    path_mm: Some(vec![[0.0, 0.0], [1.0, 1.0]]),
                    centre_mm: None,
                }],
            }],
        };
        truth.save(&path).unwrap();
        assert_eq!(SceneTruth::load(&path).unwrap(), truth);
        std::fs::write(&path, "{\"images\": 3}").unwrap();
        let e = SceneTruth::load(&path).unwrap_err().to_string();
        assert!(
            e.contains("features.json") && e.contains("not a features file"),
            "{e}"
        );
    }
}
