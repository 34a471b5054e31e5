#!/usr/bin/env python3
"""The fused score of saved detection trials split by how close each scene's lines come to
other features (standard library only): the same split as `ClearanceSplit` in
`crates/mission/src/experiments.rs`, for runs saved before the trials printed it, or at other
distances.

    python3 crates/research/scripts/clearance_split.py D SCENES RUN [SCENES RUN ...]

SCENES: the trials' scenes (`cargo run --release -p crackbot-mission --example trial_scenes --
SEED 120 SCENES --printed-cracks`); RUN: the `--out` folder of `crackbot-lab mission trials`
(its `trials.json`). A scene's lines stand apart when every crack and printed decoy keeps D mm,
edge to edge, from every other feature (a screw or bump from its rim, a wavy patch from its
rectangle). Prints, for both groups, the scenes, correct / false / missed and correct detections
as the trials count them (the mean over the group's trials) and pooled.
"""
import json
import math
import sys

from trial_errors import dist_seg, seg_inter


def segment_distance(a, b, c, d):
    if seg_inter(a, b, c, d) is not None:
        return 0.0
    return min(dist_seg(a, c, d), dist_seg(b, c, d), dist_seg(c, a, b), dist_seg(d, a, b))


def line_distance(p, q):
    return min(segment_distance(p[i], p[i + 1], q[j], q[j + 1])
               for i in range(len(p) - 1) for j in range(len(q) - 1))


def gap(f, g):
    """Edge-to-edge gap between a line and another feature, mm; None where neither is a line."""
    if not f.get("path"):
        f, g = g, f
    if not f.get("path"):
        return None
    path, half = f["path"], f["width_mm"] / 2
    if g.get("path"):
        return max(0.0, line_distance(path, g["path"]) - half - g["width_mm"] / 2)
    if g["kind"] == "wavy":
        lo, hi = g["min"], g["max"]
        if any(lo[0] <= p[0] <= hi[0] and lo[1] <= p[1] <= hi[1] for p in path):
            return 0.0
        corners = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]]
        d = min(segment_distance(path[i], path[i + 1], corners[k], corners[(k + 1) % 4])
                for i in range(len(path) - 1) for k in range(4))
        return max(0.0, d - half)
    rim = g["radius_mm"] if g["kind"] == "bump" else g["head_diameter_mm"] / 2
    d = min(dist_seg(g["centre"], path[i], path[i + 1]) for i in range(len(path) - 1))
    return max(0.0, d - rim - half)


def clearance(features):
    gaps = [gap(f, g) for i, f in enumerate(features) for g in features[i + 1:]]
    gaps = [x for x in gaps if x is not None]
    return min(gaps) if gaps else None


def main():
    if len(sys.argv) < 4 or len(sys.argv) % 2:
        sys.exit(__doc__)
    apart_mm = float(sys.argv[1])
    groups = {True: [], False: []}
    for scenes, run in zip(sys.argv[2::2], sys.argv[3::2]):
        with open(f"{run}/trials.json") as f:
            trials = json.load(f)["trials"]
        for t in trials:
            with open(f"{scenes}/scene-{t['seed']}.json") as f:
                c = clearance(json.load(f)["features"])
            groups[c is None or c >= apart_mm].append(t["fused"])
    for apart, scores in groups.items():
        c, f, m = (sum(s[k] for s in scores) for k in ("correct", "false_reports", "missed"))
        shares = [s["correct"] / n if (n := s["correct"] + s["false_reports"] + s["missed"]) else 1.0
                  for s in scores]
        mean = 100 * sum(shares) / len(shares) if shares else math.nan
        pooled = 100 * c / (c + f + m) if c + f + m else math.nan
        print(f"lines {'≥' if apart else '<'} {apart_mm:g} mm from other features: "
              f"{len(scores)} scenes, {c} / {f} / {m}, {mean:.1f} % (pooled {pooled:.1f} %)")


if __name__ == "__main__":
    main()
