//! What a mission tells its front ends while it runs ([`Progress`]): each stage, the streams as
//! they arrive, the running verdict, each pass as it is judged.

use crackbot_planner::{Candidate, Plan};
use serde::Serialize;

use super::report::{FrameInfo, PassRecord};

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

/// The verdict so far of the stroke under way.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Feeling {
    /// The slide (its id on the link).
    pub slide: u32,
    /// The recognition model's class so far.
    pub class: String,
    /// Its vote so far (mean of both forests' window probabilities), 0–1.
    pub confidence: f64,
    /// The width model's class so far, mm (read it only when `class` is a crack).
    pub width_mm: Option<f64>,
    /// Windows classified so far in this stroke.
    pub windows: usize,
    /// Where the finger is along the stroke, mm from its start.
    pub along_mm: f64,
}
