//! Property tests: training and prediction never panic and always give proper probabilities.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use crackbot_forest::{
    Classifier, Dataset, ForestParams, Knn, KnnParams, MaxFeatures, Qda, QdaParams, RandomForest,
};
use proptest::prelude::*;

fn dataset() -> impl Strategy<Value = Dataset> {
    (1usize..4, 1usize..5, 1usize..40).prop_flat_map(|(nf, nc, n)| {
        (
            // Few distinct values: many ties, constant features, duplicate rows.
            proptest::collection::vec(
                prop_oneof![Just(0.0f32), Just(1.5), Just(-2.0), -1e3f32..1e3],
                n * nf,
            ),
            proptest::collection::vec(0u32..nc as u32, n),
        )
            .prop_map(move |(x, y)| Dataset::with_classes(x, nf, y, nc).unwrap())
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn forest_is_total(data in dataset(), depth in prop_oneof![Just(None), (1usize..4).prop_map(Some)],
                       msl in 1usize..4, mf in 1usize..4, boot in any::<bool>(), q in proptest::collection::vec(-1e3f32..1e3, 4)) {
        let params = ForestParams::classifier().n_trees(3).max_depth(depth).min_samples_leaf(msl)
            .max_features(MaxFeatures::Count(mf)).bootstrap(boot).quiet(true);
        let f = RandomForest::fit(&data, &params).unwrap();
        prop_assert!(f.max_depth() <= depth.unwrap_or(usize::MAX));
        let row = &q[..data.n_features()];
        let p = f.predict_proba(row);
        prop_assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        prop_assert!((f.predict(row) as usize) < data.n_classes());
        // Training rows: batch equals single.
        let mut out = vec![0u32; data.n_rows()];
        f.predict_batch(data.x(), data.n_features(), &mut out).unwrap();
        for (i, &c) in out.iter().enumerate() {
            prop_assert_eq!(c, f.predict(data.row(i).unwrap()));
        }
        prop_assert_eq!(RandomForest::from_bytes(&f.to_bytes()).unwrap(), f);
    }

    #[test]
    fn knn_and_qda_are_total(data in dataset(), q in proptest::collection::vec(-1e4f32..1e4, 4), std in any::<bool>(), r in 0.0f64..1.0) {
        let row = &q[..data.n_features()];
        let k = data.n_rows().min(5);
        let knn = Knn::fit(&data, KnnParams { k, standardize: std }).unwrap();
        let p = knn.predict_proba(row);
        prop_assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        let qda = Qda::fit(&data, QdaParams { reg_param: r, standardize: std }).unwrap();
        let p = qda.predict_proba(row);
        prop_assert!(p.iter().all(|v| v.is_finite()), "{:?}", p);
        prop_assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-4, "{:?}", p);
    }
}
