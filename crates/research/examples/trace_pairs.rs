//! For each pair of confirmed reports of saved fused trials, how the line between their
//! crossings lies on the detector's crack map: the detector is run again on the trial's saved
//! frame. One line per pair: `SEED A B DISTANCE_MM ANGLE_DEG GAP_0.5 GAP_1.0 GAP_1.5 PATH_MM` (the largest
//! angle between the line and the two pieces' directions; the longest stretch off the crack map
//! for each reach, mm; the shortest path over the crack map's pixels from one crossing to
//! the other, mm, -1 where none). For tuning `crackbot_mission::inspect::PIECE_TRACE_GAP_MM`:
//! `cargo run --release -p crackbot-research --example trace_pairs -- TRIALS_DIR...`.

use std::path::Path;

use crackbot_mission::inspect::{turn_deg, CrackTrace};
use crackbot_vision::model::{build_detector, DetectorChoice};
use crackbot_vision::preprocess::PostprocessParams;
use serde_json::Value;

#[path = "support/trials.rs"]
mod trials;
use trials::{fused_trials, SavedTrial};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let post = PostprocessParams {
        score_threshold: 0.3,
        ..PostprocessParams::default()
    };
    let mut detector = build_detector(&DetectorChoice::default(), post)?;
    for dir in std::env::args().skip(1) {
        for SavedTrial {
            folder: trial,
            seed,
            report,
        } in fused_trials(Path::new(&dir))?
        {
            let rows: Vec<[f64; 3]> =
                serde_json::from_value(report["frame"]["surface_to_image"].clone())?;
            // The report keeps surface → image; the trace wants pixel → surface.
            let to_image = crackbot_imaging::Homography::from_matrix([rows[0], rows[1], rows[2]])?;
            let h = crackbot_imaging::Homography::from_nalgebra(*to_image.inverse())?;
            let image = image::open(trial.join("frame.png"))?.to_rgb8();
            let (_, map) = detector.detect_with_map(&image)?;
            let Some(map) = map else { continue };
            let trace = CrackTrace::new(&map, h);
            let axis = |id: &Value| {
                report["candidates"]
                    .as_array()
                    .and_then(|cs| cs.iter().find(|c| &c["id"] == id))
                    .and_then(|c| c["axis_deg"].as_f64())
            };
            let cracks = report["cracks"].as_array().cloned().unwrap_or_default();
            for (i, a) in cracks.iter().enumerate() {
                for b in &cracks[i + 1..] {
                    let (Some(aa), Some(ab)) = (axis(&a["candidate"]), axis(&b["candidate"]))
                    else {
                        continue;
                    };
                    let p: [f64; 2] = serde_json::from_value(a["position_mm"].clone())?;
                    let q: [f64; 2] = serde_json::from_value(b["position_mm"].clone())?;
                    let line = (q[1] - p[1]).atan2(q[0] - p[0]).to_degrees();
                    let turn = |ax: f64| turn_deg(line, ax);
                    let gaps: Vec<String> = [0.5, 1.0, 1.5]
                        .iter()
                        .map(|&r| format!("{:.2}", trace.longest_gap_mm(p, q, r)))
                        .collect();
                    let path = trace
                        .path_on_map_mm(p, q, 1.0)
                        .map_or("-1".into(), |d| format!("{d:.1}"));
                    println!(
                        "{seed} {} {} {:.1} {:.0} {} {path}",
                        a["candidate"],
                        b["candidate"],
                        (q[0] - p[0]).hypot(q[1] - p[1]),
                        turn(aa).max(turn(ab)),
                        gaps.join(" ")
                    );
                }
            }
        }
    }
    Ok(())
}
