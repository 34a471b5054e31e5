//! A finger that is not the authors' commissioned end to end on the simulated rig with
//! `crackbot commission run` (issue 81):
//!
//! * the simulated finger is perturbed by amounts the test draws (seeded): the deformation
//!   channels' resting levels and gains, the proximity channel's dark level and gain, its curve's
//!   peak and the fibre's height, where the fibre looks (its mount);
//! * the commissioning reads its optics: the proximity channel's dark level, its gain (the signal
//!   above dark in contact) within 5 %, the curve's half-intensity height within 0.2 mm;
//! * the shipped models read that finger's slides worse than its own models read their
//!   held-out repetitions, which meet the profile's thresholds;
//! * the profile is installed and `crackbot run --finger` takes its models and fibre;
//! * bad settings are refused naming what is wrong.

use std::path::Path;

use crackbot_fibre::fit::half_height_of;
use crackbot_fibre::{intensity, ProximityFibre};
use crackbot_sim::Scene;
use crackbot_tests::{crackbot, text};
use rand08::{Rng, SeedableRng};

fn utf8(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The built-in scene's finger perturbed (seeded): the scene, and its true fibre and proximity
/// gain.
fn perturbed(seed: u64) -> (Scene, ProximityFibre, f64) {
    let mut rng = rand08::rngs::SmallRng::seed_from_u64(seed);
    let mut scene = Scene::builtin_default();
    let o = &mut scene.sensor.optics;
    for c in 0..3 {
        o.rest_counts[c] += rng.gen_range(-25.0..25.0);
        let k: f64 = rng.gen_range(0.8..1.25);
        o.lateral_gain[c] *= k;
        o.normal_gain[c] *= k;
        o.moment_gain[c] *= k;
    }
    o.proximity_peak_counts *= rng.gen_range(0.8..1.2);
    o.proximity_dark_counts += rng.gen_range(-20.0..20.0);
    o.proximity_peak_mm *= rng.gen_range(0.85..1.15);
    o.proximity_height_mm += rng.gen_range(-0.15..0.15);
    o.proximity_offset_mm += rng.gen_range(-0.3..0.3);
    let (fibre, gain) = (o.fibre(), o.proximity_peak_counts);
    (scene, fibre, gain)
}

#[test]
fn a_perturbed_finger_is_commissioned_and_missions_use_its_profile() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (scene, truth, gain) = perturbed(81);
    let bench = dir.path().join("bench.toml");
    std::fs::write(&bench, toml::to_string(&scene).expect("the scene as TOML")).expect("bench");
    let (session, fingers) = (dir.path().join("session"), dir.path().join("fingers"));
    let args = [
        "commission",
        "run",
        "--name",
        "perturbed",
        "--scene",
        utf8(&bench),
        "--speedup",
        "16",
        "--session",
        utf8(&session),
        "--fingers",
        utf8(&fingers),
        "--json",
    ];
    let o = crackbot(&args);
    assert!(o.status.success(), "commission: {}", text(&o.stderr));
    let card: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the card as JSON");
    let f = |v: &serde_json::Value| v.as_f64().expect("a number");

    // The optics against the simulated finger's.
    let optics = &card["optics"];
    let dark = f(&optics["fibre"]["dark_counts"]);
    let contact = f(&optics["contact_counts"][3]) - dark;
    let want_contact = gain * intensity(truth.height_mm, truth.peak_mm);
    let half = f(&optics["half_height_mm"]);
    eprintln!(
        "dark {dark:.1} (truth {:.1}), contact {contact:.1} above dark (truth {want_contact:.1}), \
         half-intensity {half:.3} mm (truth {:.3})",
        truth.dark_counts,
        half_height_of(&truth)
    );
    assert!((dark - truth.dark_counts).abs() < 3.0);
    assert!((contact / want_contact - 1.0).abs() < 0.05);
    assert!((half - half_height_of(&truth)).abs() < 0.2);

    // The models: this finger's against the shipped ones on its slides.
    let e = &card["evaluation"];
    let acc = |m: &str, k: &str| f(&e[m][k]);
    eprintln!(
        "recognition windows / slides: new {:.3} / {:.3}, shipped {:.3} / {:.3}; width slide MAE: new {:.2} mm, shipped {:.2} mm",
        acc("recognition", "window_accuracy"),
        acc("recognition", "slide_accuracy"),
        acc("shipped_recognition", "window_accuracy"),
        acc("shipped_recognition", "slide_accuracy"),
        acc("width", "slide_width_mae_mm"),
        acc("shipped_width", "slide_width_mae_mm"),
    );
    assert!(acc("shipped_recognition", "window_accuracy") < acc("recognition", "window_accuracy"));
    assert!(acc("shipped_recognition", "slide_accuracy") < acc("recognition", "slide_accuracy"));
    assert!(acc("shipped_width", "slide_width_mae_mm") > acc("width", "slide_width_mae_mm"));
    let robot = f(&card["robot_time_s"][0]) + f(&card["robot_time_s"][1]);
    eprintln!(
        "robot time {robot:.0} s: approach {:.0} s, slides {:.0} s",
        f(&card["robot_time_s"][0]),
        f(&card["robot_time_s"][1])
    );
    assert!(robot < 15.0 * 60.0, "robot time {robot} s");

    // The profile, used by a mission.
    let profile = fingers.join("perturbed");
    for file in ["card.toml", "recognition.ctm", "width.ctm"] {
        assert!(profile.join(file).is_file(), "{file}");
    }
    let o = crackbot(&[
        "run",
        "--finger",
        utf8(&profile),
        "--scene",
        utf8(&bench),
        "--print-config",
    ]);
    assert!(o.status.success(), "run --finger: {}", text(&o.stderr));
    let config = text(&o.stdout);
    assert!(
        config.contains(utf8(&profile.join("recognition.ctm"))),
        "{config}"
    );
    let in_config: f64 = config
        .lines()
        .find_map(|l| l.trim().strip_prefix("dark_counts = "))
        .and_then(|v| v.trim().parse().ok())
        .expect("the fibre's dark_counts in the configuration");
    assert_eq!(in_config, dark, "{config}");
}

#[test]
fn bad_commissioning_settings_are_refused_naming_what_is_wrong() {
    let dir = tempfile::tempdir().expect("tempdir");
    let refused = |extra: &[&str]| {
        let session = dir.path().join("s");
        let mut args = vec![
            "commission",
            "run",
            "--name",
            "x",
            "--session",
            utf8(&session),
            "--fingers",
            utf8(dir.path()),
        ];
        args.extend(extra);
        let o = crackbot(&args);
        assert!(!o.status.success(), "{extra:?} accepted");
        text(&o.stderr)
    };
    let e = refused(&["--plates", "flat,crack-5mm,bump"]);
    assert!(e.contains("\"wavy\"") && e.contains("mount wavy"), "{e}");
    assert!(refused(&["--plates", "flat,crack-3mm"])
        .contains("no reference plate is called \"crack-3mm\""));
    assert!(refused(&["--repetitions", "1"]).contains("at least 2"));
    assert!(refused(&["--slides", "3"]).contains("at least 4"));
    let o = crackbot(&[
        "run",
        "--finger",
        utf8(&dir.path().join("none")),
        "--print-config",
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("no such profile folder"),
        "{}",
        text(&o.stderr)
    );
}
