//! Fits the plate mounts on one repetition (development aid; `crackbot sim calibrate` does it too).
#![allow(clippy::unwrap_used, missing_docs)]
use crackbot_sim::experiment::{Experiment, ExperimentConfig};
fn main() {
    let root = std::path::PathBuf::from(std::env::args().nth(1).unwrap());
    let rep = std::env::args().nth(2).unwrap_or("1".into());
    for (e, sub) in [
        (Experiment::Recognition, "type"),
        (Experiment::Width, "width"),
    ] {
        let mut recs = Vec::new();
        for f in std::fs::read_dir(root.join(sub)).unwrap() {
            let p = f.unwrap().path();
            if p.to_string_lossy().ends_with(&format!("_{rep}.mat")) {
                recs.push(crackbot_recording::read_recording(&p).unwrap());
            }
        }
        let cfg = ExperimentConfig::paper(e, 7);
        let m = crackbot_sim::calibrate::fit_mounts(&cfg, &recs).unwrap();
        println!("{sub}:");
        for x in m {
            println!(
                "            ([{:.2}, {:.2}, {:.2}], {:.4}),",
                x.offset_counts[0], x.offset_counts[1], x.offset_counts[2], x.reflectivity
            );
        }
    }
}
