//! The calibrated simulator against the authors' recordings: the bump gives a short
//! proximity spike as the real finger's stick-slip over it does (not a broad rise), and the
//! fitted sensor reproduces the channel statistics of repetition 1 (the repetition it was fitted
//! on) within the calibration's tolerance.

use crackbot_recording::Recording;
use crackbot_sim::calibrate::{fit_rms, fit_speed_rms};
use crackbot_sim::experiment::{simulate_recording, Experiment, ExperimentConfig};
use crackbot_sim::recordings::recordings_of_repetition;
use crackbot_testkit::median;

/// Per stroke (slide and direction) of `rec`: the proximity's largest excursion above the
/// stroke's median and the samples spent above half of it.
fn p_spikes(rec: &Recording) -> Vec<(f64, usize)> {
    let mut out = Vec::new();
    let slides = rec.rows.iter().map(|r| r.slide).max().unwrap_or(0);
    for slide in 1..=slides {
        for direction in [0u8, 1] {
            let mut p: Vec<f64> = rec
                .rows
                .iter()
                .filter(|r| r.slide == slide && r.direction == direction)
                .map(|r| r.p)
                .collect();
            if p.len() < 200 {
                continue;
            }
            let max = p.iter().copied().fold(f64::MIN, f64::max);
            let above = |level: f64, p: &[f64]| p.iter().filter(|v| **v > level).count();
            let mut sorted = p.clone();
            sorted.sort_by(f64::total_cmp);
            let base = sorted[sorted.len() / 2];
            let excursion = max - base;
            out.push((excursion, above(base + excursion / 2.0, &p)));
            p.clear();
        }
    }
    out
}

#[test]
fn bump_gives_a_short_proximity_spike() {
    let config = ExperimentConfig::paper(Experiment::Recognition, 7);
    let surfaces = config.surfaces();
    let (_, label, surface, edge_x) = &surfaces[2];
    assert_eq!(*label, 2.0);
    let rec = simulate_recording(
        &config,
        surface,
        config.mount(2),
        *label,
        1,
        *edge_x,
        7.0,
        50.0,
        10.0,
        11,
    )
    .unwrap();
    let spikes = p_spikes(&rec);
    assert_eq!(spikes.len(), 24);
    let excursion = median(&spikes.iter().map(|s| s.0).collect::<Vec<_>>());
    let width = median(&spikes.iter().map(|s| s.1 as f64).collect::<Vec<_>>());
    // The authors' bump, repetitions 1-3: excursions of 195-260 counts (medians 210-222),
    // 83-260 samples above half of it per stroke (medians 142-174). The simulator: the
    // excursion matches; the spike is still about 3 times as wide (474 samples, seed 11), so
    // the bound on the width is loose (a regression guard, not yet the real shape).
    assert!(
        (150.0..=300.0).contains(&excursion),
        "median spike {excursion} counts"
    );
    assert!(
        (60.0..=520.0).contains(&width),
        "median spike width {width} samples"
    );
}

#[test]
fn fitted_sensor_reproduces_repetition_1() {
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE);
    let recognition = recordings_of_repetition(&dir.join("type"), 1).unwrap();
    let width = recordings_of_repetition(&dir.join("width"), 1).unwrap();
    let config = ExperimentConfig::paper(Experiment::Recognition, 7);
    let rms = fit_rms(&config, &recognition, Some(&width)).unwrap();
    // `crackbot sim calibrate` reached 4.35, 2.51, 5.22 and 43.30 counts (the starting sensor:
    // 6.37, 3.03, 7.22, 90.80; the simulator before the mechanics were fitted: 64, 27, 79,
    // 100). Vertical crack walls and the roughness then gave 4.52, 2.58, 5.21, 46.7, and the
    // wavy plate's amplitude chosen by transfer (1.25 mm, docs/calibration.md) 4.57, 2.58,
    // 5.25, 47.8, the width plates' depth chosen the same way (2.8 mm) 4.76, 2.77, 5.32,
    // 50.2, the broader bump chosen the same way (8 × 1.5 mm) 5.53, 3.15, 6.32, 54.1 (the 1 mm
    // plate's 1.5 × 1.5 mm slot, chosen the same way, then 5.52, 3.14, 6.31, 53.95): the
    // quantiles prefer the paper's 1 mm wave, 2.53 mm deep width cracks and the fitted
    // 3.85 × 2.45 mm cap (over the broad bump the finger bends about half as much as the real
    // one does), the transfer measures (the goals, chosen on repetition 1 too) do not.
    // So with the darker proximity floor chosen by transfer (dark 215 counts, the peak scaled
    // so that the flat plate stays put; docs/calibration.md, "A darker proximity floor,
    // adopted"): 5.52, 3.14, 6.31, 67.86.
    eprintln!("quantile distance to repetition 1, D1 / D2 / D3 / P: {rms:.2?}");
    let limits = [5.6, 3.2, 6.4, 69.0];
    for (c, (r, l)) in rms.iter().zip(limits).enumerate() {
        assert!(
            r <= &l,
            "channel {c}: quantile distance {r:.2} counts > {l}"
        );
    }
    // The tip's speed against the authors' position column: 3.94 mm/s RMS for this fit,
    // whose tip jams in the wide cracks (docs/calibration.md, "The finger jams"); fits with
    // the speed term reach 1.3. This bound only stops it getting worse.
    let speed = fit_speed_rms(&config, &recognition, Some(&width)).unwrap();
    assert!(
        speed <= 4.2,
        "tip-speed quantile distance {speed:.2} mm/s > 4.2"
    );
    assert!(speed > 0.0);
}
