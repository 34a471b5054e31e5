//! Where the app's data comes from, and where its commands go: a mission run in-process on the
//! simulated scene ([`SimBackend`]), a live fleet over Zenoh ([`LiveBackend`]), or a saved
//! mission (replayed once, read on a thread). Each feeds a shared [`Fleet`]; nothing here blocks
//! the UI thread.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use crackbot_mission::inspect::{run_inspection, InspectConfig, InspectMode, Progress};
use crackbot_sim::Scene;
use crackbot_telemetry::wire::{self, Health, MissionFeed, Telemetry};
use crackbot_telemetry::{Command, CommandReply, Fleet, Station, ZenohOptions};

/// The name of the robot an in-process mission shows as.
pub const LOCAL_ROBOT: &str = "local";

/// How long a live command waits for the robot's answer.
pub const COMMAND_TIMEOUT: Duration = Duration::from_secs(3);

/// Locks the fleet (a poisoned lock still holds a usable fleet).
pub fn lock(fleet: &Mutex<Fleet>) -> MutexGuard<'_, Fleet> {
    fleet
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Where the data comes from.
pub enum Backend {
    /// Missions run in this process on the simulated scene.
    Sim(SimBackend),
    /// Robots over Zenoh.
    Live(LiveBackend),
    /// A saved mission.
    Replay {
        /// Its folder.
        dir: PathBuf,
    },
}

impl std::fmt::Debug for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

impl Backend {
    /// In-process missions on `scene` (`None`: the built-in default scene), `speedup` times
    /// real time, their files under `out_dir`.
    pub fn sim(scene: Option<PathBuf>, speedup: f64, out_dir: PathBuf) -> Self {
        Backend::Sim(SimBackend {
            scene,
            speedup,
            out_dir,
            stop: Arc::new(AtomicBool::new(false)),
            running: Arc::new(AtomicBool::new(false)),
            missions: 0,
        })
    }

    /// A station on the Zenoh network (opened on a thread; its fleet replaces the app's when
    /// it is up).
    pub fn live(options: ZenohOptions, key: Option<PathBuf>, scene: Option<PathBuf>) -> Self {
        Backend::Live(LiveBackend {
            options,
            key,
            scene,
            station: Arc::new(Mutex::new(None)),
            opening: false,
        })
    }

    /// A saved mission in `dir`.
    pub fn replay(dir: PathBuf) -> Self {
        Backend::Replay { dir }
    }

    /// Its name in the UI.
    pub fn label(&self) -> &'static str {
        match self {
            Backend::Sim(_) => "simulated (in-process)",
            Backend::Live(_) => "live (Zenoh)",
            Backend::Replay { .. } => "replay",
        }
    }

    /// Whether it can start missions.
    pub fn can_start(&self) -> bool {
        !matches!(self, Backend::Replay { .. })
    }
}

/// Missions run in-process on the simulated scene, one at a time.
#[derive(Debug)]
pub struct SimBackend {
    /// The scene file (`None`: the built-in default scene).
    pub scene: Option<PathBuf>,
    /// Simulation speed-up.
    pub speedup: f64,
    /// Where each mission's files go (`mission-N/`).
    pub out_dir: PathBuf,
    stop: Arc<AtomicBool>,
    running: Arc<AtomicBool>,
    missions: u32,
}

impl SimBackend {
    /// Whether a mission is running.
    pub fn running(&self) -> bool {
        self.running.load(Ordering::SeqCst)
    }

    /// Stops the running mission now: the flag the mission polls between every step (the arm
    /// stops first). Works whatever the mission thread is doing.
    pub fn emergency_stop(&self) {
        self.stop.store(true, Ordering::SeqCst);
    }

    /// Whether the stop flag is raised.
    pub fn stop_raised(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }

