//! What a mission tells its front ends while it runs ([`Progress`]) and what it leaves
//! ([`InspectReport`], saved as `report.json`).

use crackbot_planner::{Candidate, Plan};
use crackbot_tactile::model::Doubt;
use serde::Serialize;

use super::config::InspectMode;
use super::feel::Feeling;
use crate::sync::ClockFit;

/// Progress of a mission, for a front end to show.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "stage", rename_all = "snake_case")]
pub enum Progress {
    /// Setting up (controller, sensor, models).
    Starting,
    /// The camera frame the mission looks at (saved beside the report).
    Frame(FrameInfo),
    /// Candidates found in the frame.
    Perceived {
        /// How many.
        candidates: usize,
        /// Each, in surface mm (with the detector's score).
        detections: Vec<Candidate>,
    },
    /// The plan is made.
    Planned {
        /// Slides to do.
        slides: usize,
        /// The planner's time estimate, s.
        estimated_s: f64,
        /// The plan.
        plan: Plan,
    },
    /// Sensor samples as they arrive (every 25 ms or so, whether the finger is down or not).
    Samples {
        /// The new samples, oldest first.
        samples: Vec<LiveSample>,
    },
    /// The arm's states as they arrive (100 Hz, shown every 25 ms or so with the samples).
    Poses {
        /// The new states, oldest first.
        poses: Vec<ArmPose>,
    },
    /// A stroke recorded: the samples its pass is judged from, each with its position along
    /// the stroke interpolated from the arm's states (what `slide-NNN.csv` holds, with times).
    Stroked {
        /// The slide's id on the link (the pass's `id`).
        slide: u32,
        /// Its samples, oldest first.
        samples: Vec<StrokeSample>,
    },
    /// The sensor stream's and the link's counters (every 0.5 s).
    Health(StreamHealth),
    /// What the finger feels so far in the stroke under way (every 0.1 s while it is down):
    /// shown only, the pass's verdict comes with [`Progress::Slid`].
    Feeling(Feeling),
    /// A slide pass is done: judged, or left unjudged (no class; its doubt says why, and its
    /// candidate is stroked again beside it).
    Slid {
        /// Slides done.
        done: usize,
        /// Of how many.
        of: usize,
        /// Its verdict's class name.
        class: String,
        /// The pass and its verdict.
        pass: Box<PassRecord>,
    },
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

/// How the sensor stream and the link to the controller are doing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StreamHealth {
    /// Sensor samples per second over the last interval (400 nominal).
    pub sample_rate_hz: f64,
    /// Sensor frames decoded so far.
    pub frames: u64,
    /// Sensor frames rejected by their CRC.
    pub crc_errors: u64,
    /// Gaps in the sensor's sequence numbers (runs of lost frames) and the frames lost in them.
    pub gaps: u64,
    /// Frames lost in those gaps.
    pub missing_frames: u64,
    /// Link datagrams sent to the controller.
    pub link_sent: u64,
    /// Link retries (commands not acknowledged in time).
    pub link_retries: u64,
    /// Link packets refused (bad tag, replay, unsigned, other link).
    pub link_rejected: u64,
    /// Age of the controller's last state, ms (its stream runs at 100 Hz: this is the link's
    /// latency plus at most 10 ms; it grows without bound when the link is lost).
    pub state_age_ms: Option<f64>,
}

/// One sensor sample as it arrived.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LiveSample {
    /// Time since the mission's link started, s (the host's clock, from the board's through
    /// the clock fit).
    pub t_s: f64,
    /// D1, D2, D3, P, counts.
    pub raw: [u16; 4],
    /// The slide the finger was down in, if any.
    pub slide: Option<u32>,
    /// Where the finger was along the stroke under way (a slide, or a raised pass of the print
    /// check), mm from its start, by the arm's states around the sample; `None` between strokes.
    pub along_mm: Option<f64>,
}

/// One sample of a recorded stroke.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StrokeSample {
    /// Time since the mission's link started, s (the host's clock).
    pub t_s: f64,
    /// D1, D2, D3, P, counts.
    pub raw: [u16; 4],
    /// Where the finger was along the stroke, mm from its start.
    pub along_mm: f64,
}

