//! Rendering scenes with real crack appearance: image size, determinism, ground-truth boxes,
//! darkness of cracks, decoys, screws as occluders, the homography, width scaling, errors and
//! the COCO export.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crackbot_sim::camera::{apply_homography, Camera};
use crackbot_sim::render::{
    coco_dataset, render, write_coco_dataset, write_frame, BoxKind, CrackAssets, Frame,
    RenderOptions, SCREW_GREY,
};
use crackbot_sim::{Feature, Scene, SimError};

fn data_dir() -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::CRACKS)
}

fn assets() -> &'static CrackAssets {
    static ASSETS: OnceLock<CrackAssets> = OnceLock::new();
    ASSETS.get_or_init(|| CrackAssets::load(&data_dir()).unwrap())
}

fn quiet() -> RenderOptions {
    RenderOptions {
        noise_sigma: Some(0.0),
        lighting_variation: Some(0.0),
        ..RenderOptions::default()
    }
}

fn luma(frame: &Frame, uv: [f64; 2]) -> Option<f64> {
    let (c, r) = (uv[0].floor(), uv[1].floor());
    if c < 0.0 || r < 0.0 {
        return None;
    }
    let p = frame.image.get_pixel_checked(c as u32, r as u32)?;
    Some(0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2]))
}

/// Point at arc length `s` along a polyline, and the unit left normal there.
fn along(path: &[[f64; 2]], s: f64) -> ([f64; 2], [f64; 2]) {
    let mut acc = 0.0;
    for seg in path.windows(2) {
        let d = [seg[1][0] - seg[0][0], seg[1][1] - seg[0][1]];
        let l = d[0].hypot(d[1]);
        if s <= acc + l {
            let t = (s - acc) / l;
            let n = [-d[1] / l, d[0] / l];
            return ([seg[0][0] + t * d[0], seg[0][1] + t * d[1]], n);
        }
        acc += l;
    }
    let seg = &path[path.len() - 2..];
    let d = [seg[1][0] - seg[0][0], seg[1][1] - seg[0][1]];
    let l = d[0].hypot(d[1]);
    (seg[1], [-d[1] / l, d[0] / l])
}

fn length(path: &[[f64; 2]]) -> f64 {
    path.windows(2)
        .map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]))
        .sum()
}

fn cracks(scene: &Scene) -> Vec<(usize, Vec<[f64; 2]>, f64)> {
    scene
        .features
        .iter()
        .enumerate()
        .filter_map(|(i, f)| match f {
            Feature::Crack { path, width_mm, .. } => Some((i, path.clone(), *width_mm)),
            _ => None,
        })
        .collect()
}

fn screws(scene: &Scene) -> Vec<([f64; 2], f64)> {
    scene
        .features
        .iter()
        .filter_map(|f| match f {
            Feature::Screw {
                centre,
                head_diameter_mm,
                ..
            } => Some((*centre, head_diameter_mm / 2.0)),
            _ => None,
        })
        .collect()
}

fn camera(scene: &Scene) -> Camera {
    Camera::from_spec(scene.camera.as_ref().unwrap()).unwrap()
}

#[test]
fn default_scene_renders_at_the_camera_resolution_deterministically() {
    let scene = Scene::builtin_default();
    let opts = RenderOptions::default();
    let a = render(&scene, assets(), &opts, 7).unwrap();
    let b = render(&scene, assets(), &opts, 7).unwrap();
    let c = render(&scene, assets(), &opts, 8).unwrap();
    let spec = scene.camera.as_ref().unwrap();
    assert_eq!(
        a.image.dimensions(),
        (spec.resolution[0], spec.resolution[1])
    );
    assert_eq!(a.image.as_raw(), b.image.as_raw());
    assert_eq!(a.boxes, b.boxes);
    assert_ne!(a.image.as_raw(), c.image.as_raw());
    // Off the plate: dark background in the corners.
    assert!(luma(&a, [2.0, 2.0]).unwrap() < 60.0);
    // On the plate: the material's light grey.
    let cam = camera(&scene);
    let on = cam.project([100.0, 5.0, 0.0]).unwrap();
    assert!(luma(&a, on).unwrap() > 110.0);
}

