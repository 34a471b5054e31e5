//! A robot that runs missions and publishes them: the one its command line starts, or (serving)
//! those stations ask for with signed commands.

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::mpsc::{channel, Receiver};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crackbot_link::Key;
use crackbot_mission::inspect::{run_inspection, InspectConfig, InspectReport, Progress};
use crackbot_mission::MissionError;

use crate::command::Command;
use crate::wire::{MissionFeed, MissionStatus, Phase, Telemetry};
use crate::{RobotNode, TelemetryError, ZenohOptions};

/// A mission a station asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct StartRequest {
    /// `tactile`, `vision` or `fused`.
    pub mode: String,
    /// A scene file's TOML (`None`: the robot's own scene).
    pub scene_toml: Option<String>,
}

struct Flags {
    /// Stops the running mission (a stop command, an emergency stop, Ctrl-C).
    mission_stop: Arc<AtomicBool>,
    /// Ends the robot (Ctrl-C).
    shutdown: AtomicBool,
    busy: AtomicBool,
    serving: bool,
}

/// A robot on the network that runs missions and publishes everything they do.
pub struct RobotService {
    node: RobotNode,
    flags: Arc<Flags>,
    missions: AtomicU32,
    starts: Mutex<Receiver<StartRequest>>,
}

impl std::fmt::Debug for RobotService {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotService")
            .field("robot", &self.node.name())
            .finish_non_exhaustive()
    }
}

impl RobotService {
    /// Joins the network as `robot`. Serving (`serve`), it takes start commands from stations;
    /// otherwise it refuses them (it runs the mission its command line asked for). Stop and
    /// emergency-stop commands stop the running mission either way (the arm first).
    pub fn open(
        robot: &str,
        options: &ZenohOptions,
        key: Option<&Key>,
        serve: bool,
    ) -> Result<Self, TelemetryError> {
        let flags = Arc::new(Flags {
            mission_stop: Arc::new(AtomicBool::new(false)),
            shutdown: AtomicBool::new(false),
            busy: AtomicBool::new(false),
            serving: serve,
        });
        let (tx, rx) = channel();
        let tx = Mutex::new(tx);
        let handler_flags = flags.clone();
        let node = RobotNode::open(
            robot,
            options,
            key,
            Box::new(move |command| {
                let f = &handler_flags;
                match command {
                    Command::Stop | Command::EmergencyStop => {
                        f.mission_stop.store(true, Ordering::SeqCst);
                        Ok(())
                    }
                    Command::Start { mode, scene_toml } => {
                        if !f.serving {
                            return Err("this robot runs the mission of its command line; start it with --serve to take missions from a station".into());
                        }
                        if f.shutdown.load(Ordering::SeqCst) {
                            return Err("this robot is shutting down".into());
                        }
                        if f.busy.swap(true, Ordering::SeqCst) {
                            return Err("a mission is running: stop it first".into());
                        }
                        let request = StartRequest {
                            mode: mode.clone(),
                            scene_toml: scene_toml.clone(),
                        };
                        tx.lock()
                            .unwrap_or_else(std::sync::PoisonError::into_inner)
                            .send(request)
                            .map_err(|_| "this robot no longer takes missions".to_string())
                    }
                }
            }),
        )?;
        node.publish(Telemetry::Mission(MissionStatus {
            mission: 0,
            mode: String::new(),
            scene: String::new(),
            phase: Phase::Idle,
            report_json: None,
        }))?;
        Ok(RobotService {
            node,
            flags,
            missions: AtomicU32::new(0),
            starts: Mutex::new(rx),
        })
    }

    /// The robot's node (to publish more).
    pub fn node(&self) -> &RobotNode {
        &self.node
    }

    /// Stops the running mission and ends the serving loop (for a Ctrl-C handler).
    pub fn shutdown(&self) {
        self.flags.shutdown.store(true, Ordering::SeqCst);
        self.flags.mission_stop.store(true, Ordering::SeqCst);
    }

