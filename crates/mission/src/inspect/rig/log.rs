//! The mission's log, `mission.mcap` (`crackbot-mcap`): every progress event a front end sees,
//! as Foxglove messages stamped with the host's clock, and the report at the end.

use std::time::{Instant, SystemTime};

use crackbot_mcap::{JsonTopic, Label, LogLevel, LogWriter, Polyline, SampleMessage, SceneLine};
use crackbot_planner::{Candidate, Plan};
use serde::Serialize;

use super::settings::OutputConfig;
use crate::inspect::progress::Progress;
use crate::inspect::report::{FrameInfo, InspectReport};
use crate::MissionError;

/// The file's name in the mission's folder.
pub const LOG_FILE: &str = "mission.mcap";

/// Colours (RGBA): candidates, planned slides, the workspace.
const CANDIDATE_RGBA: [f64; 4] = [1.0, 0.3, 0.1, 1.0];
const SLIDE_RGBA: [f64; 4] = [0.1, 0.7, 1.0, 1.0];
const WORKSPACE_RGBA: [f64; 4] = [0.6, 0.6, 0.6, 1.0];

/// The mission's stage, on `/mission/status`.
#[derive(Debug, Serialize)]
struct Status<'a> {
    stage: &'a str,
    detail: String,
}

/// The log being written, with what it needs to draw later events (the frame's homography).
pub(crate) struct MissionLog {
    writer: LogWriter,
    /// The mission clock's zero (`t_s = 0`: the link's start).
    t0: Instant,
    surface_to_image: Option<[[f64; 3]; 3]>,
    /// The first error met while logging (reported when the log is finished).
    failed: Option<crackbot_mcap::LogError>,
    /// The same messages live on ROS 2 topics (`OutputConfig::ros2_domain`).
    #[cfg(feature = "ros2")]
    ros2: Option<super::ros2::Ros2Tap>,
}

