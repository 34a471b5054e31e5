//! `crackbot sim …` end to end: the simulated datasets are deterministic from the seed, in the
//! authors' nine-column format, and `crackbot tactile eval` reads them as they are; the
//! work-precision report and the real-vs-simulated figure are written.

use std::path::Path;

use crackbot_recording::read_recording;
use crackbot_tests::{crackbot, text};

/// The authors' recordings (`../shared/data/tactile`, or `$CRACKBOT_DATA_DIR/tactile`).
fn data() -> std::path::PathBuf {
    crackbot_datasets::require(crackbot_datasets::TACTILE)
}

fn utf8(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn dataset(out: &Path, experiment: &str, seed: &str, recordings: &str) {
    let o = crackbot(&[
        "sim",
        "dataset",
        "--experiment",
        experiment,
        "--out",
        utf8(out),
        "--seed",
        seed,
        "--recordings",
        recordings,
        "--slides",
        "3",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("real time"), "{}", text(&o.stdout));
}

#[test]
fn width_dataset_is_deterministic_and_in_the_authors_format() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let a = tmp.path().join("a");
    let b = tmp.path().join("b");
    let c = tmp.path().join("c");
    dataset(&a, "width", "5", "1");
    dataset(&b, "width", "5", "1");
    dataset(&c, "width", "6", "1");
    let mut names: Vec<String> = std::fs::read_dir(&a)
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut expected = [0, 1, 2, 5, 8, 10].map(|w| format!("crack_mm{w}_complete_1.csv"));
    expected.sort();
    assert_eq!(names, expected);
    for name in &names {
        let ra = std::fs::read(a.join(name)).expect("a");
        let rb = std::fs::read(b.join(name)).expect("b");
        let rc = std::fs::read(c.join(name)).expect("c");
        assert_eq!(ra, rb, "{name}: same seed, same bytes");
        assert_ne!(ra, rc, "{name}: another seed, other data");
        let rec = read_recording(&a.join(name)).expect("readable");
        let width: f64 = name
            .trim_start_matches("crack_mm")
            .trim_end_matches("_complete_1.csv")
            .parse()
            .expect("width");
        assert_eq!(rec.label(), Some(width));
        assert_eq!(rec.repetition(), Some(1));
        let slides: Vec<u32> = rec.rows.iter().map(|r| r.slide).collect();
        assert_eq!(slides.first(), Some(&1));
        assert_eq!(slides.last(), Some(&3));
        assert!(rec.rows.iter().any(|r| r.direction == 0));
        assert!(rec.rows.iter().any(|r| r.direction == 1));
        for r in &rec.rows {
            for v in r.channels() {
                assert!((0.0..=1023.0).contains(&v) && v.fract() == 0.0, "{v}");
            }
        }
        // At most 16 mm of travel. The position column reads the tip, which lags the arm where it
        // sticks. KNOWN DEFECT of the fitted finger (crates/sim/docs/calibration.md): it is laterally
        // too soft and jams in wide cracks for whole strokes (measured travel down to 11.4 mm); the
        // real finger climbs out. The lower bound only stops it getting worse.
        let (lo, hi) = rec
            .rows
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
                (l.min(r.x_mm), h.max(r.x_mm))
            });
        assert!((10.0..=16.5).contains(&(hi - lo)), "travel {lo}..{hi}");
    }
    // The proximity channel sees the crack: wider cracks dip further.
    let p_min = |w: u32| {
        read_recording(&a.join(format!("crack_mm{w}_complete_1.csv")))
            .expect("read")
            .rows
            .iter()
            .map(|r| r.p)
            .fold(f64::INFINITY, f64::min)
    };
    assert!(p_min(5) < p_min(0) - 100.0, "{} vs {}", p_min(5), p_min(0));
}

