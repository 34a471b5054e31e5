//! The localiser ([`crackbot_tactile::localise`]): synthetic dips with known edges, consistency on a real
//! recording, error on simulated slides against the truth, and refused inputs. Tolerances are the figures measured
//! by crackbot-research's `examples/localisation.rs` (module docs) with a margin.

use crackbot_recording::read_recording;
use crackbot_sim::experiment::{simulate_recording, Experiment, ExperimentConfig};
use crackbot_tactile::localise::{
    localise, localise_pass, localise_passes, split_passes, LocaliseConfig, Travel,
};
use crackbot_tactile::TactileError;

/// P of a slide whose fibre sees a crack between `a` and `b` mm: 520 counts, 270 inside, linear ramps of 1 mm
/// centred on the edges (half depth exactly at `a` and `b`), plus a small deterministic ripple.
fn synthetic(positions: &[f64], a: f64, b: f64) -> Vec<[f64; 4]> {
    positions
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let ramp = |d: f64| (d + 0.5).clamp(0.0, 1.0);
            let inside = ramp(x - a).min(ramp(b - x));
            let ripple = 3.0 * ((i as f64) * 0.7).sin();
            [658.0, 435.0, 711.0, 520.0 - 250.0 * inside + ripple]
        })
        .collect()
}

fn ramp_positions(from: f64, to: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| from + (to - from) * i as f64 / (n - 1) as f64)
        .collect()
}

#[test]
fn synthetic_dip_edges_both_directions() {
    let raw = LocaliseConfig::uncorrected();
    for (from, to) in [(5.0, 21.0), (21.0, 5.0)] {
        let pos = ramp_positions(from, to, 1400);
        let e = localise_pass(&synthetic(&pos, 12.0, 16.0), &pos, &raw)
            .expect("valid")
            .expect("a dip");
        assert!((e.dip_start_mm - 12.0).abs() < 0.05, "{e:?}");
        assert!((e.dip_end_mm - 16.0).abs() < 0.05, "{e:?}");
        assert!((e.centre_mm - 14.0).abs() < 0.05, "{e:?}");
        assert!((e.width_mm - 4.0).abs() < 0.1, "{e:?}");
        assert!(e.start_mm <= e.end_mm);
        assert!(!e.truncated);
        assert!(e.confidence > 0.5 && e.confidence <= 1.0, "{e:?}");
        let want = if to > from {
            Travel::Increasing
        } else {
            Travel::Decreasing
        };
        assert_eq!(e.travel, want);
    }
}

#[test]
fn corrections_shift_by_direction_and_cancel_over_a_slide() {
    let config = LocaliseConfig::default();
    let fwd = ramp_positions(5.0, 21.0, 1400);
    let back = ramp_positions(21.0, 5.0, 1400);
    let f = localise_pass(&synthetic(&fwd, 12.0, 16.0), &fwd, &config)
        .expect("valid")
        .expect("dip");
    let b = localise_pass(&synthetic(&back, 12.0, 16.0), &back, &config)
        .expect("valid")
        .expect("dip");
    let lag = config.direction_lag_mm;
    assert!((f.centre_mm - (14.0 + config.look_ahead_mm - lag)).abs() < 0.05);
    assert!((b.centre_mm - (14.0 + config.look_ahead_mm + lag)).abs() < 0.05);
    // Width through the calibration: (4 − offset) / scale.
    let w = (4.0 - config.width_offset_mm) / config.width_scale;
    assert!((f.width_mm - w).abs() < 0.1, "{f:?}");
    // There and back in one slide: two passes, fused, the lag cancels.
    let mut pos = fwd.clone();
    pos.extend(&back[1..]);
    let samples = synthetic(&pos, 12.0, 16.0);
    let passes = localise_passes(&samples, &pos, &config).expect("valid");
    assert_eq!(passes.len(), 2);
    let fused = localise(&samples, &pos, &config)
        .expect("valid")
        .expect("dip");
    assert_eq!(fused.travel, Travel::Both);
    assert_eq!(fused.passes, 2);
    assert!((fused.centre_mm - (14.0 + config.look_ahead_mm)).abs() < 0.05);
}

