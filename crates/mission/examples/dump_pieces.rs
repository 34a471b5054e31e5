//! The pieces the detector's crack map gives on saved fused trials' frames, one JSON line per
//! trial: `{"seed": S, "surface_to_image": H, "pieces": [[x, y, length], …]}` (the frame's
//! homography from the trial's report; touch point and centre-line length, image pixels), for
//! `scripts/piece_coverage.py` (which cracks of each scene have a piece to touch):
//! `cargo run --release -p crackbot-mission --example dump_pieces -- TRIALS_DIR... > pieces.jsonl`.

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
    let mut detector = build_detector(&DetectorChoice::default(), post)?;
    for dir in std::env::args().skip(1) {
        for SavedTrial {
            folder,
            seed,
            report,
        } in fused_trials(Path::new(&dir))?
        {
            let image = image::open(folder.join("frame.png"))?.to_rgb8();
            let (detections, _) = detector.detect_with_map(&image)?;
            let pieces: Vec<[f32; 3]> = detections
                .iter()
                .filter_map(|d| d.shape.as_ref())
                .flat_map(|s| s.pieces.iter())
                .map(|p| [p.touch[0], p.touch[1], p.length_px])
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
