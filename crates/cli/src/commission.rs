//! `crackbot commission`: a new finger commissioned on the papers' reference plates.
//!
//! * `plates`: the plates to print (STL, a drawing at true scale each, `plates.toml`).
//! * `run`: with the arm and the sensor connected (hardware, or the simulated rig, whose scene's
//!   `[sensor]` is the finger), the optics read, every plate slid over, the finger's own models
//!   trained, evaluated beside the shipped ones and installed as a finger profile that
//!   `crackbot run --finger NAME` uses.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use crackbot_mission::commission::{
    commission, CommissionConfig, CommissionError, CommissionProgress, CommissionReport,
    CommissionSettings, Figures, Mounts,
};
use crackbot_mission::inspect::{Hardware, InspectConfig, RigConfig, Site};
use crackbot_plates::ReferencePlate;

/// `crackbot commission …`.
#[derive(Debug, Subcommand)]
pub enum CommissionCommand {
    /// Write the reference plates to print: an STL mesh and an A4 drawing at true scale of
    /// each (flat, cracks of 1, 2, 5, 8 and 10 mm, bump, wavy), and plates.toml listing them.
    Plates {
        /// Folder for the files.
        #[arg(long, default_value = "out/plates")]
        out: PathBuf,
        /// Resolution of the drawings, pixels per mm (10 ≈ 254 dpi).
        #[arg(long, default_value_t = 10.0)]
        px_per_mm: f64,
    },
    /// Commission a finger: read its optics over the flat plate, slide over every plate you
    /// mount (the papers' protocol), train its models, evaluate them beside the shipped ones,
    /// and install them as a finger profile.
    Run(Box<RunArgs>),
}

/// `crackbot commission run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The finger's name: its profile is installed as FINGERS/NAME.
    #[arg(long)]
    name: String,
    /// The session's folder: an interrupted commissioning resumes from it with the same
    /// settings [default: out/commission/NAME].
    #[arg(long)]
    session: Option<PathBuf>,
    /// Where finger profiles are installed [default: $CRACKBOT_FINGERS, else
    /// ~/.local/share/crackbot/fingers].
    #[arg(long)]
    fingers: Option<PathBuf>,
    /// The plates to slide over, by name [default: all eight].
    #[arg(long, value_delimiter = ',')]
    plates: Vec<String>,
    /// Repetitions of each plate (at least 2: the evaluation leaves one out).
    #[arg(long, default_value_t = crackbot_mission::commission::REPETITIONS)]
    repetitions: u32,
    /// Slides per repetition, forth and back alternately (at least 4).
    #[arg(long, default_value_t = crackbot_mission::commission::SLIDES)]
    slides: u32,
    /// Slide speed, mm/s [default: the papers' 3.89].
    #[arg(long, default_value_t = crackbot_mission::commission::SPEED_MM_S)]
    speed_mm_s: f64,
    /// Trees of each forest (the shipped models': 32).
    #[arg(long, default_value_t = 32)]
    trees: usize,
    /// Depth limit of every tree [default: fully grown; the shipped models': 10, trained on
    /// far more slides].
    #[arg(long)]
    max_depth: Option<usize>,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    /// Simulated rig: the scene whose [sensor] is the finger commissioned (its plate becomes
    /// each reference plate in turn) [default: the built-in scene's finger].
    #[cfg(feature = "sim")]
    #[arg(long, conflicts_with = "serial")]
    scene: Option<PathBuf>,
    /// Simulated rig: run this many times faster than real time.
    #[arg(long, default_value_t = 1.0)]
    speedup: f64,
    /// Seed of the simulated sensor and of the slides' starts.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Hardware: the sensor's serial device (with --controller and --key).
    #[arg(long, requires_all = ["controller", "key"])]
    serial: Option<String>,
    /// Hardware: the manipulator controller's UDP address.
    #[arg(long, requires_all = ["serial", "key"])]
    controller: Option<std::net::SocketAddr>,
    /// Hardware: this host's UDP address for the link.
    #[arg(long, default_value = crackbot_mission::inspect::DEFAULT_BIND)]
    bind: std::net::SocketAddr,
    /// Hardware: the link's pre-shared key file.
    #[arg(long)]
    key: Option<PathBuf>,
    /// Hardware: the site file (the arm's box and speeds; its plate frame is the mounted
    /// plate's, origin at its corner x = 0, y = 0).
    #[arg(long, requires = "serial")]
    site: Option<PathBuf>,
}

pub fn commission_cmd(cmd: CommissionCommand) -> Result<()> {
    match cmd {
        CommissionCommand::Plates { out, px_per_mm } => plates(&out, px_per_mm),
        CommissionCommand::Run(args) => run(&args),
    }
}