    /// A handle that does what [`Self::shutdown`] does, for a signal handler.
    pub fn shutdown_handle(&self) -> impl Fn() + Send + Sync + 'static {
        let flags = self.flags.clone();
        move || {
            flags.shutdown.store(true, Ordering::SeqCst);
            flags.mission_stop.store(true, Ordering::SeqCst);
        }
    }

    /// Whether [`Self::shutdown`] was called.
    pub fn is_shut_down(&self) -> bool {
        self.flags.shutdown.load(Ordering::SeqCst)
    }

    /// The next mission a station asked for, waiting up to `timeout` (`None`: none yet, or
    /// shutting down).
    pub fn next_start(&self, timeout: Duration) -> Option<StartRequest> {
        if self.is_shut_down() {
            return None;
        }
        self.starts
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .recv_timeout(timeout)
            .ok()
    }

    /// Marks the robot idle again without running a mission (a start request that could not
    /// become a mission: its error is published as the mission's failure).
    fn refuse_start(&self, config_error: &str) -> Result<(), TelemetryError> {
        let n = self.missions.fetch_add(1, Ordering::SeqCst) + 1;
        let r = self.node.publish(Telemetry::Mission(MissionStatus {
            mission: n,
            mode: String::new(),
            scene: String::new(),
            phase: Phase::Failed(config_error.to_string()),
            report_json: None,
        }));
        self.flags.busy.store(false, Ordering::SeqCst);
        r
    }

    /// Runs one mission, publishing its stages, data and report; `progress` sees every event
    /// too (a progress bar). Publishing errors are logged, never stop the mission. (The error
    /// is the mission library's own, as large as `run_inspection`'s.)
    #[expect(
        clippy::result_large_err,
        reason = "the mission library's own error, returned as it is"
    )]
    pub fn run_mission(
        &self,
        config: &InspectConfig,
        mut progress: impl FnMut(&Progress),
    ) -> Result<InspectReport, MissionError> {
        self.flags.busy.store(true, Ordering::SeqCst);
        if !self.is_shut_down() {
            self.flags.mission_stop.store(false, Ordering::SeqCst);
        }
        let n = self.missions.fetch_add(1, Ordering::SeqCst) + 1;
        let mut feed = MissionFeed::new(n, config.mode, &config.rig.site.name);
        self.publish_logged(feed.status());
        let checked = config.check();
        let result = checked.and_then(|c| {
            run_inspection(&c, &self.flags.mission_stop, |p| {
                match feed.on_progress(p) {
                    Ok(bodies) => {
                        if let Progress::Health(h) = p {
                            self.node.set_stream_health(Some(h.into()));
                        }
                        for b in bodies {
                            self.publish_logged(b);
                        }
                    }
                    Err(e) => tracing::warn!("telemetry: {e}"),
                }
                progress(p);
            })
        });
        self.node.set_stream_health(None);
        self.publish_logged(feed.finish(result.as_ref()));
        self.flags.busy.store(false, Ordering::SeqCst);
        result
    }

    /// Serves until [`Self::shutdown`]: each mission a station starts runs with `base`'s
    /// settings, the station's mode and scene, and its report and recordings in
    /// `base.output.out_dir/mission-NNN`. `progress` sees every event of every mission (each starts with
    /// [`Progress::Starting`]); `done` gets each mission's number and result. A start whose mode
    /// or scene is unusable is published as a failed mission and answered by nothing more.
    pub fn serve(
        &self,
        base: &InspectConfig,
        mut progress: impl FnMut(&Progress),
        mut done: impl FnMut(u32, Result<InspectReport, MissionError>),
    ) {
        let mut served = 0u32;
        while !self.is_shut_down() {
            let Some(start) = self.next_start(Duration::from_millis(200)) else {
                continue;
            };
            served += 1;
            let mut config = base.clone();
            config.output.out_dir = base.output.out_dir.join(format!("mission-{served:03}"));
            match start_config(&mut config, &start) {
                Ok(()) => {
                    let result = self.run_mission(&config, &mut progress);
                    done(self.missions.load(Ordering::SeqCst), result);
                }
                Err(e) => {
                    tracing::warn!("refused a mission: {e}");
                    self.publish_logged_failure(&e.to_string());
                    done(self.missions.load(Ordering::SeqCst), Err(*e));
                }
            }
        }
    }

    fn publish_logged_failure(&self, e: &str) {
        if let Err(err) = self.refuse_start(e) {
            tracing::warn!("telemetry: {err}");
        }
    }

    fn publish_logged(&self, body: Telemetry) {
        if let Err(e) = self.node.publish(body) {
            tracing::warn!("telemetry: {e}");
        }
    }
}

/// A station's mode and scene on top of the robot's settings.
/// Applies a station's start request to `config` (boxed: the mission's error is large and this
/// is the rare path).
fn start_config(config: &mut InspectConfig, start: &StartRequest) -> Result<(), Box<MissionError>> {
    config.mode = start.mode.parse().map_err(|e: String| {
        Box::new(MissionError::StartRequest {
            field: "mode",
            reason: format!("{:?}: {e}", start.mode),
        })
    })?;
    if let Some(toml) = &start.scene_toml {
        let scene =
            crackbot_sim::Scene::from_toml_str(toml, "<scene from the station>").map_err(|e| {
                MissionError::StartRequest {
                    field: "scene_toml",
                    reason: e.to_string(),
                }
            })?;
        config.set_scene(scene);
    }
    Ok(())
}
