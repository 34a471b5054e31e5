//! Writes the detection trials' scenes as JSON (one file per seed), for looking at what each
//! report of a trial landed on: `cargo run --release -p crackbot-research --example trial_scenes --
//! FIRST_SEED N OUT_DIR [--printed-cracks]`.

use crackbot_research::{as_printed, trial_params};
use crackbot_sim::random_scene::random_scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [first, n, out, rest @ ..] = args.as_slice() else {
        return Err("usage: trial_scenes FIRST_SEED N OUT_DIR [--printed-cracks]".into());
    };
    let (first, n): (u64, u64) = (first.parse()?, n.parse()?);
    std::fs::create_dir_all(out)?;
    for seed in first..first + n {
        let mut scene = random_scene(&trial_params(), seed)?;
        if rest.iter().any(|a| a == "--printed-cracks") {
            scene = as_printed(&scene);
        }
        let path = std::path::Path::new(out).join(format!("scene-{seed}.json"));
        std::fs::write(&path, serde_json::to_string_pretty(&scene)?)?;
    }
    Ok(())
}
