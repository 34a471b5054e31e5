//! Which random draw of a simulated recording decides how it reads: the recordings of one
//! surface of `sim dataset --experiment recognition --seed SEED`, simulated again with one draw
//! swapped for another recording's, or with the stroke's start swept over its range. For
//! finding why whole recordings are misread (`crates/sim/docs/calibration.md`, "The wavy
//! misreads are whole recordings").
//!
//! ```text
//! cargo run --release -p crackbot-research --example redraw -- SEED STEM OUT swap DONOR
//! cargo run --release -p crackbot-research --example redraw -- SEED STEM OUT sweep RECORDING
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
use crackbot_sim::experiment::{recording_draws, simulate_drawn, ExperimentConfig, RecordingDraws};

type Error = Box<dyn std::error::Error>;

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
    let draws: Vec<RecordingDraws> = recording_draws(&config)
        .into_iter()
        .filter(|d| d.surface == k)
        .collect();
    for d in &draws {
        println!("{d:?}");
    }
    let write = |dir: &Path, d: &RecordingDraws| -> Result<(), Error> {
        let rec = simulate_drawn(&config, &surfaces, d)?;
        std::fs::create_dir_all(dir)?;
        write_recording(
            &dir.join(format!("{stem}_complete_{}.csv", d.repetition)),
            &rec,
        )?;
        Ok(())
    };
    let pick = |n: &str| -> Result<RecordingDraws, Error> {
        let i: usize = n.parse()?;
        Ok(*draws
            .get(i.wrapping_sub(1))
            .ok_or_else(|| format!("recording {n}: there are {}", draws.len()))?)
    };
    let out = Path::new(out);
    match mode.as_str() {
        "swap" => {
            let donor = pick(which)?;
            for d in &draws {
                let variants = [
                    ("orig", *d),
                    (
                        "start",
                        RecordingDraws {
                            start_mm: donor.start_mm,
                            ..*d
                        },
                    ),
                    (
                        "line",
                        RecordingDraws {
                            line_y: donor.line_y,
                            ..*d
                        },
                    ),
                    (
                        "offset",
                        RecordingDraws {
                            position_offset_mm: donor.position_offset_mm,
                            ..*d
                        },
                    ),
                    (
                        "noise",
                        RecordingDraws {
                            seed: donor.seed,
                            ..*d
                        },
                    ),
                ];
                for (name, v) in &variants {
                    write(&out.join(name).join(format!("r{}", d.repetition)), v)?;
                }
            }
        }
        "sweep" => {
            let d = pick(which)?;
            let (lo, hi) = config.start_range_mm;
            let steps = ((hi - lo) / 0.25).round() as u32;
            for s in 0..=steps {
                let start_mm = lo + 0.25 * f64::from(s);
                let dir = out.join(format!("start{start_mm:05.2}"));
                write(&dir, &RecordingDraws { start_mm, ..d })?;
            }
        }
        other => return Err(format!("`{other}`: swap or sweep").into()),
    }
    Ok(())
}
