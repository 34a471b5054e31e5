//! One paper plate's geometry against the authors' repetition 1: the quantile distance of that
//! plate alone (and of every plate) for a grid of two of its dimensions, everything else as
//! committed.
//!
//! `CRACKBOT_DATA_DIR=../shared/data cargo run --release -p crackbot-research --example plate_fit -- PLATE [A] [B]`
//! - `wave [AMPLITUDES] [PERIODS]`: the wavy plate (label 3);
//! - `bump [RADII] [HEIGHTS]`: the bump (label 2).
//!
//! The lists are comma-separated millimetres (defaults below).
use crackbot_sim::calibrate::fit_rms;
use crackbot_sim::experiment::{Experiment, ExperimentConfig};
use crackbot_sim::plates::Samples;
use crackbot_sim::recordings::recordings_of_repetition;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn list(arg: Option<String>, default: &[f64]) -> Result<Vec<f64>> {
    match arg {
        None => Ok(default.to_vec()),
        Some(s) => s
            .split(',')
            .map(|v| {
                v.trim()
                    .parse::<f64>()
                    .map_err(|e| format!("{v:?}: {e}").into())
            })
            .collect(),
    }
}

/// A plate the grid can vary: its label in the recognition experiment, the names of its two
/// dimensions, their default grids, and how to set them.
struct Plate {
    label: f64,
    names: [&'static str; 2],
    grids: [&'static [f64]; 2],
    set: fn(&mut Samples, f64, f64),
}

const WAVE: Plate = Plate {
    label: 3.0,
    names: ["amplitude, mm", "period, mm"],
    grids: [&[0.4, 0.5, 0.6, 0.75, 1.0], &[5.0, 6.0, 6.75, 7.5]],
    set: |s, a, p| {
        s.wave_amplitude_mm = a;
        s.wave_period_mm = p;
    },
};

const BUMP: Plate = Plate {
    label: 2.0,
    names: ["radius, mm", "height, mm"],
    grids: [&[3.85, 6.0, 7.0, 8.0], &[1.0, 1.25, 1.5, 2.0, 2.45]],
    set: |s, r, h| {
        s.bump_radius_mm = r;
        s.bump_height_mm = h;
    },
};

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let plate = match args.next().as_deref() {
        Some("wave") => WAVE,
        Some("bump") => BUMP,
        other => return Err(format!("plate must be `wave` or `bump`, got {other:?}").into()),
    };
    let first = list(args.next(), plate.grids[0])?;
    let second = list(args.next(), plate.grids[1])?;
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE);
    let recognition = recordings_of_repetition(&dir.join("type"), 1)?;
    let width = recordings_of_repetition(&dir.join("width"), 1)?;
    let own: Vec<_> = recognition
        .iter()
        .filter(|r| r.label() == Some(plate.label))
        .cloned()
        .collect();
    if own.is_empty() {
        return Err(format!("no recording of label {} in repetition 1", plate.label).into());
    }
    let [a_name, b_name] = plate.names;
    println!(
        "| {a_name} | {b_name} | this plate: D1 / D2 / D3 / P | all plates: D1 / D2 / D3 / P |"
    );
    println!("|---|---|---|---|");
    for &a in &first {
        for &b in &second {
            let mut config = ExperimentConfig::paper(Experiment::Recognition, 7);
            (plate.set)(&mut config.samples, a, b);
            let w = fit_rms(&config, &own, None)?;
            let all = fit_rms(&config, &recognition, Some(&width))?;
            println!(
                "| {a} | {b} | {:.2} / {:.2} / {:.2} / {:.1} | {:.2} / {:.2} / {:.2} / {:.1} |",
                w[0], w[1], w[2], w[3], all[0], all[1], all[2], all[3]
            );
        }
    }
    Ok(())
}
