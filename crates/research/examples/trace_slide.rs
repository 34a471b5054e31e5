//! One simulated slide over a paper plate, sample by sample: arm, tip, surface, deflections,
//! contact force, what the proximity fibre sees and the P and D1 counts. For finding out why a
//! simulated trace looks the way it does (e.g. the bump's stick and jump,
//! `docs/calibration.md`).
//!
//! `cargo run --release -p crackbot-research --example trace_slide -- [SURFACE] [PARAMS.toml]`
//! SURFACE is a file stem of `crackbot sim dataset` (`crack_bump`, `crack_pattern`, `crack_mm8`,
//! …; default `crack_bump`); PARAMS overrides parameters as `sim dataset --params` does.

use crackbot_sim::experiment::ExperimentConfig;
use crackbot_sim::plates::Experiment;
use crackbot_sim::run::{SlideLine, SlideSim};

/// Every how many samples (400 Hz) a line is printed.
const EVERY: usize = 8;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let which = args.first().map_or("crack_bump", String::as_str);
    let experiment = if which.starts_with("crack_mm") {
        Experiment::Width
    } else {
        Experiment::Recognition
    };
    let mut config = ExperimentConfig::paper(experiment, 7);
    if let Some(path) = args.get(1) {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
        config.apply_params_toml(&text)?;
    }
    let surfaces = config.surfaces();
    let Some((_, _, surface, edge)) = surfaces.iter().find(|s| s.0 == which) else {
        let names: Vec<&str> = surfaces.iter().map(|s| s.0.as_str()).collect();
        return Err(format!("no surface {which:?}; try one of {names:?}").into());
    };
    let line = SlideLine {
        start: [edge - 7.0, 50.0],
        direction: [1.0, 0.0],
        stroke_mm: config.stroke_mm,
        speed_mm_s: config.speed_mm_s,
    };
    let mut sim = SlideSim::new(surface, 1.0, &line, &config.sensor, config.integrator, 1)?;
    let n = (sim.slide_time() * 400.0) as usize;
    println!("t_s arm_mm tip_mm tip_z_mm surface_mm lateral_mm normal_mm force_n fibre_mm p d1");
    for k in 0..n {
        let s = sim.next_sample()?;
        if k % EVERY == 0 {
            let surface_mm = sim.model().surface_at(s.tip_x_mm * 1e-3 + sim.origin()) * 1e3;
            println!(
                "{:.3} {:.2} {:.2} {:.3} {:.3} {:.2} {:.3} {:.3} {:.2} {:.0} {:.0}",
                s.t,
                s.arm_mm,
                s.tip_x_mm,
                s.tip_z_mm,
                surface_mm,
                s.lateral_mm,
                s.normal_mm,
                s.contact_force_n,
                s.proximity_mm,
                s.counts[3],
                s.counts[0]
            );
        }
    }
    Ok(())
}
