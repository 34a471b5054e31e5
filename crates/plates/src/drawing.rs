//! A plate's drawing: an A4 sheet at true scale (the PNG states its pixels per metre, so a
//! printer set to "actual size" prints it 1:1) with the plan view shaded by height, the
//! section along the slide at 1:1 and the feature's detail at 5:1, the dimensions and how the
//! plate is mounted.

use std::path::{Path, PathBuf};

use ab_glyph::{Font, FontVec, PxScale, ScaleFont};
use image::{Rgb, RgbImage};

use crate::error::PlateError;
use crate::set::{ReferencePlate, FEATURE_X_MM, THICKNESS_MM};

/// The sheet: A4 portrait, mm.
const SHEET_MM: [f64; 2] = [210.0, 297.0];
/// Left edge of the plan view and the section, mm.
const LEFT_MM: f64 = 5.0;
/// Top of the plan view, mm.
const PLAN_TOP_MM: f64 = 48.0;
/// Top of the 1:1 section, mm.
const SECTION_TOP_MM: f64 = 160.0;
/// Top of the detail, mm.
const DETAIL_TOP_MM: f64 = 185.0;
/// The detail's scale and half-span around the feature, mm of plate.
const DETAIL: (f64, f64) = (5.0, 18.0);

const INK: Rgb<u8> = Rgb([20, 20, 20]);
const FEATURE: Rgb<u8> = Rgb([200, 40, 40]);

/// The font files tried, `$CRACKBOT_FONT` first.
const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

fn load_font() -> Result<FontVec, PlateError> {
    let mut tried: Vec<PathBuf> = Vec::new();
    if let Some(p) = std::env::var_os("CRACKBOT_FONT").filter(|p| !p.is_empty()) {
        tried.push(PathBuf::from(p));
    }
    tried.extend(FONT_CANDIDATES.iter().map(PathBuf::from));
    for p in &tried {
        if let Some(font) = std::fs::read(p)
            .ok()
            .and_then(|b| FontVec::try_from_vec(b).ok())
        {
            return Ok(font);
        }
    }
    Err(PlateError::Font {
        tried: tried
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
    })
}

/// The sheet being drawn: the image, its scale and the font.
struct Sheet {
    img: RgbImage,
    px_per_mm: f64,
    font: FontVec,
}

impl Sheet {
    fn px(&self, mm: f64) -> i64 {
        (mm * self.px_per_mm).round() as i64
    }

    fn put(&mut self, x: i64, y: i64, c: Rgb<u8>) {
        if x >= 0 && y >= 0 && (x as u32) < self.img.width() && (y as u32) < self.img.height() {
            self.img.put_pixel(x as u32, y as u32, c);
        }
    }

    /// A line 0.3 mm wide, mm.
    fn line(&mut self, a: [f64; 2], b: [f64; 2], c: Rgb<u8>) {
        let n = ((b[0] - a[0]).hypot(b[1] - a[1]) * self.px_per_mm * 2.0).ceil() as usize + 1;
        let r = (0.15 * self.px_per_mm).ceil() as i64;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let (x, y) = (
                self.px(a[0] + t * (b[0] - a[0])),
                self.px(a[1] + t * (b[1] - a[1])),
            );
            for dy in -r..=r {
                for dx in -r..=r {
                    self.put(x + dx, y + dy, c);
                }
            }
        }
    }

    /// Text whose top-left corner is at `at` (mm), `size_mm` high.
    fn text(&mut self, at: [f64; 2], size_mm: f64, s: &str) {
        let scale = PxScale::from((size_mm * self.px_per_mm) as f32);
        let scaled = self.font.as_scaled(scale);
        let mut caret = (at[0] * self.px_per_mm) as f32;
        let baseline = (at[1] * self.px_per_mm) as f32 + scaled.ascent();
        let mut spots = Vec::new();
        for ch in s.chars() {
            let id = scaled.glyph_id(ch);
            let glyph = id.with_scale_and_position(scale, ab_glyph::point(caret, baseline));
            caret += scaled.h_advance(id);
            if let Some(o) = self.font.outline_glyph(glyph) {
                let b = o.px_bounds();
                o.draw(|gx, gy, cover| {
                    spots.push((
                        b.min.x as i64 + i64::from(gx),
                        b.min.y as i64 + i64::from(gy),
                        cover,
                    ));
                });
            }
        }
        for (x, y, cover) in spots {
            if cover > 0.5 {
                self.put(x, y, INK);
            }
        }
    }
}

