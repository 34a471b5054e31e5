//! Every figure crackbot draws, in one place: PNG files (plotters, bitmap backend) of the
//! reports the libraries return. Only the research tools use it; the robot path never compiles
//! plotters (checked by `tests/layering.rs`).
//!
//! * [`tactile`]: confusion-matrix heat maps, the paper's Fig. 10-style accuracy box plots of the
//!   intersession grid, the random forest's accuracy against its prediction latency;
//! * [`vision`]: the detector's mAP@0.5 against ms per frame;
//! * [`sim`]: the integrators' work-precision diagram, real against simulated slides.
//!
//! Text is drawn with a TrueType font read at run time (plotters' `ab_glyph` renderer does not
//! look fonts up itself): `$CRACKBOT_FONT` if set, otherwise DejaVu Sans from Debian's
//! `fonts-dejavu-core` package, which `scripts/setup.sh` installs.

use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

pub mod sim;
pub mod tactile;
pub mod vision;

/// Why a figure could not be drawn. Every variant about a file names it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// No usable font for the text ([`load_font`]).
    #[error("{reason}")]
    Font {
        /// Which files were tried and how to get one.
        reason: String,
    },
    /// The target file does not end in `.png`.
    #[error("{}: plots are written as PNG, the file name must end in .png", path.display())]
    NotPng {
        /// The target.
        path: PathBuf,
    },
    /// The target's folder does not exist.
    #[error("{}: cannot write the plot, the folder {} does not exist", path.display(), dir.display())]
    MissingFolder {
        /// The target.
        path: PathBuf,
        /// Its folder.
        dir: PathBuf,
    },
    /// Drawing the plot failed.
    #[error("{}: could not draw the plot: {reason}", path.display())]
    Draw {
        /// The target.
        path: PathBuf,
        /// What the drawing library said.
        reason: String,
    },
    /// Encoding or writing the PNG failed.
    #[error("{}: could not write the plot: {reason}", path.display())]
    Write {
        /// The target.
        path: PathBuf,
        /// What the PNG encoder or the file system said.
        reason: String,
    },
    /// The class names do not match the confusion matrix.
    #[error("{}: {names} class names for a confusion matrix of {classes} classes", path.display())]
    ClassNames {
        /// The target.
        path: PathBuf,
        /// Class names given.
        names: usize,
        /// Classes of the matrix.
        classes: usize,
    },
    /// The tables hold no result of the classifier asked for.
    #[error("{}: no result of classifier {classifier} to plot", path.display())]
    NoResults {
        /// The target.
        path: PathBuf,
        /// The classifier.
        classifier: String,
    },
    /// The trade-off holds no forest.
    #[error("{}: no forest measured, nothing to plot", path.display())]
    NothingToPlot {
        /// The target.
        path: PathBuf,
    },
    /// No integrator of a work-precision run finished.
    #[error("{}: no integrator finished, nothing to plot", path.display())]
    NoFinishedIntegrator {
        /// The target.
        path: PathBuf,
    },
}

/// Font files tried, in order, after `$CRACKBOT_FONT`.
pub const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

pub(crate) const FONT: &str = "sans-serif";

/// Line colours of the figures with several series (matplotlib's first four).
pub(crate) const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

static LOADED_FONT: OnceLock<Result<PathBuf, String>> = OnceLock::new();

/// Loads the font that every plot draws its text with (once per process) and returns its path;
/// the error says which files were tried and how to get one.
pub fn load_font() -> Result<PathBuf, PlotError> {
    LOADED_FONT
        .get_or_init(|| {
            let mut candidates: Vec<PathBuf> = Vec::new();
            if let Some(p) = std::env::var_os("CRACKBOT_FONT").filter(|p| !p.is_empty()) {
                candidates.push(PathBuf::from(p));
            }
            candidates.extend(FONT_CANDIDATES.iter().map(PathBuf::from));
            for path in &candidates {
                let Ok(bytes) = std::fs::read(path) else {
                    continue;
                };
                // plotters keeps fonts for the life of the process; this happens once.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                return plotters::style::register_font(FONT, FontStyle::Normal, bytes)
                    .map(|()| path.clone())
                    .map_err(|_| {
                        format!(
                            "{}: not a TrueType/OpenType font the plots can use",
                            path.display()
                        )
                    });
            }
            Err(format!(
                "no font to draw the plots' text with: none of {} is readable; install Debian's \
                 fonts-dejavu-core (scripts/setup.sh does) or point CRACKBOT_FONT at a .ttf file",
                candidates
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
        .clone()
        .map_err(|reason| PlotError::Font { reason })
}

pub(crate) type DrawResult = Result<(), Box<dyn Error>>;
pub(crate) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Checks the target, draws on a white canvas of `size` and writes the PNG, with errors that name
/// the file.
pub(crate) fn render(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area<'_>) -> DrawResult,
) -> Result<(), PlotError> {
    let is_png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(PlotError::NotPng {
            path: path.to_path_buf(),
        });
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(PlotError::MissingFolder {
                path: path.to_path_buf(),
                dir: dir.to_path_buf(),
            });
        }
    }
    load_font()?;
    // Drawn into memory and encoded by the workspace's own `image` (plotters' PNG encoder would
    // bring a second, older version of it into every build).
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    let result = (|| -> DrawResult {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    })();
    result.map_err(|e| PlotError::Draw {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    image::save_buffer_with_format(
        path,
        &rgb,
        size.0,
        size.1,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| PlotError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

pub(crate) fn text_style(size: u32, color: RGBColor, h: HPos, v: VPos) -> TextStyle<'static> {
    TextStyle {
        font: (FONT, size).into_font(),
        color: color.to_backend_color(),
        pos: Pos::new(h, v),
    }
}
