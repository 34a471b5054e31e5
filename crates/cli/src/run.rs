//! `crackbot run` and `crackbot-robot`: the inspection mission (one set of flags for both).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
#[cfg(feature = "sim")]
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use crackbot_mission::inspect::{
    run_inspection, Hardware, InspectConfig, InspectMode, InspectReport, Progress, Site,
};

/// Flags of the mission. Each setting left out keeps the configuration file's value
/// (`--config`), or else its default (`--print-config` writes them all).
#[derive(Debug, Args)]
pub struct RunArgs {
    /// A mission configuration file (TOML; `--print-config` writes one with every default and
    /// where it comes from): every setting it names replaces the default, and the flags given
    /// here replace the file's.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Print the mission's configuration (the defaults, the file's and the flags' settings) as
    /// a TOML file with each key explained, and exit.
    #[arg(long)]
    pub print_config: bool,
    /// Simulated rig: the scene file, TOML (or JSON when named `.json`, as `trial_scenes` writes
    /// them; default: the built-in default scene).
    #[cfg(feature = "sim")]
    #[arg(long, conflicts_with = "serial")]
    pub scene: Option<PathBuf>,
    /// Hardware: the site file (TOML: the arm's reachable box and speeds, the finger's
    /// proximity fibre; see crackbot_mission::inspect::Site) [default: the built-in scene's
    /// site and the calibrated fibre].
    #[arg(long, requires = "serial")]
    pub site: Option<PathBuf>,
    /// tactile (scan rows, no camera), vision (camera only) or fused (camera proposes, finger
    /// confirms) [default: fused].
    #[arg(long)]
    pub mode: Option<InspectMode>,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Folder for the report and every recording of the mission [default: out/mission].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run the simulation this many times faster than real time [default: 1].
    #[arg(long)]
    pub speedup: Option<f64>,
    /// Seed of the simulated sensor and camera [default: 7].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Strokes across each candidate (forth and back count as two; the authors slid 4 and
    /// more). One stroke was as accurate as four on the simulated trials, at a third of the
    /// time (crates/research/EXPERIMENTS.md, "Error against run time before the print check:
    /// strokes, stroke length, margin") [default: 1].
    #[arg(long)]
    pub passes: Option<u32>,
    /// Shortest stroke across a candidate, mm (default: 6, or the scene's manipulator stroke
    /// if shorter; the paper's is 16); a wide candidate still gets a stroke that starts and
    /// ends on sound surface.
    #[arg(long)]
    pub stroke_mm: Option<f64>,
    /// Sound surface wanted beyond a candidate's edge and the finger's reach on each side of its stroke,
    /// mm [default: 0.5].
    #[arg(long)]
    pub margin_mm: Option<f64>,
    /// How far beyond a candidate's edge the finger still feels it, mm: each stroke starts and
    /// ends this far plus the margin beyond the edge [default: the proximity fibre's reach,
    /// 2.4 mm for the simulated finger; 4.4 keeps the whole tip on sound surface].
    #[arg(long)]
    pub reach_mm: Option<f64>,
    /// γ of the tactile-only scan (the paper's eq. 2), in (0, 1) [default: 0.5].
    #[arg(long)]
    pub gamma: Option<f64>,
    /// Vision mode: detections scoring below this are not reported [default: 0.3].
    #[arg(long, value_parser = score_in_unit_range)]
    pub min_score: Option<f32>,
    /// Fused mode: detections scoring below this are not touched (the finger confirms or
    /// rejects the rest) [default: 0.3].
    #[arg(long, value_parser = score_in_unit_range)]
    pub proposal_min_score: Option<f32>,
    /// What the finger touches: every crack a detection holds, on its centre line (cracks), or
    /// every detection once across its main axis (detections: fewer strokes, but of cracks that
    /// run close together or cross only one is touched) [default: cracks].
    #[arg(long, value_parser = ["cracks", "detections"])]
    pub candidates: Option<String>,
    /// Confirm a crack on the recognition model's vote alone, also where the proximity channel
    /// saw no dip (by default a crack must show one).
    #[arg(long)]
    pub confirm_without_dip: bool,
    /// Fused missions: height of the print check's raised pass over each candidate the finger
    /// confirmed, mm above the plate (a print's dip keeps its share of the signal there, a
    /// crack's does not); 0 turns the check off [default: 2].
    #[arg(long)]
    pub print_check_mm: Option<f64>,
    /// Shallowest proximity dip a confirmed crack needs, counts (100 suits missions without the
    /// print check) [default: 40].
    #[arg(long)]
    pub min_dip_counts: Option<f64>,
    /// Fused missions with the print check: a pass the recognition model read as "no crack"
    /// while doubting it (a surface unlike training, or a weak vote) still stands for a crack
    /// when its proximity dip is at least this confident (0–1), and the print check decides;
    /// 0: the model's verdict always stands [default: 0.6].
    #[arg(long)]
    pub doubted_dip_confidence: Option<f64>,
    /// Fused missions: report confirmed candidates whose detections continue each other
    /// across at most this gap (mm, within 40° of one direction) as one crack; 0 reports each
    /// [default: 12].
    #[arg(long)]
    pub piece_gap_mm: Option<f64>,
    /// Fused missions: also report two confirmed candidates as one crack when the straight line
    /// between the points where their strokes met it runs along both and over the detector's
    /// crack map, off it for at most this much (mm); pieces joined by --piece-gap-mm must then
    /// also have that line on the map but for their gap plus this much. Negative: off
    /// [default: 2].
    #[arg(long, allow_negative_numbers = true)]
    pub piece_trace_gap_mm: Option<f64>,
    /// Do not write the mission's log, `mission.mcap` (for Foxglove and other MCAP readers;
    /// written by default beside the report).
    #[arg(long)]
    pub no_mcap: bool,
    /// Publish the mission live on ROS 2 topics over DDS domain DOMAIN (default 0):
    /// `/crackbot/tactile`, `/crackbot/verdicts`, `/crackbot/mission/report`, … (the types of
    /// `ros/crackbot_msgs`; crates/rosbag/docs/ros2.md).
    #[cfg(feature = "ros2")]
    #[arg(long, value_name = "DOMAIN", num_args = 0..=1, default_missing_value = "0", conflicts_with = "no_mcap")]
    pub ros2: Option<u16>,
    /// Also write the log as a ROS 2 bag, `ros2/` beside it, once the mission ends (what
    /// `crackbot log to-ros2` writes; `ros2 bag play` plays it).
    #[arg(long, conflicts_with = "no_mcap")]
    pub ros2_bag: bool,
    /// Serve the mission live over the Foxglove WebSocket protocol, on ADDR (default
    /// 127.0.0.1:8765; port 0 picks a free one): open it in Foxglove with "Open connection".
    #[cfg(feature = "foxglove")]
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = crackbot_mcap_live_addr())]
    pub foxglove: Option<std::net::SocketAddr>,
    /// The finger's profile (`crackbot commission run --name NAME` installs one): its models
    /// and its proximity fibre replace the shipped ones. A folder, or a name under
    /// $CRACKBOT_FINGERS (default ~/.local/share/crackbot/fingers) [default: the shipped
    /// models, the authors' finger].
    #[arg(long, value_name = "PROFILE", conflicts_with_all = ["recognition_model", "width_model"])]
    pub finger: Option<PathBuf>,
    /// Deployed recognition model.
    #[arg(long)]
    pub recognition_model: Option<PathBuf>,
    /// Deployed width model.
    #[arg(long)]
    pub width_model: Option<PathBuf>,
    /// ONNX detector (default: models/detector/crackseg-tiles/crack-detector-320.onnx).
    #[arg(long)]
    pub detector: Option<PathBuf>,
    /// Simulated controller: clock offset, µs (the robot synchronises to it).
    #[cfg(feature = "sim")]
    #[arg(long, default_value_t = 0.0)]
    pub clock_offset_us: f64,
    /// Simulated controller: clock drift, ppm.
    #[cfg(feature = "sim")]
    #[arg(long, default_value_t = 0.0)]
    pub clock_drift_ppm: f64,
    /// Fault injection: probability that a link packet is lost (both directions).
    #[arg(long, default_value_t = 0.0)]
    pub loss: f64,
    /// Fault injection: probability that a link packet is reordered.
    #[arg(long, default_value_t = 0.0)]
    pub reorder: f64,
    /// Fault injection: probability that a link packet is duplicated.
    #[arg(long, default_value_t = 0.0)]
    pub duplicate: f64,
    /// Fault injection: the sensor stream stalls for 1 s during this slide (1-based).
    #[cfg(feature = "sim")]
    #[arg(long)]
    pub stall_slide: Option<u32>,
    /// Fault injection: the controller restarts this many seconds after it started.
    #[cfg(feature = "sim")]
    #[arg(long)]
    pub restart_after_s: Option<f64>,
    /// Hardware: the sensor's serial device (with --controller and --key).
    #[arg(long, requires_all = ["controller", "key"])]
    pub serial: Option<String>,
    /// Hardware: the manipulator controller's UDP address, e.g. 192.168.1.20:7700.
    #[arg(long, requires_all = ["serial", "key"])]
    pub controller: Option<std::net::SocketAddr>,
    /// Hardware: this host's UDP address for the link.
    #[arg(long, default_value = crackbot_mission::inspect::DEFAULT_BIND)]
    pub bind: std::net::SocketAddr,
    /// Hardware: the link's pre-shared key file (64–128 hex digits, mode 0600).
    #[arg(long)]
    pub key: Option<PathBuf>,
    /// Hardware: the camera (fused and vision modes): a V4L2 device (/dev/video0), a video file
    /// or stream URL (both through ffmpeg, installed by scripts/setup.sh), or an image file.
    #[arg(long, requires = "serial")]
    pub camera: Option<PathBuf>,
    /// Hardware: the camera's pixel → surface calibration (`crackbot homography fit`).
    #[arg(long, requires = "camera", conflicts_with = "camera_calibration")]
    pub homography: Option<PathBuf>,
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// The camera's lens and the plate's pose (`crackbot calibrate camera`, then `calibrate
    /// surface`): each frame is undistorted and mapped to the plate through it (hardware, or a
    /// simulated scene whose camera distorts).
    #[arg(long)]
    pub camera_calibration: Option<PathBuf>,
    #[command(flatten)]
    pub fleet: FleetArgs,
}

