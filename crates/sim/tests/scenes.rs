//! Scene files: every file in `crates/sim/scenes/` loads and validates, the default file is the
//! built-in scene, each validation rule is hit by a small snippet whose error names the field,
//! and scenes survive a TOML round trip.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};

use crackbot_sim::{Feature, Scene, SimError};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

fn scene_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_scene_file_loads_and_validates() {
    let files = scene_files();
    let names: Vec<String> = files
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for expected in ["default.toml", "paper_recognition.toml", "no_camera.toml"] {
        assert!(names.iter().any(|n| n == expected), "{names:?}");
    }
    for path in &files {
        let scene = Scene::load(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        scene.validate().unwrap();
        assert!(!scene.name.is_empty(), "{} has no name", path.display());
    }
}

#[test]
fn the_default_file_is_the_builtin_scene() {
    let from_file = Scene::load(&scenes_dir().join("default.toml")).unwrap();
    assert_eq!(from_file, Scene::builtin_default());
    let scene = Scene::builtin_default();
    assert_eq!(scene.plate.size_mm, [200.0, 100.0]);
    let widths: Vec<f64> = scene
        .features
        .iter()
        .filter_map(|f| match f {
            Feature::Crack { width_mm, .. } => Some(*width_mm),
            _ => None,
        })
        .collect();
    assert_eq!(widths, vec![1.0, 2.0, 5.0, 10.0]);
    let kinds: Vec<&str> = scene.features.iter().map(Feature::kind).collect();
    for k in ["bump", "wavy", "decoy", "screw"] {
        assert!(kinds.contains(&k), "{kinds:?}");
    }
    assert_eq!(kinds.iter().filter(|k| **k == "screw").count(), 2);
    // The whole plate is in view.
    let cam = crackbot_sim::camera::Camera::from_spec(scene.camera.as_ref().unwrap()).unwrap();
    for p in [[0.0, 0.0], [200.0, 0.0], [0.0, 100.0], [200.0, 100.0]] {
        assert!(cam.in_image(cam.project([p[0], p[1], 0.0]).unwrap()));
    }
    // Scenes without a camera.
    for name in ["paper_recognition.toml", "no_camera.toml"] {
        assert!(Scene::load(&scenes_dir().join(name))
            .unwrap()
            .camera
            .is_none());
    }
}

#[test]
fn scenes_survive_a_toml_round_trip() {
    for path in scene_files() {
        let scene = Scene::load(&path).unwrap();
        let text = toml::to_string(&scene).unwrap();
        let back = Scene::from_toml_str(&text, "round trip").unwrap();
        assert_eq!(back, scene, "{}:\n{text}", path.display());
    }
}

const PLATE: &str = r#"
name = "snippet"
[plate]
size_mm = [200.0, 100.0]
"#;

const CAMERA: &str = r#"
[camera]
resolution = [640, 480]
focal_px = [700.0, 700.0]
position_mm = [100.0, 50.0, 250.0]
look_at_mm = [100.0, 50.0]
"#;

fn crack(path: &str, width: &str, depth: &str) -> String {
    format!(
        "[[features]]\nkind = \"crack\"\npath = {path}\nwidth_mm = {width}\ndepth_mm = {depth}\n"
    )
}

/// Parses `text` and expects an error whose message contains every one of `needles`.
fn expect_error(text: &str, needles: &[&str]) -> SimError {
    let err = match Scene::from_toml_str(text, "snippet.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    };
    let msg = err.to_string();
    for n in needles {
        assert!(msg.contains(n), "{msg:?} lacks {n:?}\n--- snippet:\n{text}");
    }
    assert!(msg.contains("snippet.toml"), "{msg}");
    err
}

#[test]
fn the_snippets_are_valid_without_the_fault() {
    let text = format!(
        "{PLATE}{}{CAMERA}",
        crack("[[10.0, 10.0], [50.0, 20.0]]", "1.0", "1.0")
    );
    Scene::from_toml_str(&text, "ok").unwrap();
}

#[test]
fn unknown_keys_and_kinds_are_parse_errors() {
    let err = expect_error(&format!("{PLATE}colour_typo = 3\n"), &["colour_typo"]);
    assert!(matches!(err, SimError::Parse { .. }), "{err:?}");
    let err = expect_error(
        &format!("{PLATE}[[features]]\nkind = \"hole\"\ncentre = [1.0, 1.0]\n"),
        &["hole"],
    );
    assert!(matches!(err, SimError::Parse { .. }), "{err:?}");
    let text = format!(
        "{PLATE}{}",
        crack("[[10.0, 10.0], [50.0, 20.0]]", "1.0", "1.0")
    ) + "depth = 3.0\n";
    expect_error(&text, &["depth"]);
}

#[test]
fn bad_features_are_named_by_index_and_kind() {
    let good = crack("[[10.0, 10.0], [50.0, 20.0]]", "1.0", "1.0");
    let cases: Vec<(String, Vec<&str>)> = vec![
        (
            crack("[[190.0, 50.0], [210.0, 50.0]]", "1.0", "1.0"),
            vec!["features[1] (crack)", "outside the plate"],
        ),
        (
            crack("[[10.0, 10.0], [50.0, 20.0]]", "-1.0", "1.0"),
            vec!["features[1] (crack): width_mm must be ≥ 0, got -1"],
        ),
        (
            crack("[[10.0, 10.0], [50.0, 20.0]]", "nan", "1.0"),
            vec!["features[1] (crack)", "width_mm", "NaN"],
        ),
        (
            crack("[[10.0, 10.0], [nan, 20.0]]", "1.0", "1.0"),
            vec!["features[1] (crack)", "path[1]", "finite"],
        ),
        (
            crack("[[10.0, 10.0], [50.0, 20.0]]", "1.0", "0.0"),
            vec!["features[1] (crack)", "depth_mm must be > 0"],
        ),
        (
            crack("[[10.0, 10.0], [10.0, 10.0]]", "1.0", "1.0"),
            vec!["features[1] (crack)", "zero length"],
        ),
        (
            crack("[[10.0, 10.0]]", "1.0", "1.0"),
            vec!["features[1] (crack)", "at least 2 points"],
        ),
        (
            "[[features]]\nkind = \"crack\"\npath = [[10.0, 10.0], [50.0, 20.0]]\nwidth_mm = 1.0\ndepth_mm = 1.0\nedge_radius_mm = -0.1\n".into(),
            vec!["features[1] (crack)", "edge_radius_mm"],
        ),
        (
            "[[features]]\nkind = \"bump\"\ncentre = [50.0, 50.0]\nradius_mm = -5.0\nheight_mm = 2.0\n".into(),
            vec!["features[1] (bump)", "radius_mm must be > 0"],
        ),
        (
            "[[features]]\nkind = \"bump\"\ncentre = [50.0, 50.0]\nradius_mm = 5.0\nheight_mm = 0.0\n".into(),
            vec!["features[1] (bump)", "height_mm must be > 0"],
        ),
        (
            "[[features]]\nkind = \"bump\"\ncentre = [198.0, 50.0]\nradius_mm = 5.0\nheight_mm = 1.0\n".into(),
            vec!["features[1] (bump)", "outside the plate"],
        ),
        (
            "[[features]]\nkind = \"wavy\"\nmin = [60.0, 10.0]\nmax = [50.0, 40.0]\n".into(),
            vec!["features[1] (wavy)", "min must be below max"],
        ),
        (
            "[[features]]\nkind = \"wavy\"\nmin = [10.0, 10.0]\nmax = [50.0, 40.0]\nperiod_mm = 0.0\n".into(),
            vec!["features[1] (wavy)", "period_mm must be > 0"],
        ),
        (
            "[[features]]\nkind = \"wavy\"\nmin = [10.0, 10.0]\nmax = [50.0, 40.0]\namplitude_mm = -1.0\n".into(),
            vec!["features[1] (wavy)", "amplitude_mm must be ≥ 0"],
        ),
        (
            "[[features]]\nkind = \"decoy\"\npath = [[10.0, 50.0], [60.0, 50.0]]\nwidth_mm = 2.0\nreflectivity = 1.5\n".into(),
            vec!["features[1] (decoy)", "reflectivity must be in [0, 1]"],
        ),
        (
            "[[features]]\nkind = \"decoy\"\npath = [[10.0, 50.0]]\nwidth_mm = 2.0\n".into(),
            vec!["features[1] (decoy)", "at least 2 points"],
        ),
        (
            "[[features]]\nkind = \"screw\"\ncentre = [50.0, 50.0]\nhead_diameter_mm = 0.0\n".into(),
            vec!["features[1] (screw)", "head_diameter_mm must be > 0"],
        ),
        (
            "[[features]]\nkind = \"screw\"\ncentre = [50.0, 50.0]\nheight_mm = -3.0\n".into(),
            vec!["features[1] (screw)", "height_mm must be > 0"],
        ),
    ];
    for (feature, needles) in cases {
        expect_error(&format!("{PLATE}{good}{feature}"), &needles);
    }
}

#[test]
fn bad_plates_manipulators_and_sensors_are_named() {
    let cases: Vec<(String, Vec<&str>)> = vec![
        (
            "[plate]\nsize_mm = [-200.0, 100.0]\n".into(),
            vec!["plate.size_mm must be positive"],
        ),
        (
            "[plate]\nsize_mm = [nan, 100.0]\n".into(),
            vec!["plate.size_mm", "NaN"],
        ),
        (
            format!("{PLATE}[plate.material]\nreflectivity = 1.2\n"),
            vec!["plate.material.reflectivity"],
        ),
        (
            format!("{PLATE}[manipulator]\nslide_speed_mm_s = 0.0\n"),
            vec!["manipulator.slide_speed_mm_s must be positive"],
        ),
        (
            format!("{PLATE}[manipulator]\nstroke_mm = nan\n"),
            vec!["manipulator.stroke_mm", "NaN"],
        ),
        (
            format!("{PLATE}[manipulator]\nworkspace_max_mm = [150.0, 100.0, 150.0]\n"),
            vec!["manipulator workspace must cover the plate in x"],
        ),
        (
            format!("{PLATE}[manipulator]\nworkspace_min_mm = [0.0, 0.0, 200.0]\n"),
            vec!["manipulator.workspace_min_mm", "in z"],
        ),
        (
            format!("{PLATE}[sensor.finger]\ntip_radius_mm = -1.0\n"),
            vec!["sensor.finger.tip_radius_mm"],
        ),
    ];
    for (text, needles) in cases {
        expect_error(&text, &needles);
    }
}

#[test]
fn bad_cameras_are_named() {
    let camera = |replace: &str, with: &str| format!("{PLATE}{}", CAMERA.replace(replace, with));
    let cases: Vec<(String, Vec<&str>)> = vec![
        (
            camera(
                "position_mm = [100.0, 50.0, 250.0]",
                "position_mm = [100.0, 50.0, -10.0]",
            ),
            vec!["camera.position_mm", "above the plate"],
        ),
        (
            camera("look_at_mm = [100.0, 50.0]", "look_at_mm = [300.0, 50.0]"),
            vec!["camera.look_at_mm", "looks away from the plate"],
        ),
        (
            camera(
                "position_mm = [100.0, 50.0, 250.0]",
                "position_mm = [100.0, -2000.0, 10.0]",
            ),
            vec!["edge-on"],
        ),
        (
            camera("resolution = [640, 480]", "resolution = [0, 480]"),
            vec!["camera.resolution"],
        ),
        (
            camera("focal_px = [700.0, 700.0]", "focal_px = [-700.0, 700.0]"),
            vec!["camera.focal_px"],
        ),
        (
            camera(
                "focal_px = [700.0, 700.0]",
                "focal_px = [700.0, 700.0]\nprincipal_px = [5000.0, 5000.0]",
            ),
            vec!["camera does not see the plate"],
        ),
        (
            camera(
                "focal_px = [700.0, 700.0]",
                "focal_px = [700.0, 700.0]\nlighting_variation = 2.0",
            ),
            vec!["camera.lighting_variation"],
        ),
        (
            camera(
                "focal_px = [700.0, 700.0]",
                "focal_px = [700.0, 700.0]\nnoise_sigma = nan",
            ),
            vec!["camera.noise_sigma", "NaN"],
        ),
        (
            camera(
                "position_mm = [100.0, 50.0, 250.0]",
                "position_mm = [100.0, 50.0, nan]",
            ),
            vec!["camera.position_mm"],
        ),
    ];
    for (text, needles) in cases {
        expect_error(&text, &needles);
    }
}

#[test]
fn a_missing_file_is_an_io_error_naming_it() {
    let path = scenes_dir().join("no_such_scene.toml");
    let err = Scene::load(&path).unwrap_err();
    assert!(matches!(err, SimError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("no_such_scene.toml"), "{err}");
}
