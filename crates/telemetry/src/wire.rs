//! What travels: one [`Envelope`] per Zenoh sample, postcard-encoded (the link's compact serde
//! format), with a version that a peer checks before anything else.
//!
//! ```text
//! sample payload = postcard(Envelope { version: u16, robot, seq, sent_unix_ms, body: Telemetry })
//! ```
//!
//! Postcard encodes integers as varints, strings and sequences with a varint length, enums with
//! a varint variant index, `Option` with a 0/1 byte, `f64` as 8 little-endian bytes: the format
//! is documented at <https://postcard.jamesmunns.com/wire-format>. A decoder that meets another
//! `version` refuses the sample ([`WireError::Version`]) instead of misreading it.

use serde::{Deserialize, Serialize};

use crackbot_mission::inspect::{
    Feeling as MissionFeeling, FrameInfo, InspectMode, PassRecord, Progress,
    StreamHealth as MissionStreamHealth,
};
use crackbot_planner::{Candidate, Plan};

/// Version of the telemetry encoding; bumped on any change of the types below (2: the running
/// verdict, [`Telemetry::Feeling`]).
pub const WIRE_VERSION: u16 = 2;

/// One published sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Envelope {
    /// [`WIRE_VERSION`] of the sender.
    pub version: u16,
    /// The robot's name (also in the key expression).
    pub robot: String,
    /// Per-robot sequence number of the sample, from 1.
    pub seq: u64,
    /// When it was sent, ms since the Unix epoch (the robot's clock).
    pub sent_unix_ms: u64,
    /// What it carries.
    pub body: Telemetry,
}

/// The topics a robot publishes (each under `crackbot/<robot>/<topic>`, see [`crate::keys`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Telemetry {
    /// Sensor samples as they arrived (`tactile`).
    Tactile(Vec<TactileSample>),
    /// The frame the mission looked at (`camera`).
    Camera(CameraFrame),
    /// The detector's candidates in surface mm (`detections`).
    Detections(Vec<Detection>),
    /// The planned slides (`plan`).
    Plan(PlannedSlides),
    /// One judged slide pass (`verdicts`).
    Verdict(PassVerdict),
    /// The robot is alive, and how its streams are doing (`health`, at least every 250 ms).
    Health(Health),
    /// The mission's stage and, at the end, its report (`mission`).
    Mission(MissionStatus),
    /// What the finger feels so far in the stroke under way (`verdicts`, every 0.1 s while it
    /// is down): shown only; the pass's verdict follows as [`Telemetry::Verdict`].
    Feeling(Feeling),
}

impl Telemetry {
    /// The topic this sample is published under.
    pub fn topic(&self) -> crate::keys::Topic {
        use crate::keys::Topic;
        match self {
            Telemetry::Tactile(_) => Topic::Tactile,
            Telemetry::Camera(_) => Topic::Camera,
            Telemetry::Detections(_) => Topic::Detections,
            Telemetry::Plan(_) => Topic::Plan,
            Telemetry::Verdict(_) | Telemetry::Feeling(_) => Topic::Verdicts,
            Telemetry::Health(_) => Topic::Health,
            Telemetry::Mission(_) => Topic::Mission,
        }
    }
}

/// One sensor sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TactileSample {
    /// Time since the mission's link started, s.
    pub t_s: f64,
    /// D1, D2, D3, P, counts.
    pub raw: [u16; 4],
}

/// A camera frame, PNG-encoded, with the homography that draws surface mm on it.
#[derive(Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraFrame {
    /// Width, px.
    pub width: u32,
    /// Height, px.
    pub height: u32,
    /// Surface mm → pixels (row-major homography).
    pub surface_to_image: [[f64; 3]; 3],
    /// The PNG file's bytes.
    pub png: Vec<u8>,
}

impl std::fmt::Debug for CameraFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CameraFrame")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("png_bytes", &self.png.len())
            .finish()
    }
}

