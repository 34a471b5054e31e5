//! Exports: the visible range of the tactile channels to CSV, the mission report to JSON, and a
//! screenshot to PNG. Pure functions that produce bytes, and a writer that runs off the UI
//! thread.

use std::collections::VecDeque;
use std::io::Write;
use std::path::{Path, PathBuf};

use crackbot_telemetry::wire::TactileSample;

use crate::OperatorError;

/// The samples with `t0 <= t_s <= t1` as CSV: `t_s,d1,d2,d3,p`, one row per sample.
pub fn tactile_csv(samples: &VecDeque<TactileSample>, t0: f64, t1: f64) -> String {
    let range =
        crate::decimate::visible_range(samples, t0, f64::from_bits(t1.to_bits() + 1), |s| s.t_s);
    let mut out = String::with_capacity(32 * range.len() + 32);
    out.push_str("t_s,d1,d2,d3,p\n");
    for s in samples.range(range) {
        use std::fmt::Write as _;
        let _ = writeln!(
            out,
            "{:.6},{},{},{},{}",
            s.t_s, s.raw[0], s.raw[1], s.raw[2], s.raw[3]
        );
    }
    out
}

/// The report JSON, indented (it arrives compact in the mission's status).
pub fn report_json(report: &str) -> Result<String, OperatorError> {
    let v: serde_json::Value = serde_json::from_str(report)?;
    Ok(serde_json::to_string_pretty(&v)?)
}

/// An RGBA image as PNG bytes.
pub fn png(width: usize, height: usize, rgba: &[u8]) -> Result<Vec<u8>, OperatorError> {
    let img = image::RgbaImage::from_raw(width as u32, height as u32, rgba.to_vec()).ok_or_else(
        || OperatorError::Screenshot {
            reason: format!("{width}×{height} px and {} bytes disagree", rgba.len()),
        },
    )?;
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .map_err(|e| OperatorError::Screenshot {
            reason: e.to_string(),
        })?;
    Ok(out.into_inner())
}

/// A window screenshot (egui's premultiplied colours) as PNG bytes.
pub fn screenshot_png(img: &egui::ColorImage) -> Result<Vec<u8>, OperatorError> {
    let [w, h] = img.size;
    let rgba: Vec<u8> = img
        .pixels
        .iter()
        .flat_map(egui::Color32::to_srgba_unmultiplied)
        .collect();
    png(w, h, &rgba)
}

/// Writes `bytes` to `path` (creating its folder), atomically: a temporary file renamed.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OperatorError> {
    let io = |e: std::io::Error| OperatorError::Io {
        path: path.to_path_buf(),
        source: e,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let tmp = path.with_extension("part");
    let mut f = std::fs::File::create(&tmp).map_err(io)?;
    f.write_all(bytes).map_err(io)?;
    f.sync_all().map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

/// Writes on a thread; the result comes back on `done` as a line for the UI's log.
pub fn write_in_background(
    path: PathBuf,
    bytes: Vec<u8>,
    done: std::sync::mpsc::Sender<String>,
    wake: Option<egui::Context>,
) {
    std::thread::spawn(move || {
        let msg = match write_file(&path, &bytes) {
            Ok(()) => format!("saved {} ({} bytes)", path.display(), bytes.len()),
            Err(e) => format!("export failed: {e}"),
        };
        let _ = done.send(msg);
        if let Some(ctx) = wake {
            ctx.request_repaint();
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_csv_holds_exactly_the_visible_samples() {
        let s: VecDeque<TactileSample> = (0..1000)
            .map(|i| TactileSample {
                t_s: i as f64 / 400.0,
                raw: [i as u16, 1, 2, 3],
            })
            .collect();
        let csv = tactile_csv(&s, 0.5, 1.0);
        let rows: Vec<&str> = csv.lines().collect();
        assert_eq!(rows[0], "t_s,d1,d2,d3,p");
        // 0.5 s .. 1.0 s inclusive at 400 Hz: samples 200..=400.
        assert_eq!(rows.len() - 1, 201);
        assert!(rows[1].starts_with("0.500000,200,"));
        assert!(rows.last().unwrap().starts_with("1.000000,400,"));
    }

    #[test]
    fn a_bad_report_is_an_error_not_a_panic() {
        assert!(report_json("{not json").is_err());
        let pretty = report_json(r#"{"cracks":[]}"#).unwrap();
        assert!(pretty.contains("\"cracks\": []"));
    }

    #[test]
    fn png_round_trips_and_checks_its_size() {
        let bytes = png(2, 1, &[255, 0, 0, 255, 0, 255, 0, 255]).unwrap();
        let img = image::load_from_memory(&bytes).unwrap().to_rgba8();
        assert_eq!(img.dimensions(), (2, 1));
        assert!(png(3, 3, &[0; 4]).is_err());
    }

    #[test]
    fn a_screenshot_keeps_its_size_and_colours() {
        let img = egui::ColorImage::new(
            [2, 1],
            vec![
                egui::Color32::from_rgb(200, 10, 30),
                egui::Color32::from_rgba_unmultiplied(0, 0, 255, 255),
            ],
        );
        let back = image::load_from_memory(&screenshot_png(&img).unwrap())
            .unwrap()
            .to_rgba8();
        assert_eq!(back.dimensions(), (2, 1));
        assert_eq!(back.get_pixel(0, 0).0, [200, 10, 30, 255]);
        assert_eq!(back.get_pixel(1, 0).0, [0, 0, 255, 255]);
    }
}
