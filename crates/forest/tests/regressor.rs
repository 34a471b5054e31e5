//! Random-forest regressor (crack width in mm) on y = f(x) + noise.

use crackbot_forest::{synthetic, ForestParams, RandomForestRegressor, RegressionDataset};

#[test]
fn width_regression_beats_the_mean() {
    let train = synthetic::width_regression(6_000, 0.3, 1).unwrap();
    let test = synthetic::width_regression(2_000, 0.3, 2).unwrap();
    let model = RandomForestRegressor::fit(
        &train,
        &ForestParams::regressor().n_trees(40).seed(5).quiet(true),
    )
    .unwrap();
    let mean = train.y().iter().map(|&v| v as f64).sum::<f64>() / train.n_rows() as f64;
    let mut out = vec![0f32; test.n_rows()];
    model.predict_batch(test.x(), 3, &mut out).unwrap();
    let (mut mae, mut mae_mean, mut mae_true) = (0.0, 0.0, 0.0);
    for (i, &batch) in out.iter().enumerate() {
        let row = test.row(i).unwrap();
        let p = model.predict(row);
        assert_eq!(p, batch, "batch and single agree bit for bit");
        let y = test.y()[i] as f64;
        mae += (p as f64 - y).abs();
        mae_mean += (mean - y).abs();
        mae_true += (synthetic::width_function(row) as f64 - p as f64).abs();
    }
    let n = test.n_rows() as f64;
    let (mae, mae_mean, mae_true) = (mae / n, mae_mean / n, mae_true / n);
    println!("MAE {mae:.3} mm (vs noisy targets), {mae_true:.3} mm (vs f(x)), predicting the mean: {mae_mean:.3} mm");
    // Noise N(0, 0.3) alone gives an MAE of 0.24 against the noisy targets.
    assert!(mae < 0.45, "MAE {mae}");
    assert!(mae_true < 0.3, "MAE vs f(x) {mae_true}");
    assert!(
        mae < mae_mean / 3.0,
        "MAE {mae} vs mean predictor {mae_mean}"
    );
    let imp = model.feature_importances().unwrap();
    assert!(
        imp[0] > imp[1] && imp[1] > imp[2],
        "x0 drives the target, x2 is noise: {imp:?}"
    );
}

#[test]
fn regressor_determinism_and_degenerate_data() {
    let train = synthetic::width_regression(1_000, 0.3, 1).unwrap();
    let p = ForestParams::regressor().n_trees(6).seed(9).quiet(true);
    let a = RandomForestRegressor::fit(&train, &p.clone().n_threads(Some(1))).unwrap();
    let b = RandomForestRegressor::fit(&train, &p.clone().n_threads(Some(2))).unwrap();
    assert_eq!(a.to_bytes(), b.to_bytes());
    // Constant target: a single leaf per tree predicting it.
    let d = RegressionDataset::new(vec![1.0, 2.0, 3.0, 4.0], 1, vec![2.5; 4]).unwrap();
    let m = RandomForestRegressor::fit(&d, &p).unwrap();
    assert_eq!(m.n_nodes(), 6);
    assert_eq!(m.predict(&[10.0]), 2.5);
    // Shallow trees and bad input.
    let m = RandomForestRegressor::fit(&train, &p.clone().max_depth(Some(2))).unwrap();
    assert!(m.n_nodes() <= 6 * 7);
    assert!(m.try_predict(&[f32::NAN, 1.0, 1.0]).is_err());
    assert!(m.try_predict(&[1.0]).is_err());
    assert!(m.predict(&[]).is_finite());
    assert!(m.predict_batch(&[1.0; 4], 3, &mut [0.0; 1]).is_err());
}