/// How frames are asked of the camera (hardware).
#[derive(Debug, Clone, Default, Args)]
pub struct CaptureArgs {
    /// Hardware: the camera's frame size, WxH (refused, naming both sizes, if it gives another).
    #[arg(long, value_parser = size)]
    pub camera_size: Option<[u32; 2]>,
    /// Hardware: the device's pixel format as ffmpeg names it (mjpeg, yuyv422, …).
    #[arg(long)]
    pub camera_format: Option<String>,
    /// Hardware: the device's frame rate, fps.
    #[arg(long)]
    pub camera_fps: Option<f64>,
    /// Hardware: the device's exposure (V4L2 exposure_time_absolute, its units; auto-exposure
    /// off). Needs v4l2-ctl (Debian's v4l-utils).
    #[arg(long)]
    pub camera_exposure: Option<u32>,
    /// Hardware: the device's gain (V4L2 gain, its units).
    #[arg(long)]
    pub camera_gain: Option<u32>,
    /// Frames dropped before the one kept (default: 5 from a device, none from a file).
    #[arg(long)]
    pub camera_discard: Option<u32>,
}

impl CaptureArgs {
    /// The options these flags ask for.
    pub fn options(&self) -> crackbot_vision::camera::CaptureOptions {
        crackbot_vision::camera::CaptureOptions {
            size: self.camera_size,
            pixel_format: self.camera_format.clone(),
            framerate: self.camera_fps,
            exposure: self.camera_exposure,
            gain: self.camera_gain,
            discard: self.camera_discard,
        }
    }
}

