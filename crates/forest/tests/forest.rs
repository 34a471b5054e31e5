//! Random-forest classifier: training semantics, determinism, inference paths, bad input.

use std::time::Instant;

use crackbot_forest::{
    accuracy, synthetic, Classifier, Dataset, ForestError, ForestParams, MaxFeatures, RandomForest,
};

fn quiet(n_trees: usize) -> ForestParams {
    ForestParams::classifier()
        .n_trees(n_trees)
        .seed(3)
        .quiet(true)
}

#[test]
fn learns_overlapping_blobs() {
    let data = synthetic::blobs(4_000, 3, 4, 50.0, 11).unwrap();
    let (train, test) = data.split_at(3_000).unwrap();
    let forest = RandomForest::fit(&train, &quiet(30)).unwrap();
    let acc_train = accuracy(&forest, &train);
    let acc_test = accuracy(&forest, &test);
    assert!(
        acc_train > 0.97,
        "fully grown trees fit the bootstrap data: {acc_train}"
    );
    assert!(acc_test > 0.7, "test accuracy {acc_test}");
    let imp = forest.feature_importances().unwrap();
    assert_eq!(imp.len(), 3);
    assert!((imp.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    assert!(imp.iter().all(|&v| v > 0.0));
}

#[test]
fn same_seed_same_model_regardless_of_threads() {
    let data = synthetic::blobs(2_000, 3, 4, 60.0, 5).unwrap();
    let one = RandomForest::fit(&data, &quiet(12).n_threads(Some(1))).unwrap();
    let two = RandomForest::fit(&data, &quiet(12).n_threads(Some(2))).unwrap();
    let three = RandomForest::fit(&data, &quiet(12).n_threads(Some(3))).unwrap();
    let global = RandomForest::fit(&data, &quiet(12)).unwrap();
    assert_eq!(one.to_bytes(), two.to_bytes());
    assert_eq!(one.to_bytes(), three.to_bytes());
    assert_eq!(one.to_bytes(), global.to_bytes());
    let other = RandomForest::fit(&data, &quiet(12).seed(4)).unwrap();
    assert_ne!(one.to_bytes(), other.to_bytes());
    // A tree depends on (seed, index) only: the first 6 trees of a 12-tree forest equal a 6-tree forest.
    let six = RandomForest::fit(&data, &quiet(6)).unwrap();
    let end = six.tree_offsets()[6] as usize;
    assert_eq!(&one.nodes()[..end], six.nodes());
}

#[test]
fn probabilities_and_batch_paths_agree() {
    let data = synthetic::blobs(3_000, 3, 4, 70.0, 8).unwrap();
    let (train, test) = data.split_at(2_000).unwrap();
    let forest = RandomForest::fit(&train, &quiet(17)).unwrap();
    let n = test.n_rows();
    let mut batch = vec![0u32; n];
    forest.predict_batch(test.x(), 3, &mut batch).unwrap();
    let mut par = vec![0u32; n];
    forest.par_predict_batch(test.x(), 3, &mut par).unwrap();
    let mut proba = vec![0f32; n * 4];
    forest.predict_proba_batch(test.x(), 3, &mut proba).unwrap();
    for i in 0..n {
        let row = test.row(i).unwrap();
        let p = forest.predict_proba(row);
        assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert!(p.iter().all(|v| (0.0..=1.0).contains(v)));
        assert_eq!(&proba[i * 4..i * 4 + 4], &p[..], "row {i}");
        let c = forest.predict(row);
        assert_eq!(c, crackbot_forest::argmax(&p), "row {i}");
        assert_eq!(batch[i], c, "row {i}");
        assert_eq!(par[i], c, "row {i}");
        assert_eq!(forest.try_predict(row).unwrap(), c);
        assert_eq!(forest.predict_label(row), c as f64);
    }
}

#[test]
fn labels_can_be_widths() {
    let data = synthetic::blobs(600, 3, 6, 40.0, 2).unwrap();
    let widths = vec![0.0, 1.0, 2.0, 5.0, 8.0, 10.0];
    let forest = RandomForest::fit(&data, &quiet(5))
        .unwrap()
        .with_class_labels(widths.clone())
        .unwrap();
    assert_eq!(forest.class_labels(), &widths[..]);
    let row = data.row(0).unwrap();
    assert_eq!(
        forest.predict_label(row),
        widths[forest.predict(row) as usize]
    );
    assert!(forest.clone().with_class_labels(vec![1.0]).is_err());
    assert!(forest.with_class_labels(vec![f64::NAN; 6]).is_err());
}

#[test]
fn depth_and_leaf_size_limits() {
    let data = synthetic::blobs(2_000, 3, 4, 80.0, 9).unwrap();
    let shallow = RandomForest::fit(&data, &quiet(5).max_depth(Some(4))).unwrap();
    assert!(shallow.max_depth() <= 4);
    let full = RandomForest::fit(&data, &quiet(5)).unwrap();
    assert!(full.max_depth() > 4);
    let big_leaves = RandomForest::fit(&data, &quiet(5).min_samples_leaf(50)).unwrap();
    assert!(
        big_leaves.n_nodes() < full.n_nodes() / 5,
        "{} vs {}",
        big_leaves.n_nodes(),
        full.n_nodes()
    );
    // min_samples_leaf = 50 without bootstrap: every leaf holds ≥ 50 rows; check via the leaf reached by
    // each training row.
    let nb = RandomForest::fit(&data, &quiet(1).bootstrap(false).min_samples_leaf(50)).unwrap();
    let mut per_leaf = std::collections::HashMap::new();
    for i in 0..data.n_rows() {
        let row = data.row(i).unwrap();
        let (nodes, mut p) = (nb.nodes(), 0usize);
        while !nodes[p].is_leaf() {
            let n = nodes[p];
            p = if row[n.feature as usize] <= n.threshold {
                p + 1
            } else {
                n.right as usize
            };
        }
        *per_leaf.entry(p).or_insert(0) += 1;
    }
    assert!(per_leaf.values().all(|&c| c >= 50), "{per_leaf:?}");
}

#[test]
fn no_bootstrap_all_features_fits_training_data_exactly() {
    // Distinct rows, no bootstrap: fully grown trees are consistent with every training row.
    let data = synthetic::blobs(1_000, 3, 4, 90.0, 21).unwrap();
    let params = quiet(3).bootstrap(false).max_features(MaxFeatures::All);
    let forest = RandomForest::fit(&data, &params).unwrap();
    let mut seen = std::collections::HashSet::new();
    let mut wrong = 0;
    for i in 0..data.n_rows() {
        let row = data.row(i).unwrap();
        let key: Vec<u32> = row.iter().map(|v| v.to_bits()).collect();
        if seen.insert(key) && forest.predict(row) != data.y()[i] {
            wrong += 1;
        }
    }
    assert_eq!(wrong, 0);
}

#[test]
fn degenerate_data() {
    // One class only.
    let d = Dataset::new(vec![1.0, 2.0, 3.0, 4.0], 2, vec![0, 0]).unwrap();
    let f = RandomForest::fit(&d, &quiet(3)).unwrap();
    assert_eq!(f.n_nodes(), 3);
    assert_eq!(f.predict(&[9.0, 9.0]), 0);
    // Constant features with mixed classes: nothing to split on.
    let d = Dataset::new(vec![1.0; 8], 2, vec![0, 1, 1, 2]).unwrap();
    let f = RandomForest::fit(&d, &quiet(4).bootstrap(false)).unwrap();
    assert_eq!(f.n_nodes(), 4);
    assert_eq!(f.predict_proba(&[1.0, 1.0]), vec![0.25, 0.5, 0.25]);
    assert_eq!(f.predict(&[1.0, 1.0]), 1);
    // A single row.
    let d = Dataset::new(vec![5.0], 1, vec![2]).unwrap();
    let f = RandomForest::fit(&d, &quiet(2)).unwrap();
    assert_eq!(f.predict(&[0.0]), 2);
    // Classes absent from the data keep their slot.
    let d = Dataset::with_classes(vec![0.0, 1.0], 1, vec![0, 2], 4).unwrap();
    let f = RandomForest::fit(&d, &quiet(2).bootstrap(false)).unwrap();
    assert_eq!(f.n_classes(), 4);
    assert_eq!(f.predict_proba(&[1.0]), vec![0.0, 0.0, 1.0, 0.0]);
    // x == threshold goes left (scikit-learn's rule).
    assert_eq!(f.predict_proba(&[0.5]), vec![1.0, 0.0, 0.0, 0.0]);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let data = synthetic::blobs(300, 3, 3, 50.0, 1).unwrap();
    let f = RandomForest::fit(&data, &quiet(3)).unwrap();
    assert!(matches!(
        f.try_predict(&[1.0, f32::NAN, 2.0]),
        Err(ForestError::NonFinite { column: 1, .. })
    ));
    assert!(matches!(f.try_predict(&[1.0]), Err(ForestError::Shape(_))));
    let mut small = [0f32; 2];
    assert!(f
        .try_predict_proba_into(&[1.0, 2.0, 3.0], &mut small)
        .is_err());
    // The infallible paths never panic on odd shapes.
    let _ = f.predict(&[]);
    let _ = f.predict(&[f32::NAN; 3]);
    let _ = f.predict(&[1.0; 10]);
    f.predict_proba_into(&[1.0, 2.0, 3.0], &mut small);
    f.predict_proba_into(&[1.0, 2.0, 3.0], &mut []);
    let mut out = vec![0u32; 2];
    assert!(f.predict_batch(&[1.0; 5], 3, &mut out).is_err());
    assert!(f.predict_batch(&[1.0; 6], 2, &mut out).is_err());
    assert!(f.predict_batch(&[1.0; 6], 3, &mut out).is_ok());
    assert!(f.predict_proba_batch(&[1.0; 6], 3, &mut [0f32; 5]).is_err());
    assert!(f.predict_batch(&[], 3, &mut []).is_ok());
    assert!(RandomForest::fit(&data, &quiet(0)).is_err());
    assert!(RandomForest::fit(&data, &quiet(2).min_samples_leaf(0)).is_err());
    assert!(RandomForest::fit(&data, &quiet(2).max_features(MaxFeatures::Fraction(2.0))).is_err());
}

/// Not a benchmark (see crackbot-research's `examples/train_timing.rs`): guards against an accidental complexity blow-up.
/// 10 fully grown trees on 75k × 3 rows take ~0.15 s in release and a few seconds in debug here.
#[test]
fn training_is_not_absurdly_slow() {
    let data = synthetic::blobs(75_000, 3, 4, 60.0, 42).unwrap();
    let t0 = Instant::now();
    let forest = RandomForest::fit(&data, &quiet(10)).unwrap();
    let dt = t0.elapsed().as_secs_f64();
    let limit = if cfg!(debug_assertions) { 120.0 } else { 10.0 };
    assert!(dt < limit, "10 trees took {dt:.1} s (limit {limit} s)");
    assert!(
        forest.n_nodes() / 10 > 1_000,
        "fully grown trees are big: {}",
        forest.n_nodes() / 10
    );
}

#[test]
fn progress_is_reported_once_per_tree_in_order_and_changes_nothing() {
    let data = synthetic::blobs(1_500, 3, 4, 40.0, 2).unwrap();
    let params = ForestParams::classifier().n_trees(9).seed(5);
    let mut seen = Vec::new();
    let with = RandomForest::fit_with_progress(&data, &params, |done, total| {
        seen.push((done, total));
    })
    .unwrap();
    assert_eq!(seen, (1..=9).map(|d| (d, 9)).collect::<Vec<_>>());
    assert_eq!(with, RandomForest::fit(&data, &params).unwrap());
    let mut calls = 0;
    RandomForest::fit_with_progress(&data, &params.clone().quiet(true), |_, _| calls += 1).unwrap();
    assert_eq!(calls, 0, "quiet reports nothing");
    let reg = synthetic::width_regression(800, 0.1, 3).unwrap();
    let mut last = (0, 0);
    crackbot_forest::RandomForestRegressor::fit_with_progress(
        &reg,
        &ForestParams::regressor().n_trees(4),
        |done, total| last = (done, total),
    )
    .unwrap();
    assert_eq!(last, (4, 4));
}
