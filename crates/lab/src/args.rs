//! Command-line values shared by the `tactile` and `sim` commands.

use clap::ValueEnum;
use crackbot_recording::{Experiment, Format};

/// Which of the paper's experiments.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ExperimentArg {
    /// Flat, crack, bump, wavy pattern.
    Recognition,
    /// Cracks of 0, 1, 2, 5, 8, 10 mm.
    Width,
}

impl From<ExperimentArg> for Experiment {
    fn from(e: ExperimentArg) -> Self {
        match e {
            ExperimentArg::Recognition => Experiment::Recognition,
            ExperimentArg::Width => Experiment::Width,
        }
    }
}

/// File form of the recordings written.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum FormatArg {
    /// crackbot's CSV (the authors' nine columns with a header).
    Csv,
    /// MAT-file level 5, the authors' format.
    Mat,
}

impl From<FormatArg> for Format {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Csv => Format::Csv,
            FormatArg::Mat => Format::Mat,
        }
    }
}
