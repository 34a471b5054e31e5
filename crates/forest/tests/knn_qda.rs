//! KNN and QDA: accuracy on Gaussian blobs, determinism, and robustness of QDA to singular classes.

use crackbot_forest::{accuracy, synthetic, Classifier, Dataset, Knn, KnnParams, Qda, QdaParams};

fn assert_proper(p: &[f32], what: &str) {
    assert!(
        p.iter()
            .all(|v| v.is_finite() && (0.0..=1.0 + 1e-6).contains(v)),
        "{what}: {p:?}"
    );
    assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-4, "{what}: {p:?}");
}

#[test]
fn knn_and_qda_learn_blobs() {
    let data = synthetic::blobs(4_000, 3, 4, 65.0, 31).unwrap();
    let (train, test) = data.split_at(3_000).unwrap();
    let knn = Knn::fit(&train, KnnParams::default()).unwrap();
    let knn_std = Knn::fit(
        &train,
        KnnParams {
            k: 5,
            standardize: true,
        },
    )
    .unwrap();
    let qda = Qda::fit(&train, QdaParams::default()).unwrap();
    let qda_raw = Qda::fit(
        &train,
        QdaParams {
            reg_param: 0.0,
            standardize: false,
        },
    )
    .unwrap();
    let (a_knn, a_knn_std, a_qda, a_qda_raw) = (
        accuracy(&knn, &test),
        accuracy(&knn_std, &test),
        accuracy(&qda, &test),
        accuracy(&qda_raw, &test),
    );
    println!("knn {a_knn:.4} knn(std) {a_knn_std:.4} qda {a_qda:.4} qda(raw, r=0) {a_qda_raw:.4}");
    assert!(a_knn > 0.75 && a_knn_std > 0.75, "{a_knn} {a_knn_std}");
    // Gaussian classes: QDA is close to the Bayes classifier and beats KNN.
    assert!(a_qda > a_knn - 0.01, "{a_qda} vs {a_knn}");
    assert!(
        (a_qda - a_qda_raw).abs() < 0.01,
        "standardisation and a tiny r barely matter here"
    );
    for i in 0..50 {
        let row = test.row(i).unwrap();
        assert_proper(&knn.predict_proba(row), "knn");
        assert_proper(&qda.predict_proba(row), "qda");
        let p = knn.predict_proba(row);
        assert!(
            p.iter().all(|v| (v * 5.0 - (v * 5.0).round()).abs() < 1e-5),
            "votes are multiples of 1/5"
        );
    }
}

#[test]
fn knn_is_deterministic_with_duplicates() {
    // Many identical rows with different classes: the earliest rows win the distance ties.
    let x = vec![1.0f32; 20];
    let y: Vec<u32> = (0..20).map(|i| (i % 4) as u32).collect();
    let d = Dataset::new(x, 1, y).unwrap();
    let knn = Knn::fit(&d, KnnParams::default()).unwrap();
    // Rows 0..5 have classes 0, 1, 2, 3, 0.
    assert_eq!(knn.predict_proba(&[1.0]), vec![0.4, 0.2, 0.2, 0.2]);
    assert_eq!(knn.predict(&[1.0]), 0);
    let knn1 = Knn::fit(
        &d,
        KnnParams {
            k: 4,
            standardize: true,
        },
    )
    .unwrap();
    // Four-way tie of the votes: the lowest class index wins.
    assert_eq!(knn1.predict(&[7.0]), 0);
}

#[test]
fn qda_singular_classes_give_no_nan() {
    // Class 0: feature 2 is constant (singular covariance). Class 1: regular. Class 2: a single row.
    // Class 3: two rows, fewer than the three features.
    let mut x = Vec::new();
    let mut y = Vec::new();
    for i in 0..50 {
        let t = i as f32;
        x.extend_from_slice(&[400.0 + t, 500.0 - t * 0.5, 600.0]);
        y.push(0);
        x.extend_from_slice(&[
            700.0 + (t * 1.3).sin() * 30.0,
            300.0 + (t * 0.7).cos() * 20.0,
            650.0 + t,
        ]);
        y.push(1);
    }
    x.extend_from_slice(&[900.0, 900.0, 900.0]);
    y.push(2);
    x.extend_from_slice(&[200.0, 250.0, 300.0, 210.0, 240.0, 310.0]);
    y.extend([3, 3]);
    let d = Dataset::new(x, 3, y).unwrap();
    let queries: [[f32; 3]; 7] = [
        [420.0, 490.0, 600.0],
        [420.0, 490.0, 601.0],
        [700.0, 300.0, 680.0],
        [900.0, 900.0, 900.0],
        [205.0, 245.0, 305.0],
        [0.0, 0.0, 0.0],
        [1e6, -1e6, 3e7],
    ];
    for params in [
        QdaParams {
            reg_param: 0.0,
            standardize: false,
        },
        QdaParams {
            reg_param: 0.0,
            standardize: true,
        },
        QdaParams {
            reg_param: 1e-3,
            standardize: true,
        },
        QdaParams {
            reg_param: 0.5,
            standardize: false,
        },
        QdaParams {
            reg_param: 1.0,
            standardize: true,
        },
    ] {
        let qda = Qda::fit(&d, params).unwrap();
        for q in &queries {
            assert_proper(&qda.predict_proba(q), &format!("{params:?} {q:?}"));
        }
        assert_eq!(qda.predict(&queries[2]), 1, "{params:?}");
    }
    let qda = Qda::fit(&d, QdaParams::default()).unwrap();
    assert_eq!(qda.predict(&queries[0]), 0);
    assert_eq!(qda.predict(&queries[3]), 2);
    assert_eq!(qda.predict(&queries[4]), 3);
    // All rows of one class identical, plus an absent class (index 4): still finite, absent class gets 0.
    let d = Dataset::with_classes(vec![1.0, 1.0, 1.0, 1.0, 5.0, 5.0], 2, vec![0, 0, 1], 5).unwrap();
    let qda = Qda::fit(
        &d,
        QdaParams {
            reg_param: 0.0,
            standardize: true,
        },
    )
    .unwrap();
    let p = qda.predict_proba(&[1.0, 1.0]);
    assert_proper(&p, "tiny");
    assert_eq!(p[4], 0.0);
    assert_eq!(qda.predict(&[1.0, 1.0]), 0);
    assert_eq!(qda.predict(&[5.0, 5.0]), 1);
}

#[test]
fn all_three_behind_one_trait_object() {
    use crackbot_forest::{ForestParams, RandomForest};
    let data = synthetic::blobs(2_000, 3, 4, 60.0, 5).unwrap();
    let (train, test) = data.split_at(1_500).unwrap();
    let models: Vec<(&str, Box<dyn Classifier>)> = vec![
        (
            "forest",
            Box::new(
                RandomForest::fit(&train, &ForestParams::classifier().n_trees(20).quiet(true))
                    .unwrap(),
            ),
        ),
        (
            "knn",
            Box::new(Knn::fit(&train, KnnParams::default()).unwrap()),
        ),
        (
            "qda",
            Box::new(Qda::fit(&train, QdaParams::default()).unwrap()),
        ),
    ];
    for (name, m) in &models {
        assert_eq!(m.n_classes(), 4);
        assert_eq!(m.n_features(), 3);
        let acc = accuracy(m.as_ref(), &test);
        println!("{name}: {acc:.4}");
        assert!(acc > 0.8, "{name}: {acc}");
    }
}
