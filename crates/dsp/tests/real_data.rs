//! Both segmentations and the features on the authors' recordings (repetitions 1–3 of all 10 surfaces).
//!
//! Run with `--nocapture` to see the per-file measurement of the segmentations.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect; one-range vectors are the data under test"
)]

use std::path::PathBuf;

use crackbot_dsp::{
    extract_features, extract_segment_features, measure_segmentation, Extent, Feature, FeatureSet,
    FeatureSpec, PaperSegmentation, RobustSegmentation, SegmentationMethod, SegmentationReport,
    StreamingFeatures, WindowConfig,
};
use crackbot_recording::{read_mat, Recording};

/// Slides shorter than this are the trailing one-sample "slide 13" of some files, not movements.
const MIN_SLIDE: usize = 100;

struct File {
    name: String,
    /// Whether the surface has a feature (crack, bump, wavy pattern, crack of width > 0).
    featured: bool,
    rec: Recording,
}

fn files() -> Vec<File> {
    let data = crackbot_datasets::require(crackbot_datasets::TACTILE);
    let mut paths: Vec<PathBuf> = ["type", "width"]
        .iter()
        .flat_map(|d| std::fs::read_dir(data.join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mat"))
        .collect();
    paths.sort();
    assert_eq!(
        paths.len(),
        30,
        "expected the 30 recordings under {}",
        data.display()
    );
    paths
        .into_iter()
        .map(|path| {
            let rec = read_mat(&path).unwrap();
            let label = rec.label().unwrap();
            let name = format!(
                "{}/{}",
                path.parent()
                    .unwrap()
                    .file_name()
                    .unwrap()
                    .to_string_lossy(),
                path.file_stem().unwrap().to_string_lossy()
            );
            File {
                name,
                featured: label != 0.0,
                rec,
            }
        })
        .collect()
}

fn proximity_slides(rec: &Recording) -> Vec<Vec<f64>> {
    rec.slides()
        .into_iter()
        .filter(|r| r.len() >= MIN_SLIDE)
        .map(|r| rec.rows[r].iter().map(|row| row.p).collect())
        .collect()
}

fn samples(rec: &Recording) -> Vec<[f64; 4]> {
    rec.rows
        .iter()
        .map(crackbot_recording::Row::channels)
        .collect()
}

fn methods() -> Vec<(&'static str, SegmentationMethod)> {
    vec![
        (
            "paper",
            SegmentationMethod::Paper(PaperSegmentation::default()),
        ),
        (
            "paper|dp|",
            SegmentationMethod::Paper(PaperSegmentation {
                magnitude: true,
                ..Default::default()
            }),
        ),
        (
            "paper-points",
            SegmentationMethod::Paper(PaperSegmentation {
                extent: Extent::Points,
                margin_fraction: 0.0,
                ..Default::default()
            }),
        ),
        (
            "robust",
            SegmentationMethod::Robust(RobustSegmentation::default()),
        ),
    ]
}

#[test]
fn segmentations_on_every_real_slide() {
    let files = files();
    let methods = methods();
    println!(
        "{:<28} {:>6} | {}",
        "file",
        "slides",
        methods
            .iter()
            .map(|(n, _)| format!("{n:>14} kept [min-max] empty ranges"))
            .collect::<Vec<_>>()
            .join(" | ")
    );
    // method → (featured, flat) overall kept samples / samples, empty slides, slides.
    let mut totals = vec![[(0usize, 0usize, 0usize, 0usize); 2]; methods.len()];
    for f in &files {
        let slides = proximity_slides(&f.rec);
        assert_eq!(slides.len(), 12, "{}", f.name);
        let mut line = format!("{:<28} {:>6}", f.name, slides.len());
        for (mi, (_, method)) in methods.iter().enumerate() {
            let rep: SegmentationReport =
                measure_segmentation(method, slides.iter().map(Vec::as_slice));
            let s = &rep.summary;
            assert_eq!(s.n_slides, 12);
            assert_eq!(s.n_failed, 0, "{} {}", f.name, rep.method);
            for (st, p) in rep.slides.iter().zip(&slides) {
                let seg = st.segment.as_ref().unwrap();
                assert_eq!(seg.trial_len, p.len());
                assert!(st.span.end <= p.len() && st.span.start <= st.span.end);
                assert!(seg
                    .ranges
                    .iter()
                    .all(|r| r.start < r.end && r.end <= p.len()));
                assert!(seg.ranges.windows(2).all(|w| w[0].end < w[1].start));
                assert!((0.0..=1.0).contains(&st.fraction_kept));
            }
            let t = &mut totals[mi][usize::from(!f.featured)];
            t.0 += rep.slides.iter().map(|s| s.kept).sum::<usize>();
            t.1 += rep.slides.iter().map(|s| s.len).sum::<usize>();
            t.2 += s.n_empty;
            t.3 += s.n_slides;
            line += &format!(
                " | {:>14.3} [{:.2}-{:.2}] {:>5} {:>6.2}",
                s.mean_fraction_kept,
                s.min_fraction_kept,
                s.max_fraction_kept,
                s.n_empty,
                s.mean_ranges
            );
            match (rep.method.as_str(), f.featured) {
                // The paper's method keeps something on every slide.
                ("paper", _) => assert_eq!(s.n_empty, 0, "{}", f.name),
                // The robust one: every featured slide, at least one range per crossing, and everything far from
                // the flat level; next to nothing on flat slides.
                ("robust", true) => {
                    assert_eq!(s.n_empty, 0, "{}", f.name);
                    for (st, p) in rep.slides.iter().zip(&slides) {
                        let seg = st.segment.as_ref().unwrap();
                        assert!(seg.ranges.len() >= 2, "{}: {:?}", f.name, seg.ranges);
                        assert!(st.fraction_kept < 0.9, "{}: {}", f.name, st.fraction_kept);
                        if !f.name.contains("pattern") {
                            let mut sorted = p.clone();
                            sorted.sort_by(f64::total_cmp);
                            let median = sorted[sorted.len() / 2];
                            let missed = (0..p.len())
                                .filter(|&i| (p[i] - median).abs() > 100.0 && !seg.contains(i))
                                .count();
                            assert_eq!(missed, 0, "{}: deep samples missed", f.name);
                        }
                    }
                }
                ("robust", false) => {
                    assert!(s.max_fraction_kept < 0.1, "{}: {:?}", f.name, s);
                    assert!(s.n_empty >= 6, "{}: {:?}", f.name, s);
                }
                _ => {}
            }
        }
        println!("{line}");
    }
    for ((name, _), t) in methods.iter().zip(&totals) {
        let [feat, flat] = t;
        println!(
            "{name:>14}: featured surfaces kept {:.3} of samples, {} of {} slides empty; flat surfaces kept {:.3}, {} of {} slides empty",
            feat.0 as f64 / feat.1 as f64,
            feat.2,
            feat.3,
            flat.0 as f64 / flat.1 as f64,
            flat.2,
            flat.3
        );
    }
    // The paper's faithful span covers (nearly) whole slides; the robust segmentation is selective.
    let paper = totals[0][0].0 as f64 / totals[0][0].1 as f64;
    let robust = totals[3][0].0 as f64 / totals[3][0].1 as f64;
    assert!(paper > 0.95 && robust < 0.6, "{paper} {robust}");
}

#[test]
fn streaming_equals_batch_on_a_real_recording() {
    let files = files();
    for f in files.iter().filter(|f| {
        f.name.ends_with("crack_crack_complete_1") || f.name.ends_with("mm1_complete_2")
    }) {
        let x = samples(&f.rec);
        for set in FeatureSet::ALL {
            let spec = FeatureSpec {
                features: vec![Feature::Raw, Feature::Mav, Feature::Rms],
                set,
            };
            let window = WindowConfig::default();
            let batch = extract_features(&x, &spec, window).unwrap();
            assert_eq!(batch.n_rows(), (x.len() - 10) / 2 + 1);
            let mut s = StreamingFeatures::new(spec.clone(), window).unwrap();
            let mut k = 0;
            for (t, sample) in x.iter().enumerate() {
                if let Some(row) = s.push(*sample).unwrap() {
                    assert_eq!(batch.window_ends[k], t);
                    assert_eq!(row, batch.row(k).unwrap());
                    assert!(row
                        .iter()
                        .zip(batch.row(k).unwrap())
                        .all(|(a, b)| a.to_bits() == b.to_bits()));
                    k += 1;
                }
            }
            assert_eq!(k, batch.n_rows());
            // Features of ADC counts stay in the ADC range.
            assert!(
                batch.data.iter().all(|v| (0.0..=1023.0).contains(v)),
                "{}",
                f.name
            );
        }
    }
}

#[test]
fn segment_features_on_real_slides() {
    let files = files();
    let f = files
        .iter()
        .find(|f| f.name.ends_with("crack_crack_complete_1"))
        .unwrap();
    let all = samples(&f.rec);
    let spec = FeatureSpec {
        features: vec![Feature::Mav, Feature::Rms],
        set: FeatureSet::D1D2P,
    };
    for range in f.rec.slides().into_iter().filter(|r| r.len() >= MIN_SLIDE) {
        let x = &all[range];
        let p: Vec<f64> = x.iter().map(|s| s[3]).collect();
        let seg = RobustSegmentation::default().segment(&p).unwrap();
        let m = extract_segment_features(x, &seg, &spec, WindowConfig::default()).unwrap();
        assert!(m.n_rows() > 0);
        assert!(m
            .window_ends
            .iter()
            .all(|&e| seg.contains(e) && seg.contains(e + 1 - 10)));
        assert!(m.window_ends.windows(2).all(|w| w[0] < w[1]));
        // Same rows as the whole slide's batch at the same window ends when a range starts on the grid.
        let whole = extract_features(x, &spec, WindowConfig::default()).unwrap();
        for (k, &e) in m.window_ends.iter().enumerate() {
            if let Some(j) = whole.window_ends.iter().position(|&w| w == e) {
                assert_eq!(m.row(k), whole.row(j));
            }
        }
    }
}
