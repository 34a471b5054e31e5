//! The tree trainer shared by the classifier (Gini) and the regressor (MSE).
//!
//! Algorithm (per tree):
//! 1. Every feature column is sorted once for the whole forest into `(value, row)` entries (shared, read-only).
//! 2. The tree's bootstrap draw becomes a per-row count (weight); rows drawn 0 times are dropped. For each
//!    feature, the tree keeps its own list of `(value, row)` entries in sorted order (a filter of the shared
//!    list, one sequential pass per feature).
//! 3. A node is a range `start..end` that is the same in every feature's list; each list's range holds the
//!    node's rows sorted by that feature. The best split of a feature is one linear scan with incremental
//!    class counts (or sums for regression); thresholds lie at midpoints between consecutive distinct
//!    values, as in scikit-learn.
//! 4. The rows going left are marked, and every other feature's range is partitioned *stably*, so both
//!    children again have sorted ranges. Each tree level costs O(n · n_features): no sorting below the root.
//! 5. Nodes are produced in depth-first pre-order with an explicit stack, which is directly the flat layout
//!    of [`crate::flat`] (left child adjacent, right child index patched when it is produced).

use std::sync::Mutex;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{ForestError, Result};
use crate::flat::{midpoint_threshold, FlatTrees, Node};
use crate::params::ForestParams;

/// A value of one feature with its row, in a per-feature sorted list.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    v: f32,
    row: u32,
}

/// Node statistics and split search of one learning task.
pub(crate) trait Task: Sync {
    /// Sufficient statistics of a node.
    type Stats: Clone + Send;
    /// Length of a leaf's value vector.
    fn width(&self) -> usize;
    /// Statistics of a set of rows.
    fn stats(&self, rows: impl Iterator<Item = u32>, w: &[u32]) -> Self::Stats;
    /// `total − left`.
    fn sub(&self, total: &Self::Stats, left: &Self::Stats) -> Self::Stats;
    /// No split can reduce the impurity.
    fn is_pure(&self, s: &Self::Stats) -> bool;
    /// Weighted impurity (weight × impurity), for the impurity-decrease importances.
    fn weighted_impurity(&self, s: &Self::Stats) -> f64;
    /// Best split of a sorted node range: `(proxy, n_left)`, larger proxy = better, both children with at
    /// least `msl` entries; `None` when no valid split exists.
    fn scan(
        &self,
        ents: &[Entry],
        w: &[u32],
        total: &Self::Stats,
        msl: usize,
        scratch: &mut Vec<u64>,
    ) -> Option<(f64, usize)>;
    /// Leaf value(s) of a node.
    fn leaf(&self, s: &Self::Stats, out: &mut Vec<f32>);
}

/// Gini classification.
pub(crate) struct Gini<'a> {
    pub y: &'a [u32],
    pub n_classes: usize,
}

/// Class statistics: weighted counts, total weight, sum of squared counts.
#[derive(Clone)]
pub(crate) struct ClassStats {
    counts: Vec<u64>,
    w: u64,
    sumsq: u64,
}

