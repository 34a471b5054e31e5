//! The figures of the `crackbot_tactile::localise` docs.
//!
//! * Real recordings (`$CRACKBOT_DATA_DIR/tactile/{type,width}`): the direction lag and the width bias estimated on
//!   repetition 1, then per plate and repetition the spread of the 12 slides' centres and extents, by direction,
//!   and for the width plates the error of the extent against the crack's width.
//! * Simulated slides (`crackbot_sim::experiment::simulate_recording` over the width experiment's plates, whose
//!   crack lies at a known place): the mean absolute error of start, end, centre and width against the truth.
//!
//! `cargo run --release -p crackbot-research --example localisation` (add `-- real` or `-- sim` for one part).

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_sim::experiment::{simulate_recording, Experiment, ExperimentConfig};
use crackbot_tactile::localise::{localise_passes, CrackExtent, LocaliseConfig, Travel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One localised pass of a real recording.
struct Pass {
    slide: u32,
    extent: Option<CrackExtent>,
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

fn std(v: &[f64]) -> f64 {
    if v.len() < 2 {
        return f64::NAN;
    }
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_unstable_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

fn max_dev(v: &[f64]) -> f64 {
    let m = mean(v);
    v.iter().map(|x| (x - m).abs()).fold(0.0, f64::max)
}

/// Every whole slide's passes, localised.
fn passes(
    rec: &Recording,
    config: &LocaliseConfig,
) -> Result<Vec<Pass>, Box<dyn std::error::Error>> {
    let mut out = Vec::new();
    for range in rec.slides() {
        let rows = &rec.rows[range];
        if rows.len() < 1000 {
            continue;
        }
        let samples: Vec<[f64; 4]> = rows.iter().map(crackbot_recording::Row::channels).collect();
        let positions: Vec<f64> = rows.iter().map(|r| r.x_mm).collect();
        for p in localise_passes(&samples, &positions, config)? {
            out.push(Pass {
                slide: rows[0].slide,
                extent: p.extent,
            });
        }
    }
    Ok(out)
}

/// Whether the plate has a crack: the type experiment's label 1, any width above 0.
fn is_crack(width_experiment: bool, label: f64) -> bool {
    if width_experiment {
        label > 0.0
    } else {
        label == 1.0
    }
}

fn of_dir(passes: &[Pass], travel: Travel, f: fn(&CrackExtent) -> f64) -> Vec<f64> {
    passes
        .iter()
        .filter_map(|p| p.extent.as_ref())
        .filter(|e| e.travel == travel)
        .map(f)
        .collect()
}

struct Real {
    name: String,
    width_experiment: bool,
    label: f64,
    repetition: u32,
    rec: Recording,
}

#[expect(
    clippy::too_many_lines,
    reason = "a research probe (to leave the library's examples with issue 58)"
)]
fn real(data: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    let mut all = Vec::new();
    for (folder, width_experiment) in [("type", false), ("width", true)] {
        for (path, rec) in collect_recordings(&[data.join("tactile").join(folder)])? {
            let name = path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("?")
                .replace("_complete", "");
            all.push(Real {
                name,
                width_experiment,
                label: rec.label().unwrap_or(f64::NAN),
                repetition: rec.repetition().unwrap_or(0),
                rec,
            });
        }
    }

    // 1. Estimates on repetition 1, from the uncorrected reading.
    let raw = LocaliseConfig::uncorrected();
    let mut lags = Vec::new();
    let mut width_pairs = Vec::new();
    println!("## Repetition 1: estimates (uncorrected reading)\n");
    println!("| plate | increasing: median centre | decreasing: median centre | lag (half the difference) | same, near edge / far edge | median dip extent |");
    println!("|---|---|---|---|---|---|");
    for r in all
        .iter()
        .filter(|r| r.repetition == 1 && is_crack(r.width_experiment, r.label))
    {
        let p = passes(&r.rec, &raw)?;
        let inc = median(&of_dir(&p, Travel::Increasing, |e| e.centre_mm));
        let dec = median(&of_dir(&p, Travel::Decreasing, |e| e.centre_mm));
        let lag = 0.5 * (inc - dec);
        lags.push(lag);
        let sb = median(&of_dir(&p, Travel::Increasing, |e| e.dip_start_mm))
            - median(&of_dir(&p, Travel::Decreasing, |e| e.dip_start_mm));
        let eb = median(&of_dir(&p, Travel::Increasing, |e| e.dip_end_mm))
            - median(&of_dir(&p, Travel::Decreasing, |e| e.dip_end_mm));

        let extents: Vec<f64> = p
            .iter()
            .filter_map(|p| p.extent.as_ref())
            .map(|e| e.dip_end_mm - e.dip_start_mm)
            .collect();
        let extent = median(&extents);
        if r.width_experiment {
            width_pairs.push((r.label, extent));
        }
        println!(
            "| {} | {inc:.2} | {dec:.2} | {lag:.3} | {:.3} / {:.3} | {extent:.2} |",
            r.name,
            0.5 * sb,
            0.5 * eb
        );
    }
    // Least squares of extent = offset + scale × width.
    let wm = mean(&width_pairs.iter().map(|p| p.0).collect::<Vec<_>>());
    let em = mean(&width_pairs.iter().map(|p| p.1).collect::<Vec<_>>());
    let sxy: f64 = width_pairs.iter().map(|p| (p.0 - wm) * (p.1 - em)).sum();
    let sxx: f64 = width_pairs.iter().map(|p| (p.0 - wm) * (p.0 - wm)).sum();
    let scale = sxy / sxx;
    let d = LocaliseConfig::default();
    println!(
        "\nlag: median {:.3} mm over {} plates; width calibration: extent = {:.3} mm + {:.4} × width over {} width plates (defaults: lag {:.3}, offset {:.3}, scale {:.4})\n",
        median(&lags),
        lags.len(),
        em - scale * wm,
        scale,
        width_pairs.len(),
        d.direction_lag_mm,
        d.width_offset_mm,
        d.width_scale
    );

    // 2. Consistency with the defaults, every repetition.
    let config = LocaliseConfig::default();
    println!("## Consistency over the 12 slides (default settings)\n");
    println!("Per direction (+: increasing x, −: decreasing): passes with a dip / passes, std and max |deviation| of the centre from the recording's mean, direction bias (mean centre + minus −), std of the extent; width plates: MAE of the width.\n");
    println!("| plate | rep | dip +/− | centre mean | centre std + / − | centre max dev | bias +−, raw → corrected | per-slide centre std | extent mean | extent std | width MAE |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    struct Class {
        name: String,
        centre_std: Vec<f64>,
        max_dev: Vec<f64>,
        bias: Vec<f64>,
        bias_raw: Vec<f64>,
        width_abs: Vec<f64>,
        detected: usize,
        total: usize,
    }
    let mut classes: Vec<Class> = Vec::new();
    for r in &all {
        let p = passes(&r.rec, &config)?;
        let pr = passes(&r.rec, &raw)?;
        let total = p.len();
        let found: Vec<&CrackExtent> = p.iter().filter_map(|p| p.extent.as_ref()).collect();
        let n_inc = found
            .iter()
            .filter(|e| e.travel == Travel::Increasing)
            .count();
        let n_dec = found.len() - n_inc;
        let key = if r.width_experiment {
            format!("width {} mm", r.label)
        } else {
            r.name
                .trim_end_matches(|c: char| c.is_ascii_digit() || c == '_')
                .to_string()
        };
        let idx = match classes.iter().position(|c| c.name == key) {
            Some(i) => i,
            None => {
                classes.push(Class {
                    name: key.clone(),
                    centre_std: vec![],
                    max_dev: vec![],
                    bias: vec![],
                    bias_raw: vec![],
                    width_abs: vec![],
                    detected: 0,
                    total: 0,
                });
                classes.len() - 1
            }
        };
        let c = &mut classes[idx];
        c.detected += found.len();
        c.total += total;
        if found.len() < 4 {
            println!(
                "| {} | {} | {n_inc}/{n_dec} of {total} | – | – | – | – | – | – | – | – |",
                r.name, r.repetition
            );
            continue;
        }
        let centres: Vec<f64> = found.iter().map(|e| e.centre_mm).collect();
        let inc = of_dir(&p, Travel::Increasing, |e| e.centre_mm);
        let dec = of_dir(&p, Travel::Decreasing, |e| e.centre_mm);
        let bias = mean(&inc) - mean(&dec);
        let bias_raw = mean(&of_dir(&pr, Travel::Increasing, |e| e.centre_mm))
            - mean(&of_dir(&pr, Travel::Decreasing, |e| e.centre_mm));
        // Per slide: both passes averaged.
        let mut per_slide = Vec::new();
        for s in 1..=12 {
            let v: Vec<f64> = p
                .iter()
                .filter(|q| q.slide == s)
                .filter_map(|q| q.extent.as_ref())
                .map(|e| e.centre_mm)
                .collect();
            if !v.is_empty() {
                per_slide.push(mean(&v));
            }
        }
        let extents: Vec<f64> = found
            .iter()
            .map(|e| e.dip_end_mm - e.dip_start_mm)
            .collect();
        let width = if r.width_experiment {
            let abs: Vec<f64> = found.iter().map(|e| (e.width_mm - r.label).abs()).collect();
            c.width_abs.extend(&abs);
            format!("{:.2}", mean(&abs))
        } else {
            "–".into()
        };
        let pooled_std = std(&centres);
        if r.repetition > 1 {
            c.centre_std.push(pooled_std);
            c.max_dev.push(max_dev(&centres));
            c.bias.push(bias);
            c.bias_raw.push(bias_raw);
        }
        println!(
            "| {} | {} | {n_inc}/{n_dec} of {total} | {:.2} | {:.3} / {:.3} | {:.2} | {bias_raw:+.2} → {bias:+.2} | {:.3} | {:.2} | {:.3} | {width} |",
            r.name,
            r.repetition,
            mean(&centres),
            std(&inc),
            std(&dec),
            max_dev(&centres),
            std(&per_slide),
            mean(&extents),
            std(&extents),
        );
    }
    println!("\n## Per class, repetitions 2 and 3 (the lag was estimated on repetition 1)\n");
    println!("| class | passes with a dip (all reps) | centre std (mean over recordings) | max |deviation| (worst) | bias + minus −: raw → corrected (mean) | width MAE (all passes) |");
    println!("|---|---|---|---|---|---|");
    for c in &classes {
        println!(
            "| {} | {}/{} | {:.3} | {:.2} | {:+.2} → {:+.2} | {} |",
            c.name,
            c.detected,
            c.total,
            mean(&c.centre_std),
            c.max_dev.iter().copied().fold(f64::NAN, f64::max),
            mean(&c.bias_raw),
            mean(&c.bias),
            if c.width_abs.is_empty() {
                "–".into()
            } else {
                format!("{:.2}", mean(&c.width_abs))
            }
        );
    }
    Ok(())
}

/// A simulated slide with the truth: samples, positions, crack start and end in the position stream's frame.
pub struct SimSlide {
    samples: Vec<[f64; 4]>,
    positions: Vec<f64>,
    width: f64,
    start: f64,
    end: f64,
}

/// `per_width` recordings of `slides` slides over each crack plate of the width experiment.
fn simulate(
    seed: u64,
    per_width: u32,
    slides: u32,
) -> Result<Vec<SimSlide>, Box<dyn std::error::Error>> {
    let mut config = ExperimentConfig::paper(Experiment::Width, seed);
    config.slides = slides;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for (k, (_, width, surface, edge_x)) in config.surfaces().into_iter().enumerate() {
        if width <= 0.0 {
            continue;
        }
        for r in 1..=per_width {
            let start = rng.random_range(config.start_range_mm.0..config.start_range_mm.1);
            let line_y = 50.0 + rng.random_range(-1.0..1.0);
            let offset = rng.random_range(8.0..14.0);
            let rec = simulate_recording(
                &config,
                &surface,
                config.mount(k),
                width,
                r,
                edge_x,
                start,
                line_y,
                offset,
                rng.random(),
            )?;
            // The crack spans [edge_x, edge_x + width] on the plate; the position column is
            // `offset + (tip − line start)` and the line starts `start` before `edge_x`.
            for range in rec.slides() {
                let rows = &rec.rows[range];
                out.push(SimSlide {
                    samples: rows.iter().map(crackbot_recording::Row::channels).collect(),
                    positions: rows.iter().map(|r| r.x_mm).collect(),
                    width,
                    start: offset + start,
                    end: offset + start + width,
                });
            }
        }
    }
    Ok(out)
}

fn sim() -> Result<(), Box<dyn std::error::Error>> {
    let (per_width, slides) = (3, 3);
    let calib = simulate(1, per_width, slides)?;
    let test = simulate(2, per_width, slides)?;
    // Sim-fitted corrections from the calibration set's uncorrected reading.
    let raw = LocaliseConfig::uncorrected();
    let mut off_inc = Vec::new();
    let mut off_dec = Vec::new();
    let mut wb = Vec::new();
    for s in &calib {
        for p in localise_passes(&s.samples, &s.positions, &raw)? {
            if let Some(e) = p.extent {
                let truth = 0.5 * (s.start + s.end);
                match e.travel {
                    Travel::Increasing => off_inc.push(truth - e.centre_mm),
                    _ => off_dec.push(truth - e.centre_mm),
                }
                wb.push(e.dip_end_mm - e.dip_start_mm - s.width);
            }
        }
    }
    let (a_inc, a_dec) = (median(&off_inc), median(&off_dec));
    let fitted = LocaliseConfig {
        look_ahead_mm: 0.5 * (a_inc + a_dec),
        direction_lag_mm: 0.5 * (a_dec - a_inc),
        width_offset_mm: median(&wb),
        width_scale: 1.0,
        ..LocaliseConfig::default()
    };
    println!(
        "## Simulated slides\n\nCalibration set (seed 1): look-ahead {:.3} mm, direction lag {:.3} mm, width offset {:.3} mm (scale 1) (defaults {:.3}, {:.3}, {:.3}, {:.4}).\n",
        fitted.look_ahead_mm,
        fitted.direction_lag_mm,
        fitted.width_offset_mm,
        LocaliseConfig::default().look_ahead_mm,
        LocaliseConfig::default().direction_lag_mm,
        LocaliseConfig::default().width_offset_mm,
        LocaliseConfig::default().width_scale
    );
    println!("Test set (seed 2): {per_width} recordings × {slides} slides (there and back) per width; MAE in mm over passes.\n");
    println!("| settings | width mm | passes with a dip | start MAE | end MAE | centre MAE | width MAE | centre bias |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, config) in [
        ("default", LocaliseConfig::default()),
        ("sim-fitted", fitted),
    ] {
        let mut widths: Vec<f64> = test.iter().map(|s| s.width).collect();
        widths.sort_unstable_by(f64::total_cmp);
        widths.dedup();
        let mut all = [Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new()];
        let (mut found_all, mut total_all) = (0, 0);
        for w in widths {
            let mut errs = [Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new()];
            let (mut found, mut total) = (0, 0);
            for s in test.iter().filter(|s| s.width == w) {
                for p in localise_passes(&s.samples, &s.positions, &config)? {
                    total += 1;
                    if let Some(e) = p.extent {
                        found += 1;
                        let c = 0.5 * (s.start + s.end);
                        errs[0].push((e.start_mm - s.start).abs());
                        errs[1].push((e.end_mm - s.end).abs());
                        errs[2].push((e.centre_mm - c).abs());
                        errs[3].push((e.width_mm - s.width).abs());
                        errs[4].push(e.centre_mm - c);
                    }
                }
            }
            println!(
                "| {name} | {w} | {found}/{total} | {:.3} | {:.3} | {:.3} | {:.3} | {:+.3} |",
                mean(&errs[0]),
                mean(&errs[1]),
                mean(&errs[2]),
                mean(&errs[3]),
                mean(&errs[4])
            );
            for (a, e) in all.iter_mut().zip(errs) {
                a.extend(e);
            }
            found_all += found;
            total_all += total;
        }
        println!(
            "| {name} | all | {found_all}/{total_all} | {:.3} | {:.3} | {:.3} | {:.3} | {:+.3} |",
            mean(&all[0]),
            mean(&all[1]),
            mean(&all[2]),
            mean(&all[3]),
            mean(&all[4])
        );
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let part = std::env::args().nth(1).unwrap_or_default();
    let data = PathBuf::from(
        std::env::var_os("CRACKBOT_DATA_DIR").unwrap_or_else(|| "../shared/data".into()),
    );
    if part != "sim" {
        real(&data)?;
    }
    if part != "real" {
        sim()?;
    }
    Ok(())
}
