//! The app's state and its UI. [`OperatorApp::show`] draws everything into a [`egui::Ui`]; the
//! eframe window and the kittest harness both call it.
//!
//! Each frame takes one short look at the fleet under its lock (the decimated plot lines, the
//! selected robot's detections, plan, verdicts and counters), then draws without the lock, so
//! the mission and network threads are never held up by drawing and drawing never waits on them
//! for long.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crackbot_mission::inspect::InspectMode;
use crackbot_telemetry::fleet::RobotView;
use crackbot_telemetry::wire::{
    CameraFrame, Detection, Feeling, Health, MissionStatus, PassVerdict, Phase, PlannedSlide,
    TactileSample,
};
use crackbot_telemetry::{Command, Fleet};
use egui::{Color32, RichText, Stroke};

use crate::decimate;
use crate::export;
use crate::frames::{FrameStats, FrameTimes};
use crate::overlay;
use crate::source::{self, lock, Backend};

/// Channel names, in the order of the samples' `raw`.
pub const CHANNELS: [&str; 4] = ["D1", "D2", "D3", "P"];
/// Colours of the channels.
const CHANNEL_COLOURS: [Color32; 4] = [
    Color32::from_rgb(90, 170, 255),
    Color32::from_rgb(255, 160, 60),
    Color32::from_rgb(110, 210, 110),
    Color32::from_rgb(230, 90, 200),
];
/// The label of the emergency stop button (the tests find it by this).
pub const ESTOP_LABEL: &str = "EMERGENCY STOP";
/// Log lines kept.
const LOG_KEPT: usize = 200;

/// An action waiting for the operator's confirmation.
#[derive(Debug, Clone, PartialEq)]
pub enum Pending {
    /// Start a mission (the arm will move).
    Start {
        /// Which mode.
        mode: InspectMode,
        /// On which robot.
        robot: String,
    },
}

/// Frames to measure, and where the result goes (`--measure-frames`).
#[derive(Debug, Clone)]
pub struct Measure {
    /// Frames to record once data streams.
    pub frames: usize,
    /// The JSON summary's path.
    pub out: PathBuf,
    /// A screenshot taken at the end.
    pub screenshot: Option<PathBuf>,
    /// Frames counted since data started streaming (`None`: not yet).
    pub counted: Option<usize>,
    /// The measurement is written.
    pub done: bool,
    /// When the app started waiting for data.
    pub since: Instant,
}

/// What one frame shows of the selected robot, copied out under the fleet's lock.
#[derive(Default)]
struct Snapshot {
    robots: Vec<(String, bool, Option<Phase>)>,
    mission: Option<MissionStatus>,
    camera_key: Option<(u32, usize, u32, u32)>,
    camera_geom: Option<CameraFrame>,
    detections: Vec<Detection>,
    slides: Vec<PlannedSlide>,
    estimated_s: Option<f64>,
    verdicts: Vec<PassVerdict>,
    feeling: Option<Feeling>,
    lines: [Vec<[f64; 2]>; 4],
    visible_samples: usize,
    t_first: Option<f64>,
    t_last: Option<f64>,
    window: (f64, f64),
    health: Option<Health>,
    lost: bool,
    latency_ms: Option<f64>,
    received: u64,
    out_of_order: u64,
    undecodable: u64,
    tactile_total: u64,
}

/// The operator app.
pub struct OperatorApp {
    /// Where the data comes from.
    pub backend: Backend,
    fleet: Arc<Mutex<Fleet>>,
    /// The robot shown (`None`: the first one).
    pub selected: Option<String>,
    /// Paused at this end time, s (`None`: following the newest samples).
    pub paused_end: Option<f64>,
    /// The plots' time window, s.
    pub window_s: f64,
    /// Mode of the next mission.
    pub mode: InspectMode,
    /// Scene file of the next mission (empty: the built-in default, or the robot's own).
    pub scene_text: String,
    /// The action waiting for confirmation.
    pub pending: Option<Pending>,
    /// Messages, newest last.
    pub log: VecDeque<String>,
    log_tx: Sender<String>,
    log_rx: Receiver<String>,
    /// Frame intervals.
    pub frames: FrameTimes,
    /// Time spent building each frame's UI (this app's share of a frame).
    pub ui_times: FrameTimes,
    last_frame: Option<Instant>,
    texture: Option<((u32, usize, u32, u32), egui::TextureHandle)>,
    /// Emergency stops issued.
    pub estops: u32,
    /// Missions started (after confirmation).
    pub starts: u32,
    /// Where exports go.
    pub export_dir: PathBuf,
    /// The frame-time measurement, if asked.
    pub measure: Option<Measure>,
    /// Shows the frame-time panel.
    pub show_debug: bool,
    plot_width_px: f32,
    initialised: bool,
    ctx: Option<egui::Context>,
}

impl std::fmt::Debug for OperatorApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OperatorApp")
            .field("backend", &self.backend)
            .field("selected", &self.selected)
            .finish_non_exhaustive()
    }
}

