//! What a mission leaves ([`InspectReport`], saved as `report.json`): the cracks it confirmed
//! with their evidence, the candidates it rejected, every pass, the frame, the plan and times.

use crackbot_planner::{Candidate, Plan};
use serde::{Deserialize, Serialize};

use super::doubts::{CrackDoubt, PassDoubt};
use crate::sync::ClockFit;

/// What the mission uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InspectMode {
    /// Touch only: scan rows over the whole workspace.
    Tactile,
    /// Look only: the detector's candidates are the result.
    Vision,
    /// Look, then touch every candidate (the papers' method).
    Fused,
}

impl InspectMode {
    /// The mode's name as the command line spells it (what [`std::str::FromStr`] reads).
    pub fn as_str(self) -> &'static str {
        match self {
            InspectMode::Tactile => "tactile",
            InspectMode::Vision => "vision",
            InspectMode::Fused => "fused",
        }
    }
}

impl std::str::FromStr for InspectMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "tactile" => Ok(InspectMode::Tactile),
            "vision" => Ok(InspectMode::Vision),
            "fused" => Ok(InspectMode::Fused),
            _ => Err(format!("unknown mode {s:?}: tactile, vision or fused")),
        }
    }
}

/// The camera frame a mission looked at.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameInfo {
    /// Where it is saved (PNG).
    pub path: String,
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Surface mm → image pixels, a homography (row-major), to draw candidates and slides on
    /// the frame.
    pub surface_to_image: [[f64; 3]; 3],
}

/// What the finger found for one slide pass.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassRecord {
    /// Slide number (link id).
    pub id: u32,
    /// Candidate it checked, if any.
    pub candidate: Option<u64>,
    /// Start and end, mm on the plate.
    pub start_mm: [f64; 2],
    /// End, mm.
    pub end_mm: [f64; 2],
    /// Samples classified.
    pub samples: usize,
    /// The recognition verdict (class name), `None` when the slide was too short.
    pub class: Option<String>,
    /// Its vote, 0–1.
    pub confidence: f64,
    /// The width model's class, mm.
    pub width_mm: Option<f64>,
    /// The doubt, if any (unknown surface, low confidence, not judged).
    pub doubt: Option<PassDoubt>,
    /// The crack the proximity channel's dip locates on this pass: centre along the pass (mm
    /// from its start), width (mm) and the dip's clarity (0–1).
    pub dip: Option<Dip>,
    /// The recording of this pass.
    pub recording: String,
    /// Attempts needed (a stalled sensor or a restarted controller make a second).
    pub attempts: u32,
}

/// A crack located along a pass by the proximity channel's dip ([`crackbot_tactile::localise`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Dip {
    /// Centre, mm along the pass from its start.
    pub centre_mm: f64,
    /// Width, mm.
    pub width_mm: f64,
    /// Clarity of the dip, 0–1.
    pub confidence: f64,
}

/// A crack the mission reports.
#[derive(Debug, Clone, Serialize)]
pub struct ReportedCrack {
    /// The candidate (detection) it came from, if any.
    pub candidate: Option<u64>,
    /// Where, mm on the plate (the crack's crossing of the slide; the detection's centre in
    /// vision mode).
    pub position_mm: [f64; 2],
    /// Along the slide, where the crack starts and ends, mm on the plate (tactile evidence).
    pub extent_mm: Option<[[f64; 2]; 2]>,
    /// `crack`.
    pub class: String,
    /// Width, mm (the width model's class, the mean over the passes; `None` in vision mode).
    pub width_mm: Option<f64>,
    /// The width's 10–90 % range, mm: where the middle 80 % of the width model's vote lies
    /// over its classes' widths (the mean over the passes of each one's range), never below 0.
    /// Read it as "the finger's vote puts the width between these"; it is not a confidence
    /// interval of a measurement.
    pub width_range_mm: Option<[f64; 2]>,
    /// Confidence 0–1: the tactile vote (the detector's score in vision mode).
    pub confidence: f64,
    /// Evidence: `vision`, `tactile` or both, with the slide ids.
    pub evidence: Evidence,
}

