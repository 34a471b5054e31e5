//! The streaming context features equal the offline ones bit for bit: on every real recording
//! (every sample of every slide, spans reaching across slides), through the window pipeline, and
//! on random signals with random slides, configurations and extreme values (proptest).

// Helpers shared by the tests unwrap too: a failure there is a failed test.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::PathBuf;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::context::{context_row, ContextConfig, WindowPlace};
use crackbot_tactile::dataset::{Experiment, Normalisation, PipelineConfig, Segmentation};
use crackbot_tactile::stream::StreamingContext;
use proptest::prelude::*;
use rayon::prelude::*;

/// D1, D2, P: the deployed channel set.
const CHANNELS: [usize; 3] = [0, 1, 3];

/// Streams `samples` (slides starting where `starts` says) and compares the row after every
/// sample with the offline row of a window ending there. Returns the number of rows compared.
fn compare_all(
    config: &ContextConfig,
    samples: &[[f64; 4]],
    directions: &[u8],
    starts: &[bool],
    window_len: usize,
    every: usize,
) -> usize {
    let mut stream = StreamingContext::new(config, &CHANNELS, window_len).unwrap();
    let mut online = vec![0f32; stream.n_values()];
    let mut offline = Vec::new();
    let mut slide_start = 0;
    let mut compared = 0;
    for (i, (&s, &d)) in samples.iter().zip(directions).enumerate() {
        if starts[i] {
            stream.begin_slide();
            slide_start = i;
        }
        stream.push(s, d).unwrap();
        if i % every != 0 {
            continue;
        }
        stream.row_into(&mut online).unwrap();
        offline.clear();
        let place = WindowPlace {
            samples,
            directions,
            slide_start,
            end: i,
        };
        context_row(config, place, &CHANNELS, window_len, &mut offline);
        let same = online
            .iter()
            .zip(&offline)
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(
            same && offline.len() == online.len(),
            "sample {i} (slide from {slide_start}): streaming {online:?} != offline {offline:?}"
        );
        compared += 1;
    }
    compared
}

fn recordings() -> Vec<(PathBuf, Recording)> {
    let dirs = [
        crackbot_datasets::require(crackbot_datasets::TACTILE_TYPE),
        crackbot_datasets::require(crackbot_datasets::TACTILE_WIDTH),
    ];
    collect_recordings(&dirs).unwrap()
}

#[test]
fn every_real_recording_streams_to_the_offline_rows_bit_for_bit() {
    let recs = recordings();
    assert_eq!(recs.len(), 30, "types and widths, repetitions 1–3");
    let config = ContextConfig::default();
    // The state is updated at every sample; rows are compared at every 16th (every sample of two
    // files, to keep the test short: each offline row reads up to 2000 samples back).
    let total: usize = recs
        .par_iter()
        .enumerate()
        .map(|(k, (path, rec))| {
            let samples: Vec<[f64; 4]> = rec
                .rows
                .iter()
                .map(crackbot_recording::Row::channels)
                .collect();
            let directions: Vec<u8> = rec.rows.iter().map(|r| r.direction).collect();
            let mut starts = vec![false; samples.len()];
            for r in rec.slides() {
                starts[r.start] = true;
            }
            let every = if k % 15 == 0 { 1 } else { 16 };
            let n = compare_all(&config, &samples, &directions, &starts, 10, every);
            assert_eq!(n, samples.len().div_ceil(every), "{}", path.display());
            n
        })
        .sum();
    assert!(total > 120_000, "{total} rows");
}