impl Task for Gini<'_> {
    type Stats = ClassStats;
    fn width(&self) -> usize {
        self.n_classes
    }
    fn stats(&self, rows: impl Iterator<Item = u32>, w: &[u32]) -> ClassStats {
        let mut counts = vec![0u64; self.n_classes];
        let mut tot = 0u64;
        for r in rows {
            let wt = w[r as usize] as u64;
            counts[self.y[r as usize] as usize] += wt;
            tot += wt;
        }
        let sumsq = counts.iter().map(|c| c * c).sum();
        ClassStats {
            counts,
            w: tot,
            sumsq,
        }
    }
    fn sub(&self, t: &ClassStats, l: &ClassStats) -> ClassStats {
        let counts: Vec<u64> = t.counts.iter().zip(&l.counts).map(|(a, b)| a - b).collect();
        let sumsq = counts.iter().map(|c| c * c).sum();
        ClassStats {
            counts,
            w: t.w - l.w,
            sumsq,
        }
    }
    fn is_pure(&self, s: &ClassStats) -> bool {
        s.sumsq == s.w * s.w
    }
    fn weighted_impurity(&self, s: &ClassStats) -> f64 {
        if s.w == 0 {
            0.0
        } else {
            s.w as f64 - s.sumsq as f64 / s.w as f64
        }
    }
    fn scan(
        &self,
        ents: &[Entry],
        w: &[u32],
        total: &ClassStats,
        msl: usize,
        scratch: &mut Vec<u64>,
    ) -> Option<(f64, usize)> {
        let k = self.n_classes;
        scratch.clear();
        scratch.resize(2 * k, 0);
        let (left, right) = scratch.split_at_mut(k);
        right.copy_from_slice(&total.counts);
        let (mut ls, mut rs) = (0u64, total.sumsq);
        let (mut wl, mut wr) = (0u64, total.w);
        let n = ents.len();
        let mut best = f64::NEG_INFINITY;
        let mut best_pos = 0;
        let last = n.saturating_sub(msl);
        for i in 0..n.saturating_sub(1) {
            let e = ents[i];
            let c = self.y[e.row as usize] as usize;
            let wt = w[e.row as usize] as u64;
            let l = left[c];
            ls += wt * (2 * l + wt);
            left[c] = l + wt;
            let r = right[c];
            rs = rs + wt * wt - 2 * wt * r;
            right[c] = r - wt;
            wl += wt;
            wr -= wt;
            let pos = i + 1;
            if pos >= msl && pos <= last && ents[pos].v > e.v {
                let proxy = ls as f64 / wl as f64 + rs as f64 / wr as f64;
                if proxy > best {
                    best = proxy;
                    best_pos = pos;
                }
            }
        }
        (best_pos > 0).then_some((best, best_pos))
    }
    fn leaf(&self, s: &ClassStats, out: &mut Vec<f32>) {
        let tot = s.w.max(1) as f64;
        out.extend(s.counts.iter().map(|&c| (c as f64 / tot) as f32));
    }
}

/// MSE regression.
pub(crate) struct Mse<'a> {
    pub y: &'a [f32],
}

/// Regression statistics: total weight, weighted sum and weighted sum of squares.
#[derive(Clone)]
pub(crate) struct RegStats {
    w: f64,
    sum: f64,
    sumsq: f64,
}

impl Task for Mse<'_> {
    type Stats = RegStats;
    fn width(&self) -> usize {
        1
    }
    fn stats(&self, rows: impl Iterator<Item = u32>, w: &[u32]) -> RegStats {
        let mut s = RegStats {
            w: 0.0,
            sum: 0.0,
            sumsq: 0.0,
        };
        for r in rows {
            let wt = w[r as usize] as f64;
            let y = self.y[r as usize] as f64;
            s.w += wt;
            s.sum += wt * y;
            s.sumsq += wt * y * y;
        }
        s
    }
    fn sub(&self, t: &RegStats, l: &RegStats) -> RegStats {
        RegStats {
            w: t.w - l.w,
            sum: t.sum - l.sum,
            sumsq: t.sumsq - l.sumsq,
        }
    }
    fn is_pure(&self, s: &RegStats) -> bool {
        s.w <= 0.0 || s.sumsq / s.w - (s.sum / s.w).powi(2) <= f64::EPSILON
    }
    fn weighted_impurity(&self, s: &RegStats) -> f64 {
        if s.w <= 0.0 {
            0.0
        } else {
            (s.sumsq - s.sum * s.sum / s.w).max(0.0)
        }
    }
    fn scan(
        &self,
        ents: &[Entry],
        w: &[u32],
        total: &RegStats,
        msl: usize,
        _: &mut Vec<u64>,
    ) -> Option<(f64, usize)> {
        let n = ents.len();
        let (mut wl, mut sl) = (0f64, 0f64);
        let mut best = f64::NEG_INFINITY;
        let mut best_pos = 0;
        let last = n.saturating_sub(msl);
        for i in 0..n.saturating_sub(1) {
            let e = ents[i];
            let wt = w[e.row as usize] as f64;
            wl += wt;
            sl += wt * self.y[e.row as usize] as f64;
            let pos = i + 1;
            if pos >= msl && pos <= last && ents[pos].v > e.v {
                let wr = total.w - wl;
                let sr = total.sum - sl;
                let proxy = sl * sl / wl + sr * sr / wr;
                if proxy > best {
                    best = proxy;
                    best_pos = pos;
                }
            }
        }
        (best_pos > 0).then_some((best, best_pos))
    }
    fn leaf(&self, s: &RegStats, out: &mut Vec<f32>) {
        out.push(if s.w > 0.0 { (s.sum / s.w) as f32 } else { 0.0 });
    }
}