#[test]
fn tactile_eval_reads_simulated_recordings_and_tests_on_real_ones() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let sim = tmp.path().join("type");
    dataset(&sim, "recognition", "1", "2");
    let real = data().join("type/crack_crack_complete_2.mat");
    let o = crackbot(&[
        "tactile",
        "eval",
        "--train",
        utf8(&sim),
        "--test",
        utf8(&real),
        "--trees",
        "10",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    let acc = v["window_accuracy"].as_f64().expect("accuracy");
    assert!((0.0..=1.0).contains(&acc), "{v}");
    assert_eq!(v["train_recordings"].as_u64(), Some(8));
    // Simulated against itself: training on repetition 1, testing on 2 separates the surfaces.
    let o = crackbot(&[
        "tactile",
        "eval",
        "--train",
        utf8(&sim.join("crack_nocrack_complete_1.csv")),
        utf8(&sim.join("crack_crack_complete_1.csv")),
        utf8(&sim.join("crack_bump_complete_1.csv")),
        utf8(&sim.join("crack_pattern_complete_1.csv")),
        "--test",
        utf8(&sim.join("crack_nocrack_complete_2.csv")),
        utf8(&sim.join("crack_crack_complete_2.csv")),
        utf8(&sim.join("crack_bump_complete_2.csv")),
        utf8(&sim.join("crack_pattern_complete_2.csv")),
        "--trees",
        "20",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    // Whole slides are classified well; single windows on the flat stretches of every plate
    // look alike in the simulator (the real plates differ in their own baselines).
    let slides = v["slide_accuracy"].as_f64().expect("slide accuracy");
    let windows = v["window_accuracy"].as_f64().expect("window accuracy");
    assert!(slides >= 0.5, "sim→sim slide accuracy {slides}");
    assert!(windows > 0.3, "sim→sim window accuracy {windows}");
}

#[test]
fn compare_and_work_precision_write_their_figures() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let sim = tmp.path().join("type");
    dataset(&sim, "recognition", "2", "1");
    let png = tmp.path().join("cmp.png");
    let o = crackbot(&[
        "sim",
        "compare",
        "--real",
        &format!("{}/type", data().display()),
        "--sim",
        utf8(&sim),
        "--out",
        utf8(&png),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let img = image::open(&png).expect("png");
    assert_eq!(img.width(), 1600);

    let wp = tmp.path().join("wp");
    let o = crackbot(&["sim", "work-precision", "--out", utf8(&wp)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let rows: serde_json::Value =
        serde_json::from_slice(&std::fs::read(wp.join("work_precision.json")).expect("json"))
            .expect("parse");
    let rows = rows.as_array().expect("rows");
    let row = |m: &str| {
        rows.iter()
            .find(|r| r["method"] == m)
            .unwrap_or_else(|| panic!("{m} missing"))
    };
    // The default (SDIRK2, one step per sample) is far below the ADC's quantisation.
    let default = row("sdirk2 x1")["rms_error_counts"]
        .as_f64()
        .expect("finite");
    assert!(default < 0.1, "{default}");
    // Explicit Euler at the output rate cannot carry the stiff contact.
    assert!(row("symplectic-euler x1")["failure"].is_string());
    assert!(image::open(wp.join("work_precision.png")).is_ok());

    let o = crackbot(&["sim", "dataset", "--experiment", "width", "--out"]);
    assert!(!o.status.success());
    let o = crackbot(&[
        "sim",
        "calibrate",
        "--real",
        utf8(tmp.path()),
        "--repetition",
        "1",
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("no recording"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn detector_set_writes_images_masks_and_tight_crack_boxes() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("set");
    let o = crackbot(&[
        "sim",
        "detector-set",
        "--scenes",
        "2",
        "--frames-per-scene",
        "1",
        "--seed",
        "11",
        "--out",
        utf8(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("ms each"), "{}", text(&o.stdout));
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(out.join(name)).expect(name)).expect("json")
    };
    let coco = read("annotations.json");
    let images = coco["images"].as_array().expect("images");
    assert_eq!(images.len(), 2);
    assert_eq!(coco["categories"][0]["id"], 1);
    assert_eq!(coco["categories"][0]["name"], "crack");
    let annotations = coco["annotations"].as_array().expect("annotations");
    assert!(!annotations.is_empty());
    for (k, im) in images.iter().enumerate() {
        assert_eq!(im["scene_seed"], 11 + k as u64);
        let file = im["file_name"].as_str().expect("file_name");
        // Paths relative to the COCO file's folder, as in the photo datasets.
        assert!(file.starts_with("images/"), "{file}");
        let rgb = image::open(out.join(file)).expect("image");
        let mask_file = im["mask_file"].as_str().expect("mask_file");
        let mask = image::open(out.join(mask_file)).expect("mask").to_luma8();
        assert_eq!(mask.dimensions(), (rgb.width(), rgb.height()));
        assert_eq!(im["width"], rgb.width());
        assert!(mask.pixels().all(|p| p[0] == 0 || p[0] == 255));
        let on = |c: u32, r: u32| mask.get_pixel(c, r)[0] > 0;
        for a in annotations.iter().filter(|a| a["image_id"] == im["id"]) {
            let b: Vec<u32> = a["bbox"]
                .as_array()
                .expect("bbox")
                .iter()
                .map(|v| v.as_f64().expect("number") as u32)
                .collect();
            let (x0, y0, x1, y1) = (b[0], b[1], b[0] + b[2] - 1, b[1] + b[3] - 1);
            assert!(x1 < mask.width() && y1 < mask.height(), "{b:?}");
            // Every edge of the box touches a crack pixel of the mask.
            assert!((y0..=y1).any(|r| on(x0, r)), "left edge of {b:?}");
            assert!((y0..=y1).any(|r| on(x1, r)), "right edge of {b:?}");
            assert!((x0..=x1).any(|c| on(c, y0)), "top edge of {b:?}");
            assert!((x0..=x1).any(|c| on(c, y1)), "bottom edge of {b:?}");
        }
    }
    let features = read("features.json");
    let frames = features["images"].as_array().expect("images");
    assert_eq!(frames.len(), 2);
    for f in frames {
        assert_eq!(f["plate_to_image"].as_array().expect("H").len(), 3);
        for b in f["boxes"].as_array().expect("boxes") {
            let kind = b["kind"].as_str().expect("kind");
            assert!(["crack", "decoy", "screw"].contains(&kind), "{kind}");
            assert_eq!(b["bbox"].as_array().expect("bbox").len(), 4);
            if kind != "screw" {
                assert!(b["path_px"].as_array().expect("path_px").len() >= 2);
                assert!(b["width_mm"].as_f64().is_some());
            }
        }
    }

    let o = crackbot(&["sim", "detector-set", "--scenes", "0", "--out", utf8(&out)]);
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("--scenes must be at least 1"),
        "{}",
        text(&o.stderr)
    );
}

/// A start whose proximity fibre traces a cone (`proximity_cone_deg` > 0) gets its cone fitted
/// with the rest of the optics, and a start's lateral end stop is kept: both written to
/// `--params-out`, which `sim dataset --params` takes back.
#[test]
fn calibrate_fits_the_cone_and_keeps_the_end_stop_of_its_start() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let start = tmp.path().join("start.toml");
    std::fs::write(
        &start,
        "[sensor.finger]\nlateral_travel_mm = 1.5\n[sensor.optics]\nproximity_cone_deg = 20.0\n",
    )
    .expect("write");
    let fitted = tmp.path().join("fitted.toml");
    let o = crackbot(&[
        "sim",
        "calibrate",
        "--real",
        utf8(&data().join("type")),
        "--repetition",
        "1",
        // 16 evaluations move the cone (18.6° from 20°; 10 do not yet) in 23 s, 30 took 36 s.
        "--evaluations",
        "16",
        "--mechanics-evaluations",
        "1",
        "--start",
        utf8(&start),
        "--params-out",
        utf8(&fitted),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let params: toml::Value =
        toml::from_str(&std::fs::read_to_string(&fitted).expect("fitted")).expect("toml");
    let cone = params["sensor"]["optics"]["proximity_cone_deg"]
        .as_float()
        .expect("cone");
    assert!((1.0..=60.0).contains(&cone) && cone != 20.0, "cone {cone}");
    assert_eq!(
        params["sensor"]["finger"]["lateral_travel_mm"].as_float(),
        Some(1.5)
    );
    let out = tmp.path().join("set");
    let o = crackbot(&[
        "sim",
        "dataset",
        "--experiment",
        "recognition",
        "--recordings",
        "1",
        "--params",
        utf8(&fitted),
        "--out",
        utf8(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

/// `sim dataset --start-mm MIN,MAX` places the strokes before the plate's feature. The crack's
/// proximity dip comes as much later in the first stroke as the strokes start further before it,
/// and a bad range is refused by name.
#[test]
fn dataset_start_mm_places_the_strokes_before_the_feature() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let run = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let mut args = vec![
            "sim",
            "dataset",
            "--experiment",
            "recognition",
            "--out",
            utf8(&out),
            "--seed",
            "3",
            "--recordings",
            "1",
            "--slides",
            "1",
        ];
        args.extend_from_slice(extra);
        let o = crackbot(&args);
        (o, out.join("crack_crack_complete_1.csv"))
    };
    // Distance travelled from the first stroke's start to its first proximity reading below 420
    // counts.
    let onset = |path: &Path| {
        let rec = read_recording(path).expect("readable");
        let first = rec.rows.first().expect("rows");
        let stroke: Vec<_> = rec
            .rows
            .iter()
            .take_while(|r| r.direction == first.direction)
            .collect();
        let dip = stroke
            .iter()
            .find(|r| r.p < 420.0)
            .expect("the crack's dip");
        (dip.x_mm - first.x_mm).abs()
    };
    let (o, near) = run("near", &["--start-mm", "4,4"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (o, far) = run("far", &["--start-mm", "9,9"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let shift = onset(&far) - onset(&near);
    assert!(
        (shift - 5.0).abs() < 0.3,
        "dip moved {shift} mm for a 5 mm later start"
    );

    for bad in [
        ["--start-mm", "9,3"],
        ["--start-mm", "-1,3"],
        ["--start-mm", "5"],
    ] {
        let (o, _) = run("bad", &bad);
        assert!(!o.status.success(), "{bad:?} accepted");
        assert!(
            text(&o.stderr).contains("--start-mm"),
            "{bad:?}: {}",
            text(&o.stderr)
        );
    }
}

/// `sim dataset --printed-decoys` adds the paper-printed cracks to the recognition experiment
/// (labelled "no crack") and is refused by name for the width experiment.
#[test]
fn dataset_printed_decoys_add_no_crack_plates_to_recognition_only() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("w");
    let o = crackbot(&[
        "sim",
        "dataset",
        "--experiment",
        "width",
        "--printed-decoys",
        "--out",
        utf8(&out),
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o.stderr).contains("--printed-decoys"),
        "{}",
        text(&o.stderr)
    );
    let out = tmp.path().join("r");
    let o = crackbot(&[
        "sim",
        "dataset",
        "--experiment",
        "recognition",
        "--printed-decoys",
        "--recordings",
        "1",
        "--slides",
        "1",
        "--out",
        utf8(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let rec = read_recording(&out.join("crack_printed_w0p5_r0p3_complete_1.csv")).expect("decoy");
    assert_eq!(rec.label(), Some(0.0));
    let written = std::fs::read_dir(&out).expect("out").count();
    assert_eq!(written, 8, "four paper plates and four printed decoys");
}