impl OperatorApp {
    /// An app over `backend`; exports go to `export_dir`.
    pub fn new(backend: Backend, export_dir: PathBuf) -> Self {
        let (log_tx, log_rx) = channel();
        let scene_text = match &backend {
            Backend::Sim(s) => s.scene.as_ref().map(|p| p.display().to_string()),
            Backend::Live(l) => l.scene.as_ref().map(|p| p.display().to_string()),
            Backend::Replay { .. } => None,
        }
        .unwrap_or_default();
        OperatorApp {
            backend,
            fleet: Arc::new(Mutex::new(Fleet::new())),
            selected: None,
            paused_end: None,
            window_s: 60.0,
            mode: InspectMode::Fused,
            scene_text,
            pending: None,
            log: VecDeque::new(),
            log_tx,
            log_rx,
            frames: FrameTimes::new(4096),
            ui_times: FrameTimes::new(4096),
            last_frame: None,
            texture: None,
            estops: 0,
            starts: 0,
            export_dir,
            measure: None,
            show_debug: true,
            plot_width_px: 800.0,
            initialised: false,
            ctx: None,
        }
    }

    /// The shared fleet (the threads feed it).
    pub fn fleet(&self) -> Arc<Mutex<Fleet>> {
        self.fleet.clone()
    }

    /// A sender for the app's log (threads report through it).
    pub fn log_sender(&self) -> Sender<String> {
        self.log_tx.clone()
    }

    fn say(&mut self, msg: impl Into<String>) {
        self.log.push_back(msg.into());
        while self.log.len() > LOG_KEPT {
            self.log.pop_front();
        }
    }

    fn init(&mut self, ctx: &egui::Context) {
        if self.initialised {
            return;
        }
        self.initialised = true;
        self.ctx = Some(ctx.clone());
        let (log, wake) = (self.log_tx.clone(), Some(ctx.clone()));
        match &mut self.backend {
            Backend::Sim(_) => {}
            Backend::Live(l) => l.open(log, wake),
            Backend::Replay { dir } => {
                self.selected = Some(source::replay_robot_name(dir));
                source::load_replay(dir.clone(), self.fleet.clone(), log, wake);
            }
        }
    }

    /// The robot the controls act on.
    pub fn target_robot(&self) -> Option<String> {
        if let Some(s) = &self.selected {
            return Some(s.clone());
        }
        match &self.backend {
            Backend::Sim(_) => Some(source::LOCAL_ROBOT.to_string()),
            _ => lock(&self.fleet).robots().next().map(|r| r.name.clone()),
        }
    }

    /// Stops every arm now: the in-process mission's stop flag (set here, on the UI thread), or
    /// an emergency stop to every robot of the fleet (sent on threads).
    pub fn emergency_stop(&mut self) {
        self.estops += 1;
        self.pending = None;
        match &self.backend {
            Backend::Sim(s) => {
                s.emergency_stop();
                self.say("EMERGENCY STOP: the mission's stop flag is raised");
            }
            Backend::Live(l) => {
                let robots: Vec<String> =
                    lock(&self.fleet).robots().map(|r| r.name.clone()).collect();
                if robots.is_empty() {
                    self.say("EMERGENCY STOP: no robot known yet");
                } else {
                    l.send(&robots, &Command::EmergencyStop, &self.log_tx);
                    self.say(format!("EMERGENCY STOP sent to {}", robots.join(", ")));
                }
            }
            Backend::Replay { .. } => self.say("EMERGENCY STOP: nothing moves in a replay"),
        }
    }

    /// Asks to start a mission: opens the confirm step (nothing moves yet).
    pub fn request_start(&mut self) {
        if !self.backend.can_start() {
            self.say("a replay cannot start missions");
            return;
        }
        match self.target_robot() {
            Some(robot) => {
                self.pending = Some(Pending::Start {
                    mode: self.mode,
                    robot,
                });
            }
            None => self.say("no robot to start: none has been heard from yet"),
        }
    }

    /// The operator confirmed the pending action.
    pub fn confirm(&mut self) {
        let Some(p) = self.pending.take() else {
            return;
        };
        match p {
            Pending::Start { mode, robot } => self.start(mode, robot),
        }
    }

    /// The operator cancelled the pending action.
    pub fn cancel(&mut self) {
        if self.pending.take().is_some() {
            self.say("cancelled");
        }
    }

    fn scene_choice(&self) -> Option<PathBuf> {
        let t = self.scene_text.trim();
        (!t.is_empty()).then(|| PathBuf::from(t))
    }

    fn start(&mut self, mode: InspectMode, robot: String) {
        let scene = self.scene_choice();
        let (fleet, log, wake) = (self.fleet.clone(), self.log_tx.clone(), self.ctx.clone());
        let result = match &mut self.backend {
            Backend::Sim(s) => {
                s.scene = scene;
                s.start(mode, fleet, log, wake)
            }
            Backend::Live(l) => {
                l.scene = scene;
                l.send(
                    std::slice::from_ref(&robot),
                    &Command::Start {
                        mode: crackbot_telemetry::wire::mode_name(mode),
                        scene_toml: None,
                    },
                    &log,
                );
                Ok(())
            }
            Backend::Replay { .. } => Ok(()),
        };
        match result {
            Ok(()) => {
                self.starts += 1;
                self.paused_end = None;
                self.say(format!(
                    "start ({}) -> {robot}",
                    crackbot_telemetry::wire::mode_name(mode)
                ));
                self.selected = Some(robot);
            }
            Err(e) => self.say(e.to_string()),
        }
    }