/// A frame size as `WxH`.
pub fn size(s: &str) -> Result<[u32; 2], String> {
    let bad = || format!("{s:?}: expected a size as WxH, e.g. 1280x720");
    let (w, h) = s.split_once(['x', 'X', '×']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 {
        return Err(bad());
    }
    Ok([w, h])
}

/// Fleet telemetry over Zenoh (builds with `--features telemetry`).
#[derive(Debug, Args)]
pub struct FleetArgs {
    /// Publish the mission over Zenoh as robot NAME (crackbot/NAME/…) and take stop commands
    /// from stations.
    #[arg(long, value_name = "NAME")]
    pub telemetry: Option<String>,
    /// With --telemetry: wait for missions that stations start (signed with --command-key)
    /// instead of running one now; runs them one after another until Ctrl-C.
    #[arg(long, requires = "telemetry")]
    pub serve: bool,
    /// Zenoh endpoint to listen on, e.g. tcp/127.0.0.1:7448 (repeatable).
    #[arg(long, value_name = "ENDPOINT", requires = "telemetry")]
    pub zenoh_listen: Vec<String>,
    /// Zenoh endpoint to connect to (repeatable) [default, when no endpoint is given: this
    /// machine's station, tcp/127.0.0.1:7447].
    #[arg(long, value_name = "ENDPOINT", requires = "telemetry")]
    pub zenoh_connect: Vec<String>,
    /// A site's Zenoh router: join as its client instead of as a peer.
    #[arg(long, value_name = "ENDPOINT", requires = "telemetry")]
    pub zenoh_router: Option<String>,
    /// Key that signs stations' commands (the link's key format: 64–128 hex digits, mode 0600)
    /// [default: --key]. Without one, stations can watch this robot and stop its arm, nothing
    /// more.
    #[arg(long, value_name = "FILE", requires = "telemetry")]
    pub command_key: Option<PathBuf>,
}

/// Runs the mission and prints the report.
pub fn run(args: RunArgs) -> Result<()> {
    let config = config_from(&args)?;
    if args.print_config {
        print!("{}", config.to_commented_toml()?);
        return Ok(());
    }
    if args.fleet.telemetry.is_some() {
        if args.ros2_bag {
            anyhow::bail!("--ros2-bag is for a mission run here, not with --telemetry: convert the log afterwards with `crackbot log to-ros2`");
        }
        return fleet(&args, config);
    }
    if args.ros2_bag && !config.output.mcap {
        anyhow::bail!("--ros2-bag needs the mission's log, and the configuration turns it off (output.mcap = false)");
    }
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        // Ctrl-C: the mission stops the arm first, then ends with what it has recorded.
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .context("installing the Ctrl-C handler")?;
    }
    let checked = config.check().context("the mission's settings")?;
    let bar = progress_bar(args.json);
    let report = run_inspection(&checked, &stop, |p| show(&bar, p)).with_context(|| {
        format!(
            "mission failed (recordings so far are in {})",
            config.output.out_dir.display()
        )
    })?;
    bar.finish_and_clear();
    if args.ros2_bag {
        let out = &config.output.out_dir;
        let bag = crackbot_rosbag::log_to_bag(&out.join("mission.mcap"), &out.join("ros2"))
            .context("writing the mission's log as a ROS 2 bag")?;
        eprintln!(
            "ROS 2 bag: {} ({} messages)",
            bag.dir.display(),
            bag.messages()
        );
    }
    print_report(&report, args.json)
}

