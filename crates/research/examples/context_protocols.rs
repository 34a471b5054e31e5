//! The figures of the `crackbot_tactile::context` docs: for every protocol that never tests on a
//! repetition it trained on (train on one repetition and test on each other one; leave one
//! repetition out), window and slide accuracy of the paper pipeline, of the context pipeline, and
//! slide accuracy when both forests vote (100 trees, seed 1).
//!
//! `cargo run --release -p crackbot-research --example context_protocols -- ../shared/data/tactile/type`
//! (and `…/width`); files must end in `_<repetition>.mat` or `.csv`.

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::context::ContextConfig;
use crackbot_tactile::dataset::{build_windows, detect_experiment, PipelineConfig};
use crackbot_tactile::eval::{
    test_classifier, test_classifier_with_slide_voters, train_classifier, ClassifierKind,
};

fn repetition(path: &std::path::Path) -> Option<u32> {
    let stem = path.file_stem()?.to_str()?;
    stem.rsplit('_').next()?.parse().ok()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or("usage: context_protocols DIR (the authors' type/ or width/ folder)")?,
    );
    let all = collect_recordings(&[dir])?;
    let mut reps: Vec<u32> = all.iter().filter_map(|(p, _)| repetition(p)).collect();
    reps.sort_unstable();
    reps.dedup();
    let of = |r: &[u32]| -> Vec<(PathBuf, Recording)> {
        all.iter()
            .filter(|(p, _)| repetition(p).is_some_and(|k| r.contains(&k)))
            .cloned()
            .collect()
    };
    let experiment = detect_experiment(&all)?;
    let paper = PipelineConfig::default();
    let context = PipelineConfig {
        context: Some(ContextConfig::default()),
        ..PipelineConfig::default()
    };
    let mut protocols: Vec<(Vec<u32>, u32)> = Vec::new();
    for &a in &reps {
        for &b in reps.iter().filter(|&&b| b != a) {
            protocols.push((vec![a], b));
        }
    }
    for &t in &reps {
        protocols.push((reps.iter().copied().filter(|&r| r != t).collect(), t));
    }
    let kind = ClassifierKind::Forest { n_trees: 100 };
    println!("{} experiment", experiment.name());
    println!("| train → test | paper: windows | paper: slides | context: windows | context: slides | context + paper vote: slides |");
    println!("|---|---|---|---|---|---|");
    for (train, test) in protocols {
        let (tr, te) = (of(&train), of(&[test]));
        let paper_train = build_windows(&tr, experiment, &paper)?;
        let paper_test = build_windows(&te, experiment, &paper)?;
        let paper_model = train_classifier(&paper_train, kind, 1)?;
        let ctx_train = build_windows(&tr, experiment, &context)?;
        let ctx_test = build_windows(&te, experiment, &context)?;
        let ctx_model = train_classifier(&ctx_train, kind, 1)?;
        let p = test_classifier(paper_model.as_ref(), &paper_test)?;
        let c = test_classifier(ctx_model.as_ref(), &ctx_test)?;
        let both = test_classifier_with_slide_voters(
            ctx_model.as_ref(),
            &ctx_test,
            &[(paper_model.as_ref(), &paper_test)],
        )?;
        println!(
            "| {train:?} → {test} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            100.0 * p.windows.accuracy(),
            100.0 * p.slides.accuracy(),
            100.0 * c.windows.accuracy(),
            100.0 * c.slides.accuracy(),
            100.0 * both.slides.accuracy()
        );
    }
    Ok(())
}
