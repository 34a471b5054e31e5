//! Whole missions on the built-in default scene: the simulated controller over real UDP on
//! loopback, the firmware writing into a real pseudo-terminal, the deployed tactile models and the
//! ONNX detector.
#![allow(clippy::unwrap_used)]

use std::sync::atomic::AtomicBool;

use crackbot_mission::inspect::{run_inspection, InspectConfig, InspectMode};
use crackbot_sim::Scene;

#[test]
fn a_fused_mission_on_the_default_scene_confirms_cracks_and_rejects_the_decoy() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = InspectConfig::new(Scene::builtin_default(), dir.path());
    config.speedup = 4.0;
    config.mode = InspectMode::Fused;
    let stop = AtomicBool::new(false);
    let report = run_inspection(&config, &stop, |p| eprintln!("{p:?}")).unwrap();
    println!("{}", serde_json::to_string_pretty(&report.cracks).unwrap());
    for c in &report.candidates {
        println!(
            "candidate {} at {:?} axis {:.0} len {:.1}",
            c.id, c.centre_mm, c.axis_deg, c.length_mm
        );
    }
    println!(
        "rejected {}",
        serde_json::to_string_pretty(&report.rejected).unwrap()
    );
    for p in &report.passes {
        println!("pass {} cand {:?} samples {} class {:?} conf {:.2} width {:?} doubt {:?} dip {:?} from {:?} to {:?}", p.id, p.candidate, p.samples, p.class, p.confidence, p.width_mm, p.doubt, p.dip, p.start_mm, p.end_mm);
    }
    println!(
        "elapsed {:.1} s exploration {:.1} s clocks {:?} {:?}",
        report.elapsed_s, report.exploration_s, report.sensor_clock, report.controller_clock
    );
    assert!(!report.cracks.is_empty());
}
