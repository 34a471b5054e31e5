//! linfa's random forest on the real windows, and its conversion into our flat [`RandomForest`]
//! (`benches/tactile.rs`'s baseline; checked by `tests/linfa_flat_conversion.rs`).
#![allow(
    dead_code,
    reason = "included by several test or bench crates, each using a subset: dead in some, not in others"
)]

use crackbot_forest::{Node, RandomForest};
use crackbot_tactile::dataset::WindowSet;
use linfa::prelude::Fit;
use linfa_ensemble::RandomForestParams;
use linfa_trees::{DecisionTree, TreeNode};
use ndarray16::{Array1, Array2};
use rand08::{rngs::SmallRng, SeedableRng};

/// linfa's forest on `f32` features and class indices.
pub type LinfaForest = linfa_ensemble::RandomForest<f32, usize>;

/// Row-major `f32` rows as a linfa record matrix.
pub fn records(x: &[f32], n_features: usize) -> Array2<f32> {
    Array2::from_shape_vec((x.len() / n_features, n_features), x.to_vec()).expect("shape")
}

/// Trains linfa's random forest on the first `max_rows` windows of `train`: `n_trees` bagged CART trees
/// (bootstrap of n rows, every feature, Gini), depth capped at `max_depth` (linfa trains one tree after
/// another on one core and takes seconds per fully grown tree).
pub fn train_linfa(
    train: &WindowSet,
    n_trees: usize,
    max_depth: Option<usize>,
    max_rows: usize,
    seed: u64,
) -> LinfaForest {
    let rows = train.n_rows().min(max_rows);
    let nf = train.n_features;
    let x = records(&train.x[..rows * nf], nf);
    let y = Array1::from_iter(train.y[..rows].iter().map(|&c| c as usize));
    let data = linfa::Dataset::new(x, y);
    RandomForestParams::new_fixed_rng(
        DecisionTree::params().max_depth(max_depth),
        SmallRng::seed_from_u64(seed),
    )
    .ensemble_size(n_trees)
    .bootstrap_proportion(1.0)
    .feature_proportion(1.0)
    .fit(&data)
    .expect("linfa forest")
}

/// Converts linfa's forest into our flat model. linfa's trees vote with one class label per leaf, so each
/// leaf becomes a one-hot probability row and soft voting is linfa's majority vote (ties aside: linfa breaks
/// them through a `HashMap`, we take the lowest class). A tree's feature index is local to the tree's
/// feature subset (`model_features`). linfa's rule `x[f] < t` → left becomes ours, `x[f] <= t'` → left, with
/// `t'` the largest `f32` strictly below `t`: for every `f32` x the two agree.
pub fn linfa_to_flat(rf: &LinfaForest, n_features: usize, n_classes: usize) -> RandomForest {
    let mut nodes = Vec::new();
    let mut offsets = vec![0u32];
    let mut leaf_values = Vec::new();
    for (tree, features) in rf.models.iter().zip(&rf.model_features) {
        emit(
            tree.root_node(),
            features,
            n_classes,
            &mut nodes,
            &mut leaf_values,
        );
        offsets.push(nodes.len() as u32);
    }
    RandomForest::from_parts(
        n_features,
        (0..n_classes).map(|c| c as f64).collect(),
        nodes,
        offsets,
        leaf_values,
        None,
    )
    .expect("a valid flat forest")
}

fn emit(
    node: &TreeNode<f32, usize>,
    features: &[usize],
    n_classes: usize,
    nodes: &mut Vec<Node>,
    leaves: &mut Vec<f32>,
) {
    if let Some(class) = node.prediction() {
        let id = (leaves.len() / n_classes) as u32;
        leaves.extend((0..n_classes).map(|c| if c == class { 1.0 } else { 0.0 }));
        nodes.push(Node::leaf(id));
        return;
    }
    let (local, threshold, _) = node.split();
    let at = nodes.len();
    nodes.push(Node {
        feature: features[local] as u32,
        threshold: threshold.next_down(),
        right: 0,
    });
    let children = node.children();
    let child = |i: usize| {
        children[i]
            .as_deref()
            .expect("an internal linfa node has two children")
    };
    emit(child(0), features, n_classes, nodes, leaves);
    nodes[at].right = nodes.len() as u32;
    emit(child(1), features, n_classes, nodes, leaves);
}

/// Whether linfa's trees split `votes` so that two classes share the top count (linfa's winner is arbitrary).
pub fn linfa_tie(rf: &LinfaForest, row: &[f32]) -> bool {
    let n_classes = rf
        .models
        .iter()
        .flat_map(|t| t.iter_nodes().filter_map(linfa_trees::TreeNode::prediction))
        .max()
        .unwrap_or(0)
        + 1;
    let mut votes = vec![0usize; n_classes];
    for (tree, features) in rf.models.iter().zip(&rf.model_features) {
        let mut n = tree.root_node();
        while n.prediction().is_none() {
            let (local, t, _) = n.split();
            let children = n.children();
            let i = if row[features[local]] < t { 0 } else { 1 };
            n = children[i].as_deref().expect("child");
        }
        votes[n.prediction().expect("leaf")] += 1;
    }
    let top = votes.iter().copied().max().unwrap_or(0);
    votes.iter().filter(|&&v| v == top).count() > 1
}
