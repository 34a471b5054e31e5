//! The target as a printable image at true scale: a greyscale PNG whose physical pixel size is
//! recorded in the file (PNG `pHYs`, pixels per metre), so a printer set to "actual size" prints
//! the tags `tag_mm` wide.

use std::path::Path;

use image::GrayImage;

use crate::error::TargetError;
use crate::spec::TargetSpec;

/// The sheet of `spec` drawn at `px_per_mm` pixels per millimetre (each pixel black or white by
/// what is printed at its centre). The image's top edge is the sheet's top (largest `y`).
pub fn draw(spec: &TargetSpec, px_per_mm: f64) -> GrayImage {
    let (lo, hi) = spec.sheet_mm();
    let w = ((hi[0] - lo[0]) * px_per_mm).round().max(1.0) as u32;
    let h = ((hi[1] - lo[1]) * px_per_mm).round().max(1.0) as u32;
    GrayImage::from_fn(w, h, |c, r| {
        let x = lo[0] + (f64::from(c) + 0.5) / px_per_mm;
        let y = hi[1] - (f64::from(r) + 0.5) / px_per_mm;
        image::Luma([if spec.is_white([x, y]).unwrap_or(true) {
            255
        } else {
            0
        }])
    })
}

/// Writes the sheet to `path` as a PNG at `px_per_mm` with its scale in the file.
pub fn write_png(spec: &TargetSpec, px_per_mm: f64, path: &Path) -> Result<GrayImage, TargetError> {
    if !(px_per_mm.is_finite() && (1.0..=100.0).contains(&px_per_mm)) {
        return Err(TargetError::Invalid {
            field: "pixels per mm",
            value: px_per_mm.to_string(),
            expected: "1 to 100 (600 dpi is 23.6)".to_string(),
        });
    }
    let img = draw(spec, px_per_mm);
    crackbot_imaging::scaled_png::write_scaled_png(
        path,
        [img.width(), img.height()],
        png::ColorType::Grayscale,
        img.as_raw(),
        px_per_mm,
    )?;
    Ok(img)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_png_states_its_scale_and_measures_true() {
        let spec = TargetSpec::default();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.png");
        let img = write_png(&spec, 10.0, &path).unwrap();
        let (lo, hi) = spec.sheet_mm();
        assert_eq!(img.width(), ((hi[0] - lo[0]) * 10.0).round() as u32);
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let reader = decoder.read_info().unwrap();
        let dims = reader.info().pixel_dims.unwrap();
        assert_eq!((dims.xppu, dims.unit), (10_000, png::Unit::Meter));
        // The bottom-left tag's black square starts margin_mm in from the left edge: count the
        // white pixels before the first black one along its middle row.
        let row = img.height() - 1 - ((spec.margin_mm + spec.cell_mm() * 0.5) * 10.0) as u32;
        let first_black = (0..img.width())
            .find(|&c| img.get_pixel(c, row)[0] == 0)
            .unwrap();
        assert_eq!(f64::from(first_black), spec.margin_mm * 10.0);
        assert!(write_png(&spec, 0.0, &path).is_err());
    }
}
