//! Figures of the tactile pipeline's research results: confusion-matrix heat maps, the paper's
//! Fig. 10-style accuracy box plots of the intersession grid, and the random forest's accuracy
//! against its prediction latency.

use std::path::{Path, PathBuf};

use crackbot_tactile::metrics::ConfusionMatrix;
use crackbot_tactile::paper::{paper_reference, CellResult, PaperTables};
use crackbot_tactile::tradeoff::{depth_name, Tradeoff};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::{render, text_style, PlotError, FONT};

/// Size of [`confusion_png`] images, pixels (width, height).
pub const CONFUSION_SIZE: (u32, u32) = (760, 700);
/// Size of [`accuracy_boxplot_png`] images, pixels (width, height).
pub const BOXPLOT_SIZE: (u32, u32) = (1000, 580);
/// Size of [`tradeoff_png`] images, pixels (width, height).
pub const TRADEOFF_SIZE: (u32, u32) = (1300, 600);

/// Colour of a row fraction in a white → dark blue ramp.
fn heat(f: f64) -> RGBColor {
    let f = f.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64| (a + (b - a) * f).round() as u8;
    RGBColor(lerp(247.0, 8.0), lerp(251.0, 48.0), lerp(255.0, 107.0))
}

/// Draws `matrix` as a heat map (rows: true classes, columns: predicted classes; colour: the
/// fraction of the row, i.e. the class recall on the diagonal) with the count and the row
/// percentage in every cell, and writes it to `path` ([`CONFUSION_SIZE`]).
pub fn confusion_png<S: AsRef<str>>(
    path: &Path,
    matrix: &ConfusionMatrix,
    class_names: &[S],
    title: &str,
) -> Result<(), PlotError> {
    let n = matrix.n_classes();
    if n == 0 || class_names.len() != n {
        return Err(PlotError::ClassNames {
            path: path.to_path_buf(),
            names: class_names.len(),
            classes: n,
        });
    }
    let rows = matrix.rows();
    render(path, CONFUSION_SIZE, |root| {
        let (w, h) = (CONFUSION_SIZE.0 as i32, CONFUSION_SIZE.1 as i32);
        root.draw(&Text::new(
            title.to_string(),
            (w / 2, 14),
            text_style(22, BLACK, HPos::Center, VPos::Top),
        ))?;
        root.draw(&Text::new(
            format!(
                "accuracy {:.2}% over {} samples; colour and % = share of the true class's row",
                100.0 * matrix.accuracy(),
                matrix.total()
            ),
            (w / 2, 44),
            text_style(16, RGBColor(80, 80, 80), HPos::Center, VPos::Top),
        ))?;
        let (left, top, right, bottom) = (160, 80, 30, 90);
        let cell = ((w - left - right) / n as i32).min((h - top - bottom) / n as i32);
        let x0 = left + (w - left - right - cell * n as i32) / 2;
        let y0 = top;
        // Even sizes: plotters' ab_glyph renderer rounds odd half-sizes unevenly per glyph.
        let value_size = if cell >= 90 { 20 } else { 16 };
        for (t, row) in rows.iter().enumerate() {
            let total: u64 = row.iter().sum();
            for (p, &count) in row.iter().enumerate() {
                let f = if total == 0 {
                    0.0
                } else {
                    count as f64 / total as f64
                };
                let (cx, cy) = (x0 + p as i32 * cell, y0 + t as i32 * cell);
                root.draw(&Rectangle::new(
                    [(cx, cy), (cx + cell, cy + cell)],
                    heat(f).filled(),
                ))?;
                root.draw(&Rectangle::new(
                    [(cx, cy), (cx + cell, cy + cell)],
                    RGBColor(200, 200, 200).stroke_width(1),
                ))?;
                let ink = if f > 0.65 { WHITE } else { BLACK };
                root.draw(&Text::new(
                    count.to_string(),
                    (cx + cell / 2, cy + cell / 2 - 2),
                    text_style(value_size, ink, HPos::Center, VPos::Bottom),
                ))?;
                root.draw(&Text::new(
                    format!("{:.1}%", 100.0 * f),
                    (cx + cell / 2, cy + cell / 2 + 4),
                    text_style(value_size - 4, ink, HPos::Center, VPos::Top),
                ))?;
            }
        }
        root.draw(&Rectangle::new(
            [(x0, y0), (x0 + cell * n as i32, y0 + cell * n as i32)],
            BLACK.stroke_width(1),
        ))?;
        for (i, name) in class_names.iter().enumerate() {
            let c = i as i32 * cell + cell / 2;
            root.draw(&Text::new(
                name.as_ref().to_string(),
                (x0 + c, y0 + n as i32 * cell + 8),
                text_style(16, BLACK, HPos::Center, VPos::Top),
            ))?;
            root.draw(&Text::new(
                name.as_ref().to_string(),
                (x0 - 8, y0 + c),
                text_style(16, BLACK, HPos::Right, VPos::Center),
            ))?;
        }
        root.draw(&Text::new(
            "predicted class",
            (x0 + n as i32 * cell / 2, y0 + n as i32 * cell + 40),
            text_style(18, BLACK, HPos::Center, VPos::Top),
        ))?;
        root.draw(&Text::new(
            "true class",
            (22, y0 + n as i32 * cell / 2),
            TextStyle::from((FONT, 18).into_font().transform(FontTransform::Rotate270))
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
        Ok(())
    })
}

/// The `q`-quantile of sorted values, linearly interpolated (numpy's default).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// Five numbers of a box: lower whisker, Q1, median, Q3, upper whisker (whiskers reach the
/// furthest value within 1.5 IQR of the box, as matplotlib's).
fn box_stats(values: &[f64]) -> Option<[f64; 5]> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let (q1, med, q3) = (quantile(&v, 0.25), quantile(&v, 0.5), quantile(&v, 0.75));
    let iqr = q3 - q1;
    let lo = v
        .iter()
        .copied()
        .find(|&x| x >= q1 - 1.5 * iqr)
        .unwrap_or(q1);
    let hi = v
        .iter()
        .rev()
        .copied()
        .find(|&x| x <= q3 + 1.5 * iqr)
        .unwrap_or(q3);
    Some([lo, q1, med, q3, hi])
}

const SERIES_COLOURS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

fn first_seen<'a>(values: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for v in values {
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

/// Box plots of the pair accuracies (window level, %) of one classifier of `tables`, grouped by
/// channel set, one box per feature (as the paper's Fig. 10); every pair is drawn as a dot, and
/// for the random forest the paper's mean is marked with a cross. Writes [`BOXPLOT_SIZE`].
pub fn accuracy_boxplot_png(
    path: &Path,
    tables: &PaperTables,
    classifier: &str,
) -> Result<(), PlotError> {
    let cells: Vec<&CellResult> = tables
        .cells
        .iter()
        .filter(|c| c.classifier == classifier)
        .collect();
    if cells.is_empty() {
        return Err(PlotError::NoResults {
            path: path.to_path_buf(),
            classifier: classifier.to_string(),
        });
    }
    let sets = first_seen(cells.iter().map(|c| c.set.as_str()));
    let features = first_seen(cells.iter().map(|c| c.feature.as_str()));
    let reference = if classifier == "RF" {
        paper_reference(tables.experiment)
    } else {
        &[]
    };
    let all: Vec<f64> = cells
        .iter()
        .flat_map(|c| c.pairs.iter().map(|p| 100.0 * p.window_accuracy))
        .chain(reference.iter().map(|r| r.2))
        .collect();
    let lowest = all.iter().copied().fold(100.0, f64::min);
    let y_lo = ((lowest / 5.0).floor() * 5.0 - 5.0).max(0.0);
    let nf = features.len() as f64;
    let slot = 0.8 / nf;
    let box_w = slot * 0.6;
    let x_of = |s: usize, f: usize| s as f64 + 0.1 + slot * (f as f64 + 0.5);
    render(path, BOXPLOT_SIZE, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!(
                    "{} experiment, {classifier}: window accuracy of each train → test repetition pair",
                    tables.experiment.name()
                ),
                (FONT, 22),
            )
            .margin(16)
            .x_label_area_size(64)
            .y_label_area_size(64)
            .build_cartesian_2d(0f64..sets.len() as f64, y_lo..100.5)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .y_desc("window accuracy (%)")
            .y_label_formatter(&|v| format!("{v:.0}"))
            .axis_desc_style((FONT, 18))
            .label_style((FONT, 16))
            .draw()?;
        for (fi, feature) in features.iter().enumerate() {
            let colour = SERIES_COLOURS[fi % SERIES_COLOURS.len()];
            let mut boxes = Vec::new();
            let mut lines = Vec::new();
            let mut dots = Vec::new();
            for (si, set) in sets.iter().enumerate() {
                let Some(cell) = cells
                    .iter()
                    .find(|c| c.set == *set && c.feature == *feature)
                else {
                    continue;
                };
                let acc: Vec<f64> = cell
                    .pairs
                    .iter()
                    .map(|p| 100.0 * p.window_accuracy)
                    .collect();
                let x = x_of(si, fi);
                if let Some([lo, q1, med, q3, hi]) = box_stats(&acc) {
                    let (l, r) = (x - box_w / 2.0, x + box_w / 2.0);
                    boxes.push(Rectangle::new([(l, q1), (r, q3)], colour.mix(0.3).filled()));
                    lines.push(PathElement::new(
                        vec![(l, q1), (r, q1), (r, q3), (l, q3), (l, q1)],
                        colour.stroke_width(2),
                    ));
                    lines.push(PathElement::new(
                        vec![(l, med), (r, med)],
                        BLACK.stroke_width(3),
                    ));
                    for (a, b) in [(q3, hi), (q1, lo)] {
                        lines.push(PathElement::new(
                            vec![(x, a), (x, b)],
                            colour.stroke_width(2),
                        ));
                        lines.push(PathElement::new(
                            vec![(x - box_w / 4.0, b), (x + box_w / 4.0, b)],
                            colour.stroke_width(2),
                        ));
                    }
                }
                let k = acc.len().max(2) as f64 - 1.0;
                for (i, &a) in acc.iter().enumerate() {
                    let jitter = (i as f64 / k - 0.5) * box_w * 0.6;
                    dots.push(Circle::new((x + jitter, a), 3, BLACK.mix(0.7).filled()));
                }
            }
            chart
                .draw_series(boxes)?
                .label(feature.to_string())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 7), (x + 16, y + 7)], colour.mix(0.6).filled())
                });
            chart.draw_series(lines)?;
            chart.draw_series(dots)?;
        }
        let crosses: Vec<_> = reference
            .iter()
            .filter_map(|(f, s, v)| {
                let fi = features.iter().position(|x| x == f)?;
                let si = sets.iter().position(|x| x == s)?;
                Some(Cross::new((x_of(si, fi), *v), 7, RED.stroke_width(2)))
            })
            .collect();
        if !crosses.is_empty() {
            chart
                .draw_series(crosses)?
                .label("paper, mean (RF)")
                .legend(|(x, y)| Cross::new((x + 8, y), 6, RED.stroke_width(2)));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font((FONT, 16))
            .draw()?;
        for (si, set) in sets.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(si as f64 + 0.5, y_lo));
            root.draw(&Text::new(
                set.to_string(),
                (px, py + 10),
                text_style(18, BLACK, HPos::Center, VPos::Top),
            ))?;
            if si > 0 {
                let (sx, top) = chart.backend_coord(&(si as f64, 100.5));
                root.draw(&PathElement::new(
                    vec![(sx, top), (sx, py)],
                    RGBColor(190, 190, 190).stroke_width(1),
                ))?;
            }
        }
        let (px, py) = chart.backend_coord(&(sets.len() as f64 / 2.0, y_lo));
        root.draw(&Text::new(
            "channel set (boxes: features; dots: the pairs)",
            (px, py + 36),
            text_style(16, RGBColor(60, 60, 60), HPos::Center, VPos::Top),
        ))?;
        Ok(())
    })
}

