//! What can go wrong writing the plates' files.

use std::path::PathBuf;

/// Why a plate's file could not be written. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum PlateError {
    /// Creating or writing the file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// No font to write the drawing's text with.
    #[error("no font for the drawings' text: {tried}; install fonts-dejavu-core (scripts/setup.sh does) or set CRACKBOT_FONT to a .ttf file")]
    Font {
        /// The files tried.
        tried: String,
    },
    /// Writing the drawing's PNG failed.
    #[error(transparent)]
    Png(#[from] crackbot_imaging::scaled_png::ScaledPngError),
}