fn plates(out: &Path, px_per_mm: f64) -> Result<()> {
    if !(px_per_mm.is_finite() && (1.0..=40.0).contains(&px_per_mm)) {
        bail!("--px-per-mm {px_per_mm}: the drawings take 1 to 40 pixels per mm");
    }
    let written = crackbot_plates::write_set(out, px_per_mm)?;
    for w in &written {
        println!(
            "{:<11} {} ({} triangles), drawing {}: {}",
            w.name,
            out.join(&w.stl).display(),
            w.triangles,
            out.join(&w.drawing).display(),
            w.title
        );
    }
    println!(
        "wrote {} plates and {}; print the drawings at actual size and the meshes flat, then \
         `crackbot commission run --name NAME` with the arm and sensor connected",
        written.len(),
        out.join("plates.toml").display()
    );
    Ok(())
}

/// The plates mounted on hardware: the operator is asked for each, on the terminal.
struct OperatorMounts {
    rig: RigConfig,
}

impl Mounts for OperatorMounts {
    fn mount(&mut self, plate: &ReferencePlate) -> Result<RigConfig, CommissionError> {
        eprintln!(
            "mount the plate \"{}\" ({}) with its corner x = 0, y = 0 at the plate frame's \
             origin, then press Enter",
            plate.name, plate.title
        );
        let mut line = String::new();
        if !std::io::stdin().is_terminal() && std::io::stdin().read_line(&mut line).ok() == Some(0)
        {
            return Err(CommissionError::Setting {
                field: "stdin",
                value: 0.0,
                allowed: "a terminal (or a line per plate) to confirm each plate is mounted",
            });
        }
        if std::io::stdin().is_terminal() {
            std::io::stdin()
                .read_line(&mut line)
                .map_err(|e| CommissionError::Io {
                    path: PathBuf::from("stdin"),
                    source: e,
                })?;
        }
        Ok(self.rig.clone())
    }
}

/// The simulated rig: the bench scene's finger, arm and plate material over each plate.
#[cfg(feature = "sim")]
struct SimulatedMounts {
    bench: crackbot_sim::Scene,
    speedup: f64,
    seed: u64,
    mounted: u64,
}

#[cfg(feature = "sim")]
impl Mounts for SimulatedMounts {
    fn mount(&mut self, plate: &ReferencePlate) -> Result<RigConfig, CommissionError> {
        let mut scene = self.bench.clone();
        scene.name = format!("reference plate {}: {}", plate.name, plate.title);
        scene.plate.size_mm = plate.surface.size_mm;
        scene.features = plate.surface.features.clone();
        scene.camera = None;
        let mut config = InspectConfig::new(scene, "unused");
        config.rig.speedup = self.speedup;
        // Each mounting's sensor draws its own noise.
        config.rig.seed = self.seed.wrapping_add(self.mounted);
        self.mounted += 1;
        Ok(config.rig)
    }
}

fn mounts(args: &RunArgs) -> Result<Box<dyn Mounts>> {
    if let (Some(serial), Some(controller), Some(key)) = (&args.serial, args.controller, &args.key)
    {
        let site = match &args.site {
            Some(p) => Site::load(p).context("--site")?,
            None => Site::default(),
        };
        let hw = Hardware {
            serial: serial.clone(),
            controller,
            bind: args.bind,
            key_file: key.clone(),
            camera: None,
            homography: None,
            capture: Default::default(),
        };
        let rig = InspectConfig::on_hardware(hw, site, "unused").rig;
        return Ok(Box::new(OperatorMounts { rig }));
    }
    #[cfg(feature = "sim")]
    {
        let bench = crackbot_sim::Scene::load_or_default(args.scene.as_deref())?;
        Ok(Box::new(SimulatedMounts {
            bench,
            speedup: args.speedup,
            seed: args.seed,
            mounted: 0,
        }))
    }
    #[cfg(not(feature = "sim"))]
    bail!("this build has no simulator: commissioning needs --serial, --controller and --key")
}