#[test]
fn the_pipeline_windows_are_the_streaming_rows_at_their_ends() {
    // The deployed pipeline: the paper's segmentation and windows, context features only.
    let recs = recordings();
    let recs: Vec<_> = recs
        .into_iter()
        .filter(|(p, _)| p.to_string_lossy().contains("_complete_2"))
        .take(2)
        .collect();
    let config = PipelineConfig {
        context: Some(ContextConfig::default()),
        normalisation: Normalisation::None,
        ..PipelineConfig::default()
    };
    assert!(matches!(config.segmentation, Segmentation::Method(_)));
    let set = config
        .check()
        .unwrap()
        .build_windows(&recs[..1], Experiment::Recognition)
        .unwrap();
    let (_, rec) = &recs[0];
    let slides = rec.slides();
    let mut stream = StreamingContext::new(&ContextConfig::default(), &CHANNELS, 10).unwrap();
    let mut row = vec![0f32; stream.n_values()];
    // Every window row equals the streaming row at some sample of its slide (its end).
    let mut rows_at: Vec<Vec<Vec<u32>>> = Vec::new();
    for range in &slides {
        stream.begin_slide();
        let mut this = Vec::new();
        for r in &rec.rows[range.clone()] {
            stream.push(r.channels(), r.direction).unwrap();
            stream.row_into(&mut row).unwrap();
            this.push(row.iter().map(|v| v.to_bits()).collect());
        }
        rows_at.push(this);
    }
    let mut matched = 0;
    for slide in &set.slides {
        let i = slides
            .iter()
            .position(|r| rec.rows[r.start].slide == slide.slide)
            .unwrap();
        for w in slide.windows.clone() {
            let bits: Vec<u32> = set.row(w).iter().map(|v| v.to_bits()).collect();
            assert!(
                rows_at[i].contains(&bits),
                "window {w} of slide {} has no streaming twin",
                slide.slide
            );
            matched += 1;
        }
    }
    assert_eq!(matched, set.n_rows());
    assert!(matched > 10_000);
}

fn config_strategy() -> impl Strategy<Value = ContextConfig> {
    (
        prop::collection::vec(1usize..60, 1..4),
        1usize..12,
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(
            |(scales, baseline_len, prefix, direction, across_slides)| ContextConfig {
                scales,
                baseline_len,
                prefix,
                direction,
                keep_window: false,
                across_slides,
                shape: false,
            },
        )
}

fn value_strategy() -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => (400.0f64..700.0).prop_map(f64::round),
        2 => -1.0e7f64..1.0e7,
        1 => Just(8191.4),
        1 => Just(-4096.6),
        1 => Just(1.0e30),
        1 => 0.0f64..1.0,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_signals_and_slides_stream_to_the_offline_rows(
        config in config_strategy(),
        window_len in 1usize..15,
        signal in prop::collection::vec(
            (prop::array::uniform4(value_strategy()), 0u8..2, prop::bool::weighted(0.05)),
            1..300,
        ),
    ) {
        let samples: Vec<[f64; 4]> = signal.iter().map(|s| s.0).collect();
        let directions: Vec<u8> = signal.iter().map(|s| s.1).collect();
        let mut starts: Vec<bool> = signal.iter().map(|s| s.2).collect();
        starts[0] = true;
        let n = compare_all(&config, &samples, &directions, &starts, window_len, 1);
        prop_assert_eq!(n, samples.len());
    }
}

#[test]
fn bad_samples_and_configurations_are_refused_clearly() {
    let mut stream = StreamingContext::new(&ContextConfig::default(), &CHANNELS, 10).unwrap();
    let mut row = vec![0f32; stream.n_values()];
    let err = stream.row_into(&mut row).unwrap_err().to_string();
    assert!(err.contains("no sample"), "{err}");
    stream.push([600.0, 400.0, 700.0, 500.0], 0).unwrap();
    let err = stream
        .push([600.0, f64::NAN, 700.0, 500.0], 0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("D2"), "{err}");
    // The refused sample left no trace: the row is that of the single good sample.
    stream.row_into(&mut row).unwrap();
    assert_eq!(row[0], 0.0);
    assert!(stream.row_into(&mut [0.0; 3]).is_err());
    let shape = ContextConfig {
        shape: true,
        ..ContextConfig::default()
    };
    assert!(StreamingContext::new(&shape, &CHANNELS, 10).is_err());
    assert!(StreamingContext::new(&ContextConfig::default(), &[4], 10).is_err());
    assert!(StreamingContext::new(&ContextConfig::default(), &CHANNELS, 0).is_err());
}

