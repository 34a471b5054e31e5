//! The flat inference layout shared by the classifier and the regressor.
//!
//! All trees' nodes live in one `Vec<Node>`, tree `t` occupying `nodes[offsets[t]..offsets[t + 1]]` in
//! depth-first pre-order: the left child of an internal node `i` is `i + 1`, its right child is
//! `node.right` (absolute index, `> i + 1`, inside the same tree). A leaf has `feature == LEAF` and
//! `right` = its leaf id; its values are `leaf_values[id * width .. (id + 1) * width]` (class probabilities
//! for a classifier, `width = 1` mean value for a regressor).
//!
//! Traversal follows scikit-learn: `x[feature] <= threshold` goes left. A NaN feature value goes right.

use crate::error::FormatError;

/// Marker in [`Node::feature`] for a leaf.
pub const LEAF: u32 = u32::MAX;

/// One node of the flat layout (12 bytes).
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct Node {
    /// Feature index, or [`LEAF`].
    pub feature: u32,
    /// Split threshold (`x[feature] <= threshold` → left); unused (0) in leaves.
    pub threshold: f32,
    /// Absolute index of the right child, or the leaf id for a leaf.
    pub right: u32,
}

impl Node {
    /// A leaf pointing at leaf id `leaf`.
    pub fn leaf(leaf: u32) -> Self {
        Self {
            feature: LEAF,
            threshold: 0.0,
            right: leaf,
        }
    }
    /// Whether this node is a leaf.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.feature == LEAF
    }
}

/// Feature `f` of row `x`, NaN when the row is too short (never panics).
#[inline(always)]
fn feat(x: &[f32], f: u32) -> f32 {
    match x.get(f as usize) {
        Some(&v) => v,
        None => f32::NAN,
    }
}

/// One step down from internal node `i` (node `n`) for row `x`.
#[inline(always)]
fn step(i: u32, n: Node, x: &[f32]) -> u32 {
    // The comparison is unpredictable: ask for a conditional move, a branch would mispredict half the time.
    std::hint::select_unpredictable(feat(x, n.feature) <= n.threshold, i + 1, n.right)
}

/// Like [`step`] for the row starting at `x[base]`.
#[inline(always)]
fn step_at(i: u32, n: Node, x: &[f32], base: usize) -> u32 {
    let v = match x.get(base + n.feature as usize) {
        Some(&v) => v,
        None => f32::NAN,
    };
    std::hint::select_unpredictable(v <= n.threshold, i + 1, n.right)
}

/// Reusable buffers of [`FlatTrees::accumulate_block`].
#[derive(Debug, Default)]
pub(crate) struct BlockScratch {
    active: Vec<(u32, u32)>,
    last: Vec<u32>,
}

/// Flattened trees (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct FlatTrees {
    pub n_features: usize,
    pub width: usize,
    pub nodes: Vec<Node>,
    /// `n_trees + 1` offsets into `nodes`.
    pub offsets: Vec<u32>,
    pub leaf_values: Vec<f32>,
    /// The single-row layout, derived from the fields above by [`FlatTrees::finish`] (`None` until
    /// then, or when the model does not fit it: the row path then walks `nodes`).
    pub walk: Option<WalkTrees>,
}

impl PartialEq for FlatTrees {
    /// The model, not the derived layout.
    fn eq(&self, other: &Self) -> bool {
        self.n_features == other.n_features
            && self.width == other.width
            && self.nodes == other.nodes
            && self.offsets == other.offsets
            && self.leaf_values == other.leaf_values
    }
}

/// Most features the single-row layout can index (its feature field has 8 bits, one value of which
/// marks a leaf).
const WALK_MAX_FEATURES: usize = 255;

/// One node of the single-row layout (8 bytes): 5 fit in a cache line where 12-byte nodes fit 3 or 4.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub(crate) struct WalkNode {
    /// Split threshold; in a leaf, the bits of the leaf id.
    threshold: f32,
    /// Low 8 bits: the feature, `n_features` in a leaf. High 24 bits: the right child's distance
    /// from this node (≥ 2), 0 in a leaf.
    packed: u32,
}

