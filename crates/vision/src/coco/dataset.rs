//! Running a detector over every image of a COCO ground truth.

use std::path::{Path, PathBuf};

use super::{CocoDataset, CocoImage, CocoResult};
use crate::crack_map::CrackMap;
use crate::{Detector, VisionError};

/// Where [`detect_dataset`] is: called before each image.
#[derive(Debug, Clone)]
pub struct Progress<'a> {
    /// Images finished so far.
    pub done: usize,
    /// Images in the dataset.
    pub total: usize,
    /// The image about to be processed.
    pub image: &'a CocoImage,
}

/// Runs `detector` over every image of `gt` (read from `image_root.join(file_name)`), returning
/// its detections as COCO results with `category_id`. `progress` is called before each image (and
/// once more with `done == total` at the end, with the last image) so a CLI can draw a progress
/// bar. Detections with a non-finite box or score are dropped. An image that cannot be read, or
/// whose size differs from the ground truth's, is an error naming the file.
pub fn detect_dataset<D: Detector + ?Sized>(
    detector: &mut D,
    gt: &CocoDataset,
    image_root: &Path,
    category_id: u64,
    progress: impl FnMut(&Progress<'_>),
) -> Result<Vec<CocoResult>, VisionError> {
    detect_dataset_with_maps(
        detector,
        gt,
        image_root,
        category_id,
        progress,
        |_, _, _| Ok(()),
    )
}

/// [`detect_dataset`], handing each image's detections and crack map (detectors that predict
/// one) to `on_frame`.
pub fn detect_dataset_with_maps<D: Detector + ?Sized>(
    detector: &mut D,
    gt: &CocoDataset,
    image_root: &Path,
    category_id: u64,
    mut progress: impl FnMut(&Progress<'_>),
    mut on_frame: impl FnMut(
        &CocoImage,
        &[crate::Detection],
        Option<&CrackMap>,
    ) -> Result<(), VisionError>,
) -> Result<Vec<CocoResult>, VisionError> {
    let total = gt.images.len();
    let mut results = Vec::new();
    for (done, image) in gt.images.iter().enumerate() {
        progress(&Progress { done, total, image });
        let path: PathBuf = image_root.join(&image.file_name);
        let rgb = image::open(&path)
            .map_err(|e| VisionError::Image {
                path: path.clone(),
                message: e.to_string(),
            })?
            .to_rgb8();
        if rgb.width() != image.width || rgb.height() != image.height {
            return Err(VisionError::Image {
                path,
                message: format!(
                    "image is {}×{} but the ground truth says {}×{}",
                    rgb.width(),
                    rgb.height(),
                    image.width,
                    image.height
                ),
            });
        }
        let (detections, map) = detector.detect_with_map(&rgb)?;
        on_frame(image, &detections, map.as_ref())?;
        results.extend(
            detections
                .iter()
                .filter(|d| d.bbox.is_finite() && d.score.is_finite())
                .map(|d| coco_result(image.id, category_id, d)),
        );
    }
    if let Some(last) = gt.images.last() {
        progress(&Progress {
            done: total,
            total,
            image: last,
        });
    }
    Ok(results)
}

/// `d` as a COCO result of image `image_id` in category `category_id`.
pub fn coco_result(image_id: u64, category_id: u64, d: &crate::Detection) -> CocoResult {
    let [x, y, w, h] = d.bbox.to_xywh();
    CocoResult {
        image_id,
        category_id,
        bbox: [f64::from(x), f64::from(y), f64::from(w), f64::from(h)],
        score: f64::from(d.score),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Fixed;
    impl Detector for Fixed {
        fn name(&self) -> String {
            "fixed".into()
        }
        fn detect(
            &mut self,
            _image: &image::RgbImage,
        ) -> Result<Vec<crate::Detection>, VisionError> {
            Ok(vec![
                crate::Detection {
                    bbox: crate::BoundingBox::from_xywh(1.0, 2.0, 3.0, 4.0),
                    score: 0.5,
                    shape: None,
                    source: crate::DetectionSource::Primary,
                },
                crate::Detection {
                    bbox: crate::BoundingBox::from_xywh(f32::NAN, 2.0, 3.0, 4.0),
                    score: 0.5,
                    shape: None,
                    source: crate::DetectionSource::Primary,
                },
            ])
        }
    }

    #[test]
    fn detect_dataset_runs_over_images_with_progress() {
        let dir = tempfile::tempdir().unwrap();
        let mut gt = CocoDataset {
            images: [1, 2]
                .iter()
                .map(|&id| CocoImage::new(id, format!("{id}.jpg"), 500, 500))
                .collect(),
            categories: vec![super::super::CocoCategory {
                id: 1,
                name: "crack".into(),
                supercategory: None,
            }],
            ..CocoDataset::default()
        };
        for im in &mut gt.images {
            im.width = 8;
            im.height = 6;
            image::RgbImage::new(8, 6)
                .save(dir.path().join(format!("{}.png", im.id)))
                .unwrap();
            im.file_name = format!("{}.png", im.id);
        }
        let mut seen = Vec::new();
        let r = detect_dataset(&mut Fixed, &gt, dir.path(), 1, |p| {
            seen.push((p.done, p.total));
        })
        .unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[1].image_id, 2);
        assert_eq!(r[0].bbox, [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(seen, vec![(0, 2), (1, 2), (2, 2)]);
        gt.images[0].width = 9;
        let err = detect_dataset(&mut Fixed, &gt, dir.path(), 1, |_| {}).unwrap_err();
        assert!(err.to_string().contains("1.png"), "{err}");
        gt.images[0].file_name = "nope.png".into();
        assert!(detect_dataset(&mut Fixed, &gt, dir.path(), 1, |_| {}).is_err());
    }
}
