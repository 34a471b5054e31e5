//! The linfa forest that `benches/tactile.rs` uses as its baseline, converted into our flat model, predicts
//! like linfa on the real windows of repetition 2 (every row except exact vote ties, where linfa's winner is
//! arbitrary), so the bench compares two implementations of the same forest.

#[path = "../benches/common/linfa_forest.rs"]
mod linfa_forest;
#[path = "../benches/common/windows.rs"]
mod windows;

use crackbot_forest::Classifier;
use linfa::prelude::Predict;

#[test]
fn converted_linfa_forest_predicts_like_linfa_on_real_windows() {
    let real = windows::load(&windows::data_dir());
    // Small enough for a debug build (linfa is not optimised in test builds): 20 trees (an even count, so exact ties occur), depth ≤ 12.
    let rf = linfa_forest::train_linfa(&real.train, 20, Some(12), 6_000, 3);
    let nf = real.test.n_features;
    let flat = linfa_forest::linfa_to_flat(&rf, nf, real.test.experiment.n_classes());
    assert_eq!(flat.n_trees(), 20);
    let linfa_pred = rf.predict(&linfa_forest::records(&real.test.x, nf));
    let mut ties = 0;
    for (i, &expected) in linfa_pred.iter().enumerate() {
        let row = real.test.row(i);
        let ours = flat.predict(row) as usize;
        if ours != expected {
            assert!(
                linfa_forest::linfa_tie(&rf, row),
                "row {i} {row:?}: flat {ours}, linfa {expected}, and the vote is not tied"
            );
            ties += 1;
        }
    }
    let n = linfa_pred.len();
    println!("{n} rows, {ties} differ, all on exact vote ties");
    assert!(n > 1_000, "{n} windows");
    assert!(ties * 20 < n, "{ties} of {n} rows differ");
}
