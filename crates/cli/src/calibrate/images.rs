//! The calibration's images: files, or folders of PNG/JPEG files, all of one size.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use image::GrayImage;

/// The images named (a folder stands for its `.png`, `.jpg` and `.jpeg` files, sorted), in
/// grey, with their paths. Refuses an empty list and images of different sizes.
pub fn load(paths: &[PathBuf]) -> Result<Vec<(PathBuf, GrayImage)>> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut inside: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("reading the folder {}", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| is_image(f))
                .collect();
            inside.sort();
            files.extend(inside);
        } else {
            files.push(p.clone());
        }
    }
    if files.is_empty() {
        bail!("no images: name image files or folders holding .png/.jpg files");
    }
    let mut out: Vec<(PathBuf, GrayImage)> = Vec::with_capacity(files.len());
    for f in files {
        let img = image::open(&f)
            .with_context(|| format!("reading the image {}", f.display()))?
            .to_luma8();
        if let Some((first, i0)) = out.first() {
            if i0.dimensions() != img.dimensions() {
                bail!(
                    "{} is {}×{} px but {} is {}×{} px: a calibration holds for one image size \
                     (one camera mode)",
                    f.display(),
                    img.width(),
                    img.height(),
                    first.display(),
                    i0.width(),
                    i0.height()
                );
            }
        }
        out.push((f, img));
    }
    Ok(out)
}

fn is_image(f: &Path) -> bool {
    f.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"))
}
