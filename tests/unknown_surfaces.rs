//! How often the deployed pipeline calls a surface "unknown": on real known surfaces it was not
//! trained on, on real recordings with a dead or saturated channel, and on simulated surfaces
//! unlike any in training (screw heads, a 10 mm bump), with simulated known surfaces as control.
//!
//! Protocol: a model of the deployed configuration (32 trees, depth ≤ 10, as committed) is
//! trained as `crackbot tactile train` trains it, on repetitions 1 and 2 of the surface-type
//! recordings and of the width recordings read as surface types (0 mm "no crack", any other
//! width "crack"), and on the simulator's surface-type plates of seeds 8 and 9 (as
//! `--recognition-sim-seeds 8 9` adds them to the committed model); everything is tested on
//! repetition 3 of both (or on altered copies) and on simulated recordings of other seeds.
//!
//! `cargo test --release --test unknown_surfaces -- --nocapture` prints the table.

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_sim::experiment::{simulate_named, simulate_recording, ExperimentConfig};
use crackbot_sim::{Feature, Surface};
use crackbot_tactile::dataset::Experiment;
use crackbot_tactile::model::{TactileModel, TrainConfig};
use crackbot_tactile::online::classify_recording;

/// Slides, unknown, low confidence (and known), right class, slides with a class to judge.
#[derive(Debug, Default, Clone, Copy)]
struct Rates {
    n: usize,
    unknown: usize,
    low: usize,
    right: usize,
    judged: usize,
}

impl Rates {
    fn unknown_fraction(&self) -> f64 {
        self.unknown as f64 / self.n.max(1) as f64
    }

    /// Slides called unknown or known with low confidence: not a confident verdict.
    fn unsure_fraction(&self) -> f64 {
        (self.unknown + self.low) as f64 / self.n.max(1) as f64
    }

    fn right_fraction(&self) -> f64 {
        self.right as f64 / self.judged.max(1) as f64
    }
}

