//! Camera-side costs on one core, on a real validation photo of each dataset
//! (`../shared/data/cracks/*/val.json`, first image):
//!
//! * `detector/onnx_{256,320,416}`: one `detect` call of the trained model (letterbox + ONNX Runtime
//!   with one thread + crack map → boxes and courses) at each input size, as the robot and `detect`
//!   run it; `detector/onnx_320_with_box_head_boxes`: the same with the box head's boxes decoded
//!   and added (`eval-detector`, `detect --box-head`); `detector/classical`: the edge-based baseline.
//! * `preprocess/letterbox_*`: the letterbox alone; `postprocess/crack_map_to_boxes_*`: the crack
//!   map → boxes (dataset rule) and centre lines; `postprocess/box_head_boxes_*`: the box head's
//!   outputs → boxes.
//! * `homography/pixel_to_surface`: one point through a fitted homography.
//!
//! mAP@0.5 of each detector comes from `crackbot detector-tradeoff` (see `benches/README.md`).
//! `taskset -c 1 cargo bench --bench vision`.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use crackbot_vision::benchmark;
use crackbot_vision::classical::{ClassicalDetector, ClassicalParams};
use crackbot_vision::coco::CocoDataset;
use crackbot_vision::crack_map::map_detections;
use crackbot_vision::homography::{fit_dlt, PointPair};
use crackbot_vision::onnx::OnnxDetector;
use crackbot_vision::preprocess::{letterbox, PostprocessParams};
use crackbot_vision::Detector;
use criterion::{criterion_group, criterion_main, Criterion};

/// The default model's folder.
const MODELS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/models/detector/crackseg-tiles"
);

/// The first validation image of `dataset`.
fn val_image(dataset: &str) -> image::RgbImage {
    let dir = crackbot_datasets::require(crackbot_datasets::CRACKS).join(dataset);
    let coco = CocoDataset::load(dir.join("val.json")).expect("val.json");
    let file = &coco.images.first().expect("an image").file_name;
    image::open(dir.join(file)).expect("image").to_rgb8()
}

fn bench(c: &mut Criterion) {
    let photos: Vec<(&str, image::RgbImage)> = ["crackforest", "uav75", "quaywall"]
        .into_iter()
        .map(|d| (d, val_image(d)))
        .collect();
    let uav = &photos[1].1;

    let mut g = c.benchmark_group("detector");
    for size in [256, 320, 416] {
        let path: PathBuf = Path::new(MODELS).join(format!("crack-detector-{size}.onnx"));
        let mut d = OnnxDetector::load(&path, PostprocessParams::default(), 1)
            .expect("model and runtime (bash scripts/setup.sh)");
        g.bench_function(format!("onnx_{size}"), |b| {
            b.iter(|| d.detect(black_box(uav)).expect("detect"));
        });
    }
    let mut with_head = OnnxDetector::load(
        &Path::new(MODELS).join("crack-detector-320.onnx"),
        PostprocessParams {
            box_head: true,
            ..PostprocessParams::default()
        },
        1,
    )
    .expect("model");
    g.bench_function("onnx_320_with_box_head_boxes", |b| {
        b.iter(|| with_head.detect(black_box(uav)).expect("detect"));
    });
    let mut classical = ClassicalDetector::new(ClassicalParams::default()).expect("classical");
    g.bench_function("classical", |b| {
        b.iter(|| classical.detect(black_box(uav)).expect("detect"));
    });
    g.finish();

    let mut g = c.benchmark_group("preprocess");
    for (name, img) in &photos {
        g.bench_function(
            format!("letterbox_{name}_{}x{}", img.width(), img.height()),
            |b| b.iter(|| letterbox(black_box(img), 320).expect("letterbox")),
        );
    }
    g.finish();

    let mut model = OnnxDetector::load(
        &Path::new(MODELS).join("crack-detector-320.onnx"),
        PostprocessParams::default(),
        1,
    )
    .expect("model");
    let map = model.crack_map(uav).expect("crack map");
    let mut g = c.benchmark_group("postprocess");
    g.bench_function(
        format!("crack_map_to_boxes_and_courses_{0}x{0}_cells", map.cells()),
        |b| b.iter(|| map_detections(black_box(&map), &PostprocessParams::default())),
    );
    let head = model.box_head_maps(uav).expect("box head outputs");
    g.bench_function(format!("box_head_boxes_{0}x{0}_cells", head.cells()), |b| {
        b.iter(|| black_box(&head).detections(&benchmark::map_params()));
    });
    g.finish();

    // A camera 400 mm above a 200 × 100 mm plate, slightly tilted: pairs from its exact projection.
    let project = |x: f64, y: f64| -> (f64, f64) {
        let (xc, yc, zc) = (x - 100.0 + 0.05 * y, y - 50.0, 400.0 + 0.1 * x);
        (800.0 * xc / zc + 320.0, 800.0 * yc / zc + 240.0)
    };
    let pairs: Vec<PointPair> = [
        (0.0, 0.0),
        (200.0, 0.0),
        (200.0, 100.0),
        (0.0, 100.0),
        (100.0, 50.0),
        (50.0, 20.0),
    ]
    .iter()
    .map(|&(x, y)| {
        let (u, v) = project(x, y);
        PointPair::new([u, v], [x, y])
    })
    .collect();
    let h = fit_dlt(&pairs).expect("homography");
    let mut g = c.benchmark_group("homography");
    g.bench_function("pixel_to_surface", |b| {
        b.iter(|| h.pixel_to_surface(black_box([321.5, 250.25])));
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // Criterion's own plots need a system font lookup that this workspace's plotters build lacks.
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