#[test]
fn one_box_per_crack_around_its_projected_polyline() {
    let scene = Scene::builtin_default();
    let cam = camera(&scene);
    let h = cam.plate_to_image();
    for seed in 1..=12 {
        let frame = render(&scene, assets(), &RenderOptions::default(), seed).unwrap();
        for (i, path, width) in cracks(&scene) {
            let boxes: Vec<_> = frame
                .boxes
                .iter()
                .filter(|b| b.feature_index == i)
                .collect();
            assert_eq!(boxes.len(), 1, "seed {seed}, crack {i}: {:?}", frame.boxes);
            let b = boxes[0];
            assert_eq!(b.kind, BoxKind::Crack);
            assert_eq!(b.width_mm, Some(width));
            let (mid, _) = along(&path, length(&path) / 2.0);
            let mid_px = apply_homography(&h, mid).unwrap();
            assert!(
                b.contains(mid_px),
                "seed {seed}, crack {i}: {b:?} ∌ {mid_px:?}"
            );
            let pts: Vec<[f64; 2]> = path
                .iter()
                .map(|p| apply_homography(&h, *p).unwrap())
                .collect();
            let x0 = pts.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
            let x1 = pts.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
            let y0 = pts.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
            let y1 = pts.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
            let width_px = width * 700.0 / 250.0;
            let tol = width_px + 4.0;
            let close = |a: f64, b: f64| (a - b).abs() <= tol;
            assert!(
                close(b.x, x0) && close(b.x + b.w, x1) && close(b.y, y0) && close(b.y + b.h, y1),
                "seed {seed}, crack {i}: box {b:?} vs polyline [{x0:.1}, {x1:.1}] × [{y0:.1}, {y1:.1}] ± {tol:.1}"
            );
        }
    }
}

