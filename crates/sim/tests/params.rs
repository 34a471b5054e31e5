//! Parameter files (`sim dataset --params`, `sim calibrate --start/--params-out`) and the
//! calibration's measured targets: the tip-speed quantiles and the proximity dark level.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use crackbot_recording::{Recording, Row};
use crackbot_sim::calibrate::{real_dark_counts, speed_quantiles, QUANTILES};
use crackbot_sim::experiment::{Experiment, ExperimentConfig, PlateMount};
use crackbot_sim::SimError;

fn width_mounts_toml(n: usize, reflectivity: f64) -> String {
    (0..n)
        .map(|k| {
            format!(
                "[[mounts.width]]\noffset_counts = [{k}.0, 1.5, -2.0]\nreflectivity = {reflectivity}\n"
            )
        })
        .collect()
}

/// The groove of plate `k` of `c`: `(width, depth)` in mm, `None` for a plate without a crack.
fn groove(c: &ExperimentConfig, k: usize) -> Option<(f64, f64)> {
    match c.surfaces()[k].2.features.first() {
        Some(crackbot_sim::surface::Feature::Crack {
            width_mm, depth_mm, ..
        }) => Some((*width_mm, *depth_mm)),
        _ => None,
    }
}

/// The error a width-experiment configuration with `[samples]` line `line` is refused with.
fn refused_samples(line: &str) -> SimError {
    let mut c = ExperimentConfig::paper(Experiment::Width, 7);
    c.apply_params_toml(&format!("[samples]\n{line}\n"))
        .and_then(|()| c.validate())
        .unwrap_err()
}

/// The field and allowed range of `err`, a [`SimError::Setting`] whose message names the field and
/// the value.
fn setting(err: &SimError) -> (&str, &str) {
    match err {
        SimError::Setting {
            field,
            value,
            allowed,
        } => {
            assert!(
                err.to_string().contains(&format!("{field} = {value}")),
                "{err}"
            );
            (field, allowed)
        }
        other => panic!("expected SimError::Setting, got {other:?}"),
    }
}

/// The table `err`, a [`SimError::ParameterTable`], names.
fn table(err: &SimError) -> &str {
    match err {
        SimError::ParameterTable { table, .. } => table,
        other => panic!("expected SimError::ParameterTable, got {other:?}"),
    }
}

#[test]
fn mounts_of_this_experiment_are_applied() {
    let mut width = ExperimentConfig::paper(Experiment::Width, 7);
    let n = width.surfaces().len();
    let text = format!(
        "[sensor.finger]\nfriction = 0.2\n\n[[mounts.recognition]]\noffset_counts = [9.0, 9.0, 9.0]\nreflectivity = 0.5\n\n{}",
        width_mounts_toml(n, 0.9)
    );
    width.apply_params_toml(&text).unwrap();
    assert_eq!(width.sensor.finger.friction, 0.2);
    assert_eq!(width.mounts.len(), n);
    assert_eq!(
        width.mounts[2],
        PlateMount {
            offset_counts: [2.0, 1.5, -2.0],
            reflectivity: 0.9
        }
    );
    // The recognition experiment takes the recognition table, not the width one (which has
    // another number of plates and would be refused).
    let mut recognition = ExperimentConfig::paper(Experiment::Recognition, 7);
    let before = recognition.mounts.clone();
    let only_width = width_mounts_toml(n, 0.9);
    recognition.apply_params_toml(&only_width).unwrap();
    assert_eq!(recognition.mounts, before);
}

#[test]
fn bad_mounts_are_named() {
    let mut c = ExperimentConfig::paper(Experiment::Width, 7);
    let n = c.surfaces().len();
    let err = c
        .apply_params_toml("[[mounts.tank]]\noffset_counts = [0.0, 0.0, 0.0]\nreflectivity = 1.0\n")
        .unwrap_err();
    assert_eq!(table(&err), "mounts.tank", "{err}");
    let err = c
        .apply_params_toml(&width_mounts_toml(n - 1, 1.0))
        .unwrap_err();
    assert_eq!(setting(&err).0, "mounts.width", "{err}");
    assert!(
        err.to_string().contains(&format!("{} plate mounts", n - 1)),
        "{err}"
    );
    let err = c
        .apply_params_toml("[[mounts.width]]\noffset_counts = [0.0, 0.0]\nreflectivity = 1.0\n")
        .unwrap_err();
    assert_eq!(table(&err), "mounts.width", "{err}");
    let err = c.apply_params_toml("mounts = 3\n").unwrap_err();
    assert_eq!(table(&err), "mounts", "{err}");
    assert!(err.to_string().contains("[mounts]"), "{err}");
    let err = c
        .apply_params_toml("[sensor.fingr]\nfriction = 0.1\n")
        .unwrap_err();
    assert_eq!(table(&err), "sensor.fingr", "{err}");
    let err = c.apply_params_toml("[mounts\n").unwrap_err();
    assert!(matches!(err, SimError::Parameters { .. }), "{err:?}");
}