/// One state of the arm as it arrived.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ArmPose {
    /// Time since the mission's link started, s (the host's clock, from the controller's
    /// through the clock fit).
    pub t_s: f64,
    /// The controller's own clock, µs.
    pub controller_us: u64,
    /// Where the finger is, mm on the surface (z above it).
    pub pose_mm: [f64; 3],
    /// The slide it is in, if any.
    pub slide: Option<u32>,
    /// Where it is along the stroke under way, mm from its start.
    pub along_mm: Option<f64>,
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

/// How an unjudged pass's doubt begins (a stroke whose ends read unlike each other).
pub const NOT_JUDGED: &str = "not judged";

/// Announces a finished pass to front ends (`done` of `of` slides) and keeps it in the report.
/// Its class is shown as "not judged" where its stroke was left unjudged, "–" where it has none.
pub(super) fn keep_pass(
    progress: &mut dyn FnMut(&Progress),
    report: &mut InspectReport,
    done: usize,
    of: usize,
    rec: PassRecord,
) {
    let class = match (&rec.class, &rec.doubt) {
        (Some(c), _) => c.clone(),
        (None, Some(PassDoubt::NotJudged { .. })) => NOT_JUDGED.into(),
        (None, _) => "–".into(),
    };
    progress(&Progress::Slid {
        done,
        of,
        class,
        pass: Box::new(rec.clone()),
    });
    report.passes.push(rec);
}

/// Why a pass's verdict is not to be trusted (the recognition model's own doubt), or why the
/// pass was not judged. In the JSON report, an object tagged by `kind`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PassDoubt {
    /// A channel the model uses did not move over the pass.
    DeadChannel {
        /// `D1`, `D2`, `D3` or `P`.
        channel: &'static str,
    },
    /// Too many samples outside the training range (saturation, another mounting).
    OutOfRange {
        /// The channel with most samples out.
        channel: &'static str,
        /// Share of the pass's samples out of range.
        fraction: f64,
    },
    /// Too many windows unlike any the model learned (a surface unlike training).
    Novel {
        /// Share of novel windows.
        fraction: f64,
    },
    /// The vote is weak.
    LowConfidence {
        /// The winning class's vote, 0–1.
        confidence: f64,
    },
    /// Not judged: the stroke's ends read unlike each other (not both the sound surface), so
    /// the candidate was stroked again beside it.
    NotJudged {
        /// The proximity channel at the stroke's two ends, counts.
        end_counts: [f64; 2],
        /// How far along the candidate the stroke was made again, mm.
        moved_mm: f64,
    },
}

impl From<&Doubt> for PassDoubt {
    fn from(d: &Doubt) -> PassDoubt {
        match *d {
            Doubt::DeadChannel { channel } => PassDoubt::DeadChannel { channel },
            Doubt::OutOfRange { channel, fraction } => PassDoubt::OutOfRange { channel, fraction },
            Doubt::Novel { fraction } => PassDoubt::Novel { fraction },
            Doubt::LowConfidence { confidence } => PassDoubt::LowConfidence { confidence },
        }
    }
}

impl std::fmt::Display for PassDoubt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PassDoubt::DeadChannel { channel } => write!(f, "channel {channel} did not move"),
            PassDoubt::OutOfRange { channel, fraction } => write!(
                f,
                "{:.0} % of the samples outside the training range (channel {channel})",
                100.0 * fraction
            ),
            PassDoubt::Novel { fraction } => write!(
                f,
                "a surface unlike training: {:.0} % of the windows unlike any learned",
                100.0 * fraction
            ),
            PassDoubt::LowConfidence { confidence } => {
                write!(f, "a weak vote ({confidence:.2})")
            }
            PassDoubt::NotJudged {
                end_counts: [e0, e1],
                moved_mm,
            } => write!(
                f,
                "{NOT_JUDGED}: the stroke's ends read {e0:.0} and {e1:.0} counts, not both the \
                 sound surface; stroked again {moved_mm:.1} mm along the candidate"
            ),
        }
    }
}