impl CameraFrame {
    /// Where surface point `mm` lands in the frame, px (`None` behind the camera).
    pub fn to_pixel(&self, mm: [f64; 2]) -> Option<[f64; 2]> {
        let m = &self.surface_to_image;
        let w = m[2][0] * mm[0] + m[2][1] * mm[1] + m[2][2];
        if !(w.is_finite() && w > 0.0) {
            return None;
        }
        Some([
            (m[0][0] * mm[0] + m[0][1] * mm[1] + m[0][2]) / w,
            (m[1][0] * mm[0] + m[1][1] * mm[1] + m[1][2]) / w,
        ])
    }
}

/// A candidate crack from the camera.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Detection {
    /// Its id (the plan and the verdicts refer to it).
    pub id: u64,
    /// Centre, mm.
    pub centre_mm: [f64; 2],
    /// Main axis, degrees from +x.
    pub axis_deg: f64,
    /// Length along the axis, mm.
    pub length_mm: f64,
    /// Extent across it, mm, when known.
    pub width_mm: Option<f64>,
    /// The detector's score.
    pub score: f64,
}

impl From<&Candidate> for Detection {
    fn from(c: &Candidate) -> Self {
        Detection {
            id: c.id,
            centre_mm: c.centre_mm,
            axis_deg: c.axis_deg,
            length_mm: c.length_mm,
            width_mm: c.width_mm,
            score: c.score,
        }
    }
}

/// The plan's slides.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedSlides {
    /// Each slide, in order.
    pub slides: Vec<PlannedSlide>,
    /// The planner's time estimate, s.
    pub estimated_s: f64,
}

/// One planned slide.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedSlide {
    /// Candidates it crosses (none: a tactile-only scan row).
    pub candidates: Vec<u64>,
    /// Start, mm.
    pub start_mm: [f64; 2],
    /// End, mm.
    pub end_mm: [f64; 2],
    /// One-way passes.
    pub passes: u32,
    /// Sliding speed, mm/s.
    pub speed_mm_s: f64,
}

impl From<&Plan> for PlannedSlides {
    fn from(p: &Plan) -> Self {
        PlannedSlides {
            slides: p
                .slides
                .iter()
                .map(|s| PlannedSlide {
                    candidates: s.candidates.clone(),
                    start_mm: s.start_mm,
                    end_mm: s.end_mm,
                    passes: s.passes,
                    speed_mm_s: s.speed_mm_s,
                })
                .collect(),
            estimated_s: p.estimated_s,
        }
    }
}

/// One judged slide pass.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassVerdict {
    /// Slide pass id.
    pub id: u32,
    /// The candidate it checked.
    pub candidate: Option<u64>,
    /// Start, mm.
    pub start_mm: [f64; 2],
    /// End, mm.
    pub end_mm: [f64; 2],
    /// Samples classified.
    pub samples: u64,
    /// The recognition verdict (`None`: too short to judge).
    pub class: Option<String>,
    /// Its vote, 0–1.
    pub confidence: f64,
    /// The width verdict, mm.
    pub width_mm: Option<f64>,
    /// A doubt (unknown surface, dead channel…).
    pub doubt: Option<String>,
    /// Where the proximity channel's dip puts the crack: centre and width, mm along the pass.
    pub dip_mm: Option<[f64; 2]>,
}

impl From<&PassRecord> for PassVerdict {
    fn from(p: &PassRecord) -> Self {
        PassVerdict {
            id: p.id,
            candidate: p.candidate,
            start_mm: p.start_mm,
            end_mm: p.end_mm,
            samples: p.samples as u64,
            class: p.class.clone(),
            confidence: p.confidence,
            width_mm: p.width_mm,
            doubt: p.doubt.as_ref().map(ToString::to_string),
            dip_mm: p.dip.map(|d| [d.centre_mm, d.width_mm]),
        }
    }
}

/// The running verdict of the stroke under way ([`crackbot_mission::inspect::Feeling`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Feeling {
    /// The slide pass (its id, as in [`PassVerdict::id`]).
    pub id: u32,
    /// The recognition model's class so far.
    pub class: String,
    /// Its vote so far, 0–1.
    pub confidence: f64,
    /// The width model's class so far, mm.
    pub width_mm: Option<f64>,
    /// Windows classified so far.
    pub windows: u64,
    /// Where the finger is along the pass, mm from its start.
    pub along_mm: f64,
}

