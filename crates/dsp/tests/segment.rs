//! Segmentation on synthetic signals: the paper's eq. 2 and its variants, the robust method, the measurement.

use crackbot_dsp::{
    measure_segmentation, segment_paper, segment_robust, Channel, DspError, Extent, MarginBase,
    PaperSegmentation, RobustSegmentation, Segment, SegmentationMethod,
};

/// Straightforward eq. 2: indices `i` with `Δp_i > |Δp̄|` (or `|Δp_i|`).
fn passing(p: &[f64], n: usize, magnitude: bool) -> Vec<usize> {
    let d: Vec<f64> = (0..p.len() - n)
        .map(|i| (p[i + n] - p[i]) / n as f64)
        .collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    (0..d.len())
        .filter(|&i| (if magnitude { d[i].abs() } else { d[i] }) > mean.abs())
        .collect()
}

/// 100 flat samples at 500, a linear rise over 10 samples to 600, flat.
fn step_up(m: usize, at: usize) -> Vec<f64> {
    (0..m)
        .map(|i| {
            if i < at {
                500.0
            } else if i < at + 10 {
                500.0 + 10.0 * (i - at) as f64
            } else {
                600.0
            }
        })
        .collect()
}

#[test]
fn paper_span_with_trial_margins() {
    let p = step_up(200, 100);
    // Δp̄ = 100/190 ≈ 0.53; Δp_i > 0.53 for i in 91..=109 (windows that see some of the rise).
    let kept = passing(&p, 10, false);
    assert_eq!((kept[0], *kept.last().unwrap()), (91, 109));
    let s = segment_paper(&p, 10).unwrap();
    // 10 % of 200 = 20 on each side.
    assert_eq!(s.ranges, vec![71..130]);
    assert_eq!(s.trial_len, 200);
    assert_eq!(s.span(), 71..130);
    assert_eq!(s.kept(), 59);
    assert!((s.fraction_kept() - 59.0 / 200.0).abs() < 1e-12);
    assert!(s.contains(71) && s.contains(129) && !s.contains(130) && !s.contains(70));
    // Margins clamp at the trial's ends.
    let p = step_up(200, 5);
    assert_eq!(segment_paper(&p, 10).unwrap().ranges, vec![0..35]);
}

#[test]
fn paper_signed_test_ignores_falls_magnitude_does_not() {
    // Fall at 50, rise at 150: the mean derivative is 0, the signed test keeps the rise only.
    let p: Vec<f64> = (0..300)
        .map(|i| if (50..150).contains(&i) { 300.0 } else { 500.0 })
        .collect();
    let signed = segment_paper(&p, 10).unwrap();
    // Δp_i > 0 for i in 140..150; margins 30.
    assert_eq!(signed.ranges, vec![110..180]);
    let magnitude = PaperSegmentation {
        magnitude: true,
        ..Default::default()
    }
    .segment(&p)
    .unwrap();
    // |Δp_i| > 0 for i in 40..50 and 140..150.
    assert_eq!(magnitude.ranges, vec![10..180]);
    let points = PaperSegmentation {
        magnitude: true,
        extent: Extent::Points,
        margin_fraction: 0.02,
        ..Default::default()
    }
    .segment(&p)
    .unwrap();
    assert_eq!(points.ranges, vec![34..56, 134..156]);
    // Margin of the extracted part: 10 % of the kept points (20) = 2.
    let extracted = PaperSegmentation {
        magnitude: true,
        extent: Extent::Points,
        margin_base: MarginBase::Extracted,
        ..Default::default()
    }
    .segment(&p)
    .unwrap();
    assert_eq!(extracted.ranges, vec![38..52, 138..152]);
    // Margin of the span (110 samples for 40..=149 → 11).
    let span_extracted = PaperSegmentation {
        magnitude: true,
        margin_base: MarginBase::Extracted,
        ..Default::default()
    }
    .segment(&p)
    .unwrap();
    assert_eq!(span_extracted.ranges, vec![29..161]);
}