/// Shared, read-only training inputs.
pub(crate) struct Prepared<'a> {
    /// Per feature, every row's `(value, row)` sorted by value (ties by row).
    sorted: Vec<Vec<Entry>>,
    n_rows: usize,
    params: &'a ForestParams,
    mtry: usize,
}

impl<'a> Prepared<'a> {
    /// Per-feature sorted `(value, row)` lists of row-major `x`.
    pub fn new(x: &[f32], n_features: usize, params: &'a ForestParams) -> Result<Self> {
        params.validate()?;
        let n_rows = x.len() / n_features;
        // One sequential pass over the rows (not one strided pass per feature) lists every feature's
        // entries in row order; a stable radix sort by value then leaves ties in row order.
        let mut sorted: Vec<Vec<Entry>> = (0..n_features)
            .map(|_| Vec::with_capacity(n_rows))
            .collect();
        for (r, row) in x.chunks_exact(n_features).enumerate() {
            for (list, &v) in sorted.iter_mut().zip(row) {
                list.push(Entry { v, row: r as u32 });
            }
        }
        sorted
            .par_iter_mut()
            .for_each(|list| radsort::sort_by_key(list, |e| total_order_bits(e.v)));
        let mtry = params.max_features.resolve(n_features)?;
        Ok(Self {
            sorted,
            n_rows,
            params,
            mtry,
        })
    }
}

/// `v`'s bits mapped so that their unsigned order is [`f32::total_cmp`]'s order.
fn total_order_bits(v: f32) -> u32 {
    let b = v.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 1 << 31
    }
}

/// One trained tree in local indices (right children and leaf ids relative to this tree).
pub(crate) struct TreeOut {
    nodes: Vec<Node>,
    leaf_values: Vec<f32>,
    importances: Vec<f64>,
}

struct Pending<S> {
    start: usize,
    end: usize,
    depth: usize,
    parent: Option<usize>,
    stats: S,
}

/// Stable partition of `list` by `go_left[row]` using `tmp` for the right part; returns the left count.
fn stable_partition(list: &mut [Entry], go_left: &[bool], tmp: &mut [Entry]) -> usize {
    let mut nl = 0;
    let mut nr = 0;
    for i in 0..list.len() {
        let e = list[i];
        let gl = go_left[e.row as usize];
        list[nl] = e;
        tmp[nr] = e;
        nl += gl as usize;
        nr += !gl as usize;
    }
    list[nl..].copy_from_slice(&tmp[..nr]);
    nl
}

/// The entries of `list` whose row was drawn (`w[row] > 0`, `m` of them), in order: one sequential
/// pass, without a branch (a bootstrap keeps about 63 % of the rows at random, which a filter's
/// branch mispredicts).
fn drawn(list: &[Entry], w: &[u32], m: usize) -> Vec<Entry> {
    let mut out = vec![Entry { v: 0.0, row: 0 }; m + 1];
    let mut k = 0;
    for &e in list {
        out[k] = e;
        k += usize::from(w[e.row as usize] > 0);
    }
    out.truncate(m);
    out
}