#[test]
fn the_width_plates_have_their_own_crack_depth() {
    let depth_of = |c: &ExperimentConfig, k: usize| groove(c, k).map(|(_, depth)| depth);
    let mut width = ExperimentConfig::paper(Experiment::Width, 7);
    let mut recognition = ExperimentConfig::paper(Experiment::Recognition, 7);
    // The calibrated plates: 2.8 mm deep width cracks (the 1 mm plate's printed slot aside),
    // 2.53 mm deep surface-type crack.
    assert_eq!(depth_of(&width, 2), Some(2.8));
    assert_eq!(depth_of(&recognition, 1), Some(2.53));
    width
        .apply_params_toml("[samples]\nwidth_crack_depth_mm = 3.5\n")
        .unwrap();
    assert_eq!(depth_of(&width, 5), Some(3.5));
    recognition
        .apply_params_toml("[samples]\nwidth_crack_depth_mm = 3.5\ncrack_depth_mm = 2.0\n")
        .unwrap();
    assert_eq!(depth_of(&recognition, 1), Some(2.0));
    // Without its own depth, the width plates take the common one.
    let mut common = ExperimentConfig::paper(Experiment::Width, 7);
    common.samples.width_crack_depth_mm = None;
    common.samples.crack_depth_mm = 1.5;
    assert_eq!(depth_of(&common, 2), Some(1.5));
    for bad in ["-1.0", "0.0", "nan"] {
        let err = refused_samples(&format!("width_crack_depth_mm = {bad}"));
        assert_eq!(
            setting(&err).0,
            "samples.width_crack_depth_mm",
            "{bad}: {err}"
        );
    }
}

#[test]
fn printed_slots_cut_the_grooves_and_leave_the_labels() {
    // The calibrated plates: the 1 mm plate is cut 1.5 × 1.5 mm (docs/calibration.md), the
    // others as drawn, 2.8 mm deep.
    let mut c = ExperimentConfig::paper(Experiment::Width, 7);
    assert_eq!(c.surfaces()[1].1, 1.0);
    assert_eq!(groove(&c, 1), Some((1.5, 1.5)));
    assert_eq!(groove(&c, 2), Some((2.0, 2.8)));
    // A file's list replaces the calibrated one: the 1 mm plate goes back to its drawing,
    // width_crack_depth_mm still reaches the plates not listed.
    c.apply_params_toml(
        "[samples]\nwidth_crack_depth_mm = 3.0\n\
         [[samples.printed_slots]]\nnominal_mm = 10.0\nwidth_mm = 9.5\n\
         [[samples.printed_slots]]\nnominal_mm = 5.0\ndepth_mm = 2.0\n",
    )
    .unwrap();
    c.validate().unwrap();
    assert_eq!(groove(&c, 1), Some((1.0, 3.0)));
    assert_eq!(groove(&c, 5), Some((9.5, 3.0)));
    assert_eq!(groove(&c, 3), Some((5.0, 2.0)));
    // Labels and file names (so the recordings' names) stay nominal.
    assert_eq!(
        (c.surfaces()[5].0.as_str(), c.surfaces()[5].1),
        ("crack_mm10", 10.0)
    );
    let mut drawn = ExperimentConfig::paper(Experiment::Width, 7);
    drawn
        .apply_params_toml("[samples]\nprinted_slots = []\n")
        .unwrap();
    assert_eq!(groove(&drawn, 1), Some((1.0, 2.8)));
    // (slot, field, a word of the allowed range)
    for (bad, field, word) in [
        (
            "nominal_mm = 3.0\nwidth_mm = 1.0",
            "samples.printed_slots[0].nominal_mm",
            "one of samples.widths_mm",
        ),
        (
            "nominal_mm = 1.0\nwidth_mm = -1.0",
            "samples.printed_slots[0].width_mm",
            "≥ 0",
        ),
        (
            "nominal_mm = 1.0\nwidth_mm = nan",
            "samples.printed_slots[0].width_mm",
            "≥ 0",
        ),
        (
            "nominal_mm = 1.0\ndepth_mm = 0.0",
            "samples.printed_slots[0].depth_mm",
            "> 0",
        ),
        (
            "nominal_mm = 1.0\ndepth_mm = inf",
            "samples.printed_slots[0].depth_mm",
            "> 0",
        ),
        (
            "nominal_mm = 1.0\n[[samples.printed_slots]]\nnominal_mm = 1.0",
            "samples.printed_slots[1].nominal_mm",
            "listed twice",
        ),
    ] {
        let err = refused_samples(&format!("[[samples.printed_slots]]\n{bad}"));
        let (f, allowed) = setting(&err);
        assert_eq!(f, field, "{bad}: {err}");
        assert!(allowed.contains(word), "{bad}: {err}");
    }
    // A misspelt key is refused, not ignored.
    let mut c = ExperimentConfig::paper(Experiment::Width, 7);
    let err = c
        .apply_params_toml("[[samples.printed_slots]]\nnominal_mm = 1.0\nwidht_mm = 2.0\n")
        .unwrap_err();
    assert_eq!(table(&err), "samples", "{err}");
    assert!(err.to_string().contains("widht_mm"), "{err}");
}