    /// Stops the selected robot's mission (the arm stops first; the mission ends with what it
    /// has).
    pub fn stop(&mut self) {
        match &self.backend {
            Backend::Sim(s) => {
                s.emergency_stop();
                self.say("stop: the mission's stop flag is raised");
            }
            Backend::Live(l) => {
                if let Some(r) = self.target_robot() {
                    l.send(&[r], &Command::Stop, &self.log_tx);
                }
            }
            Backend::Replay { .. } => {}
        }
    }

    /// Pauses the plots at the newest sample, or follows again.
    pub fn toggle_pause(&mut self) {
        self.paused_end = match self.paused_end {
            Some(_) => None,
            None => {
                let name = self.target_robot();
                let f = lock(&self.fleet);
                let last =
                    name.and_then(|n| f.robot(&n).and_then(|r| r.tactile.back().map(|s| s.t_s)));
                Some(last.unwrap_or(0.0))
            }
        };
    }

    /// The plots' time window `[t0, t1]` for a robot whose samples span `first..last`.
    pub fn window(&self, first: Option<f64>, last: Option<f64>) -> (f64, f64) {
        let end = match (self.paused_end, last) {
            (Some(p), _) => p,
            (None, Some(l)) => l,
            (None, None) => self.window_s,
        };
        let start = end - self.window_s;
        match first {
            // Less data than the window while following: the data fills the plot.
            Some(f) if self.paused_end.is_none() && f > start => (f, end.max(f + 1.0)),
            _ => (start, end),
        }
    }

    fn snapshot(&self) -> Snapshot {
        let now = Instant::now();
        let live = matches!(self.backend, Backend::Live(_));
        let f = lock(&self.fleet);
        let mut snap = Snapshot {
            robots: f
                .robots()
                .map(|r| (r.name.clone(), live && r.is_lost(now), r.phase().cloned()))
                .collect(),
            ..Snapshot::default()
        };
        let name = self
            .selected
            .clone()
            .or_else(|| snap.robots.first().map(|r| r.0.clone()));
        let Some(r) = name.and_then(|n| f.robot(&n)) else {
            snap.window = self.window(None, None);
            return snap;
        };
        self.fill(&mut snap, r, now);
        snap
    }

    fn fill(&self, snap: &mut Snapshot, r: &RobotView, now: Instant) {
        snap.mission = r.mission.as_ref().map(|m| MissionStatus {
            report_json: m.report_json.as_ref().map(|_| String::new()),
            ..m.clone()
        });
        if let Some(c) = &r.camera {
            let key = (
                r.mission.as_ref().map_or(0, |m| m.mission),
                c.png.len(),
                c.width,
                c.height,
            );
            snap.camera_key = Some(key);
            snap.camera_geom = Some(CameraFrame {
                png: Vec::new(),
                ..c.clone()
            });
        }
        snap.detections = r.detections.clone();
        if let Some(p) = &r.plan {
            snap.slides = p.slides.clone();
            snap.estimated_s = Some(p.estimated_s);
        }
        snap.verdicts = r.verdicts.clone();
        snap.feeling = r.feeling.clone();
        snap.t_first = r.tactile.front().map(|s| s.t_s);
        snap.t_last = r.tactile.back().map(|s| s.t_s);
        let (t0, t1) = self.window(snap.t_first, snap.t_last);
        snap.window = (t0, t1);
        let range = decimate::visible_range(&r.tactile, t0, t1 + 1e-9, |s| s.t_s);
        snap.visible_samples = range.len();
        let columns = (self.plot_width_px.max(16.0)) as usize;
        let (a, b) = r.tactile.as_slices();
        for (k, line) in snap.lines.iter_mut().enumerate() {
            let pts = a
                .iter()
                .chain(b.iter())
                .skip(range.start)
                .take(range.len())
                .map(|s: &TactileSample| [s.t_s, s.raw[k] as f64]);
            *line = decimate::min_max(pts, t0, t1 + 1e-9, columns);
        }
        snap.health = r.health;
        snap.lost = match &self.backend {
            Backend::Sim(s) => s.running() && r.is_lost(now),
            Backend::Replay { .. } => false,
            Backend::Live(_) => r.is_lost(now),
        };
        snap.latency_ms = r.latency_ms;
        snap.received = r.received;
        snap.out_of_order = r.out_of_order;
        snap.undecodable = r.undecodable;
        snap.tactile_total = r.tactile_total;
    }