/// The plan view, 1:1: the plate shaded by height (darker lower), its outline, the slide.
fn plan(s: &mut Sheet, plate: &ReferencePlate) {
    let [w, h] = plate.surface.size_mm;
    let (x0, y0) = (s.px(LEFT_MM), s.px(PLAN_TOP_MM));
    for py in 0..s.px(h) {
        for px in 0..s.px(w) {
            let p = [px as f64 / s.px_per_mm, h - py as f64 / s.px_per_mm];
            let z = plate.surface.height_mm(p);
            let g = (215.0 + 25.0 * z).clamp(60.0, 250.0) as u8;
            s.put(x0 + px, y0 + py, Rgb([g, g, g]));
        }
    }
    let c = |x: f64, y: f64| [LEFT_MM + x, PLAN_TOP_MM + h - y];
    for (a, b) in [
        ([0.0, 0.0], [w, 0.0]),
        ([w, 0.0], [w, h]),
        ([w, h], [0.0, h]),
        ([0.0, h], [0.0, 0.0]),
    ] {
        s.line(c(a[0], a[1]), c(b[0], b[1]), INK);
    }
    // The section's line and the slide across the feature.
    s.line(c(0.0, h / 2.0), c(w, h / 2.0), FEATURE);
    s.text(c(2.0, h / 2.0 + 6.0), 3.0, "A");
    s.text(c(w - 5.0, h / 2.0 + 6.0), 3.0, "A");
    s.text(
        c(FEATURE_X_MM - 38.0, h - 4.0),
        3.0,
        "slides run along x, across the feature at x = 100",
    );
    s.text(c(2.0, -2.0), 3.0, "x = 0");
    s.text(c(w - 16.0, -2.0), 3.0, "x = 200 mm");
}

/// The section A–A at `scale` over plate x in `[from, to]`, its top-left at `at` (mm); the
/// plate's underside at the bottom.
fn section(
    s: &mut Sheet,
    plate: &ReferencePlate,
    (from, to): (f64, f64),
    scale: f64,
    at: [f64; 2],
) {
    let y = plate.surface.size_mm[1] / 2.0;
    let top = THICKNESS_MM + 2.0;
    let n = s.px((to - from) * scale);
    for k in 0..n {
        let x = from + k as f64 / s.px_per_mm / scale;
        let z = THICKNESS_MM + plate.surface.height_mm([x, y]);
        let bottom = s.px(at[1] + top * scale);
        let surface = s.px(at[1] + (top - z) * scale);
        for py in surface..bottom {
            s.put(s.px(at[0]) + k, py, Rgb([150, 150, 150]));
        }
        s.put(s.px(at[0]) + k, surface, INK);
    }
}

