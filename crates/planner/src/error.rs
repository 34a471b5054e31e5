//! The planner's one error type.

use crate::CandidateId;

/// Why a plan could not be made. Every variant names the offending field, candidate or mask.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// A setting, limit or workspace bound is out of its range.
    #[error("{field} must be {expected}, got {value}")]
    InvalidParam {
        /// The field, e.g. `settings.slide_speed_mm_s` or `workspace.x_min_mm`.
        field: String,
        /// What it was.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// A speed setting is above the robot's limit.
    #[error("{field} = {value} mm/s is above the limit {limit_field} = {limit} mm/s")]
    AboveSpeedLimit {
        /// The setting, e.g. `settings.slide_speed_mm_s`.
        field: String,
        /// Its value, mm/s.
        value: f64,
        /// The limit's field, e.g. `limits.max_slide_speed_mm_s`.
        limit_field: String,
        /// The limit, mm/s.
        limit: f64,
    },
    /// The start pose is outside the workspace.
    #[error("the start pose ({x}, {y}) mm is outside the workspace {workspace}")]
    StartOutside {
        /// x, mm.
        x: f64,
        /// y, mm.
        y: f64,
        /// The workspace, as text.
        workspace: String,
    },
    /// A candidate has a field that is not a number, or out of its range.
    #[error("candidate {id} (#{index} in the list): {field} must be {expected}, got {value}")]
    InvalidCandidate {
        /// The candidate's id.
        id: CandidateId,
        /// Its position in the list given to the planner.
        index: usize,
        /// The field, e.g. `centre_mm[0]`.
        field: &'static str,
        /// What it was.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// Two candidates share an id (the report could not tell their slides apart).
    #[error("candidate id {id} appears twice (#{first} and #{second} in the list)")]
    DuplicateCandidate {
        /// The id.
        id: CandidateId,
        /// Position of the first.
        first: usize,
        /// Position of the second.
        second: usize,
    },
    /// No slide across a candidate fits in the workspace with sound surface on both sides
    /// (only with [`crate::OnUnreachable::Error`]; otherwise the plan lists it).
    #[error("candidate(s) {ids:?}: {reason}")]
    Unreachable {
        /// The candidate(s): several when overlapping candidates were merged.
        ids: Vec<CandidateId>,
        /// Why.
        reason: String,
    },
    /// A polyline needs at least one point.
    #[error("candidate {id}: a polyline needs at least one point")]
    EmptyPolyline {
        /// The candidate's id.
        id: CandidateId,
    },
    /// A binary mask is malformed.
    #[error("mask{}: {reason}", .index.map(|i| format!(" #{i}")).unwrap_or_default())]
    InvalidMask {
        /// Its position in a sequence, when known.
        index: Option<usize>,
        /// What is wrong.
        reason: String,
    },
    /// No mask holds a crack pixel, so eq. 1 has nothing to average.
    #[error("none of the {masks} masks holds a crack pixel: eq. 1 needs at least one crack")]
    NoCracks {
        /// How many masks were given.
        masks: usize,
    },
    /// Eq. 2 asks for more scan rows than the planner will write.
    #[error(
        "eq. 2 gives {rows} scan rows (h = {height_mm} mm, γ·L̄ = {spacing_mm} mm), more than {max}"
    )]
    TooManyRows {
        /// Rows asked for (saturated at `usize::MAX`).
        rows: f64,
        /// The workspace height, mm.
        height_mm: f64,
        /// γ·L̄, mm.
        spacing_mm: f64,
        /// The most rows a plan may have ([`crate::MAX_SCAN_ROWS`]).
        max: usize,
    },
    /// The exact order search is limited to small cases.
    #[error("brute force is limited to {max} candidates, got {n}")]
    TooManyForBruteForce {
        /// Candidates given.
        n: usize,
        /// The limit ([`crate::MAX_BRUTE_FORCE`]).
        max: usize,
    },
}

/// `Ok` when `v` is finite and `> 0`.
pub(crate) fn positive(field: &str, v: f64) -> Result<(), PlanError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(PlanError::InvalidParam {
            field: field.to_string(),
            value: v,
            expected: "a finite number > 0",
        })
    }
}

/// `Ok` when `v` is finite and `>= 0`.
pub(crate) fn non_negative(field: &str, v: f64) -> Result<(), PlanError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(PlanError::InvalidParam {
            field: field.to_string(),
            value: v,
            expected: "a finite number ≥ 0",
        })
    }
}

/// `Ok` when `v` is finite.
pub(crate) fn finite(field: &str, v: f64) -> Result<(), PlanError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(PlanError::InvalidParam {
            field: field.to_string(),
            value: v,
            expected: "a finite number",
        })
    }
}
