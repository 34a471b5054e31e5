//! Windowed features: layout, alignment, numerics and input checks, batch and streaming.

#![expect(
    clippy::unwrap_used,
    clippy::single_range_in_vec_init,
    reason = "a test stops at the first thing it did not expect; one-range vectors are the data under test"
)]

use crackbot_dsp::{
    extract_features, extract_segment_features, mav, rms, Channel, DspError, Feature, FeatureSet,
    FeatureSpec, Segment, StreamingFeatures, WindowConfig,
};

fn all_features(set: FeatureSet) -> FeatureSpec {
    FeatureSpec {
        features: Feature::ALL.to_vec(),
        set,
    }
}

fn stream_all(
    spec: &FeatureSpec,
    window: WindowConfig,
    samples: &[[f64; 4]],
) -> (Vec<f32>, Vec<usize>) {
    let mut s = StreamingFeatures::new(spec.clone(), window).unwrap();
    let mut data = Vec::new();
    let mut ends = Vec::new();
    for (t, x) in samples.iter().enumerate() {
        if let Some(row) = s.push(*x).unwrap() {
            data.extend_from_slice(row);
            ends.push(t);
            assert_eq!(s.last_window_end(), Some(t));
        }
    }
    (data, ends)
}

#[test]
fn feature_sets_and_names() {
    assert_eq!(FeatureSet::P.channels(), &[3]);
    assert_eq!(FeatureSet::D1D2D3.channels(), &[0, 1, 2]);
    assert_eq!(FeatureSet::D1D2D3P.channels(), &[0, 1, 2, 3]);
    assert_eq!(FeatureSet::D1D2P.channels(), &[0, 1, 3]);
    let names: Vec<_> = FeatureSet::ALL.iter().map(|s| s.name()).collect();
    assert_eq!(names, ["P", "D1D2D3", "D1D2D3+P", "D1D2+P"]);
    let spec = FeatureSpec {
        features: vec![Feature::Mav, Feature::Rms],
        set: FeatureSet::D1D2P,
    };
    assert_eq!(spec.n_features(), 6);
    assert_eq!(
        spec.column_names(),
        ["MAV_D1", "MAV_D2", "MAV_P", "RMS_D1", "RMS_D2", "RMS_P"]
    );
    assert_eq!(WindowConfig::default(), WindowConfig { len: 10, step: 2 });
    assert_eq!(Channel::P.index(), 3);
}

#[test]
fn window_ends_and_layout() {
    // 25 samples, windows of 10 with step 2: ends 9, 11, …, 23 (8 rows).
    let samples: Vec<[f64; 4]> = (0..25)
        .map(|i| {
            let i = i as f64;
            [i, 100.0 + i, 200.0 + i, 300.0 + i]
        })
        .collect();
    let spec = FeatureSpec {
        features: vec![Feature::Raw, Feature::Mav],
        set: FeatureSet::D1D2P,
    };
    let m = extract_features(&samples, &spec, WindowConfig::default()).unwrap();
    assert_eq!(m.window_ends, vec![9, 11, 13, 15, 17, 19, 21, 23]);
    assert_eq!(m.n_rows(), 8);
    assert_eq!(m.n_features, 6);
    assert_eq!(m.data.len(), 48);
    // Row 0: RAW = sample 9, MAV = mean of 0..=9 = 4.5 (+ offsets).
    assert_eq!(m.row(0).unwrap(), &[9.0, 109.0, 309.0, 4.5, 104.5, 304.5]);
    // Last row ends at 23: RAW 23, MAV mean of 14..=23 = 18.5.
    assert_eq!(m.row(7).unwrap(), &[23.0, 123.0, 323.0, 18.5, 118.5, 318.5]);
    assert!(m.row(8).is_none());
    assert_eq!(m.rows().count(), 8);
    // Shorter than a window: no rows, not an error.
    let short = extract_features(&samples[..9], &spec, WindowConfig::default()).unwrap();
    assert!(short.is_empty());
    assert_eq!(short.n_features, 6);
    let none = extract_features(&[], &spec, WindowConfig::default()).unwrap();
    assert!(none.is_empty());
}

#[test]
fn constant_windows_are_exact() {
    for v in [
        0.0,
        1.0,
        0.1,
        1023.0,
        511.5,
        677.0,
        1e-300,
        3.0e38,
        1.0 + f64::EPSILON,
    ] {
        let w = [v; 10];
        assert_eq!(mav(&w), v, "mav {v}");
        assert_eq!(rms(&w), v, "rms {v}");
        for len in 1..=17 {
            let w = vec![v; len];
            assert_eq!(mav(&w), v);
            assert_eq!(rms(&w), v);
        }
        let samples = vec![[v; 4]; 30];
        let m = extract_features(
            &samples,
            &all_features(FeatureSet::D1D2D3P),
            WindowConfig::default(),
        )
        .unwrap();
        assert!(m.data.iter().all(|&x| x == v as f32), "constant {v}");
    }
    // Negative constants: |value|.
    assert_eq!(mav(&[-3.7; 10]), 3.7);
    assert_eq!(rms(&[-3.7; 10]), 3.7);
}

