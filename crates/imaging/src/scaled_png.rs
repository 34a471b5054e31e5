//! A PNG that states its scale: its pixels per metre in the `pHYs` chunk, so a printer set to
//! "actual size" prints it at true scale (the calibration target, the reference plates'
//! drawings).

use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Why a scaled PNG could not be written. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ScaledPngError {
    /// Creating the file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// The encoder refused the image or could not write it.
    #[error("{}: could not encode the PNG: {reason}", path.display())]
    Encode {
        /// The file.
        path: PathBuf,
        /// What the encoder said.
        reason: String,
    },
}

/// Writes 8-bit `data` (`color`: grey or RGB rows, top first) of `size` pixels to `path`, at
/// `px_per_mm` stated in the file.
pub fn write_scaled_png(
    path: &Path,
    [width, height]: [u32; 2],
    color: png::ColorType,
    data: &[u8],
    px_per_mm: f64,
) -> Result<(), ScaledPngError> {
    let enc = |e: png::EncodingError| ScaledPngError::Encode {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    let file = std::fs::File::create(path).map_err(|source| ScaledPngError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(color);
    encoder.set_depth(png::BitDepth::Eight);
    let per_metre = (px_per_mm * 1000.0).round() as u32;
    encoder.set_pixel_dims(Some(png::PixelDimensions {
        xppu: per_metre,
        yppu: per_metre,
        unit: png::Unit::Meter,
    }));
    let mut writer = encoder.write_header().map_err(enc)?;
    writer.write_image_data(data).map_err(enc)?;
    writer.finish().map_err(enc)
}
