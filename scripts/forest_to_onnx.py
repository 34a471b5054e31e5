#!/usr/bin/env python3
"""Exports a crackbot forest file (`CRKFORST`, crates/forest/src/format.rs) to ONNX.

    bash scripts/forest_to_onnx.sh MODEL.forest MODEL.onnx        # makes its venv on first use
    python scripts/forest_to_onnx.py MODEL.forest MODEL.onnx      # with numpy and onnx installed
    bash scripts/forest_to_onnx.sh models/tactile/recognition.ctm context.onnx \
        --section context_forest [--save-forest context.forest]

A deployed tactile model (`CRKTACTL`, crates/tactile/src/model.rs: magic, version 1, header length, JSON
header listing its sections, each a `CRKFORST` forest, CRC-32 of everything before) is read too: its
length and checksum are checked and the forest of `--section` (default `context_forest`; also
`window_forest`, `width_regressor`) is exported; `--save-forest` writes that section as a plain forest
file (for our side of a comparison).

The file is parsed here, independently of the Rust loader, with the same checks in the same order: magic,
format version, kind, exact length, CRC-32 (ISO-HDLC, as zlib), then every structural invariant (tree
offsets, children inside their tree and after their parent, feature and leaf indices in range, no NaN
threshold, finite leaf values).

The graph has one input `x` (float32 `[N, n_features]`) and one `ai.onnx.ml` (opset 3) node:

* classifier -> `TreeEnsembleClassifier` (`post_transform` `NONE`) whose leaves carry our leaf class
  probabilities as they are, so its scores are the sums over trees that our `predict` adds (f32, tree order
  on one thread: the same bits; a zero is left out, adding it changes nothing), then
  - `probabilities` (float32 `[N, K]`) = scores × f32(1 / n_trees), a `Mul`: our `predict_proba`, bit for
    bit (ours scales the same sums by the same f32);
  - `label` (int64 `[N]`) = the class index of the highest score, lowest index on ties: our `predict`. With
    K > 2 it is the operator's own label (the first highest score); with K = 2 ONNX Runtime's label is
    "score of class 1 > 0" (a binary-classifier convention), so `label` is an `ArgMax` of the scores
    instead (first maximum), and both classes get a weight at every leaf, zeros included, else ONNX
    Runtime rewrites a row without a class-1 score as [s, -s]. One class is refused (ONNX Runtime
    needs two).
  The scores are unnormalised on purpose: dividing the weights by n_trees instead would round each
  term and break exact vote ties differently from ours (seen on 1 of 66 902 real windows).
  Our class labels (f64, e.g. crack widths in mm) are kept in the metadata `crackbot_class_labels`
  (JSON); ONNX allows only int64 or string labels, so `label` is the class index, as our `predict`.
* regressor -> `TreeEnsembleRegressor` (`aggregate_function` `AVERAGE`, one target), output `variable`
  (float32 `[N, 1]`): the mean over trees of the leaf means, our `predict`.

Every split is `BRANCH_LEQ` (`x[f] <= threshold` -> the true branch = our left child, the next node in
pre-order) with `nodes_missing_value_tracks_true = 0`, so NaN goes to the false branch = our right child,
as in our traversal.
"""

import argparse
import json
import sys
import zlib
from pathlib import Path

import numpy as np

MAGIC = b"CRKFORST"
SUPPORTED_VERSIONS = (1,)
HEADER_LEN = 40
LEAF = 0xFFFFFFFF
KIND_CLASSIFIER, KIND_REGRESSOR = 1, 2
NODE_DTYPE = np.dtype([("feature", "<u4"), ("threshold", "<f4"), ("right", "<u4")])


class FormatError(Exception):
    """The file is not a valid crackbot forest."""


class Forest:
    """A parsed forest file: the flat arrays of crates/forest/src/flat.rs."""

    def __init__(self, kind, n_features, width, labels, importances, offsets, nodes, leaf_values):
        self.kind = kind
        self.n_features = n_features
        self.width = width
        self.labels = labels
        self.importances = importances
        self.offsets = offsets
        self.nodes = nodes
        self.leaf_values = leaf_values

    @property
    def n_trees(self):
        return len(self.offsets) - 1

    @property
    def kind_name(self):
        return "classifier" if self.kind == KIND_CLASSIFIER else "regressor"