/// The mission's configuration: the rig's defaults (the hardware the flags name, or the
/// simulated scene), the file's settings over them (`--config`), the flags' over those.
fn config_from(args: &RunArgs) -> Result<InspectConfig> {
    let mut config = rig_config(args)?;
    if let Some(path) = &args.config {
        config = config.overlaid_file(path)?;
        // Hardware flags name the rig whatever the file says.
        if let Some(hw) = hardware(args) {
            config.rig.hardware = Some(hw);
        }
    }
    if let Some(out) = &args.out {
        config.output.out_dir = out.clone();
    }
    settings_from_flags(args, &mut config)?;
    if let Some(finger) = &args.finger {
        let profile = crate::finger::finger_profile(finger)?;
        config.touch.recognition_model = profile.recognition_model;
        config.touch.width_model = profile.width_model;
        config.rig.site.fibre = profile.card.optics.fibre;
    }
    if args.no_mcap {
        config.output.mcap = false;
    }
    #[cfg(feature = "foxglove")]
    if args.foxglove.is_some() {
        config.output.foxglove = args.foxglove;
    }
    #[cfg(feature = "ros2")]
    if args.ros2.is_some() {
        config.output.ros2_domain = args.ros2;
    }
    link_faults_from_flags(args, &mut config);
    Ok(config)
}

