//! A detector benchmarked on a COCO ground truth: its detections, their COCO metrics and the
//! median time of one `detect` call; the `crackbot eval-detector` report.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::coco::{
    coco_result, detect_dataset_with_maps, evaluate, CocoDataset, CocoImage, CocoMetrics,
    CocoResult, Progress,
};
use crate::crack_map::{CrackMap, CrackPiece};
use crate::crack_recall::{CrackRecall, CrackRecallEvaluator};
use crate::pixel::{PixelEvaluator, PixelMetrics};
use crate::preprocess::PostprocessParams;
use crate::scene_recall::{scene_recall, SceneRecall, SceneTruth};
use crate::{Detection, DetectionSource, Detector, VisionError};

/// Post-processing for mAP: every candidate down to a score of 0.001, as COCO evaluations do,
/// with a crack-map model's box-head boxes after the crack map's.
pub fn map_params() -> PostprocessParams {
    PostprocessParams {
        score_threshold: 0.001,
        box_head: true,
        ..PostprocessParams::default()
    }
}

/// Times every `detect` call of the detector it wraps.
pub struct Timed<'a> {
    inner: &'a mut dyn Detector,
    ms: Vec<f64>,
}

impl<'a> Timed<'a> {
    /// Wraps `inner`.
    pub fn new(inner: &'a mut dyn Detector) -> Self {
        Timed {
            inner,
            ms: Vec::new(),
        }
    }

    /// The median milliseconds of one call (the upper median for an even count; NaN before
    /// the first call).
    pub fn median_ms(&self) -> f64 {
        let mut ms = self.ms.clone();
        ms.sort_by(f64::total_cmp);
        ms.get(ms.len() / 2).copied().unwrap_or(f64::NAN)
    }
}

impl Detector for Timed<'_> {
    fn name(&self) -> String {
        self.inner.name()
    }
    fn detect(&mut self, image: &image::RgbImage) -> Result<Vec<Detection>, VisionError> {
        let started = Instant::now();
        let out = self.inner.detect(image);
        self.ms.push(started.elapsed().as_secs_f64() * 1e3);
        out
    }
    fn detect_with_map(
        &mut self,
        image: &image::RgbImage,
    ) -> Result<(Vec<Detection>, Option<CrackMap>), VisionError> {
        let started = Instant::now();
        let out = self.inner.detect_with_map(image);
        self.ms.push(started.elapsed().as_secs_f64() * 1e3);
        out
    }
}

/// Pixel tolerances the crack map is scored at: 0 (pixel-exact, the protocol of the published
/// DeepCrack and CrackSCF figures), 2 px (the usual figure for CrackForest) and 5 px.
pub const PIXEL_TOLERANCES_PX: [f64; 3] = [0.0, 2.0, 5.0];

