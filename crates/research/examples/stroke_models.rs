//! Models that learn what a mission gives them: one stroke, with no past.
//!
//! The deployed pipeline's context spans reach back across the slides of a continuous recording
//! (`ContextConfig::across_slides`). A mission touches each candidate with one stroke from a fresh
//! classifier, so its windows never have that past. This example trains the deployed
//! configuration two ways on the authors' real recordings and tests both on strokes alone:
//!
//! * `slides`: as deployed (slides forth and back, spans reaching back across slides);
//! * `strokes`: every stroke its own slide, spans confined to it (what a mission sees).
//!
//! Leave one repetition out on the real recordings, then real → sim on simulated datasets.
//!
//! `cargo run --release -p crackbot-research --example stroke_models -- REAL_DIR [SIM_DIR…]`
//! (REAL_DIR holds `type/` and `width/`; each SIM_DIR holds `crackbot sim dataset` output of
//! either experiment).

use std::path::{Path, PathBuf};

use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::dataset::{Experiment, PipelineConfig};
use crackbot_tactile::model::{deployed_pipeline, TactileModel, TrainConfig};
use crackbot_tactile::online::OnlineClassifier;

type Recs = Vec<(PathBuf, Recording)>;

/// Every stroke (a run of one sliding direction within a slide) numbered as a slide of its own.
fn strokes(rec: &Recording) -> Recording {
    let mut out = rec.clone();
    let mut id = 0;
    for i in 0..out.rows.len() {
        let new = i == 0
            || rec.rows[i].slide != rec.rows[i - 1].slide
            || rec.rows[i].direction != rec.rows[i - 1].direction;
        id += u32::from(new);
        out.rows[i].slide = id;
    }
    out
}

fn split(recs: &Recs) -> Recs {
    recs.iter().map(|(p, r)| (p.clone(), strokes(r))).collect()
}

fn stroke_pipeline() -> PipelineConfig {
    let mut p = deployed_pipeline();
    if let Some(c) = p.context.as_mut() {
        c.across_slides = false;
    }
    p
}

/// Slide accuracy and the reported width's MAE (width models) of `model` on `recs`, every slide
/// from a fresh classifier (`fresh`) or with the recording's past.
fn score(
    model: &TactileModel,
    recs: &Recs,
    fresh: bool,
) -> Result<(f64, f64, usize), Box<dyn std::error::Error>> {
    let mut online = OnlineClassifier::new(model)?;
    let (mut right, mut n, mut err) = (0usize, 0usize, 0.0);
    for (_, rec) in recs {
        online.reset();
        for range in rec.slides() {
            if fresh {
                online.reset();
            }
            online.begin_slide();
            let truth = rec.rows[range.start].label;
            for r in &rec.rows[range] {
                online.push(r.channels(), r.direction, r.x_mm)?;
            }
            if let Some(v) = online.end_slide()? {
                n += 1;
                right += usize::from(v.label == truth);
                err += (v.label - truth).abs();
            }
        }
    }
    Ok((
        100.0 * right as f64 / n.max(1) as f64,
        err / n.max(1) as f64,
        n,
    ))
}

fn load(dir: &Path) -> Result<Recs, Box<dyn std::error::Error>> {
    Ok(collect_recordings(&[dir.to_path_buf()])?)
}

fn rep(recs: &Recs, keep: impl Fn(u32) -> bool) -> Recs {
    recs.iter()
        .filter(|(_, r)| r.repetition().is_some_and(&keep))
        .cloned()
        .collect()
}

fn as_recognition(recs: &Recs) -> Result<Recs, Box<dyn std::error::Error>> {
    recs.iter()
        .map(|(p, r)| Ok((p.clone(), r.width_as_recognition()?)))
        .collect()
}

fn train(
    recs: &Recs,
    e: Experiment,
    pipeline: PipelineConfig,
) -> Result<TactileModel, Box<dyn std::error::Error>> {
    let config = TrainConfig {
        n_trees: 32,
        max_depth: Some(10),
        seed: 1,
        ..TrainConfig::default()
    };
    Ok(TactileModel::train_with_pipeline(
        recs,
        Some(e),
        &config,
        pipeline,
        &mut |_, _, _| {},
    )?)
}

/// Both configurations trained on `train_*`, tested on `test_*`; prints one line per test set.
fn compare(
    name: &str,
    train_type: &Recs,
    train_width: &Recs,
    tests: &[(&str, &Recs, &Recs)],
) -> Result<(), Box<dyn std::error::Error>> {
    let mut rec_train = train_type.clone();
    rec_train.extend(as_recognition(train_width)?);
    let slides_r = train(&rec_train, Experiment::Recognition, deployed_pipeline())?;
    let strokes_r = train(
        &split(&rec_train),
        Experiment::Recognition,
        stroke_pipeline(),
    )?;
    let slides_w = train(train_width, Experiment::Width, deployed_pipeline())?;
    let strokes_w = train(&split(train_width), Experiment::Width, stroke_pipeline())?;
    for (test_name, test_type, test_width) in tests {
        let test_wr = as_recognition(test_width)?;
        let mut line = format!("{name} → {test_name}:");
        for (what, set) in [("type", *test_type), ("width as crack", &test_wr)] {
            if set.is_empty() {
                continue;
            }
            let a = score(&slides_r, set, false)?;
            let b = score(&slides_r, &split(set), true)?;
            let c = score(&strokes_r, &split(set), true)?;
            line += &format!(
                "\n  recognition on {what}: slides model, slides with past {:.1} % | slides model, strokes alone {:.1} % | strokes model, strokes alone {:.1} % ({} strokes)",
                a.0, b.0, c.0, c.2
            );
        }
        if !test_width.is_empty() {
            let a = score(&slides_w, test_width, false)?;
            let b = score(&slides_w, &split(test_width), true)?;
            let c = score(&strokes_w, &split(test_width), true)?;
            line += &format!(
                "\n  width: slides model, slides with past {:.1} % ({:.2} mm) | slides model, strokes alone {:.1} % ({:.2} mm) | strokes model, strokes alone {:.1} % ({:.2} mm)",
                a.0, a.1, b.0, b.1, c.0, c.1
            );
        }
        println!("{line}");
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let [real, sims @ ..] = args.as_slice() else {
        return Err("usage: stroke_models REAL_DIR [SIM_DIR…]".into());
    };
    let types = load(&real.join("type"))?;
    let widths = load(&real.join("width"))?;
    let only = std::env::var("ONLY").unwrap_or_default();
    if only.is_empty() || only == "loro" {
        for r in 1..=3 {
            let (tt, tw) = (rep(&types, |x| x != r), rep(&widths, |x| x != r));
            let (st, sw) = (rep(&types, |x| x == r), rep(&widths, |x| x == r));
            compare(
                &format!("reps ≠ {r}"),
                &tt,
                &tw,
                &[(&format!("rep {r}"), &st, &sw)],
            )?;
        }
    }
    if !sims.is_empty() && (only.is_empty() || only == "sim") {
        let mut sets = Vec::new();
        for dir in sims {
            let all = load(dir)?;
            let is_width = all
                .iter()
                .any(|(p, _)| p.to_string_lossy().contains("crack_mm"));
            let name = dir.display().to_string();
            sets.push((name, is_width, all));
        }
        let empty = Vec::new();
        let tests: Vec<(&str, &Recs, &Recs)> = sets
            .iter()
            .map(|(n, w, all)| {
                if *w {
                    (n.as_str(), &empty, all)
                } else {
                    (n.as_str(), all, &empty)
                }
            })
            .collect();
        compare("reps 1-3", &types, &widths, &tests)?;
    }
    Ok(())
}
