//! What can go wrong in a calibration, each naming what is wrong.

/// A calibration that cannot be made from the views given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CalibError {
    /// Fewer views than the model needs.
    #[error(
        "{got} views of the target; the lens model needs at least {need} (tilted differently)"
    )]
    TooFewViews {
        /// Views given.
        got: usize,
        /// Views needed.
        need: usize,
    },
    /// A view with too few points.
    #[error("view {view} has {got} target points; at least {need} are needed")]
    TooFewPoints {
        /// Index of the view.
        view: usize,
        /// Points in it.
        got: usize,
        /// Points needed.
        need: usize,
    },
    /// A coordinate that is not a finite number.
    #[error("view {view}, point {point}: a coordinate is not a finite number")]
    NotFinite {
        /// Index of the view.
        view: usize,
        /// Index of the point in the view.
        point: usize,
    },
    /// A view whose points do not span the plane (all on one line, repeated points).
    #[error("view {view}: {reason}")]
    Degenerate {
        /// Index of the view.
        view: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// A view of the target nearly edge-on: its points say little and its corners are unreliable.
    #[error(
        "view {view} sees the target {tilt_deg:.1}° from face-on (over {max_deg}°: nearly edge-on); \
         leave it out"
    )]
    EdgeOn {
        /// Index of the view.
        view: usize,
        /// Angle between the target's normal and the line of sight, degrees.
        tilt_deg: f64,
        /// The largest angle accepted.
        max_deg: f64,
    },
    /// The views together do not determine the model.
    #[error("the views do not constrain the lens model: {reason}")]
    Unconstrained {
        /// Why, and what to do about it.
        reason: String,
    },
    /// The refinement did not reach a finite solution.
    #[error("the fit diverged: {reason}")]
    Diverged {
        /// What went wrong.
        reason: String,
    },
}
