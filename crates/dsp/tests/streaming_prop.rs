//! Property: the streaming form emits exactly the batch form's rows, bit for bit, at the same window ends.

use crackbot_dsp::{
    extract_features, Feature, FeatureSet, FeatureSpec, StreamingFeatures, WindowConfig,
};
use proptest::prelude::*;

fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => (0u32..=1023).prop_map(f64::from),        // ADC counts
        2 => -1e6f64..1e6,                             // processed values, signs
        1 => prop_oneof![Just(0.0), Just(-0.0), Just(1023.0), Just(1e-300), Just(3e38), Just(-3e38)],
        1 => (-1e30f64..1e30).prop_map(|x| x * 1e-300), // tiny and subnormal
    ]
}

fn spec() -> impl Strategy<Value = FeatureSpec> {
    (
        prop::collection::vec(prop::sample::select(Feature::ALL.to_vec()), 1..5),
        prop::sample::select(FeatureSet::ALL.to_vec()),
    )
        .prop_map(|(features, set)| FeatureSpec { features, set })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn streaming_equals_batch(
        samples in prop::collection::vec([value(), value(), value(), value()], 0..300),
        len in 1usize..=24,
        step in 1usize..=12,
        spec in spec(),
    ) {
        let window = WindowConfig { len, step };
        let batch = extract_features(&samples, &spec, window).unwrap();
        prop_assert_eq!(batch.n_rows(), window.n_windows(samples.len()));
        prop_assert_eq!(batch.data.len(), batch.n_rows() * spec.n_features());
        let mut stream = StreamingFeatures::new(spec.clone(), window).unwrap();
        let mut rows = 0;
        for (t, x) in samples.iter().enumerate() {
            if let Some(row) = stream.push(*x).unwrap() {
                prop_assert_eq!(batch.window_ends.get(rows).copied(), Some(t));
                let expected = batch.row(rows).unwrap();
                prop_assert_eq!(row, expected);
                let bits: Vec<u32> = row.iter().map(|v| v.to_bits()).collect();
                let expected_bits: Vec<u32> = expected.iter().map(|v| v.to_bits()).collect();
                prop_assert_eq!(bits, expected_bits);
                prop_assert_eq!(stream.last_window_end(), Some(t));
                rows += 1;
            }
        }
        prop_assert_eq!(rows, batch.n_rows());
        prop_assert!(batch.data.iter().all(|v| v.is_finite()));
    }
}