/// The sheet's text: title, dimensions, how to print and mount it.
fn notes(s: &mut Sheet, plate: &ReferencePlate) {
    let mut lines = vec![
        format!("crackbot reference plate \"{}\": {}", plate.name, plate.title),
        format!(
            "200 x 100 mm, {THICKNESS_MM} mm thick under the sound surface; STL: {}.stl (mm). Sheet at true scale: print at actual size.",
            plate.name
        ),
    ];
    if let Some(span) = plate.footprint_mm() {
        lines.push(format!(
            "The feature spans x = {:.1} to {:.1} mm and y = {:.1} to {:.1} mm.",
            span[0].max(0.0),
            span[1].min(plate.surface.size_mm[0]),
            span[2].max(0.0),
            span[3].min(plate.surface.size_mm[1])
        ));
    }
    lines.push(
        "Print flat (0.2 mm layers, 0.4 mm nozzle, as the papers), matt, one colour for the whole set."
            .into(),
    );
    for (k, l) in lines.iter().enumerate() {
        s.text([LEFT_MM, 5.0 + 6.0 * k as f64], 3.2, l);
    }
    let mount = [
        "Mounting: clamp the plate's short edges (x = 0 and x = 200) to the bench, flat, sound surface up;",
        "the arm slides along x, across the feature, in both directions (crackbot commission does it).",
        "Every plate sits at the same place: the commissioning's plate frame has its origin at the corner x = 0, y = 0.",
    ];
    for (k, l) in mount.iter().enumerate() {
        s.text([LEFT_MM, 270.0 + 6.0 * k as f64], 3.0, l);
    }
}

/// Draws the plate's sheet at `px_per_mm`.
pub fn draw(plate: &ReferencePlate, px_per_mm: f64) -> Result<RgbImage, PlateError> {
    let font = load_font()?;
    let (w, h) = (
        (SHEET_MM[0] * px_per_mm).round() as u32,
        (SHEET_MM[1] * px_per_mm).round() as u32,
    );
    let mut s = Sheet {
        img: RgbImage::from_pixel(w, h, Rgb([255, 255, 255])),
        px_per_mm,
        font,
    };
    notes(&mut s, plate);
    s.text(
        [LEFT_MM, PLAN_TOP_MM - 7.0],
        3.5,
        "Plan, 1:1 (darker: lower)",
    );
    plan(&mut s, plate);
    s.text([LEFT_MM, SECTION_TOP_MM - 6.0], 3.5, "Section A-A, 1:1");
    section(&mut s, plate, (0.0, 200.0), 1.0, [LEFT_MM, SECTION_TOP_MM]);
    let (scale, half) = DETAIL;
    let from = FEATURE_X_MM - half;
    s.text(
        [LEFT_MM, DETAIL_TOP_MM - 6.0],
        3.5,
        &format!(
            "Section A-A at the feature, {scale}:1 (x = {from} to {} mm)",
            FEATURE_X_MM + half
        ),
    );
    section(
        &mut s,
        plate,
        (from, FEATURE_X_MM + half),
        scale,
        [LEFT_MM + 7.0, DETAIL_TOP_MM],
    );
    if let Some(w) = plate.width_label_mm.filter(|&w| w > 0.0) {
        let y = DETAIL_TOP_MM + 2.0 * scale - 3.0;
        let x = |v: f64| LEFT_MM + 7.0 + (v - from) * scale;
        s.line(
            [x(FEATURE_X_MM - w / 2.0), y],
            [x(FEATURE_X_MM + w / 2.0), y],
            FEATURE,
        );
        s.text(
            [x(FEATURE_X_MM + w / 2.0) + 2.0, y - 5.0],
            3.2,
            &format!("{w} mm"),
        );
        s.text(
            [x(FEATURE_X_MM + w / 2.0) + 2.0, y + 3.0],
            3.2,
            &format!(
                "{} mm deep, walls at {} deg",
                crate::set::CRACK_DEPTH_MM,
                crate::set::CRACK_WALL_ANGLE_DEG
            ),
        );
    }
    Ok(s.img)
}

/// Writes the plate's sheet to `path` as a PNG at `px_per_mm`, its scale in the file (`pHYs`).
pub fn write_png(plate: &ReferencePlate, px_per_mm: f64, path: &Path) -> Result<(), PlateError> {
    let img = draw(plate, px_per_mm)?;
    crackbot_imaging::scaled_png::write_scaled_png(
        path,
        [img.width(), img.height()],
        png::ColorType::Rgb,
        img.as_raw(),
        px_per_mm,
    )
    .map_err(PlateError::from)
}
