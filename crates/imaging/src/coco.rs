//! COCO detection files: the ground truth (`images`, `annotations`, `categories`) and the
//! results format (`[{"image_id", "category_id", "bbox", "score"}]`), read, validated and
//! written.
//!
//! Conventions:
//! * Boxes are COCO's `[x, y, width, height]` in pixels (origin at the top-left corner of the
//!   image), kept as `f64` like pycocotools keeps them.
//! * Fields crackbot does not use are ignored on reading. The ones it adds are typed optional
//!   fields, left out when absent: an image's `mask_file` (the photo datasets' crack masks), and,
//!   on frames rendered by the simulator, the image's `seed` and `plate_to_image` homography and
//!   each crack annotation's `feature_index`, `width_mm` and `crack_pixels`.
//! * Written files have their keys in alphabetical order (they go through
//!   [`serde_json::Value`]).

use std::collections::HashSet;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::ImagingError;

/// One image of a COCO file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CocoImage {
    /// Image id, unique in the file.
    pub id: u64,
    /// Path of the image, relative to the dataset's image root.
    pub file_name: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The crack mask of a photo, relative to the dataset's root (the photo datasets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mask_file: Option<String>,
    /// The seed a simulated frame was rendered with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// The exact plate (mm, z = 0) → image (px) homography of a simulated frame, row-major.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plate_to_image: Option<[[f64; 3]; 3]>,
}

impl CocoImage {
    /// An image without any of the optional fields.
    pub fn new(id: u64, file_name: impl Into<String>, width: u32, height: u32) -> Self {
        CocoImage {
            id,
            file_name: file_name.into(),
            width,
            height,
            mask_file: None,
            seed: None,
            plate_to_image: None,
        }
    }
}

/// One ground-truth box of a COCO file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CocoAnnotation {
    /// Annotation id, unique in the file.
    pub id: u64,
    /// The image it belongs to.
    pub image_id: u64,
    /// Its category.
    pub category_id: u64,
    /// `[x, y, width, height]` in pixels.
    pub bbox: [f64; 4],
    /// Area used for the small/medium/large ranges (for boxes, usually `width * height`).
    pub area: f64,
    /// Non-zero for a crowd region (matched by intersection over the detection's area, never a
    /// false negative).
    #[serde(default)]
    pub iscrowd: u8,
    /// Index of the simulated scene feature the box marks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feature_index: Option<usize>,
    /// Width of the simulated crack on the plate, mm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width_mm: Option<f64>,
    /// Number of visible crack pixels inside the box.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crack_pixels: Option<u64>,
}

impl CocoAnnotation {
    /// A box that is not a crowd region, with `area = width * height` and none of the optional
    /// fields.
    pub fn from_bbox(id: u64, image_id: u64, category_id: u64, bbox: [f64; 4]) -> Self {
        CocoAnnotation {
            id,
            image_id,
            category_id,
            bbox,
            area: bbox[2] * bbox[3],
            iscrowd: 0,
            feature_index: None,
            width_mm: None,
            crack_pixels: None,
        }
    }
}

/// One category of a COCO file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CocoCategory {
    /// Category id.
    pub id: u64,
    /// Name (e.g. `"crack"`).
    pub name: String,
    /// Parent category name, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub supercategory: Option<String>,
}

/// A COCO detection ground-truth file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CocoDataset {
    /// The file's free-form `info` block, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub info: Option<serde_json::Value>,
    /// The images.
    pub images: Vec<CocoImage>,
    /// The ground-truth boxes.
    #[serde(default)]
    pub annotations: Vec<CocoAnnotation>,
    /// The categories.
    pub categories: Vec<CocoCategory>,
}