/// The settings flags given, over `config`.
fn settings_from_flags(args: &RunArgs, config: &mut InspectConfig) -> Result<()> {
    let set = |slot: &mut f64, v: Option<f64>| {
        if let Some(v) = v {
            *slot = v;
        }
    };
    if let Some(m) = args.mode {
        config.mode = m;
    }
    set(&mut config.rig.speedup, args.speedup);
    if let Some(c) = &args.camera_calibration {
        config.rig.camera_calibration = Some(c.clone());
    }
    if let Some(s) = args.seed {
        config.rig.seed = s;
    }
    set(&mut config.plan.gamma, args.gamma);
    if let Some(v) = args.min_score {
        config.perceive.min_score = v;
    }
    if let Some(v) = args.proposal_min_score {
        config.perceive.proposal_min_score = v;
    }
    if let Some(c) = &args.candidates {
        config.perceive.candidates = c.parse().map_err(anyhow::Error::msg)?;
    }
    if args.confirm_without_dip {
        config.judge.require_dip = false;
    }
    if let Some(h) = args.print_check_mm {
        config.print_check.height_mm =
            crackbot_mission::print_check_height(h).context("--print-check-mm")?;
    }
    set(&mut config.touch.min_dip_counts, args.min_dip_counts);
    if let Some(c) = args.doubted_dip_confidence {
        config.judge.doubted_dip_confidence = crackbot_mission::inspect::doubted_dip_confidence(c)
            .context("--doubted-dip-confidence")?;
    }
    if let Some(g) = args.piece_gap_mm {
        config.pieces.gap_mm = (g != 0.0).then_some(g);
    }
    if let Some(g) = args.piece_trace_gap_mm {
        config.pieces.trace_gap_mm = (g >= 0.0).then_some(g);
    }
    planner_from_flags(args, config);
    if let Some(p) = &args.recognition_model {
        config.touch.recognition_model = p.clone();
    }
    if let Some(p) = &args.width_model {
        config.touch.width_model = p.clone();
    }
    if args.detector.is_some() {
        config.perceive.detector_model = args.detector.clone();
    }
    Ok(())
}

/// The planner's flags given, over `config`.
fn planner_from_flags(args: &RunArgs, config: &mut InspectConfig) {
    let planner = &mut config.plan.planner;
    if let Some(p) = args.passes {
        planner.passes = p;
    }
    if let Some(v) = args.stroke_mm {
        planner.min_stroke_mm = v;
    }
    if let Some(v) = args.reach_mm {
        planner.reach_mm = v;
    }
    if let Some(v) = args.margin_mm {
        planner.margin_mm = v;
        planner.min_margin_mm = planner.min_margin_mm.min(v);
    }
}

/// The link faults the flags inject (`--loss`, `--reorder`, `--duplicate`).
fn link_faults_from_flags(args: &RunArgs, config: &mut InspectConfig) {
    if args.loss > 0.0 || args.reorder > 0.0 || args.duplicate > 0.0 {
        let faults = crackbot_link::FaultConfig {
            drop: args.loss,
            reorder: args.reorder,
            duplicate: args.duplicate,
            ..Default::default()
        };
        #[cfg(feature = "sim")]
        {
            config.rig.faults.link = Some(faults.clone());
        }
        config.rig.host_link_faults = Some(crackbot_link::FaultConfig { seed: 2, ..faults });
    }
}

/// `--foxglove`'s address when none is given.
#[cfg(feature = "foxglove")]
fn crackbot_mcap_live_addr() -> &'static str {
    crackbot_mission::inspect::DEFAULT_LIVE_ADDR
}

