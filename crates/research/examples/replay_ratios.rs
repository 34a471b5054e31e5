//! The print check replayed on saved fused trials: for each candidate that was passed over
//! raised, its print ratio and floor ratio on every raised pass, computed again from the trial's
//! recordings by `crackbot_tactile::print_check` (no arm, no simulator). For judging a new rule
//! on runs already made:
//! `cargo run --release -p crackbot-research --example replay_ratios -- TRIALS_DIR...`, then
//! join with the scenes' truth (`crates/research/scripts/trial_errors.py`'s matching).
//!
//! One line per candidate: `SEED CANDIDATE DECIDED REPORTED PRINT_1,…,PRINT_N FLOOR_1,…,FLOOR_N`
//! (`DECIDED` is `confirmed` or `rejected`; `REPORTED` the report's own ratio; `-` where a pass
//! gave none). Positions along the raised passes are mapped onto the strokes' axis as the
//! mission does for a pass that runs the planner's default overrun (1.5 mm) past each end; the
//! profile fit searches ±6 mm of shift, so a pass clipped at the workspace's edge still lines up.
//! A single judged stroke that also crossed a second line is cut to the samples around the
//! candidate's own dip, as the mission cuts it (`crackbot_tactile::stroke::own_dip`).
//! On the fresh trials 9900–10019 (real time) the replayed ratios gave the report's own within
//! 0.005 for 391 of 409 candidates, and within 0.053 for all: an approximation for comparing
//! rules, not a copy of the report.

use std::path::Path;

use crackbot_mission::inspect::{
    surface_rise_mm, MIN_DIP_COUNTS, PRINT_CHECK_HEIGHT_MM, PRINT_CHECK_OVERRUN_MM,
};
use crackbot_research::trial_params;
use crackbot_tactile::localise::{localise, LocaliseConfig};
use crackbot_tactile::print_check::print_ratios;
use crackbot_tactile::stroke::{own_dip, SeparateDips};
use serde_json::Value;

#[path = "support/trials.rs"]
mod trials;
use trials::{fused_trials, SavedTrial};

type Error = Box<dyn std::error::Error>;

/// A saved pass: its samples (D1, D2, D3, P), their positions, its direction flag.
type Pass = (Vec<[f64; 4]>, Vec<f64>, u8);

/// The four channels and the position column of a saved pass, and its direction flag.
fn load_samples(path: &Path) -> Result<Pass, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let (mut s, mut x, mut dir) = (Vec::new(), Vec::new(), 0u8);
    for (n, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 6 {
            return Err(format!("{}:{}: expected 6 columns", path.display(), n + 1).into());
        }
        s.push([f[0].parse()?, f[1].parse()?, f[2].parse()?, f[3].parse()?]);
        dir = f[4].parse()?;
        x.push(f[5].parse()?);
    }
    Ok((s, x, dir))
}

/// The proximity column and the position column of a saved pass, and its direction flag.
fn load(path: &Path) -> Result<(Vec<f64>, Vec<f64>, u8), Error> {
    let (s, x, dir) = load_samples(path)?;
    Ok((s.iter().map(|v| v[3]).collect(), x, dir))
}

fn fmt(v: &[Option<f64>]) -> String {
    v.iter()
        .map(|r| r.map_or("-".to_string(), |r| format!("{r:.4}")))
        .collect::<Vec<_>>()
        .join(",")
}