fn coco_err(path: &Path, message: impl Into<String>) -> ImagingError {
    ImagingError::Coco {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

impl CocoDataset {
    /// Reads and validates a COCO ground-truth file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ImagingError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(ImagingError::io(path))?;
        Self::from_json_str(&text, path)
    }

    /// Parses and validates a COCO ground-truth document; `path` is only used in error messages
    /// (may be empty).
    pub fn from_json_str(text: &str, path: &Path) -> Result<Self, ImagingError> {
        let dataset: CocoDataset = serde_json::from_str(text)
            .map_err(|e| coco_err(path, format!("not a COCO detection file: {e}")))?;
        dataset.validate(path)?;
        Ok(dataset)
    }

    /// Checks ids are unique, every annotation refers to a known image and category, and every
    /// box is finite with a non-negative size. `path` is only used in error messages.
    pub fn validate(&self, path: &Path) -> Result<(), ImagingError> {
        let mut image_ids = HashSet::new();
        for image in &self.images {
            if !image_ids.insert(image.id) {
                return Err(coco_err(path, format!("duplicate image id {}", image.id)));
            }
        }
        let mut category_ids = HashSet::new();
        for category in &self.categories {
            if !category_ids.insert(category.id) {
                return Err(coco_err(
                    path,
                    format!("duplicate category id {}", category.id),
                ));
            }
        }
        let mut annotation_ids = HashSet::new();
        for ann in &self.annotations {
            if !annotation_ids.insert(ann.id) {
                return Err(coco_err(
                    path,
                    format!("duplicate annotation id {}", ann.id),
                ));
            }
            if !image_ids.contains(&ann.image_id) {
                return Err(coco_err(
                    path,
                    format!(
                        "annotation {} refers to unknown image id {}",
                        ann.id, ann.image_id
                    ),
                ));
            }
            if !category_ids.contains(&ann.category_id) {
                return Err(coco_err(
                    path,
                    format!(
                        "annotation {} refers to unknown category id {}",
                        ann.id, ann.category_id
                    ),
                ));
            }
            check_bbox(&ann.bbox)
                .map_err(|m| coco_err(path, format!("annotation {}: {m}", ann.id)))?;
            if !ann.area.is_finite() || ann.area < 0.0 {
                return Err(coco_err(
                    path,
                    format!("annotation {}: invalid area {}", ann.id, ann.area),
                ));
            }
        }
        Ok(())
    }

    /// The image with this id.
    pub fn image(&self, id: u64) -> Option<&CocoImage> {
        self.images.iter().find(|i| i.id == id)
    }

    /// The annotations of the image with this id, in file order.
    pub fn annotations_of(&self, image_id: u64) -> impl Iterator<Item = &CocoAnnotation> + '_ {
        self.annotations
            .iter()
            .filter(move |a| a.image_id == image_id)
    }

    /// The ground truth as perfect detections (score 1): evaluating them gives AP 1.
    pub fn ground_truth_as_results(&self) -> Vec<CocoResult> {
        self.annotations
            .iter()
            .map(|a| CocoResult {
                image_id: a.image_id,
                category_id: a.category_id,
                bbox: a.bbox,
                score: 1.0,
            })
            .collect()
    }

    /// Validates the dataset and writes it as pretty-printed JSON (keys in alphabetical order).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), ImagingError> {
        let path = path.as_ref();
        self.validate(path)?;
        let text = serde_json::to_value(self)
            .and_then(|v| serde_json::to_string_pretty(&v))
            .map_err(|e| coco_err(path, format!("cannot encode: {e}")))?;
        std::fs::write(path, text).map_err(ImagingError::io(path))
    }
}

fn check_bbox(bbox: &[f64; 4]) -> Result<(), String> {
    if bbox.iter().any(|v| !v.is_finite()) {
        return Err(format!("non-finite bbox {bbox:?}"));
    }
    if bbox[2] < 0.0 || bbox[3] < 0.0 {
        return Err(format!("negative bbox size {bbox:?}"));
    }
    Ok(())
}

/// One detection in the COCO results format.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CocoResult {
    /// The ground-truth image it was found in.
    pub image_id: u64,
    /// Its category.
    pub category_id: u64,
    /// `[x, y, width, height]` in pixels.
    pub bbox: [f64; 4],
    /// Confidence.
    pub score: f64,
}

/// Checks results against the ground truth: every image id must be known, every box finite with
/// a non-negative size, every score finite. `path` is only used in error messages.
pub fn validate_results(
    results: &[CocoResult],
    gt: &CocoDataset,
    path: &Path,
) -> Result<(), ImagingError> {
    let image_ids: HashSet<u64> = gt.images.iter().map(|i| i.id).collect();
    for (i, r) in results.iter().enumerate() {
        if !image_ids.contains(&r.image_id) {
            return Err(coco_err(
                path,
                format!(
                    "result {i} is for image id {}, which is not in the ground truth",
                    r.image_id
                ),
            ));
        }
        check_bbox(&r.bbox).map_err(|m| coco_err(path, format!("result {i}: {m}")))?;
        if !r.score.is_finite() {
            return Err(coco_err(
                path,
                format!("result {i}: non-finite score {}", r.score),
            ));
        }
    }
    Ok(())
}

/// Reads a COCO results file (`[{"image_id", "category_id", "bbox", "score"}]`) and checks it
/// against the ground truth ([`validate_results`]).
pub fn load_results(
    path: impl AsRef<Path>,
    gt: &CocoDataset,
) -> Result<Vec<CocoResult>, ImagingError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(ImagingError::io(path))?;
    parse_results(&text, path, gt)
}

/// Parses a COCO results document (see [`load_results`]); `path` is only used in error messages.
pub fn parse_results(
    text: &str,
    path: &Path,
    gt: &CocoDataset,
) -> Result<Vec<CocoResult>, ImagingError> {
    let results: Vec<CocoResult> = serde_json::from_str(text)
        .map_err(|e| coco_err(path, format!("not a COCO results file: {e}")))?;
    validate_results(&results, gt, path)?;
    Ok(results)
}

