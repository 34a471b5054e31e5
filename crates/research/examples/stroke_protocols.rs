//! How a deployed model's slide verdicts depend on how much of the finger's past it is given.
//!
//! The authors' recordings (and `crackbot sim dataset`) are continuous: twelve slides, each a
//! stroke forth and back, and the deployed context features reach back up to 2,000 samples
//! across slides. A mission touches a candidate once: one stroke, with nothing before it. This
//! example classifies the same recordings three ways:
//!
//! * `recording`: every slide with the recording's past, as `tactile eval --model` does;
//! * `slide alone`: every slide (forth and back) from a fresh classifier;
//! * `stroke alone`: every stroke (one direction) from a fresh classifier, as a one-pass mission.
//!
//! `cargo run --release -p crackbot-research --example stroke_protocols -- MODEL DIR…`

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Row};
use crackbot_tactile::model::TactileModel;
use crackbot_tactile::online::{OnlineClassifier, SlideVerdict};

/// Classifies `rows` as one slide, after `past` (fed first, not scored) from a fresh classifier.
fn verdict(
    online: &mut OnlineClassifier<'_>,
    past: &[Row],
    rows: &[Row],
) -> Result<Option<SlideVerdict>, Box<dyn std::error::Error>> {
    online.reset();
    if !past.is_empty() {
        for r in past {
            online.push(r.channels(), r.direction, r.x_mm)?;
        }
        online.end_slide()?;
        online.begin_slide();
    }
    for r in rows {
        online.push(r.channels(), r.direction, r.x_mm)?;
    }
    Ok(online.end_slide()?)
}

#[derive(Default)]
struct Tally {
    right: usize,
    total: usize,
    novel: f64,
}

impl Tally {
    fn add(&mut self, v: Option<SlideVerdict>, truth: f64) {
        if let Some(v) = v {
            self.total += 1;
            self.right += usize::from(v.label == truth);
            self.novel += v.novel_fraction;
        }
    }
    fn show(&self) -> String {
        format!(
            "{:5.1} % of {:4} (novel windows {:4.1} %)",
            100.0 * self.right as f64 / self.total.max(1) as f64,
            self.total,
            100.0 * self.novel / self.total.max(1) as f64
        )
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [model, dirs @ ..] = args.as_slice() else {
        return Err("usage: stroke_protocols MODEL DIR…".into());
    };
    let model = TactileModel::load(&PathBuf::from(model))?;
    let dirs: Vec<PathBuf> = dirs.iter().map(PathBuf::from).collect();
    let recognition = model.header.labels.len() == 4;
    let mut online = OnlineClassifier::new(&model)?;
    let (mut whole, mut slide, mut stroke, mut stroke_after) = Default::default();
    let mut per_label: std::collections::BTreeMap<i64, [Tally; 3]> = Default::default();
    for (path, rec) in collect_recordings(&dirs)? {
        let Some(label) = rec.label() else { continue };
        let truth = if recognition && path.to_string_lossy().contains("mm") {
            f64::from(u8::from(label > 0.0))
        } else {
            label
        };
        let entry = per_label.entry(label as i64).or_default();
        let mut past_start = 0;
        for range in rec.slides() {
            let rows = &rec.rows[range.clone()];
            let (a, b) = (
                verdict(&mut online, &rec.rows[past_start..range.start], rows)?,
                verdict(&mut online, &[], rows)?,
            );
            entry[0].add(a.clone(), truth);
            entry[1].add(b.clone(), truth);
            Tally::add(&mut whole, a, truth);
            Tally::add(&mut slide, b, truth);
            // Strokes: runs of one direction.
            let mut s = 0;
            for i in 1..=rows.len() {
                if i == rows.len() || rows[i].direction != rows[s].direction {
                    let v = verdict(&mut online, &[], &rows[s..i])?;
                    entry[2].add(v.clone(), truth);
                    Tally::add(&mut stroke, v, truth);
                    let v = verdict(
                        &mut online,
                        &rec.rows[past_start..range.start + s],
                        &rows[s..i],
                    )?;
                    Tally::add(&mut stroke_after, v, truth);
                    s = i;
                }
            }
            past_start = range.start;
        }
    }
    println!("recording (one slide of past): {}", whole.show());
    println!("slide alone:                   {}", slide.show());
    println!("stroke alone:                  {}", stroke.show());
    println!("stroke after one slide:        {}", stroke_after.show());
    for (label, t) in &per_label {
        println!(
            "label {label:3}: recording {} | slide alone {} | stroke alone {}",
            t[0].show(),
            t[1].show(),
            t[2].show()
        );
    }
    Ok(())
}