impl MissionLog {
    /// Opens `mission.mcap` in the mission's folder (`None` when the config turns it off), its
    /// clock zero at `t0`; with `config.foxglove`, serves it live.
    pub(crate) fn open(config: &OutputConfig, t0: Instant) -> Result<Option<Self>, MissionError> {
        if !config.mcap {
            return Ok(None);
        }
        let since = Instant::now().saturating_duration_since(t0);
        let origin = SystemTime::now()
            .checked_sub(since)
            .unwrap_or(SystemTime::UNIX_EPOCH);
        #[cfg_attr(
            not(feature = "foxglove"),
            expect(unused_mut, reason = "only the live view changes the writer")
        )]
        let mut writer = LogWriter::create(
            &config.out_dir.join(LOG_FILE),
            crackbot_mcap::unix_ns(origin),
        )?;
        #[cfg(feature = "foxglove")]
        if let Some(addr) = config.foxglove {
            let at = writer.serve(addr)?;
            tracing::info!("Foxglove live view on ws://{at}");
            writer.log(0.0, LogLevel::Info, &format!("live view on ws://{at}"));
        }
        #[cfg(feature = "ros2")]
        let ros2 = match config.ros2_domain {
            Some(domain) => Some(super::ros2::Ros2Tap::open(domain)?),
            None => None,
        };
        Ok(Some(MissionLog {
            writer,
            t0,
            surface_to_image: None,
            failed: None,
            #[cfg(feature = "ros2")]
            ros2,
        }))
    }

    /// Mission time now, s.
    fn now_s(&self) -> f64 {
        self.t0.elapsed().as_secs_f64()
    }

    fn json<T: Serialize>(&mut self, topic: JsonTopic, t_s: f64, value: &T) {
        if let Err(e) = self.writer.json(topic, t_s, value) {
            self.failed.get_or_insert(e);
        }
        #[cfg(feature = "ros2")]
        if let (Some(tap), Ok(v)) = (&mut self.ros2, serde_json::to_value(value)) {
            let ns = self.writer.ns(t_s);
            tap.tap(topic.topic(), ns, crackbot_mcap::Payload::Json(v));
        }
    }

    fn sample(&mut self, topic: JsonTopic, m: &SampleMessage) {
        self.json(topic, m.t_s, m);
    }

    /// A log line at `t_s`.
    fn line(&mut self, t_s: f64, level: LogLevel, text: &str) {
        self.writer.log(t_s, level, text);
        #[cfg(feature = "ros2")]
        if let Some(tap) = &mut self.ros2 {
            let payload = crackbot_mcap::Payload::Log {
                level: level.foxglove_level(),
                message: text.to_string(),
            };
            tap.tap("/log", self.writer.ns(t_s), payload);
        }
    }

    fn stage(&mut self, stage: &str, detail: String) {
        let t = self.now_s();
        self.line(t, LogLevel::Info, &format!("{stage}: {detail}"));
        self.json(JsonTopic::Status, t, &Status { stage, detail });
    }

    /// Logs one progress event.
    pub(crate) fn record(&mut self, p: &Progress) {
        match p {
            Progress::Starting => self.stage("starting", String::new()),
            Progress::Frame(f) => self.frame(f),
            Progress::Perceived { detections, .. } => self.perceived(detections),
            Progress::Planned {
                plan,
                slides,
                estimated_s,
            } => {
                self.plan(plan);
                self.stage(
                    "planned",
                    format!("{slides} slides, about {estimated_s:.0} s"),
                );
            }
            Progress::Samples { samples } => {
                for s in samples {
                    let m = SampleMessage::new(s.t_s, s.raw, s.slide, s.along_mm);
                    self.sample(JsonTopic::Tactile, &m);
                }
            }
            Progress::Stroked { slide, samples } => {
                for s in samples {
                    let m = SampleMessage::new(s.t_s, s.raw, Some(*slide), Some(s.along_mm));
                    self.sample(JsonTopic::Slide, &m);
                }
            }
            Progress::Poses { poses } => {
                for a in poses {
                    self.writer.finger_at(a.t_s, a.pose_mm);
                    let [x, y, z] = a.pose_mm;
                    let v = serde_json::json!({
                        "t_s": a.t_s, "x_mm": x, "y_mm": y, "z_mm": z,
                        "slide": a.slide, "along_mm": a.along_mm,
                    });
                    self.json(JsonTopic::ArmPose, a.t_s, &v);
                }
            }
            Progress::Health(h) => self.json(JsonTopic::Health, self.now_s(), h),
            Progress::Feeling(f) => self.json(JsonTopic::Feeling, self.now_s(), f),
            Progress::Slid {
                done,
                of,
                class,
                pass,
            } => {
                let t = self.now_s();
                self.json(JsonTopic::Verdict, t, pass.as_ref());
                let text = format!("slide {} ({done}/{of}): {class}", pass.id);
                self.line(t, LogLevel::Info, &text);
            }
        }
    }

    fn frame(&mut self, f: &FrameInfo) {
        self.surface_to_image = Some(f.surface_to_image);
        let t = self.now_s();
        match std::fs::read(&f.path) {
            Ok(png) => {
                self.writer.frame(t, &png);
                #[cfg(feature = "ros2")]
                if let Some(tap) = &mut self.ros2 {
                    let payload = crackbot_mcap::Payload::Image {
                        format: "png".into(),
                        data: png,
                    };
                    tap.tap("/camera/image", self.writer.ns(t), payload);
                }
            }
            Err(e) => {
                let text = format!("the frame {}: {e}", f.path);
                self.line(t, LogLevel::Warning, &text);
            }
        }
        self.stage("perceiving", format!("frame {}×{}", f.width, f.height));
    }

    /// The candidates: on the frame (centre lines and labels, px) and on the surface (mm).
    fn perceived(&mut self, candidates: &[Candidate]) {
        let t = self.now_s();
        let course = |c: &Candidate| {
            let (s, co) = c.axis_deg.to_radians().sin_cos();
            let h = c.length_mm / 2.0;
            let [x, y] = c.centre_mm;
            [[x - co * h, y - s * h], [x + co * h, y + s * h]]
        };
        if let Some(h) = self.surface_to_image {
            let lines: Vec<Polyline> = candidates
                .iter()
                .map(|c| Polyline {
                    points: course(c).iter().map(|&p| project(&h, p)).collect(),
                    closed: false,
                    rgba: CANDIDATE_RGBA,
                })
                .collect();
            let labels: Vec<Label> = candidates
                .iter()
                .map(|c| Label {
                    at: project(&h, c.centre_mm),
                    text: format!("{} {:.2}", c.id, c.score),
                })
                .collect();
            self.writer.detections(t, &lines, &labels);
        }
        let on_surface: Vec<SceneLine> = candidates
            .iter()
            .map(|c| SceneLine {
                points_mm: course(c).iter().map(|&[x, y]| [x, y, 0.0]).collect(),
                thickness_mm: c.width_mm.unwrap_or(1.0).max(0.5),
                rgba: CANDIDATE_RGBA,
            })
            .collect();
        self.writer.scene(t, "candidates", &on_surface);
        self.stage("perceived", format!("{} candidates", candidates.len()));
    }

    /// The plan on the surface: the workspace and every slide.
    fn plan(&mut self, plan: &Plan) {
        let w = &plan.workspace;
        let mut lines = vec![SceneLine {
            points_mm: vec![
                [w.x_min_mm, w.y_min_mm, 0.0],
                [w.x_max_mm, w.y_min_mm, 0.0],
                [w.x_max_mm, w.y_max_mm, 0.0],
                [w.x_min_mm, w.y_max_mm, 0.0],
                [w.x_min_mm, w.y_min_mm, 0.0],
            ],
            thickness_mm: 0.5,
            rgba: WORKSPACE_RGBA,
        }];
        lines.extend(plan.slides.iter().map(|s| SceneLine {
            points_mm: vec![
                [s.start_mm[0], s.start_mm[1], 0.0],
                [s.end_mm[0], s.end_mm[1], 0.0],
            ],
            thickness_mm: 0.8,
            rgba: SLIDE_RGBA,
        }));
        self.writer.scene(self.now_s(), "plan", &lines);
    }

    /// Logs how the mission ended (the report, or the error) and closes the file.
    pub(crate) fn finish(
        mut self,
        result: Result<&InspectReport, &MissionError>,
    ) -> Result<(), MissionError> {
        let t = self.now_s();
        match result {
            Ok(report) => {
                self.json(JsonTopic::Report, t, report);
                let n = report.cracks.len();
                self.stage("finished", format!("{n} cracks reported"));
            }
            Err(e) => {
                self.line(t, LogLevel::Error, &e.to_string());
                self.json(
                    JsonTopic::Status,
                    t,
                    &Status {
                        stage: "failed",
                        detail: e.to_string(),
                    },
                );
            }
        }
        let failed = self.failed.take();
        self.writer.finish()?;
        #[cfg(feature = "ros2")]
        if let Some(tap) = self.ros2.take() {
            // Reliable readers get the report and the last status before the node goes.
            std::thread::sleep(super::ros2::LINGER);
            if tap.failed() > 0 {
                tracing::warn!("ROS 2 live topics: {} messages not published", tap.failed());
            }
        }
        match failed {
            Some(e) => Err(e.into()),
            None => Ok(()),
        }
    }
}

/// Surface mm → image px through the homography `h`.
fn project(h: &[[f64; 3]; 3], [x, y]: [f64; 2]) -> [f64; 2] {
    let w = h[2][0] * x + h[2][1] * y + h[2][2];
    let w = if w.abs() < 1e-12 { 1e-12 } else { w };
    [
        (h[0][0] * x + h[0][1] * y + h[0][2]) / w,
        (h[1][0] * x + h[1][1] * y + h[1][2]) / w,
    ]
}
