//! Where the tactile finger goes: tactile-only scan rows from the paper's eq. 1 and 2, targeted
//! slides across detected candidates, their order, and time estimates.
//!
//! The planner works in surface millimetres and has no image or GUI dependency: the camera side
//! turns detections into [`Candidate`]s (a box, a main axis or a centre-line polyline, mapped to
//! millimetres by its homography); eq. 1 takes binary masks as plain `bool` arrays
//! ([`BinaryMask`]), read by whoever has an image decoder. `README.md` beside this crate has the
//! figures measured on the real masks and the paper's exploration-time table.
//!
//! # Checked parameters
//!
//! As linfa's checked hyper-parameters: [`Planner::new`] checks a [`Workspace`], the robot's
//! [`Limits`] and the [`Settings`] together once (every number finite, speeds at or under the
//! limits, the start pose inside the workspace) and the [`Planner`] it returns only plans inside
//! the workspace and under the limits. Candidates are checked on every call: a non-finite or
//! negative field is a [`PlanError::InvalidCandidate`] naming the candidate and the field.
//!
//! # Eq. 1 and 2
//!
//! Eq. 1 ([`mean_crack_length`]): `L_i = A_i / w̄`, `L̄ = Σ L_i / N_c`, with `A_i` the crack
//! pixels of image `i`, `w̄` the mean crack width (here measured from the masks: area over
//! centre-line length, see [`crack_length`]) and `N_c` the images holding a crack.
//!
//! Eq. 2 ([`scan_rows_count`]): `N_s = ⌊h / (γ·L̄)⌋ + 1` scan rows over a height `h`, with
//! `0 < γ < 1` making the estimate more conservative as it shrinks. The paper's figures
//! ([`PAPER_EQ1`]): `Ā = 2961` of 51 529 px, `w̄ = 20 px`, `L̄ = 148.06 px`, `N_c = 30`,
//! `h = 480 px`, giving 13, 7 and 5 rows for γ = 0.25, 0.5, 0.75 ([`PAPER_TABLE_II`]).
//!
//! # Pixels to millimetres
//!
//! Eq. 2 depends only on the ratio `h / L̄`, so the question is which height `L̄` is a fraction
//! of. The paper divides its camera frame's height (480 px) by a length measured on 227 × 227
//! dataset images, i.e. it assumes a dataset crack is as many pixels long in the camera frame,
//! and that the frame spans the workspace: `L̄_mm = L̄_px / 480 · h_mm`
//! ([`paper_mean_length_mm`], 30.85 mm on the 100 mm plate; this reproduces Table II's 13/7/5
//! rows). This crate's own mapping, for the real masks, is **`L̄` as a fraction of its own
//! image's height, applied to the workspace height**:
//! `L̄_mm = mean(L_i / H_i) · h_mm` ([`CrackLengthEstimate::mean_length_mm`]). Why: the datasets'
//! images have different sizes and scales, and a pixel count means nothing outside its image,
//! whereas "a crack spans this fraction of the view" transfers to a camera framing the
//! workspace, which is the paper's own assumption about its camera. On the paper's figures the
//! two differ by 480 / 227: 148.06 / 227 = 0.652 of the height (65.2 mm, 7/4/3 rows) against
//! 0.308 (30.85 mm, 13/7/5 rows). Neither is a physical crack length; a surface with known
//! crack statistics in millimetres should pass them to [`Planner::tactile_scan`] directly.
//!
//! # Plans
//!
//! * [`Planner::tactile_scan`]: `N_s` rows along x spread evenly from the bottom edge to the top
//!   edge of the workspace (spacing `h / (N_s − 1) ≥ γ·L̄`), swept boustrophedon from the corner
//!   nearest the start.
//! * [`Planner::targeted`]: per candidate one slide perpendicular to its main axis through its
//!   centre (or [`Settings::along_spacing_mm`]-spaced slides along it), from sound surface to
//!   sound surface: `width/2 + reach + margin` each side of the crack's centre line (at least
//!   half the paper's 16 mm stroke). A slide the workspace cuts is shifted along itself or
//!   shortened, as long as `min_margin_mm` of sound surface stays beyond the reach on both sides;
//!   else moved along the crack to where it fits; else the candidate is listed as unreachable
//!   (or refused, [`OnUnreachable::Error`]). Every endpoint lies inside the workspace, and since
//!   the workspace is a rectangle, so does every straight move between them. Overlapping
//!   candidates are each slid ([`Overlap::SlideBoth`], default) or merged ([`Overlap::Merge`]).
//!   Order: nearest neighbour + 2-opt + Or-opt ([`Order::TwoOpt`]); [`brute_force_order`] gives
//!   the exact optimum for small cases.
//!
//! # Time
//!
//! Moves at the travel speed ([`travel_time_s`], optionally with an acceleration), each slide
//! `passes × (stroke / v + ramp / 2)` as the simulator's arm runs it ([`slide_time_s`]), plus
//! [`Settings::settle_s`] per slide for lowering, settling and lifting the finger.