#[test]
fn paper_matches_reference_on_noisy_signals() {
    let mut state = 12345u64;
    for trial in 0..50 {
        let m = 50 + trial * 37;
        let p: Vec<f64> = (0..m)
            .map(|i| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let noise = ((state >> 33) % 7) as f64;
                500.0 + noise + if i > m / 3 && i < m / 2 { -200.0 } else { 0.0 }
            })
            .collect();
        for magnitude in [false, true] {
            let kept = passing(&p, 10, magnitude);
            let s = PaperSegmentation {
                magnitude,
                ..Default::default()
            }
            .segment(&p)
            .unwrap();
            let pad = (0.1 * m as f64).round() as usize;
            let expected = kept[0].saturating_sub(pad)..(kept[kept.len() - 1] + 1 + pad).min(m);
            assert_eq!(s.ranges, vec![expected]);
            let pts = PaperSegmentation {
                magnitude,
                extent: Extent::Points,
                margin_fraction: 0.0,
                ..Default::default()
            }
            .segment(&p)
            .unwrap();
            let mask: Vec<usize> = (0..m).filter(|&i| pts.contains(i)).collect();
            assert_eq!(mask, kept);
        }
    }
}

#[test]
fn paper_edge_cases() {
    // Constant: nothing passes, empty (no margins).
    let s = segment_paper(&[512.0; 100], 10).unwrap();
    assert!(s.is_empty());
    assert_eq!(s.span(), 0..0);
    assert_eq!(s.trial_len, 100);
    // A pure ramp: every Δp_i equals Δp̄, nothing is strictly greater.
    let ramp: Vec<f64> = (0..100).map(|i| i as f64 * 2.0).collect();
    assert!(segment_paper(&ramp, 10).unwrap().is_empty());
    // Too short.
    assert_eq!(
        segment_paper(&[1.0; 10], 10),
        Err(DspError::TooShort { len: 10, min: 11 })
    );
    assert!(segment_paper(&[1.0, 2.0], 1).is_ok());
    assert!(segment_paper(&[], 10).is_err());
    // Bad configuration.
    assert!(matches!(
        segment_paper(&[1.0; 100], 0),
        Err(DspError::InvalidConfig { .. })
    ));
    for f in [-0.1, f64::NAN, f64::INFINITY] {
        let c = PaperSegmentation {
            margin_fraction: f,
            ..Default::default()
        };
        assert!(matches!(
            c.segment(&[1.0; 100]),
            Err(DspError::InvalidConfig { .. })
        ));
    }
    // A huge margin fraction saturates: the whole trial.
    let c = PaperSegmentation {
        margin_fraction: 1e300,
        ..Default::default()
    };
    assert_eq!(c.segment(&step_up(100, 50)).unwrap().ranges, vec![0..100]);
    // Non-finite proximity: error naming the sample and channel P.
    let mut p = step_up(100, 50);
    p[42] = f64::NAN;
    assert!(matches!(
        segment_paper(&p, 10),
        Err(DspError::NonFinite {
            index: 42,
            channel: Channel::P,
            ..
        })
    ));
    p[42] = 1e300;
    assert!(matches!(
        segment_robust(&p),
        Err(DspError::OutOfRange {
            index: 42,
            channel: Channel::P,
            ..
        })
    ));
}

/// An out-and-back slide over a crack: flat at ~520 with ±8 counts of texture, the proximity drops to ~270 over
/// the crack on the way out and on the way back.
fn crack_slide() -> (Vec<f64>, [std::ops::Range<usize>; 2]) {
    let m = 2800;
    let cracks = [700..1000, 1800..2100];
    let p = (0..m)
        .map(|i| {
            let texture = 8.0 * ((i as f64) * 0.05).sin() + 3.0 * ((i as f64) * 0.7).sin();
            let depth = cracks
                .iter()
                .map(|r| {
                    // 20-sample ramps in and out.
                    let into = (i as f64 - r.start as f64) / 20.0;
                    let out = (r.end as f64 - i as f64) / 20.0;
                    into.min(out).clamp(0.0, 1.0)
                })
                .fold(0.0, f64::max);
            (520.0 + texture - 250.0 * depth).round()
        })
        .collect();
    (p, cracks)
}

#[test]
fn robust_finds_both_crossings() {
    let (p, cracks) = crack_slide();
    let s = segment_robust(&p).unwrap();
    assert_eq!(s.ranges.len(), 2, "{:?}", s.ranges);
    for (r, c) in s.ranges.iter().zip(&cracks) {
        // Covers the crack, with no more than the ramp, the smoothing and the pad around it.
        assert!(r.start <= c.start && r.end >= c.end, "{r:?} vs {c:?}");
        assert!(
            c.start - r.start <= 40 && r.end - c.end <= 40,
            "{r:?} vs {c:?}"
        );
    }
    // The paper's faithful reading covers nearly the whole slide.
    let paper = segment_paper(&p, 10).unwrap();
    assert!(paper.fraction_kept() > 0.9, "{}", paper.fraction_kept());
}