/// The random forest's accuracy against its median single-window latency, one line per depth
/// limit, each point labelled with its number of trees: window accuracy on the left, slide
/// accuracy on the right. Writes [`TRADEOFF_SIZE`].
pub fn tradeoff_png(path: &Path, tradeoff: &Tradeoff) -> Result<(), PlotError> {
    let rows = &tradeoff.rows;
    if rows.is_empty() {
        return Err(PlotError::NothingToPlot {
            path: path.to_path_buf(),
        });
    }
    let us: Vec<f64> = rows.iter().map(|r| 1e6 * r.latency_seconds).collect();
    let x_lo = us.iter().copied().fold(f64::INFINITY, f64::min).max(1e-3) / 1.5;
    let x_hi = us.iter().copied().fold(0.0, f64::max).max(x_lo * 2.0) * 1.5;
    let mut depths: Vec<Option<usize>> = Vec::new();
    for r in rows {
        if !depths.contains(&r.max_depth) {
            depths.push(r.max_depth);
        }
    }
    render(path, TRADEOFF_SIZE, |root| {
        let (title, body) = root.split_vertically(44);
        title.draw(&Text::new(
            format!(
                "{} experiment, random forest: accuracy vs single-window latency (one thread)",
                tradeoff.experiment.name()
            ),
            (TRADEOFF_SIZE.0 as i32 / 2, 12),
            text_style(22, BLACK, HPos::Center, VPos::Top),
        ))?;
        let halves = body.split_evenly((1, 2));
        for (half, (name, value)) in halves.iter().zip([
            (
                "window accuracy (%)",
                (|r| r.window_accuracy) as fn(&crackbot_tactile::tradeoff::TradeoffRow) -> f64,
            ),
            ("slide accuracy (%)", |r| r.slide_accuracy),
        ]) {
            let ys: Vec<f64> = rows.iter().map(|r| 100.0 * value(r)).collect();
            let lo = ys.iter().copied().fold(100.0, f64::min);
            let hi = ys.iter().copied().fold(0.0, f64::max);
            let y_lo = ((lo / 5.0).floor() * 5.0 - 2.0).max(0.0);
            let y_hi = ((hi / 5.0).ceil() * 5.0 + 2.0).min(100.5);
            let mut chart = ChartBuilder::on(half)
                .margin(14)
                .x_label_area_size(50)
                .y_label_area_size(60)
                .build_cartesian_2d((x_lo..x_hi).log_scale(), y_lo..y_hi)?;
            chart
                .configure_mesh()
                .x_desc("median latency per window (µs, log scale)")
                .y_desc(name)
                .x_label_formatter(&|v| {
                    if *v >= 10.0 {
                        format!("{v:.0}")
                    } else {
                        format!("{v:.1}")
                    }
                })
                .y_label_formatter(&|v| format!("{v:.0}"))
                .axis_desc_style((FONT, 16))
                .label_style((FONT, 14))
                .draw()?;
            for (di, depth) in depths.iter().enumerate() {
                let colour = SERIES_COLOURS[di % SERIES_COLOURS.len()];
                let mut pts: Vec<(f64, f64, usize)> = rows
                    .iter()
                    .filter(|r| r.max_depth == *depth)
                    .map(|r| (1e6 * r.latency_seconds, 100.0 * value(r), r.n_trees))
                    .collect();
                pts.sort_by_key(|p| p.2);
                chart
                    .draw_series(LineSeries::new(
                        pts.iter().map(|p| (p.0, p.1)),
                        colour.stroke_width(2),
                    ))?
                    .label(format!("max depth {}", depth_name(*depth)))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(3))
                    });
                chart.draw_series(
                    pts.iter()
                        .map(|p| Circle::new((p.0, p.1), 4, colour.filled())),
                )?;
                chart.draw_series(pts.iter().map(|p| {
                    EmptyElement::at((p.0, p.1))
                        + Text::new(
                            p.2.to_string(),
                            (5, 3),
                            text_style(12, colour, HPos::Left, VPos::Top),
                        )
                }))?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font((FONT, 14))
                .draw()?;
        }
        Ok(())
    })
}

