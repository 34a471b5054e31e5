//! The wavy plate's geometry against the authors' repetition 1: the quantile distance of the
//! wavy plate alone (and of every plate) for a grid of wave amplitudes and periods, everything
//! else as committed.
//!
//! `CRACKBOT_DATA_DIR=../shared/data cargo run --release -p crackbot-sim --example wave_fit -- [AMPS] [PERIODS]`
//! (comma-separated mm; defaults below).
use crackbot_sim::calibrate::fit_rms;
use crackbot_sim::experiment::{Experiment, ExperimentConfig};
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

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let amps = list(args.next(), &[0.4, 0.5, 0.6, 0.75, 1.0])?;
    let periods = list(args.next(), &[5.0, 6.0, 6.75, 7.5])?;
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE);
    let recognition = recordings_of_repetition(&dir.join("type"), 1)?;
    let width = recordings_of_repetition(&dir.join("width"), 1)?;
    let wavy: Vec<_> = recognition
        .iter()
        .filter(|r| r.label() == Some(3.0))
        .cloned()
        .collect();
    if wavy.is_empty() {
        return Err("no wavy recording (label 3) in repetition 1".into());
    }
    println!(
        "| amplitude, mm | period, mm | wavy: D1 / D2 / D3 / P | all plates: D1 / D2 / D3 / P |"
    );
    println!("|---|---|---|---|");
    for &a in &amps {
        for &p in &periods {
            let mut config = ExperimentConfig::paper(Experiment::Recognition, 7);
            config.samples.wave_amplitude_mm = a;
            config.samples.wave_period_mm = p;
            let w = fit_rms(&config, &wavy, None)?;
            let all = fit_rms(&config, &recognition, Some(&width))?;
            println!(
                "| {a} | {p} | {:.2} / {:.2} / {:.2} / {:.1} | {:.2} / {:.2} / {:.2} / {:.1} |",
                w[0], w[1], w[2], w[3], all[0], all[1], all[2], all[3]
            );
        }
    }
    Ok(())
}