#[expect(
    clippy::too_many_lines,
    reason = "a research probe (to leave the library's examples with issue 58)"
)]
fn main() -> Result<(), Error> {
    for dir in std::env::args().skip(1) {
        for SavedTrial {
            folder: trial,
            seed,
            report,
        } in fused_trials(Path::new(&dir))?
        {
            // The fibre's dark level the mission judged by: the trial scene's sensor's.
            let scene = crackbot_sim::random_scene(&trial_params(), seed.parse()?)?;
            let dark = scene.sensor.optics.proximity_dark_counts;
            let empty = Vec::new();
            let passes = report["passes"].as_array().unwrap_or(&empty);
            let decided = report["cracks"]
                .as_array()
                .unwrap_or(&empty)
                .iter()
                .filter_map(|c| Some((c["candidate"].as_u64()?, "confirmed", &c["evidence"])))
                .chain(
                    report["rejected"]
                        .as_array()
                        .unwrap_or(&empty)
                        .iter()
                        .filter_map(|c| Some((c["candidate"].as_u64()?, "rejected", c))),
                );
            for (cand, verdict, holder) in decided {
                let Some(reported) = holder["height_ratio"].as_f64() else {
                    continue;
                };
                // The judged strokes: the candidate's passes with a verdict.
                let judged: Vec<&Value> = passes
                    .iter()
                    .filter(|p| p["candidate"].as_u64() == Some(cand) && !p["class"].is_null())
                    .collect();
                let Some(first) = judged.first() else {
                    continue;
                };
                let ends = |p: &Value| -> Option<f64> {
                    let a: [f64; 2] = serde_json::from_value(p["start_mm"].clone()).ok()?;
                    let b: [f64; 2] = serde_json::from_value(p["end_mm"].clone()).ok()?;
                    Some((b[0] - a[0]).hypot(b[1] - a[1]))
                };
                let length = ends(first).ok_or("a pass without its ends")?;
                let mut strokes = Vec::new();
                let mut samples = Vec::new();
                let mut whole = Vec::new();
                let mut first_dir = 0u8;
                for p in &judged {
                    let path = p["recording"]
                        .as_str()
                        .ok_or("a pass without its recording")?;
                    let (s, x, d) = load_samples(Path::new(path))?;
                    let along: Vec<f64> = x
                        .iter()
                        .map(|&x| if d == 0 { x } else { length - x })
                        .collect();
                    strokes.push((s.iter().map(|v| v[3]).collect::<Vec<f64>>(), along));
                    if samples.is_empty() {
                        first_dir = d;
                    }
                    samples.push(s);
                }
                // One stroke over a second line too: the print check compares against the
                // samples around the candidate's own dip, as the mission does.
                if let ([(p, along)], [s]) = (strokes.as_mut_slice(), samples.as_slice()) {
                    let point = |key: &str| -> Option<[f64; 2]> {
                        serde_json::from_value(first[key].clone()).ok()
                    };
                    let (a, b) = (point("start_mm"), point("end_mm"));
                    // The strokes' axis runs from where a stroke in direction 0 starts.
                    let (origin, other) = match (a, b) {
                        (Some(a), Some(b)) if first_dir == 0 => (a, b),
                        (Some(a), Some(b)) => (b, a),
                        _ => return Err("a pass without its ends".into()),
                    };
                    let u = [
                        (other[0] - origin[0]) / length,
                        (other[1] - origin[1]) / length,
                    ];
                    let candidate = report["candidates"]
                        .as_array()
                        .unwrap_or(&empty)
                        .iter()
                        .find(|c| c["id"].as_u64() == Some(cand));
                    let centre: Option<[f64; 2]> =
                        candidate.and_then(|c| serde_json::from_value(c["centre_mm"].clone()).ok());
                    let width = candidate
                        .and_then(|c| c["width_mm"].as_f64())
                        .unwrap_or(crackbot_planner::Settings::default().assumed_width_mm);
                    let config = LocaliseConfig {
                        min_depth_counts: MIN_DIP_COUNTS,
                        ..Default::default()
                    };
                    let extent = localise(s, along, &config).ok().flatten();
                    if let (Some(c), Some(e)) = (centre, extent) {
                        let near = (c[0] - origin[0]) * u[0] + (c[1] - origin[1]) * u[1];
                        if let Some((r, _)) =
                            own_dip(s, along, &e, width, near, &config, &SeparateDips::default())
                        {
                            whole.push((p.clone(), along.clone()));
                            *p = p[r.clone()].to_vec();
                            *along = along[r].to_vec();
                        }
                    }
                }
                let (mut prints, mut floors, mut rises) = (Vec::new(), Vec::new(), Vec::new());
                // A first pass made again higher over a surface standing above the plate
                // (`raised-NNN-again.csv`) replaces the first.
                let again = trial.join(format!("raised-{cand:03}-again.csv"));
                for k in 1.. {
                    let name = if k == 1 {
                        format!("raised-{cand:03}.csv")
                    } else {
                        format!("raised-{cand:03}-{k}.csv")
                    };
                    let path = if k == 1 && again.exists() {
                        again.clone()
                    } else {
                        trial.join(name)
                    };
                    if !path.exists() {
                        break;
                    }
                    let (v, x, back) = load(&path)?;
                    let along: Vec<f64> = x
                        .iter()
                        .map(|&x| {
                            if back == 0 {
                                x - PRINT_CHECK_OVERRUN_MM
                            } else {
                                length + PRINT_CHECK_OVERRUN_MM - x
                            }
                        })
                        .collect();
                    let of = |strokes: &[(Vec<f64>, Vec<f64>)]| -> Vec<_> {
                        strokes
                            .iter()
                            .filter_map(|(p, x)| print_ratios((p, x), (&v, &along), dark).ok())
                            .collect()
                    };
                    // The whole stroke where its own dip gives no ratio, as the mission does.
                    let mut ratios = of(&strokes);
                    if !whole.is_empty() && ratios.iter().all(|r| r.print.is_none()) {
                        ratios = of(&whole);
                    }
                    let mean = |r: Vec<f64>| {
                        (!r.is_empty()).then(|| r.iter().sum::<f64>() / r.len() as f64)
                    };
                    prints.push(mean(ratios.iter().filter_map(|r| r.print).collect()));
                    floors.push(mean(ratios.iter().filter_map(|r| r.floor).collect()));
                    rises.push(mean(
                        ratios
                            .iter()
                            .filter_map(|r| {
                                surface_rise_mm(
                                    &scene.sensor.optics.fibre(),
                                    r.levels,
                                    dark,
                                    PRINT_CHECK_HEIGHT_MM,
                                )
                            })
                            .collect(),
                    ));
                }
                println!(
                    "{seed} {cand} {verdict} {reported:.4} {} {} {}",
                    fmt(&prints),
                    fmt(&floors),
                    fmt(&rises)
                );
            }
        }
    }
    Ok(())
}