impl From<&MissionFeeling> for Feeling {
    fn from(f: &MissionFeeling) -> Self {
        Feeling {
            id: f.slide,
            class: f.class.clone(),
            confidence: f.confidence,
            width_mm: f.width_mm,
            windows: f.windows as u64,
            along_mm: f.along_mm,
        }
    }
}

/// The robot's heartbeat.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Health {
    /// Since the robot's telemetry started, s.
    pub uptime_s: f64,
    /// The mission's streams, while one runs.
    pub stream: Option<StreamHealth>,
}

/// The sensor stream's and the link's counters ([`crackbot_mission::inspect::StreamHealth`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StreamHealth {
    /// Sensor samples per second (400 nominal, times the simulation's speed-up).
    pub sample_rate_hz: f64,
    /// Sensor frames decoded.
    pub frames: u64,
    /// Sensor frames rejected by their CRC.
    pub crc_errors: u64,
    /// Gaps in the sensor's sequence numbers.
    pub gaps: u64,
    /// Frames lost in them.
    pub missing_frames: u64,
    /// Link datagrams sent.
    pub link_sent: u64,
    /// Link retries.
    pub link_retries: u64,
    /// Link packets refused.
    pub link_rejected: u64,
    /// Age of the controller's last state, ms (the link's latency, or how long it has been lost).
    pub state_age_ms: Option<f64>,
}

impl From<&MissionStreamHealth> for StreamHealth {
    fn from(h: &MissionStreamHealth) -> Self {
        StreamHealth {
            sample_rate_hz: h.sample_rate_hz,
            frames: h.frames,
            crc_errors: h.crc_errors,
            gaps: h.gaps,
            missing_frames: h.missing_frames,
            link_sent: h.link_sent,
            link_retries: h.link_retries,
            link_rejected: h.link_rejected,
            state_age_ms: h.state_age_ms,
        }
    }
}

/// Where a mission stands.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Phase {
    /// No mission: waiting for a command.
    Idle,
    /// Starting the controller, the sensor and the models.
    Starting,
    /// Looking: frame and detector.
    Perceiving,
    /// Sliding: `done` of `of` slides.
    Exploring {
        /// Slides done.
        done: u32,
        /// Slides planned.
        of: u32,
    },
    /// Finished: the report is in [`MissionStatus::report_json`].
    Finished,
    /// Failed or stopped: the reason.
    Failed(String),
}

/// The mission's stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionStatus {
    /// Which mission (counts from 1 on each robot).
    pub mission: u32,
    /// tactile, vision or fused.
    pub mode: String,
    /// The scene's name.
    pub scene: String,
    /// Where it stands.
    pub phase: Phase,
    /// The report (the JSON that `crackbot run --json` prints), once finished.
    pub report_json: Option<String>,
}

/// The mode's name as the command line spells it.
pub fn mode_name(mode: InspectMode) -> String {
    mode.as_str().to_string()
}

/// What a mission's progress event becomes on the wire (`None`: nothing to publish; stage
/// changes are published by the robot as [`Telemetry::Mission`]).
pub fn from_progress(p: &Progress) -> Result<Option<Telemetry>, WireError> {
    Ok(Some(match p {
        Progress::Frame(f) => Telemetry::Camera(camera_frame(f)?),
        Progress::Perceived { detections, .. } => {
            Telemetry::Detections(detections.iter().map(Detection::from).collect())
        }
        Progress::Planned { plan, .. } => Telemetry::Plan(PlannedSlides::from(plan)),
        Progress::Samples { samples } => Telemetry::Tactile(
            samples
                .iter()
                .map(|s| TactileSample {
                    t_s: s.t_s,
                    raw: s.raw,
                })
                .collect(),
        ),
        Progress::Slid { pass, .. } => Telemetry::Verdict(PassVerdict::from(pass.as_ref())),
        Progress::Feeling(f) => Telemetry::Feeling(Feeling::from(f)),
        Progress::Health(_)
        | Progress::Poses { .. }
        | Progress::Stroked { .. }
        | Progress::Starting => return Ok(None),
    }))
}

