//! The tactile pipeline end to end, on the authors' recordings or the project's own: recordings →
//! segmented slides → windowed features → classifiers, the evaluation protocols of the paper
//! (and stricter ones), metrics, statistics, tables and plots.

pub mod context;
pub mod dataset;
pub mod eval;
pub mod metrics;
pub mod paper;
pub mod plots;
pub mod stats;
pub mod tradeoff;

/// Errors of the tactile pipeline.
#[derive(Debug, thiserror::Error)]
pub enum TactileError {
    /// An argument or a data set is unusable; the message says why.
    #[error("{0}")]
    Invalid(String),
}

impl From<crackbot_forest::ForestError> for TactileError {
    fn from(e: crackbot_forest::ForestError) -> Self {
        TactileError::Invalid(e.to_string())
    }
}
