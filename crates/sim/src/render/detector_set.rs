//! Training and evaluation data for a segmentation-style crack detector
//! (`crackbot-lab sim detector-set`): frames of many [random scenes](crate::random_scene), each
//! with its image, its exact per-pixel crack mask, COCO crack boxes and every ground-truth
//! feature.
//!
//! Written under the output folder:
//! * `images/<name>.png`: the frame (8-bit RGB, lossless);
//! * `masks/<name>.png`: its crack mask (8-bit grey, 255 = crack, 0 = anything else, decoys and
//!   screws included), [`Frame::crack_mask`];
//! * `annotations.json`: COCO detection file as `sim render` writes it (category `crack`, id 1,
//!   crack boxes only), its `file_name`s and each image's `mask_file` relative to the folder (as
//!   in the photo datasets: `crackbot eval-detector --coco DIR/annotations.json` needs no
//!   `--images`), each image also with `scene_seed`;
//! * `features.json`: per image, every ground-truth box (crack, decoy, screw) with its kind,
//!   `bbox` `[x, y, w, h]`, `width_mm`, the polyline projected into pixels (`path_px`, cracks and
//!   decoys) and the plate → image homography (row-major).
//!
//! Frame names are `s<scene seed>_f<frame>`; frame seeds are distinct across the set.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crackbot_imaging::coco::{CocoDataset, CocoImage};
use crackbot_imaging::homography::{apply_in_front, matrix_rows};
use crackbot_imaging::scene_truth::{FeatureTruth, FrameTruth, SceneTruth};
use serde::Serialize;
use serde_json::{json, Value};

use super::assets::{image_err, CrackAssets};
use super::draw::{render, RenderOptions};
use super::export::{categories, crack_annotations};
use super::frame::{BoxKind, Frame};
use super::texture::mix64;
use crate::random_scene::{random_scene, RandomSceneParams};
use crate::surface::Feature;
use crate::{Scene, SimError};

/// What [`write_detector_set`] did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DetectorSetSummary {
    /// Scenes drawn.
    pub scenes: usize,
    /// Frames rendered.
    pub frames: usize,
    /// Visible crack boxes over all frames.
    pub cracks: usize,
    /// Visible decoy boxes over all frames.
    pub decoys: usize,
    /// Visible screw boxes over all frames.
    pub screws: usize,
    /// Wall-clock milliseconds per frame, rendering only.
    pub ms_per_frame: f64,
    /// The COCO file.
    pub annotations: PathBuf,
    /// The per-image ground truth of every feature.
    pub features: PathBuf,
    /// The folder of the images.
    pub images: PathBuf,
    /// The folder of the crack masks.
    pub masks: PathBuf,
}

/// The seed of frame `k` of the scene drawn with `scene_seed`.
pub fn detector_frame_seed(scene_seed: u64, k: u32) -> u64 {
    mix64(scene_seed ^ 0xd37e_c70f).wrapping_add(u64::from(k))
}

/// The ground truth of one frame for `features.json`.
fn frame_features(scene: &Scene, frame: &Frame, file_name: &str, scene_seed: u64) -> FrameTruth {
    let h = &frame.plate_to_image;
    let boxes = frame
        .boxes
        .iter()
        .map(|b| {
            let feature = scene.features.get(b.feature_index);
            let path = match feature {
                Some(Feature::Crack { path, .. } | Feature::Decoy { path, .. }) => Some(path),
                _ => None,
            };
            FeatureTruth {
                kind: b.kind.as_str().to_string(),
                feature_index: b.feature_index,
                bbox: b.bbox(),
                pixels: b.pixels,
                width_mm: b.width_mm,
                path_px: path.map(|p| p.iter().map(|&q| apply_in_front(h, q)).collect()),
                path_mm: path.cloned(),
                centre_mm: match feature {
                    Some(Feature::Screw { centre, .. }) => Some(*centre),
                    _ => None,
                },
            }
        })
        .collect();
    let (width, height) = frame.image.dimensions();
    FrameTruth {
        file_name: file_name.to_string(),
        width,
        height,
        seed: frame.seed,
        scene_seed,
        material: scene.plate.material.name.clone(),
        plate_to_image: matrix_rows(h),
        boxes,
    }
}

fn write_json(path: &Path, doc: &Value) -> Result<(), SimError> {
    let text = serde_json::to_string_pretty(doc).map_err(|e| image_err(path, e))?;
    std::fs::write(path, text).map_err(SimError::io(path))
}