/// MAV and RMS of integer ADC windows against exact integer arithmetic.
#[test]
fn near_adc_rails() {
    let windows: Vec<Vec<f64>> = vec![
        vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        vec![
            1023.0, 1023.0, 1023.0, 1023.0, 1023.0, 1023.0, 1023.0, 1023.0, 1023.0, 1022.0,
        ],
        vec![
            0.0, 1023.0, 0.0, 1023.0, 0.0, 1023.0, 0.0, 1023.0, 0.0, 1023.0,
        ],
        vec![1.0, 0.0, 2.0, 1022.0, 1021.0, 1023.0, 3.0, 0.0, 1020.0, 1.0],
        vec![0.0; 10],
    ];
    for w in &windows {
        let s1: u64 = w.iter().map(|&x| x as u64).sum();
        let s2: u64 = w.iter().map(|&x| (x as u64) * (x as u64)).sum();
        let exact_mav = s1 as f64 / 10.0; // correctly rounded: s1 exact, one division
        let exact_rms = (s2 as f64 / 10.0).sqrt();
        let got_mav = mav(w);
        let got_rms = rms(w);
        assert!(
            (got_mav - exact_mav).abs() <= 4.0 * f64::EPSILON * exact_mav,
            "{w:?}"
        );
        assert!(
            (got_rms - exact_rms).abs() <= 4.0 * f64::EPSILON * exact_rms,
            "{w:?}"
        );
        // And the f32 features are the correctly rounded f32 of the exact MAV.
        let samples: Vec<[f64; 4]> = w.iter().map(|&x| [x; 4]).collect();
        let m = extract_features(
            &samples,
            &FeatureSpec::new(Feature::Mav, FeatureSet::P),
            WindowConfig::default(),
        )
        .unwrap();
        assert_eq!(m.data, vec![exact_mav as f32]);
        let r = extract_features(
            &samples,
            &FeatureSpec::new(Feature::Rms, FeatureSet::P),
            WindowConfig::default(),
        )
        .unwrap();
        assert!((r.data[0] - exact_rms as f32).abs() <= f32::EPSILON * exact_rms as f32);
        assert!(r.data[0] >= 0.0 && r.data[0] <= 1023.0);
    }
}

#[test]
fn huge_values_do_not_overflow() {
    // Squaring 1e300 overflows f64; the scaled computation does not.
    let w = [
        1e300, -1e300, 1e300, 0.0, 2e300, 1e300, 1e300, 1e300, 1e300, 1e300,
    ];
    let m = mav(&w);
    let r = rms(&w);
    assert!(m.is_finite() && r.is_finite());
    assert!((m - 1e300).abs() <= 1e285, "{m}");
    // sqrt((8·1 + 0 + 4)/10)·1e300
    assert!((r - (1.2f64).sqrt() * 1e300).abs() <= 1e286, "{r}");
    assert_eq!(rms(&[f64::MAX; 10]), f64::MAX);
    assert_eq!(mav(&[f64::MAX; 10]), f64::MAX);
    assert_eq!(rms(&[f64::MAX, -f64::MAX]), f64::MAX);
    // Largest f32 values stay finite as f32 features.
    let samples = vec![[3.0e38, -3.4e38, 3.4e38, f32::MAX as f64]; 12];
    let mat = extract_features(
        &samples,
        &all_features(FeatureSet::D1D2D3P),
        WindowConfig::default(),
    )
    .unwrap();
    assert!(mat.data.iter().all(|x| x.is_finite()));
    assert_eq!(mat.row(0).unwrap()[2 * 4 + 3], f32::MAX); // RMS of P
}

#[test]
fn tiny_values_do_not_underflow() {
    // Squaring 1e-300 underflows to 0 in f64; the scaled computation does not.
    let w = [
        1e-300, 3e-300, 1e-300, 1e-300, 1e-300, 1e-300, 1e-300, 1e-300, 1e-300, 1e-300,
    ];
    let r = rms(&w);
    let expected = (1.8f64).sqrt() * 1e-300; // sqrt((9 + 9)/10)
    assert!((r - expected).abs() <= 1e-314, "{r} vs {expected}");
    assert!((mav(&w) - 1.2e-300).abs() <= 1e-314);
    // Subnormals.
    let d = f64::from_bits(1); // 4.9e-324
    assert_eq!(rms(&[d; 10]), d);
    assert_eq!(mav(&[d, 0.0]), 0.0); // mean d/2 rounds to 0: the nearest double
                                     // A tiny value beside a large one is negligible, not an error.
    assert_eq!(rms(&[1e-300, 0.0, 0.0, 0.0]), 5e-301);
    assert_eq!(rms(&[1.0, 1e-300]), (0.5f64).sqrt());
    // As f32 features, 1e-300 rounds to 0 (the nearest f32), without error.
    let samples = vec![[1e-300; 4]; 10];
    let m = extract_features(
        &samples,
        &all_features(FeatureSet::P),
        WindowConfig::default(),
    )
    .unwrap();
    assert_eq!(m.data, vec![0.0, 0.0, 0.0]);
    assert_eq!(mav(&[]), 0.0);
    assert_eq!(rms(&[]), 0.0);
}