/// Windows of `recs` built by `config`'s fast (streaming) pipeline and by its reference
/// (`context_row` per window): equal bit for bit, with the same labels and slides.
fn assert_fast_equals_reference(config: &PipelineConfig, recs: &[(PathBuf, Recording)]) -> usize {
    let pipeline = config.check().unwrap();
    let experiment = Experiment::detect(
        &recs
            .iter()
            .filter_map(|(_, r)| r.label())
            .collect::<Vec<_>>(),
    )
    .unwrap_or(Experiment::Recognition);
    let fast = pipeline.build_windows(recs, experiment);
    let reference = pipeline
        .with_reference_context()
        .build_windows(recs, experiment);
    let (fast, reference) = match (fast, reference) {
        (Ok(f), Ok(r)) => (f, r),
        (Err(f), Err(r)) => {
            assert_eq!(f.to_string(), r.to_string());
            return 0;
        }
        (f, r) => panic!("fast {:?} but reference {:?}", f.err(), r.err()),
    };
    assert_eq!(fast.n_features, reference.n_features);
    assert_eq!(fast.y, reference.y);
    assert_eq!(fast.slides.len(), reference.slides.len());
    assert_eq!(fast.x.len(), reference.x.len());
    for (i, (a, b)) in fast.x.iter().zip(&reference.x).enumerate() {
        assert!(
            a.to_bits() == b.to_bits(),
            "value {i} (row {}): fast {a} != reference {b}",
            i / fast.n_features.max(1)
        );
    }
    fast.n_rows()
}

#[test]
fn the_fast_pipeline_builds_the_reference_windows_bit_for_bit_on_real_recordings() {
    let recs = recordings();
    let recs: Vec<_> = recs
        .into_iter()
        .filter(|(p, _)| {
            let p = p.to_string_lossy();
            p.contains("crack_bump_complete_3") || p.contains("crack_mm10_complete_1")
        })
        .collect();
    assert_eq!(recs.len(), 2);
    let robust = Segmentation::Method(crackbot_dsp::SegmentationMethod::Robust(
        crackbot_dsp::RobustSegmentation::default(),
    ));
    let configs = [
        // The deployed pipeline.
        PipelineConfig {
            context: Some(ContextConfig::default()),
            ..PipelineConfig::default()
        },
        // Whole slides, spans confined to each slide, medians removed, the window kept.
        PipelineConfig {
            segmentation: Segmentation::None,
            normalisation: Normalisation::RecordingMedian,
            context: Some(ContextConfig {
                across_slides: false,
                keep_window: true,
                prefix: false,
                ..ContextConfig::default()
            }),
            ..PipelineConfig::default()
        },
        PipelineConfig {
            segmentation: robust,
            context: Some(ContextConfig {
                scales: vec![7, 333],
                baseline_len: 1,
                direction: false,
                ..ContextConfig::default()
            }),
            ..PipelineConfig::default()
        },
    ];
    let rows: usize = configs
        .par_iter()
        .flat_map(|c| recs.par_iter().map(move |r| (c, r)))
        .map(|(c, r)| assert_fast_equals_reference(c, std::slice::from_ref(r)))
        .sum();
    assert!(rows > 5_000, "{rows} windows compared");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random recordings (slides of random lengths, some shorter than the pipeline keeps, random
    /// levels and dips) through random pipelines: the fast windows are the reference's.
    #[test]
    fn random_recordings_build_the_reference_windows(
        context in config_strategy(),
        keep_window in any::<bool>(),
        whole_slides in any::<bool>(),
        median in any::<bool>(),
        min_slide_len in 1usize..40,
        slides in prop::collection::vec((5usize..120, 300.0f64..700.0, 0usize..30), 1..6),
    ) {
        let mut rows = Vec::new();
        for (k, &(len, level, dip)) in slides.iter().enumerate() {
            for i in 0..len {
                let p = if i >= dip && i < dip + 8 { level - 150.0 } else { level };
                rows.push(crackbot_recording::Row {
                    x_mm: i as f64 * 0.01,
                    d1: 650.0 + (i % 7) as f64,
                    d2: 430.0 - (i % 5) as f64,
                    d3: 700.0,
                    p,
                    direction: u8::from(i >= len / 2),
                    slide: 1 + k as u32,
                    label: 1.0,
                    repetition: 1,
                });
            }
        }
        let recs = vec![(PathBuf::from("random.csv"), Recording { rows, extra: None })];
        let config = PipelineConfig {
            segmentation: if whole_slides {
                Segmentation::None
            } else {
                PipelineConfig::default().segmentation
            },
            normalisation: if median { Normalisation::RecordingMedian } else { Normalisation::None },
            min_slide_len,
            context: Some(ContextConfig { keep_window, ..context }),
            ..PipelineConfig::default()
        };
        let n = assert_fast_equals_reference(&config, &recs);
        // Whole slides of at least a window (10 samples) that the pipeline keeps give windows.
        if whole_slides && slides.iter().any(|s| s.0 >= min_slide_len.max(10)) {
            prop_assert!(n > 0);
        }
    }
}