#[test]
fn flat_slide_and_dip_at_the_end() {
    let pos = ramp_positions(5.0, 21.0, 1400);
    let flat: Vec<[f64; 4]> = pos
        .iter()
        .enumerate()
        .map(|(i, _)| [658.0, 435.0, 711.0, 520.0 + 8.0 * ((i as f64) * 0.05).sin()])
        .collect();
    assert_eq!(
        localise_pass(&flat, &pos, &LocaliseConfig::default()).expect("valid"),
        None
    );
    // A dip running off the end of the pass: cut there, flagged, less confident.
    let e = localise_pass(
        &synthetic(&pos, 19.0, 30.0),
        &pos,
        &LocaliseConfig::uncorrected(),
    )
    .expect("valid")
    .expect("dip");
    assert!(e.truncated);
    assert!((e.dip_end_mm - 21.0).abs() < 1e-9);
    assert!(e.confidence <= 0.5);
}

#[test]
fn splits_a_triangle_into_passes() {
    let mut pos = ramp_positions(0.0, 16.0, 100);
    pos.extend(&ramp_positions(16.0, 0.0, 100)[1..]);
    pos.extend(&ramp_positions(0.0, 16.0, 100)[1..]);
    let passes = split_passes(&pos, 0.5).expect("valid");
    assert_eq!(passes, vec![0..100, 100..199, 199..298]);
    assert_eq!(split_passes(&[], 0.5).expect("valid"), vec![]);
    assert!(split_passes(&[0.0, f64::NAN], 0.5).is_err());
}

#[test]
fn bad_inputs_are_errors() {
    let config = LocaliseConfig::default();
    let pos = ramp_positions(5.0, 21.0, 100);
    let samples = synthetic(&pos, 12.0, 16.0);
    let is_loc = |r: Result<_, TactileError>| matches!(r, Err(TactileError::Localisation { .. }));
    assert!(is_loc(localise_pass(&[], &[], &config)));
    assert!(is_loc(localise_pass(&samples, &pos[..99], &config)));
    let mut nan = samples.clone();
    nan[7][3] = f64::NAN;
    assert!(is_loc(localise_pass(&nan, &pos, &config)));
    let mut inf = pos.clone();
    inf[3] = f64::INFINITY;
    assert!(is_loc(localise_pass(&samples, &inf, &config)));
    // No travel.
    assert!(is_loc(localise_pass(&samples, &vec![3.0; 100], &config)));
    assert!(is_loc(localise(&samples, &vec![3.0; 100], &config)));
    for bad in [
        LocaliseConfig {
            smooth_samples: 0,
            ..config
        },
        LocaliseConfig {
            level_fraction: 1.0,
            ..config
        },
        LocaliseConfig {
            width_scale: 0.0,
            ..config
        },
        LocaliseConfig {
            look_ahead_mm: f64::NAN,
            ..config
        },
        LocaliseConfig {
            min_depth_counts: -1.0,
            ..config
        },
    ] {
        assert!(is_loc(localise_pass(&samples, &pos, &bad)), "{bad:?}");
    }
}