#[test]
fn batch_rejects_non_finite_with_index_and_channel() {
    let spec = all_features(FeatureSet::D1D2P);
    let mut samples = vec![[600.0, 400.0, 700.0, 500.0]; 50];
    samples[17][2] = f64::NAN; // D3: not in the set, still rejected (a sample is valid only as a whole)
    samples[23][3] = f64::INFINITY;
    samples[45][0] = f64::NEG_INFINITY; // beyond the last window's end: still checked
    match extract_features(&samples, &spec, WindowConfig::default()) {
        Err(DspError::NonFinite {
            index,
            channel,
            value,
        }) => {
            assert_eq!((index, channel), (17, Channel::D3));
            assert!(value.is_nan());
        }
        other => panic!("{other:?}"),
    }
    samples[17][2] = 700.0;
    let err = extract_features(&samples, &spec, WindowConfig::default()).unwrap_err();
    assert_eq!(
        err,
        DspError::NonFinite {
            index: 23,
            channel: Channel::P,
            value: f64::INFINITY
        }
    );
    assert_eq!(
        err.to_string(),
        "sample 23, channel P: non-finite value inf"
    );
    samples[23][3] = 500.0;
    let err = extract_features(&samples, &spec, WindowConfig::default()).unwrap_err();
    assert!(matches!(
        err,
        DspError::NonFinite {
            index: 45,
            channel: Channel::D1,
            ..
        }
    ));
    samples[45][0] = 1e300;
    let err = extract_features(&samples, &spec, WindowConfig::default()).unwrap_err();
    assert_eq!(
        err,
        DspError::OutOfRange {
            index: 45,
            channel: Channel::D1,
            value: 1e300
        }
    );
}

#[test]
fn bad_configs_are_errors() {
    let samples = vec![[1.0; 4]; 20];
    let spec = FeatureSpec::new(Feature::Mav, FeatureSet::P);
    for w in [
        WindowConfig { len: 0, step: 2 },
        WindowConfig { len: 10, step: 0 },
    ] {
        assert!(matches!(
            extract_features(&samples, &spec, w),
            Err(DspError::InvalidConfig { .. })
        ));
        assert!(matches!(
            StreamingFeatures::new(spec.clone(), w),
            Err(DspError::InvalidConfig { .. })
        ));
    }
    let empty = FeatureSpec {
        features: vec![],
        set: FeatureSet::P,
    };
    assert!(matches!(
        extract_features(&samples, &empty, WindowConfig::default()),
        Err(DspError::InvalidConfig { .. })
    ));
    assert!(StreamingFeatures::new(empty, WindowConfig::default()).is_err());
    assert!(StreamingFeatures::new(
        spec,
        WindowConfig {
            len: usize::MAX,
            step: 1
        }
    )
    .is_err());
}