fn build_tree<T: Task>(task: &T, p: &Prepared<'_>, tree: usize) -> TreeOut {
    let params = p.params;
    let n = p.n_rows;
    let nf = p.sorted.len();
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    rng.set_stream(tree as u64);
    let w: Vec<u32> = if params.bootstrap {
        let mut w = vec![0u32; n];
        for _ in 0..n {
            w[rng.random_range(0..n)] += 1;
        }
        w
    } else {
        vec![1; n]
    };
    let m = w.iter().filter(|&&c| c > 0).count();
    let mut lists: Vec<Vec<Entry>> = p.sorted.iter().map(|list| drawn(list, &w, m)).collect();
    let mut go_left = vec![false; n];
    let mut tmp = vec![Entry { v: 0.0, row: 0 }; m];
    let mut scratch = Vec::new();
    let mut feats: Vec<usize> = (0..nf).collect();
    let mut nodes: Vec<Node> = Vec::new();
    let mut leaf_values: Vec<f32> = Vec::new();
    let mut importances = vec![0f64; nf];
    let max_depth = params.max_depth.unwrap_or(usize::MAX);
    let msl = params.min_samples_leaf;
    let root = task.stats(lists[0].iter().map(|e| e.row), &w);
    let mut stack = vec![Pending {
        start: 0,
        end: m,
        depth: 0,
        parent: None,
        stats: root,
    }];
    while let Some(pd) = stack.pop() {
        let id = nodes.len();
        if let Some(par) = pd.parent {
            nodes[par].right = id as u32;
        }
        let size = pd.end - pd.start;
        let mut best: Option<(f64, usize, usize)> = None;
        let splittable = pd.depth < max_depth
            && size >= params.min_samples_split
            && size >= 2 * msl
            && !task.is_pure(&pd.stats);
        if splittable {
            let mut visited = 0;
            for j in 0..nf {
                let k = rng.random_range(j..nf);
                feats.swap(j, k);
                let f = feats[j];
                let ents = &lists[f][pd.start..pd.end];
                if ents[0].v >= ents[size - 1].v {
                    continue; // constant in this node: does not count
                }
                visited += 1;
                if let Some((proxy, pos)) = task.scan(ents, &w, &pd.stats, msl, &mut scratch) {
                    if best.is_none_or(|b| proxy > b.0) {
                        best = Some((proxy, f, pos));
                    }
                }
                if visited >= p.mtry {
                    break;
                }
            }
        }
        let Some((_, f, pos)) = best else {
            let leaf_id = (leaf_values.len() / task.width()) as u32;
            task.leaf(&pd.stats, &mut leaf_values);
            nodes.push(Node::leaf(leaf_id));
            continue;
        };
        let ents = &lists[f][pd.start..pd.end];
        let threshold = midpoint_threshold(ents[pos - 1].v, ents[pos].v);
        let left = task.stats(ents[..pos].iter().map(|e| e.row), &w);
        let right = task.sub(&pd.stats, &left);
        importances[f] += task.weighted_impurity(&pd.stats)
            - task.weighted_impurity(&left)
            - task.weighted_impurity(&right);
        for (i, e) in ents.iter().enumerate() {
            go_left[e.row as usize] = i < pos;
        }
        for (g, list) in lists.iter_mut().enumerate() {
            if g != f {
                stable_partition(&mut list[pd.start..pd.end], &go_left, &mut tmp);
            }
        }
        nodes.push(Node {
            feature: f as u32,
            threshold,
            right: 0,
        });
        let mid = pd.start + pos;
        stack.push(Pending {
            start: mid,
            end: pd.end,
            depth: pd.depth + 1,
            parent: Some(id),
            stats: right,
        });
        stack.push(Pending {
            start: pd.start,
            end: mid,
            depth: pd.depth + 1,
            parent: None,
            stats: left,
        });
    }
    TreeOut {
        nodes,
        leaf_values,
        importances,
    }
}

/// Reports training progress: called with `(trees done, trees in all)` after each tree.
pub type TrainProgress<'p> = &'p mut (dyn FnMut(usize, usize) + Send);

