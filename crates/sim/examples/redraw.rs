//! Which random draw of a simulated recording decides how it reads: the recordings of one
//! surface of `sim dataset --experiment recognition --seed SEED`, simulated again with one draw
//! swapped for another recording's, or with the stroke's start swept over its range. For
//! finding why whole recordings are misread (`crates/sim/docs/calibration.md`, "The wavy
//! misreads are whole recordings").
//!
//! ```text
//! cargo run --release -p crackbot-sim --example redraw -- SEED STEM OUT swap DONOR
//! cargo run --release -p crackbot-sim --example redraw -- SEED STEM OUT sweep RECORDING
//! ```
//!
//! `STEM` is the surface's file stem (`crack_pattern`: the wavy plate). `swap` writes
//! `OUT/<draw>/r<R>/<STEM>_complete_<R>.csv` for every recording R and each draw (`orig`: as
//! drawn, the dataset's own file; `start`, `line`, `offset`, `noise`: that draw taken from
//! recording DONOR). `sweep` writes `OUT/start<mm>/…` for recording RECORDING with the start
//! from the range's low end to its high end in 0.25 mm steps. Evaluate each folder with
//! `crackbot tactile eval --model models/tactile/recognition.ctm --test FOLDER`.

use std::path::Path;

use crackbot_recording::{write_recording, Experiment};
use crackbot_sim::experiment::{simulate_recording, ExperimentConfig};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

type Error = Box<dyn std::error::Error>;

/// One recording's draws, in the order `crackbot_sim::experiment::simulate` makes them.
#[derive(Debug, Clone, Copy)]
struct Draws {
    recording: u32,
    start_mm: f64,
    line_y: f64,
    offset_mm: f64,
    seed: u64,
}

fn main() -> Result<(), Error> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [seed, stem, out, mode, which] = args.as_slice() else {
        return Err(
            "usage: redraw SEED STEM OUT swap DONOR | redraw SEED STEM OUT sweep RECORDING".into(),
        );
    };
    let config = ExperimentConfig::paper(Experiment::Recognition, seed.parse()?);
    let surfaces = config.surfaces();
    let k = surfaces
        .iter()
        .position(|s| &s.0 == stem)
        .ok_or_else(|| format!("no surface `{stem}` in the recognition experiment"))?;
    // Replay the dataset's random stream up to and through this surface's recordings.
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    let mut draws = Vec::new();
    for i in 0..=k {
        for recording in 1..=config.recordings {
            let (lo, hi) = config.start_range_mm;
            let d = Draws {
                recording,
                start_mm: if hi > lo {
                    rng.random_range(lo..hi)
                } else {
                    lo
                },
                line_y: 50.0 + rng.random_range(-1.0..1.0),
                offset_mm: rng.random_range(8.0..14.0),
                seed: rng.random::<u64>(),
            };
            if i == k {
                println!("{d:?}");
                draws.push(d);
            }
        }
    }
    let (_, label, surface, edge_x) = &surfaces[k];
    let write = |dir: &Path, d: &Draws| -> Result<(), Error> {
        let rec = simulate_recording(
            &config,
            surface,
            config.mount(k),
            *label,
            d.recording,
            *edge_x,
            d.start_mm,
            d.line_y,
            d.offset_mm,
            d.seed,
        )?;
        std::fs::create_dir_all(dir)?;
        write_recording(
            &dir.join(format!("{stem}_complete_{}.csv", d.recording)),
            &rec,
        )?;
        Ok(())
    };
    let pick = |n: &str| -> Result<Draws, Error> {
        let i: usize = n.parse()?;
        Ok(*draws
            .get(i.wrapping_sub(1))
            .ok_or_else(|| format!("recording {n}: there are {}", draws.len()))?)
    };
    match mode.as_str() {
        "swap" => {
            let donor = pick(which)?;
            for d in &draws {
                let r = format!("r{}", d.recording);
                let out = Path::new(out);
                write(&out.join("orig").join(&r), d)?;
                let start = Draws {
                    start_mm: donor.start_mm,
                    ..*d
                };
                write(&out.join("start").join(&r), &start)?;
                let line = Draws {
                    line_y: donor.line_y,
                    ..*d
                };
                write(&out.join("line").join(&r), &line)?;
                let offset = Draws {
                    offset_mm: donor.offset_mm,
                    ..*d
                };
                write(&out.join("offset").join(&r), &offset)?;
                let noise = Draws {
                    seed: donor.seed,
                    ..*d
                };
                write(&out.join("noise").join(&r), &noise)?;
            }
        }
        "sweep" => {
            let d = pick(which)?;
            let (lo, hi) = config.start_range_mm;
            let steps = ((hi - lo) / 0.25).round() as u32;
            for s in 0..=steps {
                let start_mm = lo + 0.25 * f64::from(s);
                let dir = Path::new(out).join(format!("start{start_mm:05.2}"));
                write(&dir, &Draws { start_mm, ..d })?;
            }
        }
        other => return Err(format!("`{other}`: swap or sweep").into()),
    }
    Ok(())
}
