//! The pieces the detector's crack map gives on saved fused trials' frames, one JSON line per
//! trial: `{"seed": S, "surface_to_image": H, "pieces": [[x, y, length, ax, ay, bx, by], …]}`
//! (the frame's homography from the trial's report; touch point, centre-line length and the ends
//! of its axis, image pixels), for
//! `crates/research/scripts/piece_coverage.py` (which cracks of each scene have a piece to touch):
//! `cargo run --release -p crackbot-research --example dump_pieces -- [--detector MODEL.onnx]
//! TRIALS_DIR... > pieces.jsonl` (default: the committed detector).

use std::path::Path;

use crackbot_vision::model::{build_detector, DetectorChoice};
use crackbot_vision::preprocess::PostprocessParams;

#[path = "support/trials.rs"]
mod trials;
use trials::{fused_trials, SavedTrial};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // As the fused mission perceives: the proposal score, no box-area rule.
    let post = PostprocessParams {
        score_threshold: 0.3,
        min_area_fraction: 0.0,
        ..PostprocessParams::default()
    };
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut choice = DetectorChoice::default();
    if let Some(k) = args.iter().position(|a| a == "--detector") {
        let model = args.get(k + 1).ok_or("--detector needs a model file")?;
        choice.model = Some(model.into());
        args.drain(k..k + 2);
    }
    let mut detector = build_detector(&choice, post)?;
    for dir in args {
        for SavedTrial {
            folder,
            seed,
            report,
        } in fused_trials(Path::new(&dir))?
        {
            let image = image::open(folder.join("frame.png"))?.to_rgb8();
            let (detections, _) = detector.detect_with_map(&image)?;
            let pieces: Vec<[f32; 7]> = detections
                .iter()
                .filter_map(|d| d.shape.as_ref())
                .flat_map(|s| s.pieces.iter())
                .map(|p| {
                    let [[ax, ay], [bx, by]] = p.axis;
                    [p.touch[0], p.touch[1], p.length_px, ax, ay, bx, by]
                })
                .collect();
            let h = &report["frame"]["surface_to_image"];
            println!(
                "{}",
                serde_json::json!({"seed": seed, "surface_to_image": h, "pieces": pieces})
            );
        }
    }
    Ok(())
}
