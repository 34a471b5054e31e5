//! The detection trials, two at a time: every trial scored once, listed by seed.

use crackbot_mission::inspect::InspectConfig;
use crackbot_mission::MissionError;
use crackbot_research::{detection_trials, ExperimentConfig};
use crackbot_sim::Scene;

fn base(dir: &std::path::Path, jobs: usize) -> ExperimentConfig {
    ExperimentConfig {
        out_dir: dir.to_path_buf(),
        // Two robots at once on a small machine: each at a modest speed-up.
        speedup: 4.0,
        template: InspectConfig::new(Scene::builtin_default(), dir),
        printed_cracks: true,
        jobs,
    }
}

#[test]
fn trials_run_two_at_a_time_are_each_scored_once_and_listed_by_seed() {
    let dir = tempfile::tempdir().unwrap();
    let mut seen = Vec::new();
    let report = detection_trials(&base(dir.path(), 2), 1000, 3, |seed, t| {
        assert_eq!(seed, t.seed);
        seen.push(seed);
    })
    .unwrap();
    seen.sort();
    assert_eq!(seen, vec![1000, 1001, 1002]);
    let seeds: Vec<u64> = report.trials.iter().map(|t| t.seed).collect();
    assert_eq!(seeds, vec![1000, 1001, 1002]);
    // The totals are the trials' sums, and every trial's two missions left their folders.
    let correct: usize = report.trials.iter().map(|t| t.fused.correct).sum();
    assert_eq!(report.fused_totals.correct, correct);
    assert!(report.trials.iter().all(|t| t.cracks > 0));
    for seed in 1000..1003 {
        for mode in ["vision", "fused"] {
            let folder = dir.path().join(format!("trial-{seed}-{mode}"));
            assert!(folder.join("report.json").is_file(), "{}", folder.display());
        }
    }
    assert!(
        report.fused_correct > report.vision_correct,
        "fused {} vs vision {}",
        report.fused_correct,
        report.vision_correct
    );
}

#[test]
fn no_jobs_is_refused_before_any_mission() {
    let dir = tempfile::tempdir().unwrap();
    let e = detection_trials(&base(dir.path(), 0), 1000, 1, |_, _| {}).unwrap_err();
    assert!(matches!(e, MissionError::Setting { field: "jobs", .. }));
    assert!(e.to_string().contains("jobs"), "{e}");
    assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none());
}