/// Trains `params.n_trees` trees in parallel and flattens them. Returns the trees and the normalised
/// mean-decrease-in-impurity feature importances. `progress` (unless `params.quiet`) is called once per finished
/// tree, from the training threads but one call at a time, with `done` going 1, 2, … `n_trees` in order.
pub(crate) fn train<T: Task>(
    task: &T,
    x: &[f32],
    n_features: usize,
    params: &ForestParams,
    progress: TrainProgress<'_>,
) -> Result<(FlatTrees, Vec<f64>)> {
    let total = params.n_trees;
    let done = Mutex::new((0usize, progress));
    let run = || -> Result<(FlatTrees, Vec<f64>)> {
        let prep = Prepared::new(x, n_features, params)?;
        let trees: Vec<TreeOut> = (0..params.n_trees)
            .into_par_iter()
            .map(|t| {
                let out = build_tree(task, &prep, t);
                if !params.quiet {
                    // A panicking callback poisons the lock; later reports are then skipped.
                    if let Ok(mut guard) = done.lock() {
                        let (n, report) = &mut *guard;
                        *n += 1;
                        report(*n, total);
                    }
                }
                out
            })
            .collect();
        assemble(trees, n_features, task.width())
    };
    match params.n_threads {
        None => run(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| ForestError::ThreadPool(e.to_string()))?
            .install(run),
    }
}

fn assemble(trees: Vec<TreeOut>, n_features: usize, width: usize) -> Result<(FlatTrees, Vec<f64>)> {
    let total_nodes: usize = trees.iter().map(|t| t.nodes.len()).sum();
    if total_nodes >= crate::flat::LEAF as usize {
        return Err(ForestError::InvalidParams(format!(
            "the forest would have {total_nodes} nodes, more than the format's limit {}",
            crate::flat::LEAF - 1
        )));
    }
    let total_leaves: usize = trees.iter().map(|t| t.leaf_values.len()).sum();
    let mut nodes = Vec::with_capacity(total_nodes);
    let mut leaf_values = Vec::with_capacity(total_leaves);
    let mut offsets = Vec::with_capacity(trees.len() + 1);
    let mut importances = vec![0f64; n_features];
    for t in trees {
        let base = nodes.len() as u32;
        let leaf_base = (leaf_values.len() / width) as u32;
        offsets.push(base);
        nodes.extend(t.nodes.iter().map(|n| {
            if n.is_leaf() {
                Node::leaf(n.right + leaf_base)
            } else {
                Node {
                    right: n.right + base,
                    ..*n
                }
            }
        }));
        leaf_values.extend_from_slice(&t.leaf_values);
        let s: f64 = t.importances.iter().sum();
        if s > 0.0 {
            for (a, b) in importances.iter_mut().zip(&t.importances) {
                *a += b / s;
            }
        }
    }
    offsets.push(nodes.len() as u32);
    let s: f64 = importances.iter().sum();
    if s > 0.0 {
        for v in &mut importances {
            *v /= s;
        }
    }
    Ok((
        FlatTrees {
            n_features,
            width,
            nodes,
            offsets,
            leaf_values,
            walk: None,
        }
        .finish(),
        importances,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_is_stable() {
        let mut list: Vec<Entry> = (0..6)
            .map(|r| Entry {
                v: r as f32,
                row: r,
            })
            .collect();
        let go_left = [false, true, false, true, true, false];
        let mut tmp = vec![Entry { v: 0.0, row: 0 }; 6];
        let nl = stable_partition(&mut list, &go_left, &mut tmp);
        assert_eq!(nl, 3);
        let rows: Vec<u32> = list.iter().map(|e| e.row).collect();
        assert_eq!(rows, vec![1, 3, 4, 0, 2, 5]);
    }

    #[test]
    fn entries_sort_as_total_cmp_then_row() {
        let specials = [
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-42,
            -1e-42,
            f32::MAX,
            f32::MIN,
        ];
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        // Repeated values, so that ties have to go by row.
        let x: Vec<f32> = (0..2000)
            .map(|i| {
                if i % 3 == 0 {
                    specials[rng.random_range(0..specials.len())]
                } else {
                    f32::from(rng.random_range(-40i16..40)) / 8.0
                }
            })
            .collect();
        let params = ForestParams::default();
        let prep = Prepared::new(&x, 1, &params).expect("prepared");
        let mut want: Vec<u32> = (0..x.len() as u32).collect();
        want.sort_by(|&a, &b| x[a as usize].total_cmp(&x[b as usize]).then(a.cmp(&b)));
        let got: Vec<u32> = prep.sorted[0].iter().map(|e| e.row).collect();
        assert_eq!(got, want);
        for e in &prep.sorted[0] {
            assert_eq!(e.v.to_bits(), x[e.row as usize].to_bits());
        }
    }
}