#[test]
fn streaming_rejects_bad_sample_and_stays_usable() {
    let spec = all_features(FeatureSet::D1D2D3P);
    let window = WindowConfig::default();
    let good: Vec<[f64; 4]> = (0..40)
        .map(|i| {
            let t = i as f64;
            [
                600.0 + t,
                400.0 - t,
                700.0 + (t * 0.3).sin(),
                500.0 + t * t * 0.01,
            ]
        })
        .collect();
    let mut s = StreamingFeatures::new(spec.clone(), window).unwrap();
    let mut rows = Vec::new();
    for (k, x) in good.iter().enumerate() {
        if k == 13 {
            // Bad samples interleaved: rejected with the stream index they would have had, nothing stored.
            let err = s.push([1.0, 2.0, f64::NAN, 4.0]).unwrap_err();
            assert!(matches!(
                err,
                DspError::NonFinite {
                    index: 13,
                    channel: Channel::D3,
                    ..
                }
            ));
            let err = s.push([f64::INFINITY, 2.0, 3.0, 4.0]).unwrap_err();
            assert!(matches!(
                err,
                DspError::NonFinite {
                    index: 13,
                    channel: Channel::D1,
                    ..
                }
            ));
            let err = s.push([1.0, 2.0, 3.0, -1e39]).unwrap_err();
            assert!(matches!(
                err,
                DspError::OutOfRange {
                    index: 13,
                    channel: Channel::P,
                    ..
                }
            ));
            assert_eq!(s.samples_seen(), 13);
        }
        if let Some(r) = s.push(*x).unwrap() {
            rows.extend_from_slice(r);
        }
    }
    let batch = extract_features(&good, &spec, window).unwrap();
    assert_eq!(rows, batch.data);
    assert_eq!(s.samples_seen(), 40);
    assert_eq!(s.last_window_end(), batch.window_ends.last().copied());
    // Reset starts over.
    s.reset();
    assert_eq!(s.samples_seen(), 0);
    assert_eq!(s.last_window_end(), None);
    let (again, ends) = stream_all(&spec, window, &good);
    let mut rows2 = Vec::new();
    for x in &good {
        if let Some(r) = s.push(*x).unwrap() {
            rows2.extend_from_slice(r);
        }
    }
    assert_eq!(rows2, again);
    assert_eq!(ends, batch.window_ends);
    assert_eq!(s.n_features(), 12);
    assert_eq!(s.spec(), &spec);
    assert_eq!(s.window(), window);
}

#[test]
fn streaming_matches_batch_on_a_long_signal() {
    // 200 000 samples (over 8 minutes at 400 Hz) of noisy ADC-like data: no drift between the forms.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let samples: Vec<[f64; 4]> = (0..200_000)
        .map(|i| {
            let t = i as f64 / 400.0;
            [
                (650.0 + 20.0 * (t * 3.0).sin() + 5.0 * next()).round(),
                (430.0 + 10.0 * next()).round(),
                700.0 + 30.0 * next(),
                (500.0 + 250.0 * (t * 0.7).sin() + next()).clamp(0.0, 1023.0),
            ]
        })
        .collect();
    for window in [WindowConfig::default(), WindowConfig { len: 7, step: 3 }] {
        let spec = all_features(FeatureSet::D1D2D3P);
        let batch = extract_features(&samples, &spec, window).unwrap();
        let (data, ends) = stream_all(&spec, window, &samples);
        assert_eq!(ends, batch.window_ends);
        assert_eq!(data.len(), batch.data.len());
        assert!(data
            .iter()
            .zip(&batch.data)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}

#[test]
fn segment_features_stay_inside_ranges() {
    let samples: Vec<[f64; 4]> = (0..100).map(|i| [i as f64; 4]).collect();
    let seg = Segment {
        ranges: vec![5..30, 50..59, 70..100],
        trial_len: 100,
    };
    let spec = FeatureSpec::new(Feature::Raw, FeatureSet::P);
    let m = extract_segment_features(&samples, &seg, &spec, WindowConfig::default()).unwrap();
    // 5..30: ends 14..=28 step 2 (8); 50..59: none (9 samples); 70..100: ends 79..=99 (11).
    let mut expected: Vec<usize> = (14..=28).step_by(2).collect();
    expected.extend((79..=99).step_by(2));
    assert_eq!(m.window_ends, expected);
    // RAW is the sample at the window end.
    assert!(m
        .window_ends
        .iter()
        .zip(&m.data)
        .all(|(&e, &v)| v == e as f32));
    // A segment of another trial is refused.
    let other = Segment {
        ranges: vec![0..10],
        trial_len: 99,
    };
    assert!(matches!(
        extract_segment_features(&samples, &other, &spec, WindowConfig::default()),
        Err(DspError::LengthMismatch { .. })
    ));
    let bad = Segment {
        ranges: vec![90..120],
        trial_len: 100,
    };
    assert!(matches!(
        extract_segment_features(&samples, &bad, &spec, WindowConfig::default()),
        Err(DspError::InvalidConfig { .. })
    ));
    #[expect(
        clippy::reversed_empty_ranges,
        reason = "an empty range is the case under test"
    )]
    let reversed = Segment {
        ranges: vec![50..40],
        trial_len: 100,
    };
    assert_eq!(reversed.kept(), 0);
    assert_eq!(reversed.span(), 50..50);
    assert!(extract_segment_features(&samples, &reversed, &spec, WindowConfig::default()).is_err());
    // Samples outside the ranges are not checked; inside, they are.
    let mut s2 = samples.clone();
    s2[40][1] = f64::NAN;
    assert!(extract_segment_features(&s2, &seg, &spec, WindowConfig::default()).is_ok());
    s2[75][1] = f64::NAN;
    assert!(matches!(
        extract_segment_features(&s2, &seg, &spec, WindowConfig::default()),
        Err(DspError::NonFinite {
            index: 75,
            channel: Channel::D2,
            ..
        })
    ));
}
