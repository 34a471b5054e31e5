//! Writing rendered frames: a PNG and a JSON description per frame, and a COCO detection file
//! over all of them (the COCO types are `crackbot_imaging::coco`'s, with the simulator's extra
//! fields: each image's seed and plate → image homography, each crack's feature index, width
//! and pixel count).

use std::path::{Path, PathBuf};

use crackbot_imaging::coco::{CocoAnnotation, CocoCategory, CocoDataset, CocoImage};
use crackbot_imaging::homography::matrix_rows;
use serde_json::{json, Value};

use super::assets::image_err;
use super::frame::{BoxKind, Frame};
use crate::SimError;

/// The one category of the exports: `crack` (id 1).
pub(super) fn categories() -> Vec<CocoCategory> {
    vec![CocoCategory {
        id: 1,
        name: "crack".into(),
        supercategory: Some("defect".into()),
    }]
}

/// The crack boxes of `frame` as annotations of image `image_id`, ids from `first_id`.
pub(super) fn crack_annotations(
    frame: &Frame,
    image_id: u64,
    first_id: u64,
) -> Vec<CocoAnnotation> {
    frame
        .boxes_of(BoxKind::Crack)
        .enumerate()
        .map(|(k, b)| CocoAnnotation {
            feature_index: Some(b.feature_index),
            width_mm: b.width_mm,
            crack_pixels: Some(b.pixels),
            ..CocoAnnotation::from_bbox(first_id + k as u64, image_id, 1, b.bbox())
        })
        .collect()
}

/// The JSON description of a frame saved as `file_name`: size, seed, every ground-truth box,
/// the plate → image homography (3 × 3, row-major), and COCO-style `images`, `annotations`
/// (cracks only) and `categories`.
pub fn frame_json(frame: &Frame, file_name: &str) -> serde_json::Result<Value> {
    let (width, height) = frame.image.dimensions();
    let coco = CocoDataset {
        info: None,
        images: vec![CocoImage::new(1, file_name, width, height)],
        annotations: crack_annotations(frame, 1, 1),
        categories: categories(),
    };
    let mut doc = serde_json::to_value(&coco)?;
    if let Some(obj) = doc.as_object_mut() {
        obj.insert("file_name".into(), json!(file_name));
        obj.insert("width".into(), json!(width));
        obj.insert("height".into(), json!(height));
        obj.insert("seed".into(), json!(frame.seed));
        obj.insert(
            "plate_to_image".into(),
            json!(matrix_rows(&frame.plate_to_image)),
        );
        obj.insert("boxes".into(), serde_json::to_value(&frame.boxes)?);
    }
    Ok(doc)
}

/// Writes `dir/<stem>.png` and `dir/<stem>.json` ([`frame_json`]), creating `dir`.
pub fn write_frame(frame: &Frame, dir: &Path, stem: &str) -> Result<(), SimError> {
    std::fs::create_dir_all(dir).map_err(SimError::io(dir))?;
    let png = dir.join(format!("{stem}.png"));
    frame
        .image
        .save_with_format(&png, image::ImageFormat::Png)
        .map_err(|e| image_err(&png, e))?;
    let json_path = dir.join(format!("{stem}.json"));
    let text = frame_json(frame, &format!("{stem}.png"))
        .and_then(|doc| serde_json::to_string_pretty(&doc))
        .map_err(|e| image_err(&json_path, e))?;
    std::fs::write(&json_path, text).map_err(SimError::io(&json_path))?;
    Ok(())
}

/// A COCO detection dataset of frames saved under the given file names: image ids 1, 2, …,
/// annotation ids from 1, one category `crack` (id 1). Only cracks are annotated: decoys and
/// screws are not cracks. Readable by `crackbot eval-detector --coco FILE --images DIR`.
pub fn coco_file(frames: &[(&str, &Frame)]) -> CocoDataset {
    let mut images = Vec::new();
    let mut annotations = Vec::new();
    for (k, (file_name, frame)) in frames.iter().enumerate() {
        let id = k as u64 + 1;
        let (width, height) = frame.image.dimensions();
        images.push(CocoImage {
            seed: Some(frame.seed),
            plate_to_image: Some(matrix_rows(&frame.plate_to_image)),
            ..CocoImage::new(id, *file_name, width, height)
        });
        let first = annotations.len() as u64 + 1;
        annotations.extend(crack_annotations(frame, id, first));
    }
    CocoDataset {
        info: Some(json!({ "description": "crackbot-sim rendered frames", "version": "1" })),
        images,
        annotations,
        categories: categories(),
    }
}

/// [`coco_file`] as JSON.
pub fn coco_dataset(frames: &[(&str, &Frame)]) -> serde_json::Result<Value> {
    serde_json::to_value(coco_file(frames))
}

/// Writes `frames` as a COCO dataset: `dir/images/frame_NNNN.png` (with their
/// [`write_frame`] JSON) and `dir/coco.json`; returns the path of `coco.json` (pass
/// `--images dir/images`).
pub fn write_coco_dataset(frames: &[Frame], dir: &Path) -> Result<PathBuf, SimError> {
    let images = dir.join("images");
    let names: Vec<String> = (0..frames.len()).map(|k| format!("frame_{k:04}")).collect();
    for (frame, stem) in frames.iter().zip(&names) {
        write_frame(frame, &images, stem)?;
    }
    let files: Vec<String> = names.iter().map(|s| format!("{s}.png")).collect();
    let entries: Vec<(&str, &Frame)> = files.iter().map(String::as_str).zip(frames).collect();
    let coco_path = dir.join("coco.json");
    coco_file(&entries).save(&coco_path)?;
    Ok(coco_path)
}