#[test]
fn speed_quantiles_see_a_steady_tip_and_a_stuck_one() {
    // 4.6 mm/s at 400 Hz: every quantile is 4.6 mm/s.
    let steady: Vec<f64> = (0..4000).map(|i| 4.6 * i as f64 / 400.0).collect();
    let q = speed_quantiles(&steady).unwrap();
    assert_eq!(q.len(), QUANTILES.len());
    for v in &q {
        assert!((v - 4.6).abs() < 1e-9, "{q:?}");
    }
    // Stuck for the first half: the lower quantiles are 0, the upper ones the pace.
    let stuck: Vec<f64> = (0..4000)
        .map(|i| {
            if i < 2000 {
                0.0
            } else {
                4.6 * (i - 2000) as f64 / 400.0
            }
        })
        .collect();
    let q = speed_quantiles(&stuck).unwrap();
    assert!(q[0].abs() < 1e-9 && q[3].abs() < 1e-9, "{q:?}");
    assert!((q[QUANTILES.len() - 1] - 4.6).abs() < 1e-9, "{q:?}");
    // Too short to measure.
    assert!(speed_quantiles(&steady[..10]).is_none());
}

#[test]
fn dark_level_is_a_low_quantile_of_every_proximity_reading() {
    let rows = |p: &[f64]| -> Vec<Row> {
        p.iter()
            .enumerate()
            .map(|(i, &p)| Row {
                x_mm: i as f64,
                d1: 600.0,
                d2: 400.0,
                d3: 700.0,
                p,
                direction: 0,
                slide: 1,
                label: 5.0,
                repetition: 1,
            })
            .collect()
    };
    let bright: Vec<f64> = (0..1000).map(|i| 500.0 + (i % 7) as f64).collect();
    let mut dipped = bright.clone();
    dipped[100..150].iter_mut().for_each(|p| *p = 265.0);
    let a = Recording {
        rows: rows(&bright),
        extra: None,
    };
    let b = Recording {
        rows: rows(&dipped),
        extra: None,
    };
    let dark = real_dark_counts(&[&a, &b]).unwrap();
    assert_eq!(dark, 265.0);
    assert_eq!(real_dark_counts(&[&a]).unwrap(), 500.0);
    assert!(real_dark_counts(&[]).is_none());
}

#[test]
fn calibration_search_settings_name_what_is_wrong() {
    use crackbot_sim::calibrate::{SearchSettings, MECHANICS};
    let all_free = SearchSettings::default().free_mask().unwrap();
    assert!(all_free.iter().all(|f| *f));
    let some = SearchSettings {
        fixed: vec![MECHANICS[0].to_string(), MECHANICS[3].to_string()],
        ..SearchSettings::default()
    };
    let free = some.free_mask().unwrap();
    assert!(!free[0] && !free[3] && free[1] && free[2]);
    let typo = SearchSettings {
        fixed: vec!["finger.stiffness".into()],
        ..SearchSettings::default()
    };
    let err = typo.free_mask().unwrap_err();
    let (field, allowed) = setting(&err);
    assert_eq!(field, "fixed", "{err}");
    assert!(allowed.contains(MECHANICS[1]), "{err}");
    assert!(err.to_string().contains("finger.stiffness"), "{err}");
    let nan = SearchSettings {
        speed_weight: f64::NAN,
        ..SearchSettings::default()
    };
    assert_eq!(setting(&nan.free_mask().unwrap_err()).0, "speed_weight");
    let spot = SearchSettings {
        proximity: crackbot_sim::calibrate::ProximityRules {
            min_spot_mm: -1.0,
            ..Default::default()
        },
        ..SearchSettings::default()
    };
    assert_eq!(
        setting(&spot.free_mask().unwrap_err()).0,
        "proximity.min_spot_mm"
    );
}

