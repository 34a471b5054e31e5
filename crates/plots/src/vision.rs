//! Figures of the crack detector: accuracy against run time.

use std::path::Path;

use crackbot_vision::tradeoff::TradeoffRow;
use plotters::prelude::*;

use crate::{render, PlotError, FONT};

/// Size of [`detector_tradeoff_png`] images, pixels (width, height).
pub const DETECTOR_TRADEOFF_SIZE: (u32, u32) = (900, 600);

/// The detector's accuracy against its run time: mAP@0.5 against ms per frame, the ONNX models
/// (by input size) as a line, the classical baseline as a red point.
pub fn detector_tradeoff_png(path: &Path, rows: &[TradeoffRow]) -> Result<(), PlotError> {
    render(path, DETECTOR_TRADEOFF_SIZE, |root| {
        let x_max = rows
            .iter()
            .map(|r| r.ms_per_frame)
            .filter(|v| v.is_finite())
            .fold(1.0f64, f64::max)
            * 1.2;
        let mut chart = ChartBuilder::on(root)
            .caption("Crack detector: mAP@0.5 against ms per frame", (FONT, 24))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(0f64..x_max, 0f64..1f64)?;
        chart
            .configure_mesh()
            .x_desc("ms per frame (one core)")
            .y_desc("mAP@0.5")
            .label_style((FONT, 16))
            .draw()?;
        let onnx: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.input_size.is_some())
            .map(|r| (r.ms_per_frame, r.map50))
            .collect();
        chart.draw_series(LineSeries::new(onnx.clone(), BLUE.stroke_width(2)))?;
        for r in rows {
            let colour = if r.input_size.is_some() { BLUE } else { RED };
            let label = r
                .input_size
                .map_or(r.detector.clone(), |s| format!("{s}×{s}"));
            chart.draw_series(std::iter::once(Circle::new(
                (r.ms_per_frame, r.map50),
                6,
                colour.filled(),
            )))?;
            chart.draw_series(std::iter::once(Text::new(
                label,
                (r.ms_per_frame, r.map50 + 0.03),
                (FONT, 16),
            )))?;
        }
        Ok(())
    })
}