/// Draws `scenes` random scenes from `params` (seeds `first_seed`, `first_seed + 1`, …),
/// renders `frames_per_scene` frames of each and writes them under `out` (see the module
/// docs); `progress(done, total)` after each frame. Errors on zero scenes or frames, invalid
/// parameters, seeds that overflow, and files that cannot be written.
pub fn write_detector_set(
    params: &RandomSceneParams,
    assets: &CrackAssets,
    scenes: u32,
    frames_per_scene: u32,
    first_seed: u64,
    out: &Path,
    mut progress: impl FnMut(usize, usize),
) -> Result<DetectorSetSummary, SimError> {
    if scenes == 0 {
        return Err(SimError::setting("scenes", scenes, "≥ 1"));
    }
    if frames_per_scene == 0 {
        return Err(SimError::setting(
            "frames_per_scene",
            frames_per_scene,
            "≥ 1",
        ));
    }
    let last_first_seed = u64::MAX - (u64::from(scenes) - 1);
    if first_seed > last_first_seed {
        return Err(SimError::setting(
            "first_seed",
            first_seed,
            format!("≤ {last_first_seed}, so that the seeds of {scenes} scenes fit in u64"),
        ));
    }
    params.validate()?;
    let images_dir = out.join("images");
    let masks_dir = out.join("masks");
    for dir in [&images_dir, &masks_dir] {
        std::fs::create_dir_all(dir).map_err(SimError::io(dir))?;
    }
    let total = scenes as usize * frames_per_scene as usize;
    let options = RenderOptions::default();
    let mut coco = CocoDataset {
        info: Some(json!({
            "description": "crackbot-sim random scenes for crack detection, with crack masks",
            "version": "1",
        })),
        images: Vec::with_capacity(total),
        annotations: Vec::new(),
        categories: categories(),
    };
    let mut scene_seeds = Vec::with_capacity(total);
    let mut features = Vec::with_capacity(total);
    let (mut cracks, mut decoys, mut screws) = (0, 0, 0);
    let mut render_s = 0.0;
    for i in 0..scenes {
        let scene_seed = first_seed + u64::from(i);
        let scene = random_scene(params, scene_seed)?;
        for k in 0..frames_per_scene {
            let start = Instant::now();
            let frame = render(&scene, assets, &options, detector_frame_seed(scene_seed, k))?;
            render_s += start.elapsed().as_secs_f64();
            let stem = format!("s{scene_seed:08}_f{k:02}");
            let file_name = format!("images/{stem}.png");
            let mask_file = format!("masks/{stem}.png");
            let png = out.join(&file_name);
            frame
                .image
                .save_with_format(&png, image::ImageFormat::Png)
                .map_err(|e| image_err(&png, e))?;
            let mask_png = out.join(&mask_file);
            frame
                .crack_mask
                .save_with_format(&mask_png, image::ImageFormat::Png)
                .map_err(|e| image_err(&mask_png, e))?;
            let id = coco.images.len() as u64 + 1;
            let (width, height) = frame.image.dimensions();
            coco.images.push(CocoImage {
                mask_file: Some(mask_file),
                seed: Some(frame.seed),
                plate_to_image: Some(matrix_rows(&frame.plate_to_image)),
                ..CocoImage::new(id, file_name.as_str(), width, height)
            });
            let first = coco.annotations.len() as u64 + 1;
            coco.annotations
                .extend(crack_annotations(&frame, id, first));
            scene_seeds.push(scene_seed);
            features.push(frame_features(&scene, &frame, &file_name, scene_seed));
            cracks += frame.boxes_of(BoxKind::Crack).count();
            decoys += frame.boxes_of(BoxKind::Decoy).count();
            screws += frame.boxes_of(BoxKind::Screw).count();
            progress(coco.images.len(), total);
        }
    }
    let annotations = out.join("annotations.json");
    let mut doc = serde_json::to_value(&coco).map_err(|e| image_err(&annotations, e))?;
    if let Some(images) = doc.get_mut("images").and_then(Value::as_array_mut) {
        for (image, seed) in images.iter_mut().zip(&scene_seeds) {
            if let Some(obj) = image.as_object_mut() {
                obj.insert("scene_seed".into(), json!(seed));
            }
        }
    }
    write_json(&annotations, &doc)?;
    let features_path = out.join("features.json");
    SceneTruth {
        description: "every ground-truth box of each image (cracks, printed decoys, screws), the \
                      features' paths in pixels and mm, and the plate → image homography \
                      (row-major)"
            .into(),
        images: features,
    }
    .save(&features_path)?;
    Ok(DetectorSetSummary {
        scenes: scenes as usize,
        frames: total,
        cracks,
        decoys,
        screws,
        ms_per_frame: render_s * 1e3 / total as f64,
        annotations,
        features: features_path,
        images: images_dir,
        masks: masks_dir,
    })
}