/// A written figure.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotFile {
    /// Where it was written.
    pub path: PathBuf,
    /// What it shows.
    pub caption: String,
}

/// File-name form of a cell: `rf-mav-d1d2p`.
fn slug(parts: &[&str]) -> String {
    parts
        .iter()
        .map(|p| {
            p.chars()
                .filter(char::is_ascii_alphanumeric)
                .collect::<String>()
                .to_ascii_lowercase()
        })
        .collect::<Vec<_>>()
        .join("-")
}

/// The figures of one experiment of the paper's grid, written into `dir` (which must exist):
/// the confusion matrix (summed over the pairs) of the random forest on MAV D1D2+P and of the
/// best cell of every classifier, and one accuracy box plot per classifier.
pub fn paper_plots(dir: &Path, tables: &PaperTables) -> Result<Vec<PlotFile>, PlotError> {
    let exp = tables.experiment.name();
    let mut chosen: Vec<&CellResult> = Vec::new();
    if let Some(c) = tables
        .cells
        .iter()
        .find(|c| c.classifier == "RF" && c.feature == "MAV" && c.set == "D1D2+P")
    {
        chosen.push(c);
    }
    let classifiers = first_seen(tables.cells.iter().map(|c| c.classifier.as_str()));
    for clf in &classifiers {
        let best = tables
            .cells
            .iter()
            .filter(|c| c.classifier == *clf)
            .max_by(|a, b| a.accuracy_mean.total_cmp(&b.accuracy_mean));
        if let Some(b) = best {
            if !chosen.iter().any(|c| std::ptr::eq(*c, b)) {
                chosen.push(b);
            }
        }
    }
    let mut out = Vec::new();
    for c in chosen {
        let path = dir.join(format!(
            "confusion-{exp}-{}.png",
            slug(&[&c.classifier, &c.feature, &c.set])
        ));
        let best = tables
            .cells
            .iter()
            .filter(|x| x.classifier == c.classifier)
            .all(|x| x.accuracy_mean <= c.accuracy_mean);
        let title = format!(
            "{exp}: {} on {} {}, windows of all {} test pairs",
            c.classifier,
            c.feature,
            c.set,
            c.pairs.len()
        );
        confusion_png(&path, &c.confusion, &tables.classes, &title)?;
        out.push(PlotFile {
            path,
            caption: format!(
                "confusion matrix, {} {} {}{} (windows, summed over the pairs)",
                c.classifier,
                c.feature,
                c.set,
                if best {
                    format!(", the best {} cell", c.classifier)
                } else {
                    String::new()
                }
            ),
        });
    }
    for clf in &classifiers {
        let path = dir.join(format!("accuracy-{exp}-{}.png", slug(&[clf])));
        accuracy_boxplot_png(&path, tables, clf)?;
        out.push(PlotFile {
            path,
            caption: format!("{clf}: pair accuracies per channel set and feature (box plots)"),
        });
    }
    Ok(out)
}

/// A Markdown list of `files`, linked relative to `dir` (the folder of the Markdown file).
pub fn plots_markdown(files: &[PlotFile], dir: &Path) -> String {
    let mut md = String::from("Plots:\n\n");
    for f in files {
        let rel = f.path.strip_prefix(dir).unwrap_or(&f.path);
        md.push_str(&format!(
            "- [{}]({}) — {}\n",
            rel.display(),
            rel.display(),
            f.caption
        ));
    }
    md.push('\n');
    md
}
