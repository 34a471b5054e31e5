//! Scene files: every file in `crates/sim/scenes/` loads and validates, the default file is the
//! built-in scene, each validation rule is hit by a small snippet whose error names the field,
//! and scenes survive a TOML round trip.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

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

/// Parses `text` and expects it refused as a scene named `snippet.toml`: the error inside the
/// [`SimError::InScene`], whose message starts with the snippet's name.
fn refused(text: &str) -> SimError {
    let err = match Scene::from_toml_str(text, "snippet.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    };
    let message = err.to_string();
    match err {
        SimError::InScene { path, source } => {
            assert_eq!(path, "snippet.toml");
            assert_eq!(message, format!("snippet.toml: {source}"));
            *source
        }
        other => panic!("expected SimError::InScene, got {other:?}\n--- snippet:\n{text}"),
    }
}

/// Parses `text` and expects the setting `field` refused; checks that the message names the field,
/// the value and the allowed range, and returns the value and the allowed range.
fn refused_setting(text: &str, field: &str) -> (String, String) {
    let err = refused(text);
    let message = err.to_string();
    match err {
        SimError::Setting {
            field: f,
            value,
            allowed,
        } => {
            assert_eq!(f, field, "{message}\n--- snippet:\n{text}");
            assert_eq!(
                message,
                format!("invalid setting {field} = {value}: it must be {allowed}")
            );
            (value, allowed)
        }
        other => {
            panic!("expected SimError::Setting of {field}, got {other:?}\n--- snippet:\n{text}")
        }
    }
}

#[test]
fn bad_features_are_named_by_index_and_kind() {
    let good = crack("[[10.0, 10.0], [50.0, 20.0]]", "1.0", "1.0");
    // (feature, field, kind, a word of the value or the allowed range)
    let cases: Vec<(String, &str, &str, &str)> = vec![
        (
            crack("[[190.0, 50.0], [210.0, 50.0]]", "1.0", "1.0"),
            "features[1]",
            "crack",
            "outside the plate",
        ),
        (
            crack("[[10.0, 10.0], [50.0, 20.0]]", "-1.0", "1.0"),
            "features[1].width_mm",
            "crack",
            "-1",
        ),
        (
            crack("[[10.0, 10.0], [50.0, 20.0]]", "nan", "1.0"),
            "features[1].width_mm",
            "crack",
            "NaN",
        ),
        (
            crack("[[10.0, 10.0], [nan, 20.0]]", "1.0", "1.0"),
            "features[1].path[1]",
            "crack",
            "finite",
        ),
        (
            crack("[[10.0, 10.0], [50.0, 20.0]]", "1.0", "0.0"),
            "features[1].depth_mm",
            "crack",
            "> 0",
        ),
        (
            crack("[[10.0, 10.0], [10.0, 10.0]]", "1.0", "1.0"),
            "features[1].path",
            "crack",
            "zero length",
        ),
        (
            crack("[[10.0, 10.0]]", "1.0", "1.0"),
            "features[1].path",
            "crack",
            "at least 2 points",
        ),
        (
            "[[features]]\nkind = \"crack\"\npath = [[10.0, 10.0], [50.0, 20.0]]\nwidth_mm = 1.0\ndepth_mm = 1.0\nedge_radius_mm = -0.1\n".into(),
            "features[1].edge_radius_mm",
            "crack",
            "-0.1",
        ),
        (
            "[[features]]\nkind = \"bump\"\ncentre = [50.0, 50.0]\nradius_mm = -5.0\nheight_mm = 2.0\n".into(),
            "features[1].radius_mm",
            "bump",
            "> 0",
        ),
        (
            "[[features]]\nkind = \"bump\"\ncentre = [50.0, 50.0]\nradius_mm = 5.0\nheight_mm = 0.0\n".into(),
            "features[1].height_mm",
            "bump",
            "> 0",
        ),
        (
            "[[features]]\nkind = \"bump\"\ncentre = [198.0, 50.0]\nradius_mm = 5.0\nheight_mm = 1.0\n".into(),
            "features[1]",
            "bump",
            "outside the plate",
        ),
        (
            "[[features]]\nkind = \"wavy\"\nmin = [60.0, 10.0]\nmax = [50.0, 40.0]\n".into(),
            "features[1].min",
            "wavy",
            "below max",
        ),
        (
            "[[features]]\nkind = \"wavy\"\nmin = [10.0, 10.0]\nmax = [50.0, 40.0]\nperiod_mm = 0.0\n".into(),
            "features[1].period_mm",
            "wavy",
            "> 0",
        ),
        (
            "[[features]]\nkind = \"wavy\"\nmin = [10.0, 10.0]\nmax = [50.0, 40.0]\namplitude_mm = -1.0\n".into(),
            "features[1].amplitude_mm",
            "wavy",
            "≥ 0",
        ),
        (
            "[[features]]\nkind = \"decoy\"\npath = [[10.0, 50.0], [60.0, 50.0]]\nwidth_mm = 2.0\nreflectivity = 1.5\n".into(),
            "features[1].reflectivity",
            "decoy",
            "in [0, 1]",
        ),
        (
            "[[features]]\nkind = \"decoy\"\npath = [[10.0, 50.0]]\nwidth_mm = 2.0\n".into(),
            "features[1].path",
            "decoy",
            "at least 2 points",
        ),
        (
            "[[features]]\nkind = \"screw\"\ncentre = [50.0, 50.0]\nhead_diameter_mm = 0.0\n".into(),
            "features[1].head_diameter_mm",
            "screw",
            "> 0",
        ),
        (
            "[[features]]\nkind = \"screw\"\ncentre = [50.0, 50.0]\nheight_mm = -3.0\n".into(),
            "features[1].height_mm",
            "screw",
            "> 0",
        ),
    ];
    for (feature, field, kind, word) in cases {
        let text = format!("{PLATE}{good}{feature}");
        let (value, allowed) = refused_setting(&text, field);
        assert!(
            allowed.ends_with(&format!("for a {kind}")),
            "{field}: {allowed:?} does not name the {kind}"
        );
        assert!(
            value.contains(word) || allowed.contains(word),
            "{field} = {value}, {allowed:?} lacks {word:?}"
        );
    }
}

#[test]
fn bad_plates_manipulators_and_sensors_are_named() {
    // (snippet, field, a word of the value or the allowed range)
    let cases: Vec<(String, &str, &str)> = vec![
        (
            "[plate]\nsize_mm = [-200.0, 100.0]\n".into(),
            "plate.size_mm",
            "-200",
        ),
        (
            "[plate]\nsize_mm = [nan, 100.0]\n".into(),
            "plate.size_mm",
            "NaN",
        ),
        (
            format!("{PLATE}[plate.material]\nreflectivity = 1.2\n"),
            "plate.material.reflectivity",
            "in [0, 1]",
        ),
        (
            format!("{PLATE}[manipulator]\nslide_speed_mm_s = 0.0\n"),
            "manipulator.slide_speed_mm_s",
            "> 0",
        ),
        (
            format!("{PLATE}[manipulator]\nstroke_mm = nan\n"),
            "manipulator.stroke_mm",
            "NaN",
        ),
        (
            format!("{PLATE}[manipulator]\nworkspace_max_mm = [150.0, 100.0, 150.0]\n"),
            "manipulator.workspace_max_mm",
            "cover the plate",
        ),
        (
            format!("{PLATE}[manipulator]\nworkspace_min_mm = [0.0, 0.0, 200.0]\n"),
            "manipulator.workspace_min_mm",
            "in z",
        ),
        (
            format!("{PLATE}[sensor.finger]\ntip_radius_mm = -1.0\n"),
            "sensor.finger.tip_radius_mm",
            "-1",
        ),
    ];
    for (text, field, word) in cases {
        let (value, allowed) = refused_setting(&text, field);
        assert!(
            value.contains(word) || allowed.contains(word),
            "{field} = {value}, {allowed:?} lacks {word:?}"
        );
    }
}

#[test]
fn bad_cameras_are_named() {
    let camera = |replace: &str, with: &str| format!("{PLATE}{}", CAMERA.replace(replace, with));
    // (snippet, field, a word of the value or the allowed range)
    let cases: Vec<(String, &str, &str)> = vec![
        (
            camera(
                "position_mm = [100.0, 50.0, 250.0]",
                "position_mm = [100.0, 50.0, -10.0]",
            ),
            "camera.position_mm",
            "above the plate",
        ),
        (
            camera("look_at_mm = [100.0, 50.0]", "look_at_mm = [300.0, 50.0]"),
            "camera.look_at_mm",
            "looks away from the plate",
        ),
        (
            camera(
                "position_mm = [100.0, 50.0, 250.0]",
                "position_mm = [100.0, -2000.0, 10.0]",
            ),
            "camera.position_mm",
            "edge-on",
        ),
        (
            camera("resolution = [640, 480]", "resolution = [0, 480]"),
            "camera.resolution",
            "[0, 480]",
        ),
        (
            camera("focal_px = [700.0, 700.0]", "focal_px = [-700.0, 700.0]"),
            "camera.focal_px",
            "[-700, 700]",
        ),
        (
            camera(
                "focal_px = [700.0, 700.0]",
                "focal_px = [700.0, 700.0]\nlighting_variation = 2.0",
            ),
            "camera.lighting_variation",
            "in [0, 1]",
        ),
        (
            camera(
                "focal_px = [700.0, 700.0]",
                "focal_px = [700.0, 700.0]\nnoise_sigma = nan",
            ),
            "camera.noise_sigma",
            "NaN",
        ),
        (
            camera(
                "position_mm = [100.0, 50.0, 250.0]",
                "position_mm = [100.0, 50.0, nan]",
            ),
            "camera.position_mm",
            "NaN",
        ),
    ];
    for (text, field, word) in cases {
        let (value, allowed) = refused_setting(&text, field);
        assert!(
            value.contains(word) || allowed.contains(word),
            "{field} = {value}, {allowed:?} lacks {word:?}"
        );
    }
    // A camera that sees none of the plate is not one setting out of range.
    let text = camera(
        "focal_px = [700.0, 700.0]",
        "focal_px = [700.0, 700.0]\nprincipal_px = [5000.0, 5000.0]",
    );
    let err = refused(&text);
    assert!(matches!(err, SimError::CameraMissesPlate), "{err:?}");
    assert!(err.to_string().contains("does not see the plate"), "{err}");
}

#[test]
fn a_setting_error_reads_field_value_and_range() {
    let text = format!(
        "{PLATE}{}",
        CAMERA.replace(
            "focal_px = [700.0, 700.0]",
            "focal_px = [700.0, 700.0]\nnoise_sigma = -2.5"
        )
    );
    let err = Scene::from_toml_str(&text, "snippet.toml").unwrap_err();
    assert_eq!(
        err.to_string(),
        "snippet.toml: invalid setting camera.noise_sigma = -2.5: it must be ≥ 0"
    );
    // Validating the scene itself gives the setting without the file.
    let mut scene = Scene::builtin_default();
    if let Some(camera) = scene.camera.as_mut() {
        camera.noise_sigma = -2.5;
    }
    let err = scene.validate().unwrap_err();
    assert!(
        matches!(
            &err,
            SimError::Setting { field, value, allowed }
                if field == "camera.noise_sigma" && value == "-2.5" && allowed == "≥ 0"
        ),
        "{err:?}"
    );
}

#[test]
fn a_missing_file_is_an_io_error_naming_it() {
    let path = scenes_dir().join("no_such_scene.toml");
    let err = Scene::load(&path).unwrap_err();
    assert!(matches!(err, SimError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("no_such_scene.toml"), "{err}");
}