/// Every tree re-encoded for branch-free descent of one row: a leaf reads the padding feature
/// (always NaN), which sends it "right" by a distance of 0, i.e. to itself. A group of trees
/// therefore steps together with no branch per tree (a tree that reached its leaf stays there):
/// as many steps as its shallowest leaf's depth unchecked, then one check per step for the group.
#[derive(Debug, Clone)]
pub(crate) struct WalkTrees {
    nodes: Vec<WalkNode>,
    /// Per [`TREE_LANES`] group of trees, the depth of its shallowest and of its deepest leaf:
    /// the steps every row takes, and the most steps a row can take.
    group_steps: Vec<(u32, u32)>,
    /// The leaf values again, each leaf's padded with zeros to `stride` values (a power of two
    /// ≤ [`WALK_MAX_STRIDE`]), so that a whole leaf is added to a register accumulator at once.
    /// Empty when the width is larger (the sums then go through the caller's slice).
    leaves: Vec<f32>,
    /// Values per leaf in `leaves`.
    stride: usize,
}

/// Widest leaf (classes, or 1 for a regressor) whose sums are kept in registers by the single-row
/// walk.
const WALK_MAX_STRIDE: usize = 16;

/// A row copied into a fixed buffer for the single-row layout: features past the row's length and
/// the leaf padding slot `n_features` are NaN, so every 8-bit feature index is in bounds.
#[inline(always)]
fn padded_row(x: &[f32], n_features: usize) -> [f32; WALK_MAX_FEATURES + 1] {
    let mut xs = [f32::NAN; WALK_MAX_FEATURES + 1];
    let n = x.len().min(n_features);
    xs[..n].copy_from_slice(&x[..n]);
    xs
}

/// One step of the single-row layout (a leaf stays where it is).
#[inline(always)]
fn walk_step(i: u32, n: WalkNode, xs: &[f32; WALK_MAX_FEATURES + 1]) -> u32 {
    let v = xs[(n.packed & 0xFF) as usize];
    std::hint::select_unpredictable(v <= n.threshold, i + 1, i + (n.packed >> 8))
}

/// Number of trees traversed together for one row (overlaps their cache misses and dependency
/// chains; 16 measured fastest of 4, 8, 16 on the real windows, `benches/tactile.rs`).
const TREE_LANES: usize = 16;
/// Deepest leaf up to which a group of trees walks every row to that depth with no check for
/// "every tree on a leaf": measured 5 % faster than checking on the deployed depth-≤ 10 forests,
/// while fully grown trees (a few leaves 30 deep) need the checks (half again as many steps
/// without them; `scripts/callgrind_check.sh`).
const UNCHECKED_DEPTH: u32 = 12;
/// Rows per block in the batch path: each tree (~150 KB with its leaves for 7k nodes) is used for a whole
/// block while it sits in the L2 cache, next to the block's rows (96 KB) and accumulators (128 KB).
pub(crate) const BLOCK_ROWS: usize = 8192;

