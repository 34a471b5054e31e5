//! Rendering a run of frames of one scene and writing them as a COCO dataset
//! (`crackbot sim render`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::assets::CrackAssets;
use super::draw::{render, RenderOptions};
use super::export::write_coco_dataset;
use crate::scene::Scene;
use crate::SimError;

/// What [`render_dataset`] did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RenderSummary {
    /// Frames rendered.
    pub frames: usize,
    /// Wall-clock milliseconds per frame (rendering only, writing excluded).
    pub ms_per_frame: f64,
    /// Ground-truth boxes over all frames (cracks, decoys and screws).
    pub boxes: usize,
    /// The COCO file written.
    pub coco: PathBuf,
    /// The folder of the images and their JSON descriptions.
    pub images: PathBuf,
}

/// Renders `frames` frames of `scene` with seeds `first_seed`, `first_seed + 1`, … and writes
/// them to `out` ([`write_coco_dataset`]); `progress(done, total)` after each frame. Errors
/// when the scene has no camera or `frames` is 0.
pub fn render_dataset(
    scene: &Scene,
    assets: &CrackAssets,
    options: &RenderOptions,
    frames: u32,
    first_seed: u64,
    out: &Path,
    mut progress: impl FnMut(usize, usize),
) -> Result<RenderSummary, SimError> {
    if scene.camera.is_none() {
        return Err(SimError::NoCamera {
            scene: scene.name.clone(),
        });
    }
    if frames == 0 {
        return Err(SimError::setting("frames", frames, "≥ 1"));
    }
    let start = Instant::now();
    let mut rendered = Vec::with_capacity(frames as usize);
    for k in 0..frames {
        rendered.push(render(scene, assets, options, first_seed + u64::from(k))?);
        progress(k as usize + 1, frames as usize);
    }
    let per_frame = start.elapsed().as_secs_f64() / f64::from(frames);
    let coco = write_coco_dataset(&rendered, out)?;
    Ok(RenderSummary {
        frames: rendered.len(),
        ms_per_frame: per_frame * 1e3,
        boxes: rendered.iter().map(|f| f.boxes.len()).sum(),
        coco,
        images: out.join("images"),
    })
}