/// The hardware the flags name (`--serial`, `--controller` and `--key` together).
fn hardware(args: &RunArgs) -> Option<Hardware> {
    let (serial, controller, key) = (args.serial.as_ref()?, args.controller?, args.key.as_ref()?);
    Some(Hardware {
        serial: serial.clone(),
        controller,
        bind: args.bind,
        key_file: key.clone(),
        camera: args.camera.clone(),
        homography: args.homography.clone(),
        capture: args.capture.options(),
    })
}

/// The mission on the hardware the flags name, at its site (`--site`).
fn hardware_config(args: &RunArgs, hw: Hardware) -> Result<InspectConfig> {
    let site = match &args.site {
        Some(path) => Site::load(path).context("--site")?,
        None => Site::default(),
    };
    Ok(InspectConfig::on_hardware(hw, site, out_dir(args)))
}

/// The mission's rig: the hardware the flags name, or the simulated scene (`--scene`) with the
/// simulated controller's clock and faults.
#[cfg(feature = "sim")]
fn rig_config(args: &RunArgs) -> Result<InspectConfig> {
    if let Some(hw) = hardware(args) {
        return hardware_config(args, hw);
    }
    let scene = crackbot_sim::Scene::load_or_default(args.scene.as_deref())?;
    let mut config = InspectConfig::new(scene, out_dir(args));
    config.rig.clock.offset_us = args.clock_offset_us;
    config.rig.clock.drift_ppm = args.clock_drift_ppm;
    config.rig.faults.stall = args
        .stall_slide
        .map(|slide| crackbot_controller::SensorStall {
            slide,
            duration: Duration::from_secs(1),
        });
    config.rig.faults.restart_after = args.restart_after_s.map(Duration::from_secs_f64);
    Ok(config)
}

/// The mission's folder by default, or `--out`.
fn out_dir(args: &RunArgs) -> PathBuf {
    args.out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/mission"))
}

/// The mission's rig: the hardware the flags name, or the one the configuration file names
/// (this build has no simulator).
#[cfg(not(feature = "sim"))]
fn rig_config(args: &RunArgs) -> Result<InspectConfig> {
    match hardware(args) {
        Some(hw) => hardware_config(args, hw),
        None if args.config.is_some() => Ok(InspectConfig::at(Site::default(), out_dir(args))),
        None => anyhow::bail!(
            "this build has no simulator (built without the `sim` feature): a mission needs \
             hardware, --serial DEVICE --controller ADDR --key FILE (or [rig.hardware] in --config)"
        ),
    }
}

fn progress_bar(hidden: bool) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(0);
    if hidden {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// A mission's progress on the bar.
fn show(bar: &indicatif::ProgressBar, p: &Progress) {
    match p {
        Progress::Starting => bar.set_message("starting the controller, the sensor and the models"),
        Progress::Perceived { candidates, .. } => {
            bar.set_message(format!("{candidates} candidates in the frame"));
        }
        Progress::Planned {
            slides,
            estimated_s,
            ..
        } => {
            bar.set_length(*slides as u64);
            bar.set_message(format!("{slides} slides planned, about {estimated_s:.0} s"));
        }
        Progress::Slid { done, class, .. } => {
            bar.set_position(*done as u64);
            bar.set_message(format!("last pass: {class}"));
        }
        Progress::Feeling(f) => {
            let width = match f.width_mm {
                Some(w) if f.class == "crack" => format!(", about {w} mm wide"),
                _ => String::new(),
            };
            bar.set_message(format!(
                "sliding, {:.0} mm in: feels like {} ({:.0} %{width})",
                f.along_mm,
                f.class,
                100.0 * f.confidence
            ));
        }
        Progress::Frame(_)
        | Progress::Samples { .. }
        | Progress::Poses { .. }
        | Progress::Stroked { .. }
        | Progress::Health(_) => {}
    }
}

fn print_report(report: &InspectReport, json: bool) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string(report)?);
    } else {
        print_summary(report);
    }
    Ok(())
}