    /// Draws the whole app into `ui` (one frame).
    pub fn show(&mut self, ui: &mut egui::Ui) {
        let now = Instant::now();
        if let Some(last) = self.last_frame.replace(now) {
            self.frames.push(now.duration_since(last).as_secs_f64());
        }
        let ctx = ui.ctx().clone();
        self.init(&ctx);
        // Live: once the station is up, the views show its fleet (fed by its Zenoh threads).
        if let Backend::Live(l) = &self.backend {
            if let Some(st) = l.station() {
                let theirs = st.fleet_handle();
                if !Arc::ptr_eq(&theirs, &self.fleet) {
                    self.fleet = theirs;
                }
            }
        }
        while let Ok(msg) = self.log_rx.try_recv() {
            self.say(msg);
        }
        let snap = self.snapshot();
        self.update_texture(&ctx, &snap);

        egui::Panel::top("controls").show(ui, |ui| self.controls(ui, &snap));
        egui::Panel::bottom("status")
            .resizable(true)
            .default_size(150.0)
            .show(ui, |ui| self.status_panel(ui, &snap));
        let half = (ui.available_width() * 0.45).max(200.0);
        egui::Panel::left("camera")
            .resizable(true)
            .default_size(half.min(520.0))
            .max_size(half)
            .show(ui, |ui| self.camera_panel(ui, &snap));
        egui::CentralPanel::default().show(ui, |ui| self.signals_panel(ui, &snap));
        self.confirm_modal(&ctx);
        self.measure_step(&ctx, &snap);
        self.ui_times.push(now.elapsed().as_secs_f64());
        // Live data: keep drawing.
        ctx.request_repaint();
    }

    fn update_texture(&mut self, ctx: &egui::Context, snap: &Snapshot) {
        let Some(key) = snap.camera_key else {
            self.texture = None;
            return;
        };
        if self.texture.as_ref().is_some_and(|t| t.0 == key) {
            return;
        }
        let png = {
            let f = lock(&self.fleet);
            let name = self
                .selected
                .clone()
                .or_else(|| snap.robots.first().map(|r| r.0.clone()));
            name.and_then(|n| {
                f.robot(&n)
                    .and_then(|r| r.camera.as_ref().map(|c| c.png.clone()))
            })
        };
        let Some(png) = png else { return };
        match image::load_from_memory(&png) {
            Ok(img) => {
                let rgba = img.to_rgba8();
                let size = [rgba.width() as usize, rgba.height() as usize];
                let ci = egui::ColorImage::from_rgba_unmultiplied(size, rgba.as_raw());
                let tex = ctx.load_texture("camera-frame", ci, egui::TextureOptions::LINEAR);
                self.texture = Some((key, tex));
            }
            Err(e) => {
                // Remember the key so a bad frame is reported once.
                self.say(format!("camera frame: {e}"));
                let ci = egui::ColorImage::new([1, 1], vec![Color32::BLACK]);
                let tex = ctx.load_texture("camera-frame", ci, egui::TextureOptions::LINEAR);
                self.texture = Some((key, tex));
            }
        }
    }

    fn controls(&mut self, ui: &mut egui::Ui, snap: &Snapshot) {
        ui.horizontal_wrapped(|ui| {
            let estop = egui::Button::new(
                RichText::new(ESTOP_LABEL)
                    .strong()
                    .size(18.0)
                    .color(Color32::WHITE),
            )
            .fill(Color32::from_rgb(200, 20, 20))
            .min_size(egui::vec2(170.0, 32.0));
            if ui.add(estop).on_hover_text("Stops every arm now").clicked() {
                self.emergency_stop();
            }
            ui.separator();
            ui.label(format!("Source: {}", self.backend.label()));
            ui.separator();
            let can_start = self.backend.can_start();
            ui.add_enabled_ui(can_start, |ui| {
                egui::ComboBox::from_label("Mode")
                    .selected_text(crackbot_telemetry::wire::mode_name(self.mode))
                    .show_ui(ui, |ui| {
                        for m in [
                            InspectMode::Fused,
                            InspectMode::Tactile,
                            InspectMode::Vision,
                        ] {
                            ui.selectable_value(
                                &mut self.mode,
                                m,
                                crackbot_telemetry::wire::mode_name(m),
                            );
                        }
                    });
                ui.label("Scene:");
                ui.add(
                    egui::TextEdit::singleline(&mut self.scene_text)
                        .hint_text("built-in default")
                        .desired_width(140.0),
                );
                if ui.button("Start...").clicked() {
                    self.request_start();
                }
                if ui.button("Stop").clicked() {
                    self.stop();
                }
            });
            ui.separator();
            let pause = if self.paused_end.is_some() {
                "Follow"
            } else {
                "Pause"
            };
            if ui.button(pause).clicked() {
                self.toggle_pause();
            }
            ui.separator();
            if ui.button("Export CSV").clicked() {
                self.export_csv(snap.window);
            }
            if ui.button("Export report").clicked() {
                self.export_report();
            }
            if ui.button("Screenshot").clicked() {
                self.screenshot(
                    ui.ctx(),
                    self.export_dir.join(format!(
                        "screenshot-{}.png",
                        crackbot_telemetry::command::unix_ms()
                    )),
                );
            }
            ui.checkbox(&mut self.show_debug, "Frame times");
        });
        ui.horizontal_wrapped(|ui| {
            ui.label("Robots:");
            if snap.robots.is_empty() {
                ui.weak("none yet");
            }
            let current = self
                .selected
                .clone()
                .or_else(|| snap.robots.first().map(|r| r.0.clone()));
            for (name, lost, phase) in &snap.robots {
                let state = match (lost, phase) {
                    (true, _) => "lost".to_string(),
                    (false, Some(p)) => phase_text(p),
                    (false, None) => "idle".to_string(),
                };
                let text = RichText::new(format!("{name} | {state}")).color(if *lost {
                    Color32::from_rgb(220, 120, 60)
                } else {
                    Color32::from_rgb(120, 220, 120)
                });
                if ui
                    .selectable_label(current.as_deref() == Some(name.as_str()), text)
                    .clicked()
                {
                    self.selected = Some(name.clone());
                    self.paused_end = None;
                }
            }
        });
    }