/// A doubt raised over a candidate, pass by pass or by the print check. In the JSON report, an
/// object tagged by `kind`; its text ([`std::fmt::Display`]) says it in words.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum CrackDoubt {
    /// A pass's verdict was doubted.
    Pass {
        /// The pass (slide id).
        slide: u32,
        /// Why.
        doubt: PassDoubt,
    },
    /// A pass read "no crack" but doubted it, over a proximity dip deep enough to stand for a
    /// crack; the print check decides.
    DoubtedNoCrack {
        /// The pass.
        slide: u32,
        /// Its "no crack" vote, 0–1.
        confidence: f64,
        /// Its dip's confidence, 0–1.
        dip_confidence: f64,
    },
    /// The print check's raised pass was stopped: something stands under the line.
    RaisedPassStopped {
        /// Where, mm along the pass.
        at_mm: f64,
        /// The pass's length, mm.
        length_mm: f64,
        /// How far the proximity channel rose above the sound surface, counts.
        rise_counts: f64,
    },
    /// The surface at the line stood above the plate: the raised pass was made again higher.
    SurfaceRise {
        /// How far above the plate, mm.
        rise_mm: f64,
        /// The height the pass was made again at, mm.
        height_mm: f64,
    },
    /// The raised pass made again higher was stopped; the first pass's ratio stands.
    RaisedAgainStopped {
        /// Where, mm along it.
        at_mm: f64,
        /// The rise, counts.
        rise_counts: f64,
    },
    /// One of the raised passes made because the first ratio was in doubt was stopped.
    RaisedInDoubtStopped {
        /// Which pass (2 and up).
        pass: usize,
        /// Where, mm along it.
        at_mm: f64,
        /// The rise, counts.
        rise_counts: f64,
        /// Passes the ratio rests on.
        passes: usize,
    },
    /// The first print ratio lay near the threshold: several passes' mean decides.
    RatioInDoubt {
        /// The first pass's print ratio.
        first: f64,
        /// Passes whose mean decides.
        passes: usize,
    },
    /// A contact stroke the print check could not compare with.
    UnusableStroke {
        /// Why.
        reason: String,
    },
}

impl std::fmt::Display for CrackDoubt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use crackbot_tactile::print_check::PRINT_RATIO;
        match self {
            CrackDoubt::Pass { slide, doubt } => write!(f, "slide {slide}: {doubt}"),
            CrackDoubt::DoubtedNoCrack {
                slide,
                confidence,
                dip_confidence,
            } => write!(
                f,
                "slide {slide}: read as no crack ({confidence:.2}), doubted; its proximity dip \
                 ({dip_confidence:.2}) stands for a crack"
            ),
            CrackDoubt::RaisedPassStopped {
                at_mm,
                length_mm,
                rise_counts,
            } => write!(
                f,
                "the raised pass was stopped {at_mm:.1} mm along its {length_mm:.1} mm: the \
                 proximity fibre read {rise_counts:.0} counts above the sound surface, \
                 something stands under the line"
            ),
            CrackDoubt::SurfaceRise { rise_mm, height_mm } => write!(
                f,
                "the surface at the line stood {rise_mm:.2} mm above the plate: the raised pass \
                 was made again {height_mm:.2} mm up"
            ),
            CrackDoubt::RaisedAgainStopped { at_mm, rise_counts } => write!(
                f,
                "the raised pass made again was stopped {at_mm:.1} mm along: the proximity \
                 fibre read {rise_counts:.0} counts above the sound surface; the first pass's \
                 ratio stands"
            ),
            CrackDoubt::RaisedInDoubtStopped {
                pass,
                at_mm,
                rise_counts,
                passes,
            } => write!(
                f,
                "raised pass {pass} was stopped {at_mm:.1} mm along: the proximity fibre read \
                 {rise_counts:.0} counts above the sound surface; the print ratio rests on \
                 {passes} passes"
            ),
            CrackDoubt::RatioInDoubt { first, passes } => write!(
                f,
                "the first raised pass's print ratio {first:.3} was within {} of {PRINT_RATIO}: \
                 the mean of {passes} passes' print and floor ratios decides",
                super::PRINT_RATIO_DOUBT
            ),
            CrackDoubt::UnusableStroke { reason } => write!(f, "{reason}"),
        }
    }
}

/// A crack's width as the finger felt it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Width {
    /// The mean of the passes' width classes, mm.
    pub mm: f64,
    /// The mean of their votes' 10–90 % ranges, mm ([`ReportedCrack::width_range_mm`]).
    pub range_mm: [f64; 2],
}