TACTILE_MAGIC = b"CRKTACTL"
TACTILE_VERSIONS = (1,)


def tactile_section(data: bytes, name: str) -> bytes:
    """The `CRKFORST` bytes of section `name` of a deployed tactile model (`CRKTACTL`)."""
    if len(data) < 20:
        raise FormatError(f"truncated tactile model: {len(data)} bytes")
    version, header_len = np.frombuffer(data, dtype="<u4", count=2, offset=8).tolist()
    if version not in TACTILE_VERSIONS:
        raise FormatError(f"tactile model format version {version} not supported ({TACTILE_VERSIONS})")
    if 16 + header_len + 4 > len(data):
        raise FormatError(f"truncated tactile model: a {header_len}-byte header in {len(data)} bytes")
    try:
        header = json.loads(data[16:16 + header_len])
        sections = [(str(s["name"]), int(s["bytes"])) for s in header["sections"]]
    except (ValueError, KeyError, TypeError) as e:
        raise FormatError(f"tactile model header: {e}") from e
    expected = 16 + header_len + sum(n for _, n in sections) + 4
    if len(data) != expected:
        raise FormatError(f"tactile model of {len(data)} bytes, its header announces {expected}")
    stored = int(np.frombuffer(data, dtype="<u4", count=1, offset=len(data) - 4)[0])
    computed = zlib.crc32(data[:-4]) & 0xFFFFFFFF
    if stored != computed:
        raise FormatError(f"tactile model checksum mismatch: stored {stored:#010x}, computed {computed:#010x}")
    at = 16 + header_len
    for section, n in sections:
        if section == name:
            return data[at:at + n]
        at += n
    raise FormatError(f"no section {name!r} in this tactile model (it has {[s for s, _ in sections]})")


def parse(data: bytes) -> Forest:
    """Decodes and validates a forest file, in the order of `format::decode`."""
    if len(data) < 8 or data[:8] != MAGIC:
        raise FormatError(f"bad magic {data[:8]!r}, expected {MAGIC!r}: not a crackbot forest file")
    if len(data) < HEADER_LEN:
        raise FormatError(f"truncated: {len(data)} bytes, the header alone is {HEADER_LEN}")
    version, kind, n_features, width, n_trees, n_nodes, n_leaves, flags = np.frombuffer(
        data, dtype="<u4", count=8, offset=8).tolist()
    if version not in SUPPORTED_VERSIONS:
        raise FormatError(f"format version {version} not supported (this exporter reads {SUPPORTED_VERSIONS})")
    if kind not in (KIND_CLASSIFIER, KIND_REGRESSOR):
        raise FormatError(f"unknown model kind {kind}")
    if flags & ~1:
        raise FormatError(f"unknown flags {flags:#x}")
    has_imp = flags & 1 == 1
    n_labels = width if kind == KIND_CLASSIFIER else 0
    expected = (HEADER_LEN + 8 * n_labels + (8 * n_features if has_imp else 0) + 4 * (n_trees + 1)
                + 12 * n_nodes + 4 * width * n_leaves + 4)
    if len(data) < expected:
        raise FormatError(f"truncated: {len(data)} bytes, the header announces {expected}")
    if len(data) > expected:
        raise FormatError(f"{len(data) - expected} trailing bytes after the model")
    stored = int(np.frombuffer(data, dtype="<u4", count=1, offset=len(data) - 4)[0])
    computed = zlib.crc32(data[:-4]) & 0xFFFFFFFF
    if stored != computed:
        raise FormatError(f"checksum mismatch: stored {stored:#010x}, computed {computed:#010x}")

    pos = HEADER_LEN

    def take(dtype, count):
        nonlocal pos
        a = np.frombuffer(data, dtype=dtype, count=count, offset=pos)
        pos += a.nbytes
        return a

    labels = take("<f8", n_labels).astype(np.float64)
    importances = take("<f8", n_features).astype(np.float64) if has_imp else None
    offsets = take("<u4", n_trees + 1).astype(np.int64)
    nodes = take(NODE_DTYPE, n_nodes)
    leaf_values = take("<f4", width * n_leaves).astype(np.float32).reshape(n_leaves, width) if width else None
    forest = Forest(kind, n_features, width, labels, importances, offsets, nodes, leaf_values)
    validate(forest, n_leaves)
    return forest