#[test]
#[expect(
    clippy::too_many_lines,
    reason = "one scenario test that reads top to bottom"
)]
fn unlike_surfaces_and_broken_channels_come_out_unknown() -> Result<(), Box<dyn std::error::Error>>
{
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE_TYPE);
    let all = collect_recordings(&[dir])?;
    let widths =
        collect_recordings(&[crackbot_datasets::require(crackbot_datasets::TACTILE_WIDTH)])?
            .into_iter()
            .map(|(p, r)| Ok((p, r.width_as_recognition()?)))
            .collect::<Result<Vec<_>, crackbot_recording::RecordingError>>()?;
    let rep = |set: &[(PathBuf, Recording)], r: u32| -> Vec<(PathBuf, Recording)> {
        set.iter()
            .filter(|(p, _)| p.to_string_lossy().ends_with(&format!("_{r}.mat")))
            .cloned()
            .collect()
    };
    let mut train: Vec<_> = [rep(&all, 1), rep(&all, 2), rep(&widths, 1), rep(&widths, 2)].concat();
    for seed in [8, 9] {
        let config = ExperimentConfig::paper(Experiment::Recognition, seed);
        train.extend(simulate_named(&config, |_, _| {})?);
    }
    let test = rep(&all, 3);
    let config = TrainConfig {
        n_trees: 32,
        max_depth: Some(10),
        seed: 1,
        ..TrainConfig::default()
    };
    let model = TactileModel::train(
        &train,
        Some(Experiment::Recognition),
        &config,
        &mut |_, _, _| {},
    )?;

    println!("| surface | slides | unknown | low confidence | right class (of the rest) |");
    println!("|---|---|---|---|---|");
    let report = |name: &str,
                  recs: &[(String, Recording, Option<u32>)]|
     -> Result<Rates, Box<dyn std::error::Error>> {
        let (mut n, mut unknown, mut low, mut right, mut judged) = (0, 0, 0, 0, 0);
        for (_, rec, truth) in recs {
            for v in classify_recording(&model, rec)?.into_iter().flatten() {
                n += 1;
                if v.is_unknown() {
                    unknown += 1;
                    continue;
                }
                if v.doubt.is_some() {
                    low += 1;
                }
                if let Some(t) = truth {
                    judged += 1;
                    right += usize::from(v.class == *t);
                }
            }
        }
        let pct = |a: usize, b: usize| {
            if b == 0 {
                "–".to_string()
            } else {
                format!("{:.1} %", 100.0 * a as f64 / b as f64)
            }
        };
        println!(
            "| {name} | {n} | {} | {} | {} |",
            pct(unknown, n),
            pct(low, n),
            if judged == 0 {
                "–".to_string()
            } else {
                format!("{right}/{judged}")
            }
        );
        Ok(Rates {
            n,
            unknown,
            low,
            right,
            judged,
        })
    };

    // Recordings with their own labels as the truth.
    let labelled = |set: Vec<(PathBuf, Recording)>| -> Vec<(String, Recording, Option<u32>)> {
        set.into_iter()
            .map(|(p, r)| {
                let truth = r.label().map(|l| l as u32);
                (p.display().to_string(), r, truth)
            })
            .collect()
    };
    let known = labelled(test);
    let real = report("real, repetition 3 (known surfaces)", &known)?;
    let plates = report(
        "real, width plates of repetition 3 (0–10 mm, as no crack / crack)",
        &labelled(rep(&widths, 3)),
    )?;
    let altered =
        |f: &dyn Fn(&mut crackbot_recording::Row)| -> Vec<(String, Recording, Option<u32>)> {
            known
                .iter()
                .map(|(n, r, _)| {
                    let mut r = r.clone();
                    r.rows.iter_mut().for_each(f);
                    (n.clone(), r, None)
                })
                .collect()
        };
    let broken = [
        report("real, D2 dead (constant 450)", &altered(&|r| r.d2 = 450.0))?,
        report("real, P dead (constant 0)", &altered(&|r| r.p = 0.0))?,
        report("real, P saturated (1023)", &altered(&|r| r.p = 1023.0))?,
        report("real, D1 saturated (1023)", &altered(&|r| r.d1 = 1023.0))?,
    ];
    let clipped = report(
        "real, P clipped at 500 (saturating on the flat)",
        &altered(&|r| r.p = r.p.min(500.0)),
    )?;

    // Simulated plates: the controls (the paper's four surfaces) and the unknown ones.
    let sim = ExperimentConfig::paper(Experiment::Recognition, 7);
    let simulate = |surface: &Surface, edge: f64, seed: u64| {
        simulate_recording(
            &sim,
            surface,
            sim.mount(0),
            0.0,
            1,
            edge,
            4.0,
            50.0,
            10.0,
            seed,
        )
    };
    let mut controls = Vec::new();
    for (k, (stem, label, surface, edge)) in sim.surfaces().into_iter().enumerate() {
        let mut r = simulate_recording(
            &sim,
            &surface,
            sim.mount(k),
            label,
            1,
            edge,
            4.0,
            50.0,
            10.0,
            11 + k as u64,
        )?;
        r.rows.iter_mut().for_each(|row| row.label = label);
        controls.push((stem, r, Some(label as u32)));
    }
    let control = report("simulated known surfaces (control)", &controls)?;
    let plate = |features: Vec<Feature>| Surface {
        size_mm: [200.0, 100.0],
        features,
    };
    let screw = plate(vec![Feature::Screw {
        centre: [100.0, 50.0],
        head_diameter_mm: 7.0,
        height_mm: 3.0,
    }]);
    let bump10 = plate(vec![Feature::Bump {
        centre: [100.0, 50.0],
        radius_mm: 8.0,
        height_mm: 10.0,
    }]);
    let screw = report(
        "simulated screw head (7 mm, 3 mm high)",
        &[("screw".into(), simulate(&screw, 96.5, 21)?, None)],
    )?;
    let bump = report(
        "simulated 10 mm bump",
        &[("bump10".into(), simulate(&bump10, 92.0, 22)?, None)],
    )?;
    println!("{real:?} {plates:?} {clipped:?} {control:?} {screw:?} {bump:?}");
    for known in [real, plates, control] {
        assert!(
            known.unknown_fraction() <= 0.10 && known.right_fraction() >= 0.9,
            "known surfaces called unknown or misread: {known:?}"
        );
    }
    // Surfaces unlike any in training: never a confident verdict.
    for novel in [screw, bump] {
        assert!(
            novel.unsure_fraction() >= 0.9,
            "an unlike surface got confident verdicts: {novel:?}"
        );
    }
    for b in broken {
        assert!(
            b.unknown_fraction() >= 0.95,
            "a broken channel passed: {b:?}"
        );
    }
    Ok(())
}