    fn camera_panel(&mut self, ui: &mut egui::Ui, snap: &Snapshot) {
        ui.heading("Camera");
        let avail = ui.available_width();
        match (&self.texture, &snap.camera_geom) {
            (Some((_, tex)), Some(geom)) => {
                let size = overlay::fit(
                    geom.width,
                    geom.height,
                    [avail, (ui.available_height() * 0.55).max(120.0)],
                );
                let (rect, _) =
                    ui.allocate_exact_size(egui::vec2(size[0], size[1]), egui::Sense::hover());
                let painter = ui.painter_at(rect);
                painter.image(
                    tex.id(),
                    rect,
                    egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                    Color32::WHITE,
                );
                let (min, max) = ([rect.min.x, rect.min.y], [rect.max.x, rect.max.y]);
                let to = |mm: [f64; 2]| {
                    overlay::mm_to_screen(geom, mm, min, max).map(|p| egui::pos2(p[0], p[1]))
                };
                for s in &snap.slides {
                    if let (Some(a), Some(b)) = (to(s.start_mm), to(s.end_mm)) {
                        painter.arrow(a, b - a, Stroke::new(1.5, Color32::from_rgb(80, 200, 255)));
                    }
                }
                for d in &snap.detections {
                    let [a, b] = overlay::segment(d.centre_mm, d.axis_deg, d.length_mm);
                    if let (Some(a), Some(b)) = (to(a), to(b)) {
                        painter.line_segment([a, b], Stroke::new(2.0, Color32::YELLOW));
                    }
                    if let Some(c) = to(d.centre_mm) {
                        painter.text(
                            c + egui::vec2(4.0, -4.0),
                            egui::Align2::LEFT_BOTTOM,
                            format!("#{} ({:.0}, {:.0})", d.id, d.centre_mm[0], d.centre_mm[1]),
                            egui::FontId::proportional(12.0),
                            Color32::YELLOW,
                        );
                    }
                }
                for v in &snap.verdicts {
                    let col = class_colour(v.class.as_deref());
                    if let (Some(a), Some(b)) = (to(v.start_mm), to(v.end_mm)) {
                        painter.line_segment([a, b], Stroke::new(3.0, col));
                    }
                    if let Some([c, _]) = v.dip_mm {
                        let len = ((v.end_mm[0] - v.start_mm[0]).powi(2)
                            + (v.end_mm[1] - v.start_mm[1]).powi(2))
                        .sqrt()
                        .max(1e-9);
                        let f = (c / len).clamp(0.0, 1.0);
                        let at = [
                            v.start_mm[0] + f * (v.end_mm[0] - v.start_mm[0]),
                            v.start_mm[1] + f * (v.end_mm[1] - v.start_mm[1]),
                        ];
                        if let Some(p) = to(at) {
                            painter.circle_filled(p, 4.0, col);
                        }
                    }
                }
            }
            _ => {
                ui.weak("no frame yet");
            }
        }
        ui.horizontal(|ui| {
            ui.colored_label(Color32::YELLOW, "- detection");
            ui.colored_label(Color32::from_rgb(80, 200, 255), "-> planned slide");
            ui.colored_label(class_colour(Some("crack")), "- crack");
            ui.colored_label(class_colour(Some("flat")), "- other verdict");
        });
        if let Some(e) = snap.estimated_s {
            ui.label(format!("{} slides planned, ~{e:.0} s", snap.slides.len()));
        }
        ui.separator();
        ui.heading("Candidates");
        egui::ScrollArea::vertical()
            .id_salt("candidates")
            .show(ui, |ui| {
                egui::Grid::new("candidates-grid")
                    .striped(true)
                    .show(ui, |ui| {
                        for h in [
                            "Id",
                            "Verdict",
                            "Conf.",
                            "Width mm",
                            "Position mm",
                            "Evidence",
                        ] {
                            ui.strong(h);
                        }
                        ui.end_row();
                        for d in &snap.detections {
                            let passes: Vec<&PassVerdict> = snap
                                .verdicts
                                .iter()
                                .filter(|v| v.candidate == Some(d.id))
                                .collect();
                            let last = passes.last();
                            ui.label(format!("#{}", d.id));
                            match last {
                                Some(v) => {
                                    let class =
                                        v.class.clone().unwrap_or_else(|| "too short".into());
                                    ui.colored_label(class_colour(v.class.as_deref()), class);
                                    ui.label(format!("{:.2}", v.confidence));
                                    ui.label(v.width_mm.map_or("-".into(), |w| format!("{w:.1}")));
                                }
                                None => {
                                    ui.weak("pending");
                                    ui.label(format!("cam {:.2}", d.score));
                                    ui.label(d.width_mm.map_or("-".into(), |w| format!("{w:.1}")));
                                }
                            }
                            ui.label(format!("({:.1}, {:.1})", d.centre_mm[0], d.centre_mm[1]));
                            ui.label(evidence(&passes));
                            ui.end_row();
                        }
                        for v in snap.verdicts.iter().filter(|v| v.candidate.is_none()) {
                            ui.label(format!("scan {}", v.id));
                            ui.colored_label(
                                class_colour(v.class.as_deref()),
                                v.class.clone().unwrap_or_else(|| "too short".into()),
                            );
                            ui.label(format!("{:.2}", v.confidence));
                            ui.label(v.width_mm.map_or("-".into(), |w| format!("{w:.1}")));
                            ui.label(format!("({:.0}, {:.0})", v.start_mm[0], v.start_mm[1]));
                            ui.label(evidence(&[v]));
                            ui.end_row();
                        }
                    });
            });
    }