#[test]
fn cracks_are_darker_than_the_plate_around_them() {
    let scene = Scene::builtin_default();
    let cam = camera(&scene);
    let screws = screws(&scene);
    let frame = render(&scene, assets(), &RenderOptions::default(), 11).unwrap();
    for (i, path, width) in cracks(&scene) {
        let len = length(&path);
        let (mut on, mut off) = (Vec::new(), Vec::new());
        for k in 1..40 {
            let (p, n) = along(&path, len * f64::from(k) / 40.0);
            let near_screw = screws
                .iter()
                .any(|(c, r)| (p[0] - c[0]).hypot(p[1] - c[1]) < r + width + 2.0);
            if near_screw {
                continue;
            }
            on.extend(luma(&frame, cam.project([p[0], p[1], 0.0]).unwrap()));
            let side = width * 1.5 + 3.0;
            for sgn in [-1.0, 1.0] {
                let q = [p[0] + sgn * side * n[0], p[1] + sgn * side * n[1], 0.0];
                off.extend(luma(&frame, cam.project(q).unwrap()));
            }
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (m_on, m_off) = (mean(&on), mean(&off));
        assert!(
            m_on < m_off - 15.0,
            "crack {i} ({width} mm): on {m_on:.1} vs around {m_off:.1}"
        );
    }
}

#[test]
fn decoys_are_boxed_as_decoys_and_not_annotated_as_cracks() {
    let scene = Scene::builtin_default();
    let frame = render(&scene, assets(), &RenderOptions::default(), 5).unwrap();
    let decoy_index = scene
        .features
        .iter()
        .position(|f| matches!(f, Feature::Decoy { .. }))
        .unwrap();
    let decoys: Vec<_> = frame.boxes_of(BoxKind::Decoy).collect();
    assert_eq!(decoys.len(), 1);
    assert_eq!(decoys[0].feature_index, decoy_index);
    let coco = coco_dataset(&[("a.png", &frame)]).unwrap();
    let anns = coco["annotations"].as_array().unwrap();
    assert_eq!(anns.len(), cracks(&scene).len());
    assert!(anns
        .iter()
        .all(|a| a["feature_index"].as_u64().unwrap() as usize != decoy_index));
}

#[test]
fn screws_occlude_what_is_under_them() {
    let scene = Scene::builtin_default();
    let cam = camera(&scene);
    let frame = render(&scene, assets(), &quiet(), 3).unwrap();
    let (screw_index, centre, rad, height) = scene
        .features
        .iter()
        .enumerate()
        .find_map(|(i, f)| match f {
            Feature::Screw {
                centre,
                head_diameter_mm,
                height_mm,
            } => Some((i, *centre, head_diameter_mm / 2.0, *height_mm)),
            _ => None,
        })
        .unwrap();
    let b = frame
        .boxes
        .iter()
        .find(|b| b.feature_index == screw_index)
        .unwrap();
    assert_eq!(b.kind, BoxKind::Screw);
    let c = cam.project([centre[0], centre[1], height]).unwrap();
    assert!(b.contains(c));
    // Pixels of the head: metal grey (bluish, unlike the warm PLA) around its centre.
    let mut pixels = Vec::new();
    let r_px = 0.5 * rad * 700.0 / (250.0 - height);
    for dy in -6i32..=6 {
        for dx in -6i32..=6 {
            let (x, y) = (c[0] + f64::from(dx), c[1] + f64::from(dy));
            if f64::from(dx).hypot(f64::from(dy)) <= r_px {
                pixels.push(*frame.image.get_pixel(x as u32, y as u32));
            }
        }
    }
    let median = |ch: usize| {
        let mut v: Vec<u8> = pixels.iter().map(|p| p[ch]).collect();
        v.sort_unstable();
        v[v.len() / 2]
    };
    let med = [median(0), median(1), median(2)];
    for ch in 0..3 {
        assert!(
            (i32::from(med[ch]) - i32::from(SCREW_GREY[ch])).abs() < 45,
            "{med:?}"
        );
    }
    assert!(med[2] > med[0], "screw grey is bluish: {med:?}");
    // The 5 mm crack runs under it: without the screw it has more visible pixels.
    let crack_under = 2;
    let mut bare = scene.clone();
    bare.features.remove(screw_index);
    let without = render(&bare, assets(), &quiet(), 3).unwrap();
    let with_px = frame
        .boxes
        .iter()
        .find(|b| b.feature_index == crack_under)
        .unwrap()
        .pixels;
    let without_px = without
        .boxes
        .iter()
        .find(|b| b.feature_index == crack_under)
        .unwrap()
        .pixels;
    assert!(with_px < without_px, "{with_px} vs {without_px}");
    // Where the screw is, the crack image is gone.
    let l_with = luma(&frame, c).unwrap();
    let l_without = luma(&without, c).unwrap();
    assert!(l_with != l_without);
}

#[test]
fn the_homography_is_the_cameras() {
    let mut scene = Scene::builtin_default();
    {
        let cam = scene.camera.as_mut().unwrap();
        cam.position_mm = [40.0, -60.0, 220.0];
        cam.roll_deg = 12.0;
        cam.focal_px = [520.0, 520.0];
    }
    scene.validate().unwrap();
    let frame = render(&scene, assets(), &RenderOptions::default(), 9).unwrap();
    let cam = camera(&scene);
    assert_eq!(frame.plate_to_image, cam.plate_to_image());
    for p in [[0.0, 0.0], [200.0, 0.0], [0.0, 100.0], [200.0, 100.0]] {
        let a = apply_homography(&frame.plate_to_image, p).unwrap();
        let b = cam.project([p[0], p[1], 0.0]).unwrap();
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
    }
    // Even seen obliquely and rolled, each crack has one box holding its midpoint.
    for (i, path, _) in cracks(&scene) {
        let b = frame.boxes.iter().find(|b| b.feature_index == i).unwrap();
        let (mid, _) = along(&path, length(&path) / 2.0);
        assert!(b.contains(cam.project([mid[0], mid[1], 0.0]).unwrap()));
    }
}

fn single_crack_scene(width_mm: f64) -> Scene {
    let mut scene = Scene::builtin_default();
    scene.features = vec![Feature::Crack {
        path: vec![[40.0, 50.0], [160.0, 50.0]],
        width_mm,
        depth_mm: 2.0,
        edge_radius_mm: 0.2,
        wall_angle_deg: 90.0,
    }];
    scene
}

fn dark_pixels(frame: &Frame, threshold: f64) -> usize {
    frame
        .image
        .pixels()
        .filter(|p| {
            0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2]) < threshold
                && p[0] > 40
        })
        .count()
}