pub mod candidate;
pub mod crack_length;
mod error;
pub mod geometry;
pub mod order;
pub mod plan;
mod planner;
pub mod scan;
mod settings;

pub use candidate::Candidate;
pub use crack_length::{
    mean_crack_length, measure_mask, BinaryMask, CrackLengthEstimate, MaskMeasure, PaperEq1,
    PAPER_EQ1,
};
pub use error::PlanError;
pub use geometry::{Limits, Point, Workspace};
pub use order::Order;
pub use plan::{
    raised_pass, slide_along, slide_time_s, travel_time_s, Move, Plan, PlanKind, Slide,
    TimeEstimate, Unreachable,
};
pub use planner::Planner;
pub use scan::{
    paper_mean_length_mm, scan_rows_count, scan_rows_exact, PaperTimeRow, PAPER_TABLE_II,
};
pub use settings::{OnUnreachable, Overlap, RaisedPass, Settings};

/// A candidate's id, as the detector numbered it; unique within one request.
pub type CandidateId = u64;

/// The papers' sliding speed: "The average sliding velocity was 3.89 mm/s" (both papers).
pub const PAPER_SLIDE_SPEED_MM_S: f64 = 3.89;
/// The speed the simulator fitted to the recordings' sample counts (`crackbot_sim::experiment::PAPER_SPEED_MM_S`).
pub const SIM_SLIDE_SPEED_MM_S: f64 = 4.6;
/// The papers' stroke: "the periodic sliding has a magnitude of 1.6 cm".
pub const PAPER_STROKE_MM: f64 = 16.0;
/// Most rows of a tactile-only scan.
pub const MAX_SCAN_ROWS: usize = 10_000;
/// Most candidates [`brute_force_order`] takes (8! orders).
pub const MAX_BRUTE_FORCE: usize = 8;
/// Most slides along one candidate ([`Settings::along_spacing_mm`]).
pub const MAX_SLIDES_PER_CANDIDATE: usize = 64;
/// Largest coordinate or length accepted, mm (1000 km: anything beyond is a unit mistake).
pub const MAX_COORD_MM: f64 = 1e9;

/// The targeted plan in a checked-once call: [`Planner::new`] then [`Planner::targeted`].
pub fn targeted(
    workspace: Workspace,
    limits: Limits,
    settings: Settings,
    candidates: &[Candidate],
) -> Result<Plan, PlanError> {
    Planner::new(workspace, limits, settings)?.targeted(candidates)
}

/// The tactile-only scan in one call: [`Planner::new`] then [`Planner::tactile_scan`].
pub fn tactile_scan(
    workspace: Workspace,
    limits: Limits,
    settings: Settings,
    gamma: f64,
    mean_length_mm: f64,
) -> Result<Plan, PlanError> {
    Planner::new(workspace, limits, settings)?.tactile_scan(gamma, mean_length_mm)
}

/// The targeted plan with the exact shortest order (every order tried, the best variants of
/// each): for measuring how far the heuristic is from the optimum. At most
/// [`MAX_BRUTE_FORCE`] reachable candidates (or merged groups).
pub fn brute_force_order(planner: &Planner, candidates: &[Candidate]) -> Result<Plan, PlanError> {
    planner.targeted_with(candidates, Order::BruteForce)
}