impl FlatTrees {
    pub fn n_trees(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Checks every invariant the traversal relies on, so that traversal of a validated model always
    /// terminates and never indexes out of range.
    pub fn validate(&self) -> Result<(), FormatError> {
        let bad = |m: String| Err(FormatError::Inconsistent(m));
        if self.n_features == 0 || self.n_features >= LEAF as usize {
            return bad(format!("n_features {} out of range", self.n_features));
        }
        if self.width == 0 {
            return bad("leaf width 0".into());
        }
        if self.offsets.len() < 2 {
            return bad("no trees".into());
        }
        if self.offsets[0] != 0 {
            return bad(format!(
                "first tree starts at node {}, not 0",
                self.offsets[0]
            ));
        }
        if self.nodes.len() >= LEAF as usize
            || self.offsets.last().map(|&o| o as usize) != Some(self.nodes.len())
        {
            return bad(format!(
                "last tree ends at {:?}, node count is {}",
                self.offsets.last(),
                self.nodes.len()
            ));
        }
        if !self.leaf_values.len().is_multiple_of(self.width) {
            return bad(format!(
                "leaf table length {} not a multiple of {}",
                self.leaf_values.len(),
                self.width
            ));
        }
        let n_leaves = self.leaf_values.len() / self.width;
        if let Some(i) = self.leaf_values.iter().position(|v| !v.is_finite()) {
            return bad(format!("leaf value {i} is not finite"));
        }
        for t in 0..self.n_trees() {
            let (start, end) = (self.offsets[t], self.offsets[t + 1]);
            if end <= start {
                return bad(format!("tree {t} is empty (nodes {start}..{end})"));
            }
            if end as usize > self.nodes.len() {
                return bad(format!(
                    "tree {t} ends at node {end}, past the {} nodes",
                    self.nodes.len()
                ));
            }
            for i in start..end {
                let n = self.nodes[i as usize];
                if n.is_leaf() {
                    if n.right as usize >= n_leaves {
                        return bad(format!(
                            "node {i}: leaf id {} ≥ leaf count {n_leaves}",
                            n.right
                        ));
                    }
                    continue;
                }
                if n.feature as usize >= self.n_features {
                    return bad(format!(
                        "node {i}: feature {} ≥ n_features {}",
                        n.feature, self.n_features
                    ));
                }
                if n.threshold.is_nan() {
                    return bad(format!("node {i}: NaN threshold"));
                }
                if i + 1 >= end {
                    return bad(format!(
                        "node {i}: left child {} outside tree {t} ({start}..{end})",
                        i + 1
                    ));
                }
                if n.right <= i + 1 || n.right >= end {
                    return bad(format!(
                        "node {i}: right child {} not in {}..{end} (tree {t})",
                        n.right,
                        i + 2
                    ));
                }
            }
        }
        Ok(())
    }

    /// Leaf id reached by row `x` in tree `t`.
    #[inline]
    pub fn leaf_of(&self, t: usize, x: &[f32]) -> usize {
        let mut i = self.offsets[t];
        loop {
            let n = self.nodes[i as usize];
            if n.is_leaf() {
                return n.right as usize;
            }
            i = step(i, n, x);
        }
    }

    /// Derives the single-row layout ([`WalkTrees`]) of a validated model, when it fits (at most
    /// 255 features, right children less than 2^24 nodes away).
    pub fn finish(mut self) -> Self {
        self.walk = self.build_walk();
        self
    }

    fn build_walk(&self) -> Option<WalkTrees> {
        if self.n_features >= WALK_MAX_FEATURES {
            return None;
        }
        let mut nodes = Vec::with_capacity(self.nodes.len());
        for (i, n) in self.nodes.iter().enumerate() {
            nodes.push(if n.is_leaf() {
                WalkNode {
                    threshold: f32::from_bits(n.right),
                    packed: self.n_features as u32,
                }
            } else {
                let distance = n.right.checked_sub(i as u32)?;
                if distance >= 1 << 24 {
                    return None;
                }
                WalkNode {
                    threshold: n.threshold,
                    packed: n.feature | (distance << 8),
                }
            });
        }
        // Depths of each tree's shallowest and deepest leaf, then of each group of lanes.
        let mut depths = Vec::with_capacity(self.n_trees());
        let mut stack: Vec<(u32, u32)> = Vec::new();
        for t in 0..self.n_trees() {
            let (mut shallowest, mut deepest) = (u32::MAX, 0);
            stack.push((self.offsets[t], 0));
            while let Some((i, d)) = stack.pop() {
                let n = self.nodes[i as usize];
                if n.is_leaf() {
                    shallowest = shallowest.min(d);
                    deepest = deepest.max(d);
                } else {
                    stack.push((i + 1, d + 1));
                    stack.push((n.right, d + 1));
                }
            }
            depths.push((shallowest, deepest));
        }
        let group_steps = depths
            .chunks(TREE_LANES)
            .map(|g| {
                let sure = g.iter().map(|d| d.0).min().unwrap_or(0);
                let most = g.iter().map(|d| d.1).max().unwrap_or(0);
                (sure, most)
            })
            .collect();
        let stride = self.width.next_power_of_two();
        let leaves = if stride <= WALK_MAX_STRIDE {
            let mut leaves = vec![0f32; self.leaf_values.len() / self.width * stride];
            for (dst, src) in leaves
                .chunks_exact_mut(stride)
                .zip(self.leaf_values.chunks_exact(self.width))
            {
                dst[..self.width].copy_from_slice(src);
            }
            leaves
        } else {
            Vec::new()
        };
        Some(WalkTrees {
            nodes,
            group_steps,
            leaves,
            stride,
        })
    }

    /// Adds every tree's leaf values for row `x` to `acc[..width]` (tree order, f32).
    pub fn accumulate_row(&self, x: &[f32], acc: &mut [f32]) {
        match &self.walk {
            Some(walk) => self.accumulate_row_walk(walk, x, acc),
            None => self.accumulate_row_nodes(x, acc),
        }
    }

    /// [`accumulate_row`](Self::accumulate_row) on the single-row layout: groups of
    /// [`TREE_LANES`] trees step together without a branch per tree, until the row has reached a
    /// leaf in each; the sums stay in registers when the leaves are narrow enough.
    fn accumulate_row_walk(&self, walk: &WalkTrees, x: &[f32], acc: &mut [f32]) {
        match walk.stride {
            1 => self.walk_in_registers::<1>(walk, x, acc),
            2 => self.walk_in_registers::<2>(walk, x, acc),
            4 => self.walk_in_registers::<4>(walk, x, acc),
            8 => self.walk_in_registers::<8>(walk, x, acc),
            16 => self.walk_in_registers::<16>(walk, x, acc),
            _ => {
                let w = self.width;
                self.walk_leaves(walk, x, |leaf| {
                    add(acc, &self.leaf_values[leaf * w..leaf * w + w]);
                });
            }
        }
    }

    /// The walk with the sums in an `S`-wide local accumulator (`S` = the padded leaf stride):
    /// each value is still the sum of its trees' leaves in tree order, added one by one in `f32`,
    /// so the result is the one [`add`] into `acc` gives, bit for bit.
    #[inline(always)]
    fn walk_in_registers<const S: usize>(&self, walk: &WalkTrees, x: &[f32], acc: &mut [f32]) {
        let mut sums = [0f32; S];
        let n = acc.len().min(self.width).min(S);
        sums[..n].copy_from_slice(&acc[..n]);
        self.walk_leaves(walk, x, |leaf| {
            if let Some(v) = walk.leaves.get(leaf * S..leaf * S + S) {
                for (a, b) in sums.iter_mut().zip(v) {
                    *a += *b;
                }
            }
        });
        acc[..n].copy_from_slice(&sums[..n]);
    }

    /// Walks every tree for row `x` on the single-row layout and hands each tree's leaf id to
    /// `leaf`, in tree order.
    #[inline(always)]
    fn walk_leaves(&self, walk: &WalkTrees, x: &[f32], mut leaf: impl FnMut(usize)) {
        let xs = &padded_row(x, self.n_features);
        let nodes = &walk.nodes;
        let n_trees = self.n_trees();
        let mut t = 0;
        for &(sure, most) in &walk.group_steps {
            let lanes = TREE_LANES.min(n_trees - t);
            let mut pos = [0u32; TREE_LANES];
            pos[..lanes].copy_from_slice(&self.offsets[t..t + lanes]);
            // Unused lanes sit on tree t's root and repeat its walk; their leaves are not added.
            for p in &mut pos[lanes..] {
                *p = self.offsets[t];
            }
            if most <= UNCHECKED_DEPTH {
                // Shallow trees: every step to the deepest leaf, with no check at all.
                for _ in 0..most {
                    for p in &mut pos {
                        *p = walk_step(*p, nodes[*p as usize], xs);
                    }
                }
            } else {
                // Deep trees: the steps every tree takes, then only the trees not yet on a leaf
                // step, until none is left.
                for _ in 0..sure {
                    for p in &mut pos {
                        *p = walk_step(*p, nodes[*p as usize], xs);
                    }
                }
                loop {
                    let mut active = false;
                    for p in &mut pos {
                        let n = nodes[*p as usize];
                        if n.packed >> 8 != 0 {
                            *p = walk_step(*p, n, xs);
                            active = true;
                        }
                    }
                    if !active {
                        break;
                    }
                }
            }
            for &p in &pos[..lanes] {
                leaf(nodes[p as usize].threshold.to_bits() as usize);
            }
            t += lanes;
        }
    }

    /// [`accumulate_row`](Self::accumulate_row) on `nodes`.
    fn accumulate_row_nodes(&self, x: &[f32], acc: &mut [f32]) {
        let w = self.width;
        let n_trees = self.n_trees();
        let mut t = 0;
        while t + TREE_LANES <= n_trees {
            let mut pos = [0u32; TREE_LANES];
            pos.copy_from_slice(&self.offsets[t..t + TREE_LANES]);
            loop {
                let mut active = false;
                for p in &mut pos {
                    let n = self.nodes[*p as usize];
                    if !n.is_leaf() {
                        *p = step(*p, n, x);
                        active = true;
                    }
                }
                if !active {
                    break;
                }
            }
            for p in pos {
                let leaf = self.nodes[p as usize].right as usize;
                add(acc, &self.leaf_values[leaf * w..leaf * w + w]);
            }
            t += TREE_LANES;
        }
        while t < n_trees {
            let leaf = self.leaf_of(t, x);
            add(acc, &self.leaf_values[leaf * w..leaf * w + w]);
            t += 1;
        }
    }

    /// Adds every tree's leaf values for each row of the block `x` (row-major, `n_features` per row, at most
    /// [`BLOCK_ROWS`] rows) to `acc` (`rows × width`), in tree order for each row.
    pub fn accumulate_block(&self, x: &[f32], acc: &mut [f32], scratch: &mut BlockScratch) {
        match &self.walk {
            // Row by row on the single-row layout: its 16 lanes of trees measured faster than the
            // level-by-level block walk (0.56 vs 0.33 M windows/s at depth ≤ 8, equal on fully grown
            // trees; `benches/tactile.rs`).
            Some(walk) => {
                let (nf, w) = (self.n_features, self.width);
                for (xr, ar) in x.chunks_exact(nf).zip(acc.chunks_exact_mut(w)) {
                    self.accumulate_row_walk(walk, xr, ar);
                }
            }
            None => self.accumulate_block_nodes(x, acc, scratch),
        }
    }

    /// [`accumulate_block`](Self::accumulate_block) on `nodes`, tree by tree.
    ///
    /// Per tree, all rows of the block descend one level at a time: the list of rows still at an internal
    /// node is compacted without branches after each level. The iterations of a level are independent, so
    /// the CPU overlaps their memory accesses, and there is no mispredicted branch per row or per node.
    fn accumulate_block_nodes(&self, x: &[f32], acc: &mut [f32], scratch: &mut BlockScratch) {
        let nf = self.n_features;
        let w = self.width;
        let rows = x.len() / nf;
        let BlockScratch { active, last } = scratch;
        last.clear();
        last.resize(rows, 0);
        for t in 0..self.n_trees() {
            let root = self.offsets[t];
            active.clear();
            active.extend((0..rows as u32).map(|r| (r, root)));
            let mut len = active.len();
            while len > 0 {
                let mut wp = 0;
                for i in 0..len {
                    let (r, p) = active[i];
                    let n = self.nodes[p as usize];
                    last[r as usize] = p;
                    let np = step_at(p, n, x, r as usize * nf);
                    active[wp] = (r, np);
                    wp += !n.is_leaf() as usize;
                }
                len = wp;
            }
            for (r, &p) in last.iter().enumerate() {
                let l = self.nodes[p as usize].right as usize;
                add(
                    &mut acc[r * w..(r + 1) * w],
                    &self.leaf_values[l * w..l * w + w],
                );
            }
        }
    }

    /// Depth of the deepest leaf over all trees.
    pub fn max_depth(&self) -> usize {
        let mut best = 0;
        let mut stack: Vec<(u32, usize)> = Vec::new();
        for t in 0..self.n_trees() {
            stack.push((self.offsets[t], 0));
            while let Some((i, d)) = stack.pop() {
                let n = self.nodes[i as usize];
                if n.is_leaf() {
                    best = best.max(d);
                } else {
                    stack.push((i + 1, d + 1));
                    stack.push((n.right, d + 1));
                }
            }
        }
        best
    }
}

#[inline(always)]
fn add(acc: &mut [f32], v: &[f32]) {
    for (a, b) in acc.iter_mut().zip(v) {
        *a += *b;
    }
}

/// Largest `f32` that is `<= v` (for finite `v` within the `f32` range; `v` itself when exactly
/// representable). With `t = round_down_f32(t64)`, `x <= t` ⟺ `x <= t64` for every `f32` x.
pub fn round_down_f32(v: f64) -> f32 {
    if v.is_nan() {
        return f32::NAN;
    }
    let f = v as f32; // round to nearest
    if (f as f64) <= v {
        f
    } else {
        next_down(f)
    }
}

/// The next `f32` below `f` (finite or +inf input).
fn next_down(f: f32) -> f32 {
    if f.is_nan() || f == f32::NEG_INFINITY {
        return f;
    }
    if f == 0.0 {
        return -f32::from_bits(1);
    }
    let bits = f.to_bits();
    if f > 0.0 {
        f32::from_bits(bits - 1)
    } else {
        f32::from_bits(bits + 1)
    }
}

/// Split threshold between two consecutive distinct sorted values `a < b`, like scikit-learn (midpoint in
/// `f64`, falling back to `a` when the midpoint rounds to `b`), rounded down to `f32` so that
/// `a <= t < b`.
pub(crate) fn midpoint_threshold(a: f32, b: f32) -> f32 {
    let mid = a as f64 / 2.0 + b as f64 / 2.0;
    let t = round_down_f32(mid);
    if t >= b || t < a || !t.is_finite() {
        a
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_down_is_largest_below() {
        for &v in &[
            0.1f64,
            512.35,
            -3.3,
            1e-40,
            -1e-40,
            0.0,
            1.0,
            1e30,
            -7.000000001,
        ] {
            let t = round_down_f32(v);
            assert!(t as f64 <= v, "{v}: {t}");
            assert!(next_up(t) as f64 > v, "{v}: {t}");
        }
        assert_eq!(round_down_f32(0.5), 0.5);
    }

    fn next_up(f: f32) -> f32 {
        if f == 0.0 {
            return f32::from_bits(1);
        }
        if f > 0.0 {
            f32::from_bits(f.to_bits() + 1)
        } else {
            f32::from_bits(f.to_bits() - 1)
        }
    }

    #[test]
    fn midpoint_between() {
        let a = 512.3f32;
        let b = 512.4f32;
        let t = midpoint_threshold(a, b);
        assert!(a <= t && t < b);
        let c = f32::from_bits(a.to_bits() + 1);
        assert_eq!(midpoint_threshold(a, c), a);
        assert_eq!(midpoint_threshold(-1.0, 1.0), 0.0);
    }

    #[test]
    fn validation_catches_bad_children() {
        let ok = FlatTrees {
            n_features: 2,
            width: 1,
            nodes: vec![
                Node {
                    feature: 1,
                    threshold: 0.5,
                    right: 2,
                },
                Node::leaf(0),
                Node::leaf(1),
            ],
            offsets: vec![0, 3],
            leaf_values: vec![1.0, 2.0],
            walk: None,
        };
        assert!(ok.validate().is_ok());
        assert_eq!(ok.leaf_of(0, &[0.0, 0.0]), 0);
        assert_eq!(ok.leaf_of(0, &[0.0, 1.0]), 1);
        assert_eq!(ok.leaf_of(0, &[0.0, f32::NAN]), 1);
        assert_eq!(ok.leaf_of(0, &[0.0]), 1);
        assert_eq!(ok.max_depth(), 1);
        let mut b = ok.clone();
        b.nodes[0].right = 0;
        assert!(b.validate().is_err());
        let mut b = ok.clone();
        b.nodes[0].right = 3;
        assert!(b.validate().is_err());
        let mut b = ok.clone();
        b.nodes[0].feature = 2;
        assert!(b.validate().is_err());
        let mut b = ok.clone();
        b.nodes[2].right = 2;
        assert!(b.validate().is_err());
        let mut b = ok.clone();
        b.nodes[2] = Node {
            feature: 0,
            threshold: 0.0,
            right: 1,
        };
        assert!(b.validate().is_err());
        let mut b = ok;
        b.offsets = vec![0, 2];
        assert!(b.validate().is_err());
    }

    /// The single-row layout gives bit for bit the same sums as the 12-byte nodes, on forests of
    /// every shape (single-leaf trees, tree counts not a multiple of the lanes, depth caps) and on
    /// rows with NaN, infinities and missing features.
    #[test]
    fn walk_layout_matches_the_nodes() {
        use crate::{synthetic, ForestParams, RandomForest};
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        // Both walks (unchecked, checked) must be exercised.
        let (mut deep_seen, mut shallow_seen) = (false, false);
        // Class counts: leaves padded to 2, 4, 8 and 16 values, and wider than the registers.
        for (n_trees, depth, spread, k) in [
            (1, None, 40.0, 4),
            (7, Some(3), 60.0, 4),
            (13, None, 25.0, 4),
            (40, Some(9), 50.0, 4),
            (33, Some(10), 50.0, 2),
            (32, Some(10), 50.0, 6),
            (17, None, 30.0, 11),
            (20, Some(8), 30.0, 19),
        ] {
            let data = synthetic::blobs(600, 3, k, spread, n_trees as u64).unwrap();
            let forest = RandomForest::fit(
                &data,
                &ForestParams::classifier()
                    .n_trees(n_trees)
                    .max_depth(depth)
                    .seed(3)
                    .quiet(true),
            )
            .unwrap();
            let trees = &forest.trees;
            assert!(trees.walk.is_some());
            deep_seen |= trees.max_depth() > UNCHECKED_DEPTH as usize;
            shallow_seen |= trees.max_depth() <= UNCHECKED_DEPTH as usize;
            for r in 0..400 {
                let mut row: Vec<f32> = (0..3).map(|_| rng.random_range(300.0..900.0)).collect();
                match r % 8 {
                    0 => row[r % 3] = f32::NAN,
                    1 => row[r % 3] = f32::INFINITY,
                    2 => row[r % 3] = f32::NEG_INFINITY,
                    3 => row.truncate(r % 3),
                    4 => row.push(1.0),
                    _ => {}
                }
                let (mut a, mut b) = (vec![0.25f32; k], vec![0.25f32; k]);
                trees.accumulate_row(&row, &mut a);
                trees.accumulate_row_nodes(&row, &mut b);
                assert_eq!(
                    a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    b.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    "row {row:?}, {n_trees} trees"
                );
            }
        }
        assert!(
            deep_seen && shallow_seen,
            "deep {deep_seen}, shallow {shallow_seen}"
        );
    }

    /// The same for a regressor (one value per leaf, summed in a register).
    #[test]
    fn walk_layout_matches_the_nodes_for_a_regressor() {
        use crate::{ForestParams, RandomForestRegressor, RegressionDataset};
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let x: Vec<f32> = (0..1500).map(|_| rng.random_range(-5.0..5.0)).collect();
        let y: Vec<f32> = x.chunks_exact(3).map(|r| r[0] * r[1] + r[2]).collect();
        let data = RegressionDataset::new(x, 3, y).unwrap();
        let forest = RandomForestRegressor::fit(
            &data,
            &ForestParams::regressor()
                .n_trees(21)
                .max_depth(Some(7))
                .seed(5)
                .quiet(true),
        )
        .unwrap();
        let trees = &forest.trees;
        assert!(trees.walk.is_some());
        for _ in 0..300 {
            let row: Vec<f32> = (0..3).map(|_| rng.random_range(-6.0..6.0)).collect();
            let (mut a, mut b) = ([1.5f32], [1.5f32]);
            trees.accumulate_row(&row, &mut a);
            trees.accumulate_row_nodes(&row, &mut b);
            assert_eq!(a[0].to_bits(), b[0].to_bits(), "row {row:?}");
        }
    }

    #[test]
    fn walk_layout_is_skipped_when_features_do_not_fit() {
        let mut leaf_values = vec![0f32; 2];
        leaf_values[1] = 1.0;
        let t = FlatTrees {
            n_features: 300,
            width: 1,
            nodes: vec![
                Node {
                    feature: 299,
                    threshold: 0.5,
                    right: 2,
                },
                Node::leaf(0),
                Node::leaf(1),
            ],
            offsets: vec![0, 3],
            leaf_values,
            walk: None,
        };
        assert!(t.validate().is_ok());
        let t = t.finish();
        assert!(t.walk.is_none());
        let mut row = vec![0f32; 300];
        let mut acc = [0f32];
        t.accumulate_row(&row, &mut acc);
        assert_eq!(acc, [0.0]);
        row[299] = 1.0;
        t.accumulate_row(&row, &mut acc);
        assert_eq!(acc, [1.0]);
        // The block path falls back to the 12-byte nodes too.
        let mut block = vec![0f32; 600];
        block[599] = 1.0;
        let mut acc = [0f32; 2];
        t.accumulate_block(&block, &mut acc, &mut BlockScratch::default());
        assert_eq!(acc, [0.0, 1.0]);
    }
}
