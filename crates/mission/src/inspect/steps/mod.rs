//! The steps layer: what a mission decides, one step a file (or a folder), each over the rig
//! layer below it and taking only its own section of the configuration.
//!
//! | step | file | section |
//! |---|---|---|
//! | wait for the streams | `wait.rs` | – |
//! | perceive | `perceive.rs` | [`PerceiveConfig`] |
//! | plan | `plan.rs` | [`PlanConfig`] |
//! | touch | `touch/` | [`TouchConfig`] |
//! | print check | `print_check/` | [`PrintCheckConfig`] |
//! | judge | `judge.rs` (what was felt: `felt.rs`; the rules: `rules.rs`) | [`JudgeConfig`] |
//! | pieces | `pieces.rs` (the crack map seen from the plate: `trace.rs`) | [`PiecesConfig`] |
//! | report | `finish.rs` | – |
//!
//! Within the layer, files import only those listed above them here: `trace`, `rules`, `felt`,
//! `judge`, `pieces`, `perceive`, `plan`, `wait`, `touch`, `print_check`, `finish`.

pub(crate) mod felt;
pub(crate) mod finish;
pub(crate) mod judge;
pub(crate) mod perceive;
pub(crate) mod pieces;
pub(crate) mod plan;
pub(crate) mod print_check;
pub(crate) mod rules;
pub(crate) mod touch;
pub(crate) mod trace;
pub(crate) mod wait;

pub use perceive::PerceiveConfig;
pub use pieces::PiecesConfig;
pub use plan::PlanConfig;
pub use print_check::PrintCheckConfig;
pub use rules::JudgeConfig;
pub use touch::TouchConfig;
