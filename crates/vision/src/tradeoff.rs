//! `crackbot detector-tradeoff`: accuracy (COCO mAP) against run time for the trained models of
//! several input sizes and the classical baseline, as rows, a markdown table and JSON.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::benchmark::{Benchmark, BenchmarkRun};
use crate::classical::{ClassicalDetector, ClassicalParams};
use crate::coco::Progress;
use crate::{Detector, VisionError};

/// One row of the detector trade-off.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TradeoffRow {
    /// The detector's name.
    pub detector: String,
    /// The model's square input size, pixels (`None` for the classical baseline).
    pub input_size: Option<usize>,
    /// mAP@[.5:.95].
    pub map: f64,
    /// mAP@0.5.
    pub map50: f64,
    /// AR@100.
    pub ar100: f64,
    /// Median milliseconds of one `detect` call.
    pub ms_per_frame: f64,
}

impl TradeoffRow {
    /// The row of a benchmark run.
    pub fn new(run: &BenchmarkRun, input_size: Option<usize>) -> Self {
        TradeoffRow {
            detector: run.detector.clone(),
            input_size,
            map: run.metrics.map,
            map50: run.metrics.map50,
            ar100: run.metrics.ar100,
            ms_per_frame: run.median_ms,
        }
    }
}

/// What to compare.
#[derive(Debug, Clone)]
pub struct TradeoffConfig {
    /// ONNX models (e.g. [`trained_models`](crate::model::trained_models)).
    pub models: Vec<PathBuf>,
    /// Include the classical baseline.
    pub classical: bool,
    /// ONNX Runtime threads.
    pub threads: usize,
}

/// The trade-off: where it was measured and one row per detector.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TradeoffReport {
    /// The ground-truth file.
    pub coco: String,
    /// Images in it.
    pub images: usize,
    /// Ground-truth boxes in it.
    pub boxes: usize,
    /// ONNX Runtime threads.
    pub threads: usize,
    /// One row per detector, models first.
    pub rows: Vec<TradeoffRow>,
}

/// Runs every detector of `config` over `bench`. `progress(detector, p)` is called as
/// [`Benchmark::run`] calls its callback; `on_row` with each finished row.
pub fn detector_tradeoff(
    bench: &Benchmark,
    config: &TradeoffConfig,
    mut progress: impl FnMut(&str, &Progress<'_>),
    mut on_row: impl FnMut(&TradeoffRow),
) -> Result<TradeoffReport, VisionError> {
    let mut rows = Vec::new();
    let mut measure = |d: &mut dyn Detector, size: Option<usize>| -> Result<(), VisionError> {
        let name = d.name();
        let run = bench.run(d, |p| progress(&name, p))?;
        let row = TradeoffRow::new(&run, size);
        on_row(&row);
        rows.push(row);
        Ok(())
    };
    #[cfg(feature = "onnx")]
    for m in &config.models {
        let mut d =
            crate::onnx::OnnxDetector::load(m, crate::benchmark::map_params(), config.threads)?;
        let size = d.input_size();
        measure(&mut d, Some(size))?;
    }
    #[cfg(not(feature = "onnx"))]
    if let Some(m) = config.models.first() {
        return Err(VisionError::Runtime(format!(
            "{}: crackbot-vision was built without the `onnx` feature",
            m.display()
        )));
    }
    if config.classical {
        let mut d = ClassicalDetector::new(ClassicalParams::default())?;
        measure(&mut d, None)?;
    }
    Ok(TradeoffReport {
        coco: bench.coco.display().to_string(),
        images: bench.gt.images.len(),
        boxes: bench.gt.annotations.len(),
        threads: config.threads,
        rows,
    })
}

impl TradeoffReport {
    /// The report as markdown: how it was measured, one table row per detector, and the plot
    /// `tradeoff.png` beside it.
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "# Crack detector: accuracy against run time (`crackbot detector-tradeoff`)\n\n\
             On {} ({} images, {} boxes); {} ONNX Runtime thread(s); ms = median of one `detect` call \
             (letterbox + model + NMS), image decoding excluded.\n\n\
             | detector | input | mAP@0.5 | mAP@[.5:.95] | AR@100 | ms/frame |\n|---|---|---|---|---|---|\n",
            self.coco, self.images, self.boxes, self.threads
        );
        for r in &self.rows {
            md += &format!(
                "| {} | {} | {:.3} | {:.3} | {:.3} | {:.1} |\n",
                r.detector,
                r.input_size.map_or("–".to_string(), |s| format!("{s}×{s}")),
                r.map50,
                r.map,
                r.ar100,
                r.ms_per_frame
            );
        }
        md += "\n![mAP50 against ms per frame](tradeoff.png)\n";
        md
    }

    /// Writes `dir/tradeoff.md` ([`TradeoffReport::markdown`]) and `dir/tradeoff.json` (the
    /// rows) into the existing folder `dir`; returns the markdown and both paths.
    pub fn write(&self, dir: &Path) -> Result<(String, PathBuf, PathBuf), VisionError> {
        let md = self.markdown();
        let md_path = dir.join("tradeoff.md");
        std::fs::write(&md_path, &md).map_err(VisionError::io(&md_path))?;
        let json_path = dir.join("tradeoff.json");
        let json = serde_json::to_string_pretty(&self.rows).map_err(|e| VisionError::Encode {
            what: "the trade-off rows",
            message: e.to_string(),
        })?;
        std::fs::write(&json_path, json).map_err(VisionError::io(&json_path))?;
        Ok((md, md_path, json_path))
    }
}