#[test]
fn wider_cracks_cover_more_pixels() {
    let mut areas = Vec::new();
    for width in [0.0, 1.0, 3.0, 10.0] {
        let frame = render(&single_crack_scene(width), assets(), &quiet(), 21).unwrap();
        assert_eq!(frame.boxes.len(), 1, "width {width}: {:?}", frame.boxes);
        let b = &frame.boxes[0];
        areas.push((width, b.pixels, dark_pixels(&frame, 120.0), b.h));
    }
    for pair in areas.windows(2) {
        assert!(pair[1].1 > pair[0].1, "mask pixels: {areas:?}");
    }
    let (one, ten) = (areas[1], areas[3]);
    assert!(ten.1 > 4 * one.1, "{areas:?}");
    assert!(ten.2 > 3 * one.2, "dark pixels: {areas:?}");
    // The hairline is drawn, but faintly: fewer dark pixels than the 1 mm crack.
    assert!(areas[0].2 < one.2, "{areas:?}");
}

#[test]
fn a_hairline_is_visible_but_faint() {
    let cam = camera(&single_crack_scene(0.0));
    let hair = render(&single_crack_scene(0.0), assets(), &quiet(), 4).unwrap();
    let wide = render(&single_crack_scene(1.0), assets(), &quiet(), 4).unwrap();
    let mut none = single_crack_scene(1.0);
    none.features.clear();
    let bare = render(&none, assets(), &quiet(), 4).unwrap();
    let mean_on = |f: &Frame| {
        let v: Vec<f64> = (0..=100)
            .filter_map(|k| {
                let x = 45.0 + 1.1 * f64::from(k);
                luma(f, cam.project([x, 50.0, 0.0]).unwrap())
            })
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (h, w, b) = (mean_on(&hair), mean_on(&wide), mean_on(&bare));
    assert!(h < b - 3.0, "hairline {h:.1} vs bare plate {b:.1}");
    assert!(w < h - 3.0, "1 mm crack {w:.1} vs hairline {h:.1}");
}

#[test]
fn missing_asset_folder_names_the_path() {
    let dir = Path::new("/nonexistent/crackbot-cracks");
    let err = CrackAssets::load(dir).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, SimError::Io { .. }), "{err:?}");
    assert!(msg.contains("/nonexistent/crackbot-cracks"), "{msg}");
    assert!(msg.contains("CRACKBOT_CRACKS_DIR"), "{msg}");
    // A folder without the datasets.
    let tmp = tempfile::tempdir().unwrap();
    let msg = CrackAssets::load(tmp.path()).unwrap_err().to_string();
    assert!(msg.contains(&tmp.path().display().to_string()), "{msg}");
}