/// Writes a COCO results file (refuses non-finite values, which JSON cannot hold).
pub fn save_results(path: impl AsRef<Path>, results: &[CocoResult]) -> Result<(), ImagingError> {
    let path = path.as_ref();
    for (i, r) in results.iter().enumerate() {
        if r.bbox.iter().any(|v| !v.is_finite()) || !r.score.is_finite() {
            return Err(coco_err(
                path,
                format!("result {i} has a non-finite value: {r:?}"),
            ));
        }
    }
    let text = serde_json::to_string(results)
        .map_err(|e| coco_err(path, format!("cannot encode results: {e}")))?;
    std::fs::write(path, text).map_err(ImagingError::io(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dataset() -> CocoDataset {
        let mut ann = CocoAnnotation::from_bbox(1, 1, 1, [0.0, 0.0, 10.0, 10.0]);
        ann.width_mm = Some(2.0);
        let mut image = CocoImage::new(1, "a.png", 20, 20);
        image.seed = Some(7);
        CocoDataset {
            info: None,
            images: vec![image],
            annotations: vec![ann],
            categories: vec![CocoCategory {
                id: 1,
                name: "crack".into(),
                supercategory: Some("defect".into()),
            }],
        }
    }

    fn res(image_id: u64, bbox: [f64; 4], score: f64) -> CocoResult {
        CocoResult {
            image_id,
            category_id: 1,
            bbox,
            score,
        }
    }

    #[test]
    fn results_are_validated() {
        let gt = dataset();
        let p = Path::new("dets.json");
        let err = parse_results(
            r#"[{"image_id": 9, "category_id": 1, "bbox": [0,0,1,1], "score": 0.5}]"#,
            p,
            &gt,
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("dets.json") && err.to_string().contains('9'),
            "{err}"
        );
        assert!(parse_results("{}", p, &gt).is_err());
        assert!(parse_results(
            r#"[{"image_id": 1, "category_id": 1, "bbox": [0,0,1], "score": 0.5}]"#,
            p,
            &gt
        )
        .is_err());
        assert!(parse_results(
            r#"[{"image_id": 1, "category_id": 1, "bbox": [0,0,1,1]}]"#,
            p,
            &gt
        )
        .is_err());
        let ok = parse_results(
            r#"[{"image_id": 1, "category_id": 1, "bbox": [0,0,1,1], "score": 0.5}]"#,
            p,
            &gt,
        )
        .unwrap();
        assert_eq!(ok.len(), 1);
        assert!(validate_results(&[res(1, [f64::NAN, 0.0, 1.0, 1.0], 0.5)], &gt, p).is_err());
        assert!(validate_results(&[res(1, [0.0, 0.0, -1.0, 1.0], 0.5)], &gt, p).is_err());
    }

    #[test]
    fn ground_truth_is_validated() {
        let p = Path::new("gt.json");
        let cats = r#""categories": [{"id": 1, "name": "crack"}]"#;
        let img = r#"{"id": 1, "file_name": "a.jpg", "width": 10, "height": 10, "extra": 3}"#;
        let ann = |s: &str| format!(r#"{{"images": [{img}], {cats}, "annotations": [{s}]}}"#);
        let ok = CocoDataset::from_json_str(
            &ann(r#"{"id": 1, "image_id": 1, "category_id": 1, "bbox": [1, 2, 3, 4], "area": 12}"#),
            p,
        )
        .unwrap();
        assert_eq!(ok.annotations[0].iscrowd, 0);
        let bad = [
            "not json".to_string(),
            format!(r#"{{"images": [{img}, {img}], {cats}}}"#),
            ann(r#"{"id": 1, "image_id": 2, "category_id": 1, "bbox": [1, 2, 3, 4], "area": 12}"#),
            ann(r#"{"id": 1, "image_id": 1, "category_id": 1, "bbox": [1, 2, -3, 4], "area": 12}"#),
            ann(r#"{"id": 1, "image_id": 1, "category_id": 1, "bbox": [1, 2, 3, 4]}"#),
            ann(r#"{"id": 1, "image_id": 1, "category_id": 5, "bbox": [1, 2, 3, 4], "area": 12}"#),
            ann(
                r#"{"id": 1, "image_id": 1, "category_id": 1, "bbox": [1, 2, 3, 1e999], "area": 12}"#,
            ),
        ];
        for b in &bad {
            let err = CocoDataset::from_json_str(b, p).unwrap_err();
            assert!(err.to_string().contains("gt.json"), "{err}");
        }
    }

    #[test]
    fn datasets_and_results_round_trip_through_files_with_the_optional_fields() {
        let gt = dataset();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("gt.json");
        gt.save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("\"seed\": 7") && text.contains("\"width_mm\": 2.0"),
            "{text}"
        );
        assert!(
            !text.contains("mask_file") && !text.contains("info"),
            "{text}"
        );
        assert_eq!(CocoDataset::load(&path).unwrap(), gt);
        assert_eq!(gt.annotations_of(1).count(), 1);
        let path = dir.path().join("dets.json");
        let r = vec![res(1, [0.5, 1.25, 3.0, 4.0], 0.75)];
        save_results(&path, &r).unwrap();
        assert_eq!(load_results(&path, &gt).unwrap(), r);
        assert!(save_results(&path, &[res(1, [0.0, 0.0, 1.0, 1.0], f64::NAN)]).is_err());
        let err = load_results(dir.path().join("missing.json"), &gt).unwrap_err();
        assert!(matches!(err, ImagingError::Io { .. }), "{err}");
    }
}
