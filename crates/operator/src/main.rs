//! `crackbot-operator`: the operator's desktop app. `--source sim` (default) runs missions
//! in-process on the simulated scene, `--source live` watches and commands robots over Zenoh,
//! `--source replay DIR` shows a saved mission.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context as _};
use clap::{Parser, ValueEnum};
use crackbot_operator::app::Measure;
use crackbot_operator::{Backend, OperatorApp};
use crackbot_telemetry::{ZenohOptions, DEFAULT_STATION_ENDPOINT};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SourceArg {
    /// Missions run in this process on the simulated scene (no network).
    Sim,
    /// Robots over Zenoh.
    Live,
    /// A saved mission folder (`crackbot run --out DIR`).
    Replay,
}

/// The crackbot operator app.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Args {
    /// Where the data comes from.
    #[arg(long, value_enum, default_value = "sim")]
    source: SourceArg,
    /// The saved mission's folder (with `--source replay`).
    #[arg(value_name = "DIR")]
    replay_dir: Option<PathBuf>,
    /// Scene file of the missions started from the app (default: the built-in scene, or the
    /// robot's own).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Simulation speed-up of in-process missions.
    #[arg(long, default_value_t = 4.0)]
    speedup: f64,
    /// Start an in-process mission right away (no confirm step: the operator asked for it on
    /// the command line).
    #[arg(long)]
    start: bool,
    /// Zenoh endpoints to connect to (live).
    #[arg(long)]
    connect: Vec<String>,
    /// Zenoh endpoints to listen on (live; default tcp/127.0.0.1:7447).
    #[arg(long)]
    listen: Vec<String>,
    /// A site's Zenoh router (live): the station is its client.
    #[arg(long)]
    router: Option<String>,
    /// The link key file that signs commands (64–128 hex digits, mode 0600); without it the
    /// station can watch and e-stop only.
    #[arg(long)]
    key: Option<PathBuf>,
    /// Where exports (CSV, report, screenshots) and in-process missions' files go.
    #[arg(long, default_value = "out/operator")]
    out: PathBuf,
    /// Measure N frames once four channels stream, write the frame-time summary to
    /// `--measure-out`, and exit.
    #[arg(long, value_name = "N")]
    measure_frames: Option<usize>,
    /// The frame-time summary (JSON).
    #[arg(long, default_value = "frame-times.json")]
    measure_out: PathBuf,
    /// A screenshot saved when the measurement ends.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// The plots' time window, s (1–60).
    #[arg(long, default_value_t = 60.0)]
    window: f64,
    /// Draw as fast as possible instead of at the display's refresh rate (measurements).
    #[arg(long)]
    no_vsync: bool,
    /// Window size, px.
    #[arg(long, default_value = "1280x800")]
    size: String,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    if !(args.speedup.is_finite() && args.speedup > 0.0) {
        bail!("--speedup {}: must be a positive number", args.speedup);
    }
    let (w, h) = args
        .size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<f32>().ok()?, h.parse::<f32>().ok()?)))
        .filter(|(w, h)| *w >= 320.0 && *h >= 240.0)
        .with_context(|| {
            format!(
                "--size {:?}: want WIDTHxHEIGHT, at least 320x240",
                args.size
            )
        })?;
    let backend = match args.source {
        SourceArg::Sim => Backend::sim(args.scene.clone(), args.speedup, args.out.join("missions")),
        SourceArg::Live => {
            let listen = if args.listen.is_empty() && args.router.is_none() {
                vec![DEFAULT_STATION_ENDPOINT.to_string()]
            } else {
                args.listen.clone()
            };
            Backend::live(
                ZenohOptions {
                    listen,
                    connect: args.connect.clone(),
                    router: args.router.clone(),
                    multicast_scouting: false,
                },
                args.key.clone(),
                args.scene.clone(),
            )
        }
        SourceArg::Replay => {
            let dir = args.replay_dir.clone().context(
                "--source replay needs the mission's folder: crackbot-operator --source replay DIR",
            )?;
            let is_log = dir
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("mcap"));
            let saved = dir.join("report.json").is_file() || (is_log && dir.is_file());
            if !saved {
                bail!(
                    "{}: no report.json there (a folder written by `crackbot run --out DIR`, \
                     or its mission.mcap)",
                    dir.display()
                );
            }
            Backend::replay(dir)
        }
    };
    if args.replay_dir.is_some() && args.source != SourceArg::Replay {
        bail!("a folder was given without --source replay");
    }
    if let Some(scene) = &args.scene {
        if !scene.is_file() {
            bail!("--scene {}: no such file", scene.display());
        }
    }
    if !(1.0..=60.0).contains(&args.window) {
        bail!("--window {}: between 1 and 60 s", args.window);
    }
    let mut app = OperatorApp::new(backend, args.out.clone());
    app.window_s = args.window;
    if let Some(n) = args.measure_frames {
        app.measure = Some(Measure {
            frames: n.max(1),
            out: args.measure_out.clone(),
            screenshot: args.screenshot.clone(),
            counted: None,
            done: false,
            since: Instant::now(),
        });
    }
    if args.start {
        app.request_start();
        app.confirm();
    }
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([w, h])
            .with_title("crackbot operator"),
        renderer: eframe::Renderer::Glow,
        glow_options: eframe::egui_glow::GlowConfiguration {
            vsync: !args.no_vsync,
            ..Default::default()
        },
        ..Default::default()
    };
    eframe::run_native(
        "crackbot operator",
        options,
        Box::new(move |_cc| Ok(Box::new(app))),
    )
    .map_err(|e| anyhow::anyhow!("the window did not open: {e}"))?;
    Ok(())
}