/// Repetition 2 of the recognition experiment's crack plate: every one of the 12 slides finds the crack, the
/// fused centres (both directions) agree within 0.2 mm (measured: std 0.033 mm, max deviation 0.07 mm), each pass
/// within 0.35 mm of the mean (measured: 0.14 mm); the 2 mm width plate's width within 0.3 mm (measured MAE 0.16).
#[test]
fn real_recording_slides_agree() {
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE);
    let config = LocaliseConfig::default();
    let rec = read_recording(&dir.join("type/crack_crack_complete_2.mat")).expect("readable");
    let mut centres = Vec::new();
    let mut pass_centres = Vec::new();
    for range in rec.slides().into_iter().filter(|r| r.len() > 1000) {
        let rows = &rec.rows[range];
        let samples: Vec<[f64; 4]> = rows.iter().map(crackbot_recording::Row::channels).collect();
        let positions: Vec<f64> = rows.iter().map(|r| r.x_mm).collect();
        let e = localise(&samples, &positions, &config)
            .expect("valid")
            .expect("the crack");
        assert_eq!(e.passes, 2);
        centres.push(e.centre_mm);
        for p in localise_passes(&samples, &positions, &config).expect("valid") {
            pass_centres.push(p.extent.expect("the crack").centre_mm);
        }
    }
    assert_eq!(centres.len(), 12);
    let mean = centres.iter().sum::<f64>() / 12.0;
    for c in &centres {
        assert!((c - mean).abs() < 0.2, "{centres:?}");
    }
    for c in &pass_centres {
        assert!((c - mean).abs() < 0.35, "{pass_centres:?}");
    }

    let rec = read_recording(&dir.join("width/crack_mm2_complete_2.mat")).expect("readable");
    let mut errs = Vec::new();
    for range in rec.slides().into_iter().filter(|r| r.len() > 1000) {
        let rows = &rec.rows[range];
        let samples: Vec<[f64; 4]> = rows.iter().map(crackbot_recording::Row::channels).collect();
        let positions: Vec<f64> = rows.iter().map(|r| r.x_mm).collect();
        for p in localise_passes(&samples, &positions, &config).expect("valid") {
            errs.push((p.extent.expect("the crack").width_mm - 2.0).abs());
        }
    }
    let mae = errs.iter().sum::<f64>() / errs.len() as f64;
    assert!(mae < 0.3, "width MAE {mae}");
}

/// Simulated slides over the 2 mm and 5 mm plates (seed 2, as the example's test set): every pass finds the
/// crack and the centre's MAE against the truth stays within 1.5 mm with the default (real-data) settings
/// (measured: 1.00 and 1.18 mm, the simulated dip sits ahead of the real one: module docs).
#[test]
fn simulated_slides_within_measured_error() {
    let mut config = ExperimentConfig::paper(Experiment::Width, 2);
    config.slides = 2;
    let mut errs = Vec::new();
    let mut total = 0;
    for (k, (_, width, surface, edge_x)) in config.surfaces().into_iter().enumerate() {
        if !(width == 2.0 || width == 5.0) {
            continue;
        }
        let (start, offset) = (7.0, 10.0);
        let rec = simulate_recording(
            &config,
            &surface,
            config.mount(k),
            width,
            1,
            edge_x,
            start,
            50.0,
            offset,
            17 + k as u64,
        )
        .expect("simulated");
        let truth = offset + start + width / 2.0;
        for range in rec.slides() {
            let rows = &rec.rows[range];
            let samples: Vec<[f64; 4]> =
                rows.iter().map(crackbot_recording::Row::channels).collect();
            let positions: Vec<f64> = rows.iter().map(|r| r.x_mm).collect();
            for p in
                localise_passes(&samples, &positions, &LocaliseConfig::default()).expect("valid")
            {
                total += 1;
                if let Some(e) = p.extent {
                    errs.push((e.centre_mm - truth).abs());
                }
            }
        }
    }
    assert!(total >= 6, "{total} passes");
    assert_eq!(errs.len(), total, "every simulated pass shows the crack");
    let mae = errs.iter().sum::<f64>() / errs.len() as f64;
    assert!(mae < 1.5, "centre MAE {mae} mm");
}

#[test]
fn the_moving_average_is_centred_and_shortened_at_the_ends() {
    use crackbot_tactile::localise::centred_moving_average;
    let v = [0.0, 3.0, 6.0, 9.0, 12.0];
    // Three samples: each value's neighbours, fewer at the ends.
    assert_eq!(centred_moving_average(v, 3), vec![1.5, 3.0, 6.0, 9.0, 10.5]);
    // One sample (or none asked for): the values themselves.
    assert_eq!(centred_moving_average(v, 1), v.to_vec());
    assert_eq!(centred_moving_average(v, 0), v.to_vec());
    assert!(centred_moving_average(std::iter::empty(), 9).is_empty());
}