def validate(f: Forest, n_leaves: int):
    """`format::validate_parts` + `FlatTrees::validate`: what traversal relies on."""
    if f.n_features == 0 or f.n_features >= LEAF:
        raise FormatError(f"n_features {f.n_features} out of range")
    if f.width == 0:
        raise FormatError("leaf width 0")
    if f.kind == KIND_CLASSIFIER:
        if not np.all(np.isfinite(f.labels)):
            raise FormatError("non-finite class label")
    elif f.width != 1:
        raise FormatError(f"regressor with leaf width {f.width}")
    if f.importances is not None and not np.all(np.isfinite(f.importances)):
        raise FormatError("feature importances: non-finite")
    if len(f.offsets) < 2:
        raise FormatError("no trees")
    if f.offsets[0] != 0:
        raise FormatError(f"first tree starts at node {f.offsets[0]}, not 0")
    if f.offsets[-1] != len(f.nodes):
        raise FormatError(f"last tree ends at {f.offsets[-1]}, node count is {len(f.nodes)}")
    bad = np.flatnonzero(~np.isfinite(f.leaf_values.ravel()))
    if len(bad):
        raise FormatError(f"leaf value {bad[0]} is not finite")
    if np.any(np.diff(f.offsets) <= 0):
        t = int(np.flatnonzero(np.diff(f.offsets) <= 0)[0])
        raise FormatError(f"tree {t} is empty (nodes {f.offsets[t]}..{f.offsets[t + 1]})")
    idx = np.arange(len(f.nodes), dtype=np.int64)
    tree = np.searchsorted(f.offsets, idx, side="right") - 1
    end = f.offsets[tree + 1]
    feature = f.nodes["feature"].astype(np.int64)
    right = f.nodes["right"].astype(np.int64)
    leaf = feature == LEAF
    checks = [
        (leaf & (right >= n_leaves), "leaf id >= leaf count"),
        (~leaf & (feature >= f.n_features), "feature index >= n_features"),
        (~leaf & np.isnan(f.nodes["threshold"]), "NaN threshold"),
        (~leaf & (idx + 1 >= end), "left child outside its tree"),
        (~leaf & ((right <= idx + 1) | (right >= end)), "right child not after the left child inside its tree"),
    ]
    for mask, what in checks:
        if mask.any():
            i = int(np.flatnonzero(mask)[0])
            raise FormatError(f"node {i} (tree {tree[i]}): {what}")