fn run(args: &RunArgs) -> Result<()> {
    if args.name.is_empty() || args.name.contains(['/', '\\']) || args.name.starts_with('.') {
        bail!(
            "--name {:?}: a finger's name is one folder name (no slashes, not hidden)",
            args.name
        );
    }
    let mut settings = CommissionSettings {
        repetitions: args.repetitions,
        slides: args.slides,
        speed_mm_s: args.speed_mm_s,
        seed: args.seed,
        trees: args.trees,
        max_depth: args.max_depth,
        ..CommissionSettings::default()
    };
    if !args.plates.is_empty() {
        settings.plates.clone_from(&args.plates);
    }
    let config = CommissionConfig {
        settings,
        session: args
            .session
            .clone()
            .unwrap_or_else(|| PathBuf::from("out/commission").join(&args.name)),
        profile: crate::finger::fingers_dir(args.fingers.as_deref()).join(&args.name),
        name: args.name.clone(),
        date: humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string(),
        shipped: (
            crackbot_datasets::model_path("tactile/recognition.ctm"),
            crackbot_datasets::model_path("tactile/width.ctm"),
        ),
    };
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .context("installing the Ctrl-C handler")?;
    }
    let mut mounts = mounts(args)?;
    let bar = bar(args.json);
    let report = commission(&config, mounts.as_mut(), &stop, &mut |p| show(&bar, p))
        .with_context(|| {
            format!(
                "commissioning stopped (what was recorded is kept in {}; run the same command to resume)",
                config.session.display()
            )
        })?;
    bar.finish_and_clear();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report.card)?);
    } else {
        print_report(&report);
    }
    Ok(())
}

fn bar(hidden: bool) -> indicatif::ProgressBar {
    let bar = if hidden {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(0)
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} slides ({eta} left)")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    bar
}

fn show(bar: &indicatif::ProgressBar, p: &CommissionProgress) {
    match p {
        CommissionProgress::Approach => bar.set_message("reading the optics over the flat plate"),
        CommissionProgress::Optics(o) => {
            bar.println(format!(
            "optics: dark {:.1} counts, {:.1} above it in contact, half of that {:.2} mm higher",
            o.fibre.dark_counts, o.contact_counts[3] - o.fibre.dark_counts, o.half_height_mm
        ));
        }
        CommissionProgress::Slides { plate, done, total } => {
            bar.set_length(*total);
            bar.set_position(*done);
            bar.set_message(format!("sliding over {plate}"));
        }
        CommissionProgress::Training(what) => bar.set_message(format!("training: {what}")),
        CommissionProgress::Evaluated(_) => {}
    }
}

fn pct(f: &Figures) -> (String, String, String) {
    (
        format!("{:.1} %", 100.0 * f.window_accuracy),
        format!("{:.1} %", 100.0 * f.slide_accuracy),
        f.slide_width_mae_mm
            .map_or_else(|| "–".into(), |m| format!("{m:.2} mm")),
    )
}

fn print_report(r: &CommissionReport) {
    let c = &r.card;
    let o = &c.optics;
    println!(
        "finger \"{}\" commissioned, profile installed in {}",
        c.name,
        r.profile.display()
    );
    println!(
        "optics: proximity dark {:.1} counts, contact {:.1} above dark, half-intensity {:.2} mm above contact, curve peak {:.3} mm, fibre {:.3} mm above the tip (fit RMS {:.2} counts)",
        o.fibre.dark_counts,
        o.contact_counts[3] - o.fibre.dark_counts,
        o.half_height_mm,
        o.fibre.peak_mm,
        o.fibre.height_mm,
        o.fit_rms_counts
    );
    println!(
        "        D1–D3 in contact {:.0} / {:.0} / {:.0}, load response {:+.1} / {:+.1} / {:+.1}; noise D1–D3, P {:.2} / {:.2} / {:.2} / {:.2} counts",
        o.contact_counts[0], o.contact_counts[1], o.contact_counts[2],
        o.load_response_counts[0], o.load_response_counts[1], o.load_response_counts[2],
        o.noise_counts[0], o.noise_counts[1], o.noise_counts[2], o.noise_counts[3]
    );
    let e = &c.evaluation;
    println!("\n| model | windows | slides | width slide MAE |\n|---|---:|---:|---:|");
    for (name, f) in [
        (
            "recognition, this finger's (held-out repetitions)",
            &e.recognition,
        ),
        (
            "recognition, shipped (every recording)",
            &e.shipped_recognition,
        ),
        ("width, this finger's (held-out repetitions)", &e.width),
        ("width, shipped (every recording)", &e.shipped_width),
    ] {
        let (w, s, m) = pct(f);
        println!("| {name} | {w} | {s} | {m} |");
    }
    println!(
        "\n{} slides on {} plates; robot time {:.0} s (optics {:.0} s, slides {:.0} s)",
        c.slides,
        c.plates.len(),
        c.robot_time_s[0] + c.robot_time_s[1],
        c.robot_time_s[0],
        c.robot_time_s[1]
    );
    println!("use it: crackbot run --finger {}", c.name);
}