/// Reads the frame's PNG from where the mission saved it.
pub fn camera_frame(f: &FrameInfo) -> Result<CameraFrame, WireError> {
    let png = std::fs::read(&f.path).map_err(|e| WireError::Frame {
        path: f.path.clone(),
        source: e,
    })?;
    Ok(CameraFrame {
        width: f.width,
        height: f.height,
        surface_to_image: f.surface_to_image,
        png,
    })
}

/// Why a sample could not be encoded or decoded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WireError {
    /// The bytes are not an envelope.
    #[error("malformed telemetry sample ({len} bytes): {source}")]
    Malformed {
        /// Payload length.
        len: usize,
        /// What postcard said.
        source: postcard::Error,
    },
    /// Another version of the encoding.
    #[error("telemetry of wire version {got} (this build speaks {WIRE_VERSION}): update one side")]
    Version {
        /// The version the sample claims.
        got: u16,
    },
    /// Encoding failed.
    #[error("encoding telemetry: {0}")]
    Encode(postcard::Error),
    /// The frame file could not be read.
    #[error("reading the camera frame {path}: {source}")]
    Frame {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
}

/// The sample's bytes.
pub fn encode(envelope: &Envelope) -> Result<Vec<u8>, WireError> {
    postcard::to_allocvec(envelope).map_err(WireError::Encode)
}

/// An envelope from a sample's bytes: the version is checked first (it is the first field), so
/// a sample of another version is named as such, not as garbage.
pub fn decode(bytes: &[u8]) -> Result<Envelope, WireError> {
    let (version, _) =
        postcard::take_from_bytes::<u16>(bytes).map_err(|source| WireError::Malformed {
            len: bytes.len(),
            source,
        })?;
    if version != WIRE_VERSION {
        return Err(WireError::Version { got: version });
    }
    postcard::from_bytes(bytes).map_err(|source| WireError::Malformed {
        len: bytes.len(),
        source,
    })
}

/// Turns one mission's progress events into telemetry: the data they carry and the mission's
/// stage as it changes. The robot publishes what it returns; the operator app applies it to a
/// [`crate::RobotView`] for missions it runs in-process.
#[derive(Debug, Clone)]
pub struct MissionFeed {
    status: MissionStatus,
}

impl MissionFeed {
    /// Mission number `mission` (from 1 on each robot) of `mode` on scene `scene`.
    pub fn new(mission: u32, mode: InspectMode, scene: &str) -> Self {
        MissionFeed {
            status: MissionStatus {
                mission,
                mode: mode_name(mode),
                scene: scene.to_string(),
                phase: Phase::Starting,
                report_json: None,
            },
        }
    }

    /// The mission's status now.
    pub fn status(&self) -> Telemetry {
        Telemetry::Mission(self.status.clone())
    }

    /// What `p` becomes: its data, preceded by the new stage when the stage changed.
    pub fn on_progress(&mut self, p: &Progress) -> Result<Vec<Telemetry>, WireError> {
        let phase = match p {
            Progress::Starting => Some(Phase::Starting),
            Progress::Frame(_) => Some(Phase::Perceiving),
            Progress::Planned { slides, .. } => Some(Phase::Exploring {
                done: 0,
                of: *slides as u32,
            }),
            Progress::Slid { done, of, .. } => Some(Phase::Exploring {
                done: *done as u32,
                of: *of as u32,
            }),
            _ => None,
        };
        let mut out = Vec::new();
        if let Some(phase) = phase.filter(|ph| *ph != self.status.phase) {
            self.status.phase = phase;
            out.push(self.status());
        }
        out.extend(from_progress(p)?);
        Ok(out)
    }