    fn signals_panel(&mut self, ui: &mut egui::Ui, snap: &Snapshot) {
        ui.horizontal(|ui| {
            ui.heading("Tactile channels");
            ui.label(format!(
                "{} samples in view | {} points drawn",
                snap.visible_samples,
                snap.lines.iter().map(Vec::len).sum::<usize>()
            ));
            ui.add(
                egui::Slider::new(&mut self.window_s, 1.0..=60.0)
                    .text("window s")
                    .logarithmic(true),
            );
        });
        if let (Some(first), Some(last)) = (snap.t_first, snap.t_last) {
            if let Some(end) = &mut self.paused_end {
                let lo = (first + self.window_s).min(last);
                ui.horizontal(|ui| {
                    ui.label("Scrub:");
                    ui.add(
                        egui::Slider::new(end, lo..=last.max(lo))
                            .text("end s")
                            .fixed_decimals(2),
                    );
                });
            }
        }
        // Verdicts along the slides, newest first.
        ui.horizontal_wrapped(|ui| {
            ui.strong("Verdicts:");
            if let Some(f) = &snap.feeling {
                // The pass under way: what it feels like so far.
                let txt = format!(
                    "pass {} so far ({:.1} mm): {} {:.2}",
                    f.id, f.along_mm, f.class, f.confidence
                );
                ui.colored_label(class_colour(Some(&f.class)), txt)
                    .on_hover_text("running verdict of the stroke under way; the pass's verdict comes when it ends");
            }
            if snap.verdicts.is_empty() && snap.feeling.is_none() {
                ui.weak("none yet");
            }
            for v in snap.verdicts.iter().rev().take(8) {
                let txt = format!(
                    "pass {}{}: {} {:.2}{}",
                    v.id,
                    v.candidate.map_or(String::new(), |c| format!(" (#{c})")),
                    v.class.as_deref().unwrap_or("too short"),
                    v.confidence,
                    v.dip_mm
                        .map_or(String::new(), |d| format!(", dip at {:.1} mm", d[0]))
                );
                ui.colored_label(class_colour(v.class.as_deref()), txt);
            }
        });
        let (t0, t1) = snap.window;
        let h = ((ui.available_height() - 8.0) / 4.0).max(40.0);
        self.plot_width_px = ui.available_width().max(16.0);
        let link = egui::Id::unique("tactile-time");
        for (k, name) in CHANNELS.iter().enumerate() {
            let line = egui_plot::Line::new(*name, snap.lines[k].clone()).color(CHANNEL_COLOURS[k]);
            egui_plot::Plot::new(*name)
                .height(h)
                .link_axis(link, [true, false])
                .link_cursor(link, [true, false])
                .allow_drag(false)
                .allow_zoom(false)
                .allow_scroll(false)
                .allow_boxed_zoom(false)
                .allow_double_click_reset(false)
                .y_axis_min_width(40.0)
                .y_axis_label(*name)
                .show_x(true)
                .show(ui, |pu| {
                    pu.set_plot_bounds_x(t0..=t1);
                    pu.line(line);
                });
        }
    }