    /// Starts a mission of `mode` on a thread; its telemetry goes into `fleet` as robot
    /// [`LOCAL_ROBOT`], its messages to `log`.
    pub fn start(
        &mut self,
        mode: InspectMode,
        fleet: Arc<Mutex<Fleet>>,
        log: Sender<String>,
        wake: Option<egui::Context>,
    ) -> Result<(), crate::OperatorError> {
        if self.running() {
            return Err(crate::OperatorError::AlreadyRunning);
        }
        self.missions += 1;
        let n = self.missions;
        self.stop.store(false, Ordering::SeqCst);
        self.running.store(true, Ordering::SeqCst);
        let (stop, running) = (self.stop.clone(), self.running.clone());
        let scene_path = self.scene.clone();
        let speedup = self.speedup;
        let out = self
            .out_dir
            .join(format!("mission-{}-{n}", std::process::id()));
        let spawned = std::thread::Builder::new()
            .name(format!("mission-{n}"))
            .spawn(move || {
                run_sim(
                    n,
                    mode,
                    scene_path.as_deref(),
                    speedup,
                    &out,
                    &stop,
                    &fleet,
                    &log,
                );
                running.store(false, Ordering::SeqCst);
                if let Some(ctx) = wake {
                    ctx.request_repaint();
                }
            });
        if let Err(e) = spawned {
            self.running.store(false, Ordering::SeqCst);
            return Err(crate::OperatorError::Thread(e));
        }
        Ok(())
    }
}

#[expect(
    clippy::too_many_arguments,
    reason = "each argument is one the step needs, and a struct would only rename them"
)]
fn run_sim(
    n: u32,
    mode: InspectMode,
    scene_path: Option<&Path>,
    speedup: f64,
    out: &Path,
    stop: &AtomicBool,
    fleet: &Mutex<Fleet>,
    log: &Sender<String>,
) {
    let started = Instant::now();
    let put = |body: Telemetry| {
        let mut f = lock(fleet);
        let r = f.robot_mut(LOCAL_ROBOT);
        r.alive = Some(true);
        r.last_heard = Some(Instant::now());
        r.received += 1;
        r.apply_body(body);
    };
    let scene = match Scene::load_or_default(scene_path) {
        Ok(s) => s,
        Err(e) => {
            let mut feed = MissionFeed::new(n, mode, "?");
            let msg = format!("scene: {e}");
            put(feed.status());
            put(feed.finish::<(), _>(Err(&msg)));
            let _ = log.send(format!("mission {n} did not start: {msg}"));
            return;
        }
    };
    let mut feed = MissionFeed::new(n, mode, &scene.name);
    put(feed.status());
    let _ = log.send(format!(
        "mission {n} ({}) on {:?} started; files in {}",
        wire::mode_name(mode),
        scene.name,
        out.display()
    ));
    let mut config = InspectConfig::new(scene, out);
    config.mode = mode;
    config.rig.speedup = speedup;
    let mut wire_errors = 0u32;
    let result = match config.check() {
        Err(e) => Err(e),
        Ok(checked) => run_inspection(&checked, stop, |p| {
            if let Progress::Health(h) = p {
                put(Telemetry::Health(Health {
                    uptime_s: started.elapsed().as_secs_f64(),
                    stream: Some(wire::StreamHealth::from(h)),
                }));
                return;
            }
            match feed.on_progress(p) {
                Ok(bodies) => {
                    let mut f = lock(fleet);
                    let r = f.robot_mut(LOCAL_ROBOT);
                    r.alive = Some(true);
                    r.last_heard = Some(Instant::now());
                    for b in bodies {
                        r.received += 1;
                        r.apply_body(b);
                    }
                }
                Err(e) => {
                    wire_errors += 1;
                    if wire_errors <= 3 {
                        let _ = log.send(format!("mission {n}: {e}"));
                    }
                }
            }
        }),
    };
    put(feed.finish(result.as_ref()));
    let _ = log.send(match &result {
        Ok(r) => format!(
            "mission {n} finished: {} cracks, {} rejected, {:.1} s",
            r.cracks.len(),
            r.rejected.len(),
            r.elapsed_s
        ),
        Err(e) => format!("mission {n} ended: {e}"),
    });
}

/// A station on the Zenoh network.
pub struct LiveBackend {
    /// How the station joins.
    pub options: ZenohOptions,
    /// The link key file that signs commands (`None`: watch and e-stop only).
    pub key: Option<PathBuf>,
    /// A scene file sent with Start (`None`: the robot's own scene).
    pub scene: Option<PathBuf>,
    station: Arc<Mutex<Option<Arc<Station>>>>,
    opening: bool,
}

impl std::fmt::Debug for LiveBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveBackend")
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