#[test]
fn assets_come_from_the_training_split_only() {
    let val_names: Vec<String> = ["crackforest", "uav75"]
        .iter()
        .flat_map(|ds| {
            let text = std::fs::read_to_string(data_dir().join(ds).join("val.json")).unwrap();
            let v: serde_json::Value = serde_json::from_str(&text).unwrap();
            v["images"]
                .as_array()
                .unwrap()
                .iter()
                .map(|im| format!("{ds}/{}", im["file_name"].as_str().unwrap()))
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(assets().strips().len() >= 20);
    for s in assets().strips() {
        assert!(
            !val_names.contains(&s.source),
            "{} is a val image",
            s.source
        );
    }
}

#[test]
fn a_scene_without_camera_does_not_render() {
    let scene =
        Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/no_camera.toml")).unwrap();
    let err = render(&scene, assets(), &RenderOptions::default(), 1).unwrap_err();
    assert!(err.to_string().contains("no camera"), "{err}");
}

#[test]
fn frames_and_coco_datasets_are_written_and_readable() {
    let scene = Scene::builtin_default();
    let frames: Vec<Frame> = (0..2)
        .map(|s| render(&scene, assets(), &RenderOptions::default(), s).unwrap())
        .collect();
    let tmp = tempfile::tempdir().unwrap();
    write_frame(&frames[0], tmp.path(), "one").unwrap();
    let png = image::open(tmp.path().join("one.png")).unwrap().to_rgb8();
    assert_eq!(png.as_raw(), frames[0].image.as_raw());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(tmp.path().join("one.json")).unwrap())
            .unwrap();
    let h = json["plate_to_image"].as_array().unwrap();
    assert_eq!(h.len(), 3);
    for (r, row) in h.iter().enumerate() {
        for (c, v) in row.as_array().unwrap().iter().enumerate() {
            assert_eq!(v.as_f64().unwrap(), frames[0].plate_to_image[(r, c)]);
        }
    }
    assert_eq!(
        json["boxes"].as_array().unwrap().len(),
        frames[0].boxes.len()
    );
    assert_eq!(json["boxes"][0]["kind"], "crack");
    let coco_path = write_coco_dataset(&frames, &tmp.path().join("ds")).unwrap();
    let coco = crackbot_vision::coco::CocoDataset::load(&coco_path).unwrap();
    assert_eq!(coco.images.len(), 2);
    assert_eq!(coco.categories.len(), 1);
    assert_eq!(coco.categories[0].name, "crack");
    let n_cracks = cracks(&scene).len();
    assert_eq!(coco.annotations.len(), 2 * n_cracks);
    assert!(coco.annotations.iter().all(|a| a.id > 0));
    for im in &coco.images {
        assert!(tmp.path().join("ds/images").join(&im.file_name).is_file());
    }
}

/// The tight box `[x, y, w, h]` of the mask's non-zero pixels inside `b`, if any.
fn mask_box_inside(mask: &image::GrayImage, b: [f64; 4]) -> Option<[f64; 4]> {
    let (x0, y0) = (b[0] as u32, b[1] as u32);
    let (x1, y1) = (x0 + b[2] as u32, y0 + b[3] as u32);
    let (mut c0, mut c1, mut r0, mut r1) = (u32::MAX, 0, u32::MAX, 0);
    for r in y0..y1 {
        for c in x0..x1 {
            if mask.get_pixel(c, r)[0] > 0 {
                (c0, c1, r0, r1) = (c0.min(c), c1.max(c), r0.min(r), r1.max(r));
            }
        }
    }
    (c0 != u32::MAX).then(|| {
        [
            f64::from(c0),
            f64::from(r0),
            f64::from(c1 - c0 + 1),
            f64::from(r1 - r0 + 1),
        ]
    })
}

#[test]
fn crack_mask_is_exactly_the_cracks_visible_pixels() {
    let scene = Scene::builtin_default();
    let frame = render(&scene, assets(), &RenderOptions::default(), 3).unwrap();
    let mask = &frame.crack_mask;
    assert_eq!(mask.dimensions(), frame.image.dimensions());
    assert!(mask.pixels().all(|p| p[0] == 0 || p[0] == 255));
    let cracks: Vec<_> = frame.boxes_of(BoxKind::Crack).collect();
    assert!(cracks.len() >= 3, "{cracks:?}");
    let mut crack_pixels = 0u64;
    for b in &cracks {
        assert_eq!(mask_box_inside(mask, b.bbox()), Some(b.bbox()), "{b:?}");
        crack_pixels += b.pixels;
    }
    // The default scene's cracks do not overlap: the mask holds exactly their pixels.
    let on = mask.pixels().filter(|p| p[0] > 0).count() as u64;
    assert_eq!(on, crack_pixels);
    // Nothing of the decoy, nor of the screw heads, is in the mask.
    let others: Vec<_> = frame
        .boxes
        .iter()
        .filter(|b| b.kind != BoxKind::Crack)
        .collect();
    assert!(others.iter().any(|b| b.kind == BoxKind::Decoy));
    for b in others {
        let [x, y, w, h] = b.bbox();
        for r in y as u32..(y + h) as u32 {
            for c in x as u32..(x + w) as u32 {
                let uv = [f64::from(c) + 0.5, f64::from(r) + 0.5];
                if b.kind == BoxKind::Decoy && !cracks.iter().any(|k| k.contains(uv)) {
                    assert_eq!(
                        mask.get_pixel(c, r)[0],
                        0,
                        "decoy pixel ({c}, {r}) in the mask"
                    );
                }
            }
        }
    }
    // Same seed, same mask.
    let again = render(&scene, assets(), &RenderOptions::default(), 3).unwrap();
    assert_eq!(again.crack_mask, frame.crack_mask);
}
