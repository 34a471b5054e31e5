//! The tactile pipeline end to end, on the authors' recordings or the project's own: recordings →
//! segmented slides → windowed features → classifiers, the evaluation protocols of the paper
//! (and stricter ones), metrics, statistics and tables (their figures: `crackbot-plots`).
//!
//! * [`dataset`]: recordings → labelled feature windows ([`dataset::PipelineConfig`], checked once into a
//!   [`dataset::Pipeline`]);
//! * [`model`]: the deployed models (training them, their files, the unknown-surface gate);
//!   [`online`]: a slide classified sample by sample, as the robot does; [`vote`]: how a slide's
//!   windows vote;
//! * [`context`]: causal context features of a window; [`stream`]: the same, sample by sample;
//! * [`localise`]: where a crack starts and ends along a slide, from the proximity dip and the position stream;
//! * [`stroke`]: what one stroke's proximity channel says (a candidate's own dip among several, the ends' levels,
//!   a row cut into stroke-long pieces); [`print_check`] and [`raised`]: prints told from cracks by raised passes;
//!
//! The evaluation, also in the robot's build (a finger's commissioning evaluates its models,
//! `crackbot_mission::commission`): [`eval`], training and testing classifiers, slide verdicts,
//! width regression; [`evaluation`], the whole `crackbot-lab tactile eval` flow as one call
//! returning a `Serialize` report; [`metrics`].
//!
//! Cargo feature `research` (default off, never in the robot's build): the paper's grid
//! (`paper`, with its Kruskal–Wallis statistics in `stats`, `statrs`) and the random forest's
//! accuracy/run-time sweep (`tradeoff`). Their figures are drawn by `crackbot-plots`,
//! passed in as closures.
//!
//! Nothing here draws progress bars: long calls take a progress callback and the binary draws.

pub mod context;
pub mod dataset;
mod error;
pub mod eval;
pub mod evaluation;
pub mod localise;
pub mod metrics;
pub mod model;
pub mod online;
#[cfg(feature = "research")]
pub mod paper;
pub mod print_check;
pub mod raised;
#[cfg(feature = "research")]
pub mod stats;
pub mod stream;
pub mod stroke;
#[cfg(feature = "research")]
pub mod tradeoff;
pub mod vote;

pub use error::TactileError;