    /// The final status: finished with the report's JSON, or failed with the error.
    pub fn finish<R: Serialize, E: std::fmt::Display>(
        &mut self,
        result: Result<&R, &E>,
    ) -> Telemetry {
        match result {
            Ok(report) => {
                self.status.phase = Phase::Finished;
                self.status.report_json = serde_json::to_string(report).ok();
            }
            Err(e) => {
                self.status.phase = Phase::Failed(e.to_string());
            }
        }
        self.status()
    }
}

/// A judged pass for the crate's tests.
#[cfg(test)]
pub(crate) fn example_verdict(id: u32) -> PassVerdict {
    PassVerdict {
        id,
        candidate: Some(3),
        start_mm: [0.0, 0.0],
        end_mm: [16.0, 0.0],
        samples: 1400,
        class: Some("crack".into()),
        confidence: 0.8,
        width_mm: Some(5.0),
        doubt: None,
        dip_mm: Some([8.0, 5.1]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn samples() -> Vec<Telemetry> {
        vec![
            Telemetry::Tactile(vec![TactileSample {
                t_s: 1.25,
                raw: [1, 2, 3, u16::MAX],
            }]),
            Telemetry::Camera(CameraFrame {
                width: 2,
                height: 1,
                surface_to_image: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                png: vec![0x89, b'P', b'N', b'G'],
            }),
            Telemetry::Detections(vec![Detection {
                id: 3,
                centre_mm: [10.0, 20.0],
                axis_deg: 45.0,
                length_mm: 30.0,
                width_mm: None,
                score: 0.9,
            }]),
            Telemetry::Plan(PlannedSlides {
                slides: vec![PlannedSlide {
                    candidates: vec![3],
                    start_mm: [0.0, 0.0],
                    end_mm: [16.0, 0.0],
                    passes: 1,
                    speed_mm_s: 4.6,
                }],
                estimated_s: 4.0,
            }),
            Telemetry::Verdict(example_verdict(1)),
            Telemetry::Health(Health {
                uptime_s: 3.0,
                stream: Some(StreamHealth::default()),
            }),
            Telemetry::Mission(MissionStatus {
                mission: 1,
                mode: "fused".into(),
                scene: "default".into(),
                phase: Phase::Failed("interrupted".into()),
                report_json: Some("{}".into()),
            }),
            Telemetry::Feeling(Feeling {
                id: 2,
                class: "crack".into(),
                confidence: 0.6,
                width_mm: Some(2.0),
                windows: 57,
                along_mm: 7.5,
            }),
        ]
    }

    #[test]
    fn every_topic_round_trips_and_a_truncated_or_foreign_sample_is_named() {
        for (i, body) in samples().into_iter().enumerate() {
            let env = Envelope {
                version: WIRE_VERSION,
                robot: "r1".into(),
                seq: i as u64 + 1,
                sent_unix_ms: 1_790_000_000_000,
                body,
            };
            let bytes = encode(&env).unwrap();
            assert_eq!(decode(&bytes).unwrap(), env);
            for cut in 0..bytes.len() {
                assert!(
                    matches!(decode(&bytes[..cut]), Err(WireError::Malformed { .. })),
                    "{i}: {cut} of {} bytes decoded",
                    bytes.len()
                );
            }
            let mut other = bytes.clone();
            other[0] = 1; // the version before the running verdict
            assert!(matches!(decode(&other), Err(WireError::Version { got: 1 })));
        }
    }

    #[test]
    fn the_frame_maps_surface_points_to_pixels_and_refuses_points_behind_the_camera() {
        let mut f = CameraFrame {
            width: 640,
            height: 480,
            surface_to_image: [[2.0, 0.0, 10.0], [0.0, 2.0, 20.0], [0.0, 0.0, 1.0]],
            png: Vec::new(),
        };
        assert_eq!(f.to_pixel([5.0, 5.0]), Some([20.0, 30.0]));
        f.surface_to_image[2] = [0.0, 0.0, -1.0];
        assert_eq!(f.to_pixel([5.0, 5.0]), None);
    }
}