#[test]
fn proximity_tails_join_only_the_proximity_targets() {
    use crackbot_sim::calibrate::{real_quantiles, real_quantiles_with, P_TAILS};
    let rows: Vec<Row> = (0..2000)
        .map(|i| Row {
            x_mm: i as f64 * 0.01,
            d1: 600.0 + (i % 5) as f64,
            d2: 400.0,
            d3: 700.0,
            // Dark for 1 % of the samples: the 5 % quantile cannot see it, the tails do.
            p: if i % 100 == 0 { 265.0 } else { 520.0 },
            direction: 0,
            slide: 1,
            label: 1.0,
            repetition: 1,
        })
        .collect();
    let rec = Recording { rows, extra: None };
    let plain = real_quantiles(std::slice::from_ref(&rec));
    let tails = real_quantiles_with(std::slice::from_ref(&rec), true);
    assert_eq!(plain.len(), tails.len());
    for (a, b) in plain.iter().zip(&tails) {
        if a.channel == 3 {
            assert_eq!(b.values.len(), QUANTILES.len() + P_TAILS.len());
            assert_eq!(b.values[..QUANTILES.len()], a.values[..]);
            // Direction 0 holds every row (direction 1 has none: zeros).
            if a.direction == 0 {
                assert_eq!(a.values[0], 520.0);
                assert_eq!(b.values[QUANTILES.len()], 265.0, "{:?}", b.values);
            }
        } else {
            assert_eq!(a.values, b.values);
        }
    }
}

/// The printed decoys: plates after the paper's four, labelled "no crack", on the flat plate's
/// mount. The finger feels them as the flat plate (the same deformation to a count) while the
/// proximity fibre reads the ink darker; bad values and the width experiment are refused by name.
#[test]
fn printed_decoys_are_flat_plates_with_a_dark_line_labelled_no_crack() {
    let mut c = ExperimentConfig::paper(Experiment::Recognition, 5);
    c.recordings = 1;
    c.slides = 2;
    assert_eq!(c.surfaces().len(), 4, "none in the calibrated samples");
    c.samples.printed_decoys = crackbot_sim::plates::paper_printed_decoys();
    c.validate().unwrap();
    let plates = c.surfaces();
    assert_eq!(plates.len(), 8);
    assert_eq!(plates[5].0, "crack_printed_w1_r0p5");
    assert!(plates[4..].iter().all(|p| p.1 == 0.0));
    assert_eq!(c.mount(6), c.mount(0));
    // The flat plate and the 2 mm line of ink 0.2, simulated on the same line with the same
    // seed: the deformation channels agree everywhere, the proximity dips over the ink.
    let flat = &plates[0];
    let decoy = plates
        .iter()
        .find(|p| p.0 == "crack_printed_w2_r0p2")
        .unwrap();
    let run = |p: &(String, f64, crackbot_sim::surface::Surface, f64)| {
        crackbot_sim::experiment::simulate_recording(
            &c,
            &p.2,
            c.mount(0),
            p.1,
            1,
            99.0,
            8.0,
            50.0,
            10.0,
            3,
        )
        .unwrap()
    };
    let (a, b) = (run(flat), run(decoy));
    assert_eq!(a.rows.len(), b.rows.len());
    let max_dd = a
        .rows
        .iter()
        .zip(&b.rows)
        .map(|(x, y)| {
            (x.d1 - y.d1)
                .abs()
                .max((x.d2 - y.d2).abs())
                .max((x.d3 - y.d3).abs())
        })
        .fold(0.0, f64::max);
    assert!(max_dd <= 1.0, "deformation differs by {max_dd} counts");
    let min_p = |r: &Recording| r.rows.iter().map(|x| x.p).fold(f64::INFINITY, f64::min);
    assert!(
        min_p(&b) < min_p(&a) - 60.0,
        "ink {} vs plate {}",
        min_p(&b),
        min_p(&a)
    );

    for (bad, field) in [
        (
            "width_mm = 0.0\nreflectivity = 0.3",
            "samples.printed_decoys[0].width_mm",
        ),
        (
            "width_mm = 1.0\nreflectivity = 1.5",
            "samples.printed_decoys[0].reflectivity",
        ),
        (
            "width_mm = nan\nreflectivity = 0.3",
            "samples.printed_decoys[0].width_mm",
        ),
    ] {
        let mut c = ExperimentConfig::paper(Experiment::Recognition, 5);
        let err = c
            .apply_params_toml(&format!("[[samples.printed_decoys]]\n{bad}\n"))
            .and_then(|()| c.validate())
            .unwrap_err();
        assert_eq!(setting(&err).0, field, "{bad}: {err}");
    }
    let err = refused_samples("printed_decoys = [{ width_mm = 1.0, reflectivity = 0.3 }]");
    let (field, allowed) = setting(&err);
    assert_eq!(field, "samples.printed_decoys", "{err}");
    assert!(allowed.contains("recognition experiment only"), "{err}");
}