def to_onnx(f: Forest, name="crackbot_forest"):
    """The ONNX model of a parsed forest (see the module docs)."""
    from onnx import TensorProto, helper

    idx = np.arange(len(f.nodes), dtype=np.int64)
    tree = np.searchsorted(f.offsets, idx, side="right") - 1
    local = idx - f.offsets[tree]
    feature = f.nodes["feature"].astype(np.int64)
    leaf = feature == LEAF
    right = f.nodes["right"].astype(np.int64)
    true_ids = np.where(leaf, 0, local + 1)
    false_ids = np.where(leaf, 0, right - f.offsets[tree])
    common = dict(
        nodes_treeids=tree.tolist(),
        nodes_nodeids=local.tolist(),
        nodes_featureids=np.where(leaf, 0, feature).tolist(),
        nodes_values=np.where(leaf, 0.0, f.nodes["threshold"]).astype(np.float32).tolist(),
        nodes_modes=np.where(leaf, "LEAF", "BRANCH_LEQ").tolist(),
        nodes_truenodeids=true_ids.tolist(),
        nodes_falsenodeids=false_ids.tolist(),
        nodes_missing_value_tracks_true=[0] * len(f.nodes),
        post_transform="NONE",
    )
    leaf_nodes = np.flatnonzero(leaf)
    leaf_ids = right[leaf_nodes]
    x = helper.make_tensor_value_info("x", TensorProto.FLOAT, [None, f.n_features])
    if f.kind == KIND_CLASSIFIER:
        k = f.width
        if k < 2:
            raise FormatError(f"a classifier with {k} class: ONNX Runtime's TreeEnsembleClassifier needs two or more")
        probs = f.leaf_values[leaf_ids]  # [n_leaf_nodes, k]
        keep = probs != 0 if k > 2 else np.ones_like(probs, dtype=bool)
        for c in np.flatnonzero(~keep.any(axis=0)):
            keep[0, c] = True  # every class at least once
        rows, cls = np.nonzero(keep)
        tree_label = "label" if k > 2 else "tree_label"
        nodes = [helper.make_node(
            "TreeEnsembleClassifier", ["x"], [tree_label, "scores"], domain="ai.onnx.ml", name="forest",
            classlabels_int64s=list(range(k)),
            class_treeids=tree[leaf_nodes][rows].tolist(),
            class_nodeids=local[leaf_nodes][rows].tolist(),
            class_ids=cls.tolist(),
            class_weights=probs[rows, cls].astype(np.float32).tolist(),
            **common)]
        nodes.append(helper.make_node("Mul", ["scores", "inv_n_trees"], ["probabilities"], name="mean"))
        if k == 2:
            nodes.append(helper.make_node("ArgMax", ["scores"], ["label"], name="argmax", axis=1, keepdims=0,
                                          select_last_index=0))
        initializers = [helper.make_tensor("inv_n_trees", TensorProto.FLOAT, [],
                                           [float(np.float32(1.0) / np.float32(f.n_trees))])]
        outputs = [helper.make_tensor_value_info("label", TensorProto.INT64, [None]),
                   helper.make_tensor_value_info("probabilities", TensorProto.FLOAT, [None, k])]
    else:
        values = f.leaf_values[leaf_ids, 0]
        node = helper.make_node(
            "TreeEnsembleRegressor", ["x"], ["variable"], domain="ai.onnx.ml", name="forest",
            n_targets=1,
            aggregate_function="AVERAGE",
            target_treeids=tree[leaf_nodes].tolist(),
            target_nodeids=local[leaf_nodes].tolist(),
            target_ids=[0] * len(leaf_nodes),
            target_weights=values.astype(np.float32).tolist(),
            **common)
        nodes, initializers = [node], []
        outputs = [helper.make_tensor_value_info("variable", TensorProto.FLOAT, [None, 1])]
    graph = helper.make_graph(nodes, name, [x], outputs, initializer=initializers)
    model = helper.make_model(
        graph, producer_name="crackbot scripts/forest_to_onnx.py",
        opset_imports=[helper.make_opsetid("", 17), helper.make_opsetid("ai.onnx.ml", 3)])
    model.ir_version = 8
    meta = {
        "crackbot_kind": f.kind_name,
        "crackbot_n_trees": str(f.n_trees),
        "crackbot_n_features": str(f.n_features),
    }
    if f.kind == KIND_CLASSIFIER:
        meta["crackbot_class_labels"] = json.dumps(f.labels.tolist())
    helper.set_model_props(model, meta)
    return model


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("forest", type=Path, help="crackbot forest file (CRKFORST) or deployed tactile model (CRKTACTL)")
    p.add_argument("onnx", type=Path, help="ONNX file to write")
    p.add_argument("--section", default="context_forest",
                   help="the forest of a deployed tactile model (CRKTACTL) to export (default: context_forest)")
    p.add_argument("--save-forest", type=Path, help="also write the exported forest as a plain CRKFORST file")
    a = p.parse_args(argv)
    import onnx

    try:
        data = a.forest.read_bytes()
        if data[:8] == TACTILE_MAGIC:
            data = tactile_section(data, a.section)
        forest = parse(data)
        model = to_onnx(forest)
        if a.save_forest:
            a.save_forest.write_bytes(data)
    except (OSError, FormatError) as e:
        print(f"forest_to_onnx: {a.forest}: {e}", file=sys.stderr)
        return 1
    onnx.checker.check_model(model)
    a.onnx.parent.mkdir(parents=True, exist_ok=True)
    tmp = a.onnx.with_name(f".{a.onnx.name}.tmp")
    tmp.write_bytes(model.SerializeToString())
    tmp.replace(a.onnx)
    print(f"{a.onnx}: {forest.kind_name}, {forest.n_trees} trees, {len(forest.nodes)} nodes, "
          f"{forest.n_features} features" + (f", {forest.width} classes" if forest.kind == KIND_CLASSIFIER else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
