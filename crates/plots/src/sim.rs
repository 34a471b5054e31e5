//! Figures of the simulator: the integrators' work-precision diagram and real against simulated
//! slides.

use std::path::Path;

use crackbot_protocol::Channel;
use crackbot_sim::recordings::Comparison;
use crackbot_sim::work_precision::WorkPrecisionRow;
use plotters::prelude::*;

use crate::{render, PlotError, COLOURS, FONT};

/// Size of [`work_precision_png`] images, pixels (width, height).
pub const WORK_PRECISION_SIZE: (u32, u32) = (1000, 650);

/// The integrators' work-precision diagram: RMS error of the channels against wall milliseconds per
/// simulated second, one line per method family, with the ADC's quantisation for scale.
pub fn work_precision_png(path: &Path, rows: &[WorkPrecisionRow]) -> Result<(), PlotError> {
    let ok: Vec<&WorkPrecisionRow> = rows
        .iter()
        .filter(|r| r.rms_error_counts.is_some_and(f64::is_finite))
        .collect();
    if ok.is_empty() {
        return Err(PlotError::NoFinishedIntegrator {
            path: path.to_path_buf(),
        });
    }
    let err = |r: &WorkPrecisionRow| r.rms_error_counts.unwrap_or(1.0).max(1e-7);
    let (x_lo, x_hi) = ok.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
        (lo.min(r.ms_per_sim_second), hi.max(r.ms_per_sim_second))
    });
    let (y_lo, y_hi) = ok.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
        (lo.min(err(r)), hi.max(err(r)))
    });
    render(path, WORK_PRECISION_SIZE, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                "Work-precision: one slide over a 5 mm crack (error vs DOPRI5 rtol 1e-10)",
                (FONT, 20),
            )
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (x_lo / 1.5..x_hi * 1.5).log_scale(),
                (y_lo / 3.0..y_hi * 3.0).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("wall ms per simulated second (log)")
            .y_desc("RMS error of the channels, ADC counts (log)")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .axis_desc_style((FONT, 16))
            .label_style((FONT, 13))
            .draw()?;
        for (k, fam) in ["sdirk2", "backward-euler", "dopri5", "symplectic-euler"]
            .iter()
            .enumerate()
        {
            let pts: Vec<(f64, f64)> = ok
                .iter()
                .filter(|r| r.family == *fam)
                .map(|r| (r.ms_per_sim_second, err(r)))
                .collect();
            let c = COLOURS[k];
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
                .label(*fam)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(3))
                });
            chart.draw_series(pts.iter().map(|p| Circle::new(*p, 4, c.filled())))?;
        }
        // Quantisation of a 10-bit ADC: an error below this is invisible in the data.
        let q = 1.0 / 12f64.sqrt();
        chart
            .draw_series(LineSeries::new(
                vec![(x_lo / 1.5, q), (x_hi * 1.5, q)],
                BLACK.mix(0.5).stroke_width(1),
            ))?
            .label("ADC quantisation (RMS 0.29 counts)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.5)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT, 14))
            .draw()?;
        Ok(())
    })
}

/// Draws the comparison: one row per class, one column per channel, real in blue and simulated
/// in red.
pub fn compare_png(path: &Path, comparison: &Comparison) -> Result<(), PlotError> {
    let rate = f64::from(crackbot_protocol::SAMPLE_RATE_HZ);
    let n = comparison.classes.len();
    render(path, (1600, 260 * n as u32 + 60), |root| {
        let (title, body) = root.split_vertically(50);
        title.draw(&Text::new(
            format!(
                "slide {} of the first recording per class: real (blue) vs simulated (red)",
                comparison.slide
            ),
            (20, 14),
            (FONT, 22),
        ))?;
        let cells = body.split_evenly((n, 4));
        for (i, class) in comparison.classes.iter().enumerate() {
            let r = &class.real;
            let s = &class.simulated;
            for ch in 0..4 {
                let cell = &cells[i * 4 + ch];
                let vals = r
                    .iter()
                    .chain(s.iter())
                    .flat_map(|v| v.iter().map(move |x| x[ch]));
                let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                });
                if !lo.is_finite() {
                    continue;
                }
                let len = r
                    .as_ref()
                    .map_or(0, std::vec::Vec::len)
                    .max(s.as_ref().map_or(0, std::vec::Vec::len));
                let mut chart = ChartBuilder::on(cell)
                    .caption(
                        format!("{} — {}", class.name, Channel::ALL[ch].name()),
                        (FONT, 15),
                    )
                    .margin(6)
                    .x_label_area_size(22)
                    .y_label_area_size(42)
                    .build_cartesian_2d(0f64..len as f64 / rate, lo - 5.0..hi + 5.0)?;
                chart
                    .configure_mesh()
                    .label_style((FONT, 11))
                    .x_labels(5)
                    .y_labels(5)
                    .draw()?;
                for (series, colour) in [(r, COLOURS[0]), (s, COLOURS[1])] {
                    if let Some(v) = series {
                        chart.draw_series(LineSeries::new(
                            v.iter().enumerate().map(|(k, x)| (k as f64 / rate, x[ch])),
                            colour.stroke_width(1),
                        ))?;
                    }
                }
            }
        }
        Ok(())
    })
}
