//! A detector benchmarked on a COCO ground truth: its detections, their COCO metrics and the
//! median time of one `detect` call; the `crackbot eval-detector` report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::coco::{detect_dataset, evaluate, CocoDataset, CocoMetrics, CocoResult, Progress};
use crate::preprocess::PostprocessParams;
use crate::{Detection, Detector, VisionError};

/// Post-processing for mAP: every candidate down to a score of 0.001, as COCO evaluations do.
pub fn map_params() -> PostprocessParams {
    PostprocessParams {
        score_threshold: 0.001,
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
                .map(Path::to_path_buf)
                .unwrap_or_else(|| PathBuf::from(".")),
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
        Ok(Self {
            coco: coco.to_path_buf(),
            gt,
            root,
            category,
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
        let results = detect_dataset(&mut timed, &self.gt, &self.root, self.category, progress)?;
        let metrics = evaluate(&self.gt, &results)?;
        Ok(BenchmarkRun {
            detector: timed.name(),
            median_ms: timed.median_ms(),
            results,
            metrics,
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
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
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