#[test]
fn robust_keeps_nothing_on_a_flat_slide() {
    let p: Vec<f64> = (0..2800)
        .map(|i| (520.0 + 8.0 * ((i as f64) * 0.05).sin() + 3.0 * ((i as f64) * 0.7).sin()).round())
        .collect();
    assert!(segment_robust(&p).unwrap().is_empty());
    assert!(segment_robust(&[600.0; 5]).unwrap().is_empty());
    assert!(segment_robust(&[600.0]).unwrap().is_empty());
    assert_eq!(
        segment_robust(&[]),
        Err(DspError::TooShort { len: 0, min: 1 })
    );
}

#[test]
fn robust_parameters() {
    let (p, _) = crack_slide();
    // A large merge gap joins the two crossings.
    let joined = RobustSegmentation {
        min_gap: 1000,
        ..Default::default()
    }
    .segment(&p)
    .unwrap();
    assert_eq!(joined.ranges.len(), 1);
    // A minimum span longer than a crossing drops both.
    let none = RobustSegmentation {
        min_span: 400,
        ..Default::default()
    }
    .segment(&p)
    .unwrap();
    assert!(none.is_empty());
    // Pad widens; ranges stay inside the trial.
    let padded = RobustSegmentation {
        pad: 5000,
        ..Default::default()
    }
    .segment(&p)
    .unwrap();
    assert_eq!(padded.ranges, vec![0..p.len()]);
    // Invalid parameters.
    for bad in [
        RobustSegmentation {
            smooth: 0,
            ..Default::default()
        },
        RobustSegmentation {
            edge_fraction: 0.0,
            ..Default::default()
        },
        RobustSegmentation {
            edge_fraction: 0.7,
            ..Default::default()
        },
        RobustSegmentation {
            k_exit: 7.0,
            ..Default::default()
        },
        RobustSegmentation {
            min_exit: 40.0,
            ..Default::default()
        },
        RobustSegmentation {
            k_enter: f64::NAN,
            ..Default::default()
        },
    ] {
        assert!(
            matches!(bad.segment(&p), Err(DspError::InvalidConfig { .. })),
            "{bad:?}"
        );
    }
}

#[test]
fn measurement_summarises_per_slide() {
    let (crack, _) = crack_slide();
    let flat = vec![520.0; 2800];
    let short = vec![520.0; 1];
    let slides: Vec<&[f64]> = vec![&crack, &flat, &short];
    let robust = measure_segmentation(
        &SegmentationMethod::Robust(RobustSegmentation::default()),
        slides.clone(),
    );
    assert_eq!(robust.method, "robust");
    assert_eq!(robust.slides.len(), 3);
    assert_eq!(robust.summary.n_slides, 3);
    assert_eq!(robust.summary.n_failed, 0);
    assert_eq!(robust.summary.n_empty, 2);
    let s0 = &robust.slides[0];
    assert!(!s0.empty && s0.error.is_none());
    assert_eq!(s0.segment.as_ref().map(Segment::kept), Some(s0.kept));
    assert_eq!(s0.span_len, s0.span.end - s0.span.start);
    assert!((robust.summary.mean_ranges - 2.0 / 3.0).abs() < 1e-12);
    assert!(
        (robust.summary.overall_fraction_kept - s0.kept as f64 / 5601.0).abs() < 1e-12,
        "{:?}",
        robust.summary
    );
    assert_eq!(robust.summary.min_fraction_kept, 0.0);
    assert_eq!(robust.summary.max_fraction_kept, s0.fraction_kept);

    let paper = measure_segmentation(
        &SegmentationMethod::Paper(PaperSegmentation::default()),
        slides,
    );
    assert_eq!(paper.method, "paper");
    // The one-sample slide is too short for eq. 2: recorded, not propagated.
    assert_eq!(paper.summary.n_failed, 1);
    assert!(paper.slides[2]
        .error
        .as_deref()
        .unwrap_or("")
        .contains("too short"));
    assert!(paper.slides[2].empty);
    assert_eq!(paper.summary.n_empty, 1); // the flat slide
                                          // Serialisable for the evaluation's reports.
    fn is_serialize<T: serde::Serialize>(_: &T) {}
    is_serialize(&paper);
    let empty = measure_segmentation(
        &SegmentationMethod::Paper(PaperSegmentation::default()),
        Vec::<&[f64]>::new(),
    );
    assert_eq!(empty.summary.n_slides, 0);
    assert_eq!(empty.summary.mean_fraction_kept, 0.0);
}
