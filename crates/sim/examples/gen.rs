//! Quick generation of both experiments (development aid).
#![allow(clippy::unwrap_used, missing_docs)]
use crackbot_sim::experiment::{generate, Experiment, ExperimentConfig};
fn main() {
    let out = std::path::PathBuf::from(std::env::args().nth(1).unwrap());
    let t = std::time::Instant::now();
    for (e, name) in [
        (Experiment::Recognition, "type"),
        (Experiment::Width, "width"),
    ] {
        let c = ExperimentConfig::paper(e, 1);
        generate(&c, &out.join(name), "csv", |d, n| eprint!("\r{d}/{n}")).unwrap();
    }
    eprintln!("\n{:.1} s", t.elapsed().as_secs_f64());
}