    fn status_panel(&mut self, ui: &mut egui::Ui, snap: &Snapshot) {
        ui.columns(3, |cols| {
            let ui = &mut cols[0];
            ui.strong("Stream health");
            let m = snap.mission.as_ref();
            ui.label(format!(
                "mission: {}",
                m.map_or("none".to_string(), |m| format!(
                    "#{} {} on {:?}: {}",
                    m.mission,
                    m.mode,
                    m.scene,
                    phase_text(&m.phase)
                ))
            ));
            ui.label(format!(
                "link: {}{}",
                if snap.lost { "LOST" } else { "up" },
                snap.latency_ms
                    .map_or(String::new(), |l| format!(", telemetry latency {l:.0} ms"))
            ));
            match snap.health.and_then(|h| h.stream) {
                Some(s) => {
                    ui.label(format!(
                        "sensor: {:.0} samples/s, {} frames, {} CRC errors, {} gaps ({} lost)",
                        s.sample_rate_hz, s.frames, s.crc_errors, s.gaps, s.missing_frames
                    ));
                    ui.label(format!(
                        "arm link: {} sent, {} retries, {} refused, state age {}",
                        s.link_sent,
                        s.link_retries,
                        s.link_rejected,
                        s.state_age_ms.map_or("-".into(), |a| format!("{a:.0} ms"))
                    ));
                }
                None => {
                    ui.weak("no stream health yet");
                }
            }
            ui.label(format!(
                "telemetry: {} received, {} out of order, {} undecodable, {} tactile samples",
                snap.received, snap.out_of_order, snap.undecodable, snap.tactile_total
            ));

            let ui = &mut cols[1];
            ui.strong("Frame times");
            if self.show_debug {
                frame_time_panel(ui, self.frames.stats());
                if let Some(u) = self.ui_times.stats() {
                    ui.small(format!(
                        "UI build: median {:.1} ms, p99 {:.1} ms",
                        u.median_ms, u.p99_ms
                    ));
                }
            }

            let ui = &mut cols[2];
            ui.strong("Log");
            egui::ScrollArea::vertical()
                .id_salt("log")
                .stick_to_bottom(true)
                .show(ui, |ui| {
                    for l in &self.log {
                        ui.label(l);
                    }
                });
        });
    }

    fn confirm_modal(&mut self, ctx: &egui::Context) {
        let Some(Pending::Start { mode, robot }) = self.pending.clone() else {
            return;
        };
        let mut choice = None;
        let mut estop_now = false;
        egui::Modal::new(egui::Id::unique("confirm-start")).show(ctx, |ui| {
            ui.heading("Start a mission?");
            ui.label(format!(
                "A {} mission on {robot}: the arm will move.",
                crackbot_telemetry::wire::mode_name(mode)
            ));
            ui.horizontal(|ui| {
                if ui.button("Confirm").clicked() {
                    choice = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    choice = Some(false);
                }
            });
            ui.separator();
            // The dialog covers the window's controls: it carries its own emergency stop.
            let estop = egui::Button::new(
                RichText::new("EMERGENCY STOP now")
                    .strong()
                    .color(Color32::WHITE),
            )
            .fill(Color32::from_rgb(200, 20, 20));
            if ui.add(estop).clicked() {
                estop_now = true;
            }
        });
        if estop_now {
            self.emergency_stop();
            return;
        }
        match choice {
            Some(true) => self.confirm(),
            Some(false) => self.cancel(),
            None => {}
        }
    }

    /// Exports the selected robot's samples in `[t0, t1]` to CSV (written on a thread).
    pub fn export_csv(&mut self, (t0, t1): (f64, f64)) -> Option<PathBuf> {
        let name = self.target_robot()?;
        let samples: VecDeque<TactileSample> = {
            let f = lock(&self.fleet);
            let r = f.robot(&name)?;
            let range = decimate::visible_range(&r.tactile, t0, t1 + 1e-9, |s| s.t_s);
            r.tactile.range(range).copied().collect()
        };
        let path = self
            .export_dir
            .join(format!("signals-{}-{t0:.2}-{t1:.2}.csv", file_safe(&name)));
        let (p, log, wake) = (path.clone(), self.log_tx.clone(), self.ctx.clone());
        std::thread::spawn(move || {
            let csv = export::tactile_csv(&samples, t0, t1);
            export::write_in_background(p, csv.into_bytes(), log, wake);
        });
        Some(path)
    }

    /// Exports the selected robot's mission report to JSON (written on a thread).
    pub fn export_report(&mut self) -> Option<PathBuf> {
        let name = self.target_robot()?;
        let (report, mission) = {
            let f = lock(&self.fleet);
            let m = f.robot(&name).and_then(|r| r.mission.clone());
            (
                m.as_ref().and_then(|m| m.report_json.clone()),
                m.map_or(0, |m| m.mission),
            )
        };
        let Some(report) = report else {
            self.say("no report yet: the mission has not finished");
            return None;
        };
        match export::report_json(&report) {
            Ok(text) => {
                let path = self
                    .export_dir
                    .join(format!("report-{}-{mission}.json", file_safe(&name)));
                export::write_in_background(
                    path.clone(),
                    text.into_bytes(),
                    self.log_tx.clone(),
                    self.ctx.clone(),
                );
                Some(path)
            }
            Err(e) => {
                self.say(e.to_string());
                None
            }
        }
    }

    /// Asks the window for a screenshot, saved to `path` on a thread.
    pub fn screenshot(&mut self, ctx: &egui::Context, path: PathBuf) {
        let log = self.log_tx.clone();
        let wake = ctx.clone();
        self.say(format!("screenshot -> {}", path.display()));
        ctx.request_screenshot(move |img| {
            std::thread::spawn(move || match export::screenshot_png(&img) {
                Ok(bytes) => export::write_in_background(path, bytes, log, Some(wake)),
                Err(e) => {
                    let _ = log.send(e.to_string());
                }
            });
        });
    }