/// Reads a crack mask (any image; non-zero luma is crack), checking its size.
fn read_mask(path: &Path, width: u32, height: u32) -> Result<Vec<bool>, VisionError> {
    let mask = image::open(path)
        .map_err(|e| VisionError::Image {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?
        .to_luma8();
    if mask.dimensions() != (width, height) {
        return Err(VisionError::Image {
            path: path.to_path_buf(),
            message: format!(
                "mask is {}×{} but its image is {width}×{height}",
                mask.width(),
                mask.height()
            ),
        });
    }
    Ok(mask.as_raw().iter().map(|&v| v > 0).collect())
}

/// A COCO ground truth, the folder of its images and the category to report.
#[derive(Debug, Clone)]
pub struct Benchmark {
    /// The ground-truth file.
    pub coco: PathBuf,
    /// The ground truth.
    pub gt: CocoDataset,
    /// The folder the COCO `file_name`s are relative to.
    pub root: PathBuf,
    /// The category detections are reported as: the only one, or the one named `crack`.
    pub category: u64,
    /// Every feature of every frame, for rendered frames (`features.json` beside the COCO file).
    pub scene_truth: Option<SceneTruth>,
}

/// One run of a detector over a [`Benchmark`].
#[derive(Debug, Clone)]
pub struct BenchmarkRun {
    /// The detector's name.
    pub detector: String,
    /// Its detections as COCO results.
    pub results: Vec<CocoResult>,
    /// Their metrics.
    pub metrics: CocoMetrics,
    /// Median milliseconds of one `detect` call (image decoding excluded).
    pub median_ms: f64,
    /// Pixel-level metrics of the crack map at each of [`PIXEL_TOLERANCES_PX`], over the images
    /// with a `mask_file` (empty for detectors without a map, or without masks).
    pub pixel: Vec<PixelMetrics>,
    /// Cracks of the masks found by the crack map (over the same images as `pixel`).
    pub cracks: Option<CrackRecall>,
    /// Cracks found and decoys proposed at the `detect` threshold (rendered frames with a
    /// `features.json`).
    pub scene: Option<SceneRecall>,
}

impl Benchmark {
    /// Reads the ground truth `coco`; its images are under `images`, or beside the file.
    /// Errors when it has no category, or several and none named `crack`.
    pub fn load(coco: &Path, images: Option<&Path>) -> Result<Self, VisionError> {
        let gt = CocoDataset::load(coco)?;
        let root = match images {
            Some(d) => d.to_path_buf(),
            None => coco
                .parent()
                .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        };
        let err = |message: &str| VisionError::Coco {
            path: coco.to_path_buf(),
            message: message.into(),
        };
        let category = match gt.categories.as_slice() {
            [one] => one.id,
            [] => return Err(err("no categories")),
            many => many
                .iter()
                .find(|c| c.name == "crack")
                .map(|c| c.id)
                .ok_or_else(|| err("several categories and none named `crack`"))?,
        };
        let features = coco.with_file_name("features.json");
        let scene_truth = if features.is_file() {
            Some(SceneTruth::load(&features)?)
        } else {
            None
        };
        Ok(Self {
            coco: coco.to_path_buf(),
            gt,
            root,
            category,
            scene_truth,
        })
    }

    /// Runs `detector` over every image (`progress` as [`detect_dataset`] calls it): the
    /// results, their metrics and the median milliseconds of one `detect` call.
    pub fn run(
        &self,
        detector: &mut dyn Detector,
        progress: impl FnMut(&Progress<'_>),
    ) -> Result<BenchmarkRun, VisionError> {
        let mut timed = Timed::new(detector);
        let mut pixel: Vec<PixelEvaluator> = PIXEL_TOLERANCES_PX
            .iter()
            .map(|&t| PixelEvaluator::new(t))
            .collect::<Result<_, _>>()?;
        let mut cracks = CrackRecallEvaluator::default();
        let root = &self.root;
        let threshold = PostprocessParams::default().score_threshold;
        let mut pieces: HashMap<u64, Vec<CrackPiece>> = HashMap::new();
        // The robot's proposals: the box head's boxes are for box metrics, never touched.
        let mut proposals: Vec<CocoResult> = Vec::new();
        let on_frame = |image: &CocoImage,
                        detections: &[crate::Detection],
                        map: Option<&CrackMap>|
         -> Result<(), VisionError> {
            let counted = detections
                .iter()
                .filter(|d| d.score >= threshold && d.source == DetectionSource::Primary);
            proposals.extend(
                counted
                    .clone()
                    .map(|d| coco_result(image.id, self.category, d)),
            );
            let own = counted
                .filter_map(|d| d.shape.as_ref())
                .flat_map(|s| s.pieces.iter().cloned());
            pieces.entry(image.id).or_default().extend(own);
            let (Some(mask_file), Some(map)) = (&image.mask_file, map) else {
                return Ok(());
            };
            let truth = read_mask(&root.join(mask_file), image.width, image.height)?;
            let prob = map.to_image();
            let size = (image.width as usize, image.height as usize);
            for e in &mut pixel {
                e.add(&prob, &truth, size.0, size.1)?;
            }
            cracks.add(&prob, &truth, size.0, size.1)
        };
        let results = detect_dataset_with_maps(
            &mut timed,
            &self.gt,
            &self.root,
            self.category,
            progress,
            on_frame,
        )?;
        let metrics = evaluate(&self.gt, &results)?;
        let scene = match &self.scene_truth {
            Some(truth) => Some(scene_recall(
                &self.gt,
                truth,
                &proposals,
                threshold,
                (!pieces.values().all(Vec::is_empty)).then_some(&pieces),
            )?),
            None => None,
        };
        Ok(BenchmarkRun {
            scene,
            detector: timed.name(),
            median_ms: timed.median_ms(),
            results,
            metrics,
            pixel: pixel.iter().filter_map(PixelEvaluator::finish).collect(),
            cracks: cracks.finish(),
        })
    }
}

/// What `crackbot eval-detector` reports (its `--json` object).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalReport {
    /// The twelve COCO metrics (top-level keys `map`, `map50`, …).
    #[serde(flatten)]
    pub metrics: CocoMetrics,
    /// The detector's name.
    pub detector: String,
    /// The ground-truth file.
    pub coco: String,
    /// Images evaluated.
    pub images: usize,
    /// Ground-truth boxes.
    pub ground_truth_boxes: usize,
    /// Detections made.
    pub detections: usize,
    /// Median milliseconds per image.
    pub ms_per_image: f64,
    /// What `ms_per_image` measures.
    pub ms_per_image_is: &'static str,
    /// Pixel-level precision/recall/F1 of the crack map where the ground truth has masks.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pixel: Vec<PixelMetrics>,
    /// Cracks of the masks the crack map covers (crack-level recall), where the ground truth
    /// has masks.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cracks: Option<CrackRecall>,
    /// Cracks found and decoys proposed, on rendered frames with a `features.json`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneRecall>,
}

impl EvalReport {
    /// The report of `run` on `bench`.
    pub fn new(bench: &Benchmark, run: &BenchmarkRun) -> Self {
        EvalReport {
            metrics: run.metrics,
            detector: run.detector.clone(),
            coco: bench.coco.display().to_string(),
            images: bench.gt.images.len(),
            ground_truth_boxes: bench.gt.annotations.len(),
            detections: run.results.len(),
            ms_per_image: run.median_ms,
            ms_per_image_is: "median of one detect call, image decoding excluded",
            pixel: run.pixel.clone(),
            cracks: run.cracks,
            scene: run.scene.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coco::{CocoAnnotation, CocoCategory, CocoImage};

    struct Whole;
    impl Detector for Whole {
        fn name(&self) -> String {
            "whole".into()
        }
        fn detect(&mut self, image: &image::RgbImage) -> Result<Vec<Detection>, VisionError> {
            let (w, h) = image.dimensions();
            Ok(vec![Detection {
                bbox: crate::BoundingBox::from_xywh(0.0, 0.0, w as f32, h as f32),
                score: 0.9,
                shape: None,
                source: crate::DetectionSource::Primary,
            }])
        }
    }

    #[test]
    fn a_benchmark_reports_metrics_and_a_median_time() {
        let dir = tempfile::tempdir().unwrap();
        image::RgbImage::new(8, 6)
            .save(dir.path().join("a.png"))
            .unwrap();
        let gt = CocoDataset {
            images: vec![CocoImage::new(1, "a.png", 8, 6)],
            annotations: vec![CocoAnnotation::from_bbox(1, 1, 3, [0.0, 0.0, 8.0, 6.0])],
            categories: vec![CocoCategory {
                id: 3,
                name: "crack".into(),
                supercategory: None,
            }],
            ..CocoDataset::default()
        };
        let path = dir.path().join("gt.json");
        gt.save(&path).unwrap();
        let bench = Benchmark::load(&path, None).unwrap();
        assert_eq!((bench.category, bench.root.as_path()), (3, dir.path()));
        let run = bench.run(&mut Whole, |_| {}).unwrap();
        assert_eq!(run.results.len(), 1);
        assert!((run.metrics.map50 - 1.0).abs() < 1e-12);
        assert!(run.median_ms >= 0.0);
        let report = serde_json::to_value(EvalReport::new(&bench, &run)).unwrap();
        for key in [
            "map",
            "ar100",
            "detector",
            "coco",
            "images",
            "ms_per_image_is",
        ] {
            assert!(report.get(key).is_some(), "{key}: {report}");
        }
        let mut none = gt.clone();
        none.categories.clear();
        none.annotations.clear();
        none.save(&path).unwrap();
        let err = Benchmark::load(&path, None).unwrap_err();
        assert!(err.to_string().contains("no categories"), "{err}");
    }
}