/// The mission with fleet telemetry: published over Zenoh; serving, missions come from
/// stations.
#[cfg(feature = "telemetry")]
fn fleet(args: &RunArgs, config: InspectConfig) -> Result<()> {
    use crackbot_telemetry::{RobotService, ZenohOptions, DEFAULT_STATION_ENDPOINT};
    let f = &args.fleet;
    let name = f.telemetry.as_deref().unwrap_or_default();
    let options = ZenohOptions {
        listen: f.zenoh_listen.clone(),
        // No endpoint given: join the station of this machine.
        connect: if f.zenoh_connect.is_empty()
            && f.zenoh_listen.is_empty()
            && f.zenoh_router.is_none()
        {
            vec![DEFAULT_STATION_ENDPOINT.to_string()]
        } else {
            f.zenoh_connect.clone()
        },
        router: f.zenoh_router.clone(),
        multicast_scouting: false,
    };
    let key = match f.command_key.as_ref().or(args.key.as_ref()) {
        Some(path) => Some(
            crackbot_link::Key::from_file(path)
                .with_context(|| format!("the command key {}", path.display()))?,
        ),
        None => None,
    };
    let service = RobotService::open(name, &options, key.as_ref(), f.serve)
        .with_context(|| format!("joining the fleet as robot {name}"))?;
    ctrlc::set_handler(service.shutdown_handle()).context("installing the Ctrl-C handler")?;
    if !f.serve {
        let bar = progress_bar(args.json);
        let report = service
            .run_mission(&config, |p| show(&bar, p))
            .with_context(|| {
                format!(
                    "mission failed (recordings so far are in {})",
                    config.output.out_dir.display()
                )
            })?;
        bar.finish_and_clear();
        return print_report(&report, args.json);
    }
    eprintln!(
        "robot {name}: waiting for missions from stations ({}); Ctrl-C ends",
        if key.is_some() {
            "signed commands"
        } else {
            "no command key: only emergency stops"
        }
    );
    let bar = progress_bar(args.json);
    service.serve(
        &config,
        |p| {
            if matches!(p, Progress::Starting) {
                bar.reset();
            }
            show(&bar, p);
        },
        |n, result| {
            bar.suspend(|| match result {
                Ok(report) => {
                    if let Err(e) = print_report(&report, args.json) {
                        eprintln!("robot {name}: mission {n}: {e:#}");
                    }
                }
                Err(e) => eprintln!("robot {name}: mission {n} failed: {e}"),
            });
        },
    );
    bar.finish_and_clear();
    Ok(())
}

#[cfg(not(feature = "telemetry"))]
fn fleet(_: &RunArgs, _: InspectConfig) -> Result<()> {
    anyhow::bail!(
        "--telemetry needs a build with fleet telemetry: cargo build --release -p crackbot-cli --features telemetry"
    )
}

fn print_summary(r: &InspectReport) {
    println!(
        "mission ({:?}) on {}: {:.1} s wall, exploration {:.1} s (robot time)",
        r.mode, r.scene, r.elapsed_s, r.exploration_s
    );
    println!(
        "{} candidates from the camera, {} slide passes",
        r.candidates.len(),
        r.passes.len()
    );
    println!("confirmed cracks: {}", r.cracks.len());
    for c in &r.cracks {
        let width = c
            .width_mm
            .map_or("–".to_string(), |w| match c.width_range_mm {
                Some([lo, hi]) => format!("{w:.1} mm (vote 10–90 %: {lo:.1}–{hi:.1})"),
                None => format!("{w:.1} mm"),
            });
        println!(
            "  at ({:.1}, {:.1}) mm  width {width}  confidence {:.2}  slides {:?}",
            c.position_mm[0], c.position_mm[1], c.confidence, c.evidence.slides,
        );
        for d in &c.evidence.doubts {
            println!("      doubt: {d}");
        }
    }
    println!("rejected by the finger: {}", r.rejected.len());
    for c in &r.rejected {
        println!(
            "  candidate {} at ({:.1}, {:.1}) mm felt {}",
            c.candidate, c.position_mm[0], c.position_mm[1], c.felt
        );
    }
    println!("report and recordings: {}", r.out_dir);
}

/// A detector score threshold: a number in [0, 1].
fn score_in_unit_range(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|e| format!("{s:?} is not a number: {e}"))?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("a detector score lies in [0, 1], got {v}"))
    }
}