    fn measure_step(&mut self, ctx: &egui::Context, snap: &Snapshot) {
        let Some(m) = &mut self.measure else { return };
        if m.done {
            return;
        }
        let streaming = snap.lines.iter().all(|l| !l.is_empty())
            && (matches!(
                snap.mission.as_ref().map(|m| &m.phase),
                Some(Phase::Exploring { .. })
            ) || matches!(self.backend, Backend::Replay { .. }));
        match m.counted {
            None if streaming => {
                m.counted = Some(0);
                self.frames.clear();
                self.ui_times.clear();
            }
            None => {
                // A mission that failed before streaming (no ONNX Runtime, a bad scene…) ends
                // the measurement at once, with its reason.
                let failed = match snap.mission.as_ref().map(|m| &m.phase) {
                    Some(Phase::Failed(why)) => Some(why.clone()),
                    _ => None,
                };
                if failed.is_some() || m.since.elapsed().as_secs() > 300 {
                    m.done = true;
                    let msg = match failed {
                        Some(why) => format!("measure: the mission failed before streaming: {why}"),
                        None => "measure: no data streamed within 300 s".to_string(),
                    };
                    let _ =
                        export::write_file(&m.out, format!("{{\"error\": {msg:?}}}").as_bytes());
                    self.say(msg);
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            }
            Some(n) if n + 1 >= m.frames => {
                m.done = true;
                let stats = self.frames.stats();
                let body = serde_json::json!({
                    "frames": stats,
                    "ui_build": self.ui_times.stats(),
                    "channels": CHANNELS.len(),
                    "window_s": self.window_s,
                    "visible_samples_last_frame": snap.visible_samples,
                    "points_drawn_last_frame": snap.lines.iter().map(Vec::len).sum::<usize>(),
                    "plot_width_px": self.plot_width_px,
                    "robot_phase": snap.mission.as_ref().map(|m| phase_text(&m.phase)),
                });
                let out = m.out.clone();
                let shot = m.screenshot.clone();
                let text = serde_json::to_string_pretty(&body).unwrap_or_default();
                if let Err(e) = export::write_file(&out, text.as_bytes()) {
                    self.say(e.to_string());
                }
                match shot {
                    Some(path) => {
                        let wake = ctx.clone();
                        ctx.request_screenshot(move |img| {
                            if let Ok(bytes) = export::screenshot_png(&img) {
                                let _ = export::write_file(&path, &bytes);
                            }
                            wake.send_viewport_cmd(egui::ViewportCommand::Close);
                            wake.request_repaint();
                        });
                    }
                    None => ctx.send_viewport_cmd(egui::ViewportCommand::Close),
                }
            }
            Some(n) => m.counted = Some(n + 1),
        }
    }
}

impl eframe::App for OperatorApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }

    fn on_exit(&mut self, _gl: Option<&eframe::glow::Context>) {
        // Closing the window stops an in-process mission's arm.
        if let Backend::Sim(s) = &self.backend {
            if s.running() {
                s.emergency_stop();
            }
        }
    }
}

fn frame_time_panel(ui: &mut egui::Ui, stats: Option<FrameStats>) {
    match stats {
        Some(s) => {
            ui.label(format!(
                "{} frames: median {:.1} ms, p99 {:.1} ms, max {:.1} ms, {:.0} fps",
                s.frames, s.median_ms, s.p99_ms, s.max_ms, s.mean_fps
            ));
            let line: String = s
                .histogram
                .iter()
                .map(|(b, n)| match b {
                    Some(b) => format!("<={b}:{n} "),
                    None => format!(">:{n}"),
                })
                .collect();
            ui.small(line);
        }
        None => {
            ui.weak("no frames yet");
        }
    }
}

/// A phase in words.
pub fn phase_text(p: &Phase) -> String {
    match p {
        Phase::Idle => "idle".into(),
        Phase::Starting => "starting".into(),
        Phase::Perceiving => "perceiving".into(),
        Phase::Exploring { done, of } => format!("exploring {done}/{of}"),
        Phase::Finished => "finished".into(),
        Phase::Failed(why) => format!("failed: {why}"),
    }
}

fn class_colour(class: Option<&str>) -> Color32 {
    match class {
        Some("crack") => Color32::from_rgb(240, 60, 60),
        Some(_) => Color32::from_rgb(80, 210, 120),
        None => Color32::GRAY,
    }
}

fn evidence(passes: &[&PassVerdict]) -> String {
    if passes.is_empty() {
        return "not touched yet".into();
    }
    let samples: u64 = passes.iter().map(|v| v.samples).sum();
    let mut s = format!("{} pass(es), {samples} samples", passes.len());
    if let Some([c, w]) = passes.iter().rev().find_map(|v| v.dip_mm) {
        s.push_str(&format!(", dip at {c:.1} mm (w {w:.1})"));
    }
    if let Some(d) = passes.iter().rev().find_map(|v| v.doubt.as_deref()) {
        s.push_str(&format!(
            ", doubt: {}",
            d.chars().take(40).collect::<String>()
        ));
    }
    s
}

fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}