/// What a report entry rests on.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Evidence {
    /// The detector's score, when the camera saw it.
    pub detector_score: Option<f64>,
    /// The slides that felt it.
    pub slides: Vec<u32>,
    /// Recognition votes per class (summed over the slides).
    pub votes: Vec<f64>,
    /// Doubts raised.
    pub doubts: Vec<CrackDoubt>,
    /// The print check's ratio (the dip's share of the signal raised over in contact; about 1
    /// for a print), when the candidate was passed over raised: the mean of `print_ratios`, or
    /// where the first was in doubt, the mean over the passes of each one's print and floor
    /// ratios.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_ratio: Option<f64>,
    /// The print check's ratio of each raised pass, in order: one, or two to
    /// [`PRINT_CHECK_PASSES_IN_DOUBT`](super::PRINT_CHECK_PASSES_IN_DOUBT) where the first was within [`PRINT_RATIO_DOUBT`](super::PRINT_RATIO_DOUBT) of the
    /// threshold ([`PRINT_RATIO_SETTLED`](super::PRINT_RATIO_SETTLED)).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub print_ratios: Vec<f64>,
    /// Where the first print ratio was in doubt, each pass's floor ratio
    /// ([`floor_ratio`](crackbot_tactile::print_check::floor_ratio); `None` where it gave none), in the order of
    /// `print_ratios`; empty otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub floor_ratios: Vec<Option<f64>>,
    /// Other confirmed candidates reported as pieces of this crack (their slides are in
    /// `slides`; see [`PIECE_GAP_MM`](super::PIECE_GAP_MM) and [`PIECE_TRACE_GAP_MM`](super::PIECE_TRACE_GAP_MM)).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pieces: Vec<u64>,
}

/// A candidate the finger rejected.
#[derive(Debug, Clone, Serialize)]
pub struct RejectedCandidate {
    /// The candidate.
    pub candidate: u64,
    /// Its centre, mm.
    pub position_mm: [f64; 2],
    /// What the finger felt instead (`no crack`, `bump`, `wavy`, or `unknown`).
    pub felt: String,
    /// The detector's score.
    pub detector_score: f64,
    /// The slides.
    pub slides: Vec<u32>,
    /// The print check's ratio, when the candidate was passed over raised.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_ratio: Option<f64>,
    /// The print check's ratio of each raised pass, as [`Evidence::print_ratios`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub print_ratios: Vec<f64>,
    /// Each raised pass's floor ratio where the first was in doubt, as
    /// [`Evidence::floor_ratios`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub floor_ratios: Vec<Option<f64>>,
    /// Recognition votes per class (summed over the slides), as a confirmed crack's evidence
    /// has them: how close the finger came to calling it a crack.
    pub votes: Vec<f64>,
}

/// Wall time per stage, s.
#[derive(Debug, Clone, Default, Serialize)]
pub struct StageTimes {
    /// Start-up: controller, sensor, models.
    pub setup_s: f64,
    /// Frame and detection.
    pub perceive_s: f64,
    /// Planning.
    pub plan_s: f64,
    /// Moving and sliding (the exploration).
    pub explore_s: f64,
}

/// The mission's report.
#[derive(Debug, Clone, Serialize)]
pub struct InspectReport {
    /// The mode.
    pub mode: InspectMode,
    /// The scene's name.
    pub scene: String,
    /// Confirmed cracks.
    pub cracks: Vec<ReportedCrack>,
    /// Candidates the finger rejected.
    pub rejected: Vec<RejectedCandidate>,
    /// Candidates from the camera.
    pub candidates: Vec<Candidate>,
    /// The camera frame (saved as `frame.png`) and its surface → pixel homography, when the
    /// mission looked.
    pub frame: Option<FrameInfo>,
    /// Every slide pass.
    pub passes: Vec<PassRecord>,
    /// The plan.
    pub plan: Option<Plan>,
    /// Wall time, s.
    pub elapsed_s: f64,
    /// Exploration time in the robot's time (wall time × speed-up), s: what the papers report.
    pub exploration_s: f64,
    /// Wall time per stage.
    pub stages: StageTimes,
    /// Sensor clock → host clock fit.
    pub sensor_clock: Option<ClockFit>,
    /// Controller clock → host clock fit.
    pub controller_clock: Option<ClockFit>,
    /// Link counters (host side).
    pub link: LinkCounters,
    /// The report's folder.
    pub out_dir: String,
}

/// The host's link counters.
#[derive(Debug, Clone, Default, Serialize)]
pub struct LinkCounters {
    /// Packets sent.
    pub sent: u64,
    /// Retries of unacknowledged commands.
    pub retries: u64,
    /// Packets refused (bad tag, replay, unsigned, other link…).
    pub rejected: u64,
    /// Duplicates dropped.
    pub duplicates: u64,
}