impl LiveBackend {
    /// Opens the station on a thread (once); it catches up with every robot's state.
    pub fn open(&mut self, log: Sender<String>, wake: Option<egui::Context>) {
        if self.opening {
            return;
        }
        self.opening = true;
        let slot = self.station.clone();
        let options = self.options.clone();
        let key_file = self.key.clone();
        std::thread::spawn(move || {
            let key = match key_file.as_deref().map(crackbot_link::Key::from_file) {
                None => None,
                Some(Ok(k)) => Some(k),
                Some(Err(e)) => {
                    let _ = log.send(format!("link key: {e} (watching and e-stop only)"));
                    None
                }
            };
            match Station::open(&options, key.as_ref()) {
                Ok(st) => {
                    let st = Arc::new(st);
                    *slot
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(st.clone());
                    let _ = log.send(format!(
                        "station up (listening on {:?}, connecting to {:?}{})",
                        options.listen,
                        options.connect,
                        if st.has_key() {
                            ", signing commands"
                        } else {
                            ", no key: watch and e-stop only"
                        }
                    ));
                    match st.catch_up(Duration::from_secs(2)) {
                        Ok(n) => {
                            let _ = log.send(format!("caught up: {n} state samples"));
                        }
                        Err(e) => {
                            let _ = log.send(format!("catching up: {e}"));
                        }
                    }
                }
                Err(e) => {
                    let _ = log.send(format!("the station did not open: {e}"));
                }
            }
            if let Some(ctx) = wake {
                ctx.request_repaint();
            }
        });
    }

    /// The station, once open.
    pub fn station(&self) -> Option<Arc<Station>> {
        self.station
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone()
    }

    /// Sends `command` to each of `robots` on its own thread; the answers go to `log`.
    pub fn send(&self, robots: &[String], command: &Command, log: &Sender<String>) {
        let Some(st) = self.station() else {
            let _ = log.send("no station yet: the command was not sent".into());
            return;
        };
        let scene_file = self.scene.clone();
        for robot in robots {
            let (st, robot, log) = (st.clone(), robot.clone(), log.clone());
            let mut command = command.clone();
            let scene_file = scene_file.clone();
            std::thread::spawn(move || {
                if let (Command::Start { scene_toml, .. }, Some(path)) = (&mut command, scene_file)
                {
                    match std::fs::read_to_string(&path) {
                        Ok(t) => *scene_toml = Some(t),
                        Err(e) => {
                            let _ = log.send(format!("scene {}: {e}", path.display()));
                            return;
                        }
                    }
                }
                let what = command_name(&command);
                let msg = match st.command(&robot, command, COMMAND_TIMEOUT) {
                    Ok(CommandReply::Accepted) => format!("{robot}: {what} accepted"),
                    Ok(CommandReply::Refused(why)) => format!("{robot}: {what} refused: {why}"),
                    Err(e) => format!("{robot}: {what} failed: {e}"),
                };
                let _ = log.send(msg);
            });
        }
    }
}

/// A command's name for the log.
pub fn command_name(c: &Command) -> &'static str {
    match c {
        Command::Start { .. } => "start",
        Command::Stop => "stop",
        Command::EmergencyStop => "EMERGENCY STOP",
    }
}

/// Reads the saved mission in `dir` on a thread and applies it to `fleet` as robot `name`.
pub fn load_replay(
    dir: PathBuf,
    fleet: Arc<Mutex<Fleet>>,
    log: Sender<String>,
    wake: Option<egui::Context>,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        let name = replay_robot_name(&dir);
        match crate::replay::load(&dir) {
            Ok(r) => {
                let n = r.telemetry.len();
                {
                    let mut f = lock(&fleet);
                    let robot = f.robot_mut(&name);
                    for t in r.telemetry {
                        robot.received += 1;
                        robot.apply_body(t);
                    }
                    robot.alive = Some(false);
                }
                let _ = log.send(format!(
                    "replayed {} ({n} samples){}",
                    dir.display(),
                    if r.approximate_overlay {
                        "; the report has no camera homography: the overlay fits the workspace to the frame"
                    } else {
                        ""
                    }
                ));
            }
            Err(e) => {
                let _ = log.send(format!("{e}"));
            }
        }
        if let Some(ctx) = wake {
            ctx.request_repaint();
        }
    })
}

/// The robot name a replay shows as: `replay:<folder name>`.
pub fn replay_robot_name(dir: &std::path::Path) -> String {
    format!(
        "replay:{}",
        dir.file_name()
            .map_or_else(|| "mission".into(), |n| n.to_string_lossy().into_owned())
    )
}
