#!/usr/bin/env python3
"""Which true cracks of saved trial scenes have a piece of the detector's crack map to touch
(standard library only): a crack has one when a piece's touch point lies within 2.5 mm plus half
its width of its centre line. Also counts the pieces and those on no crack or print.

    cargo run --release -p crackbot-mission --example dump_pieces -- RUN... > pieces.jsonl
    python3 crates/research/scripts/piece_coverage.py SCENES pieces.jsonl [--against OLD.jsonl]

RUN is a `mission trials --out` folder; SCENES holds its `scene-<seed>.json`
(`examples/trial_scenes`). With `--against` (a dump of another build on the same frames), lists
the cracks that gain or lose a piece between the two (2026-11-27, the thinning fix).
"""
import json
import os
import sys

from trial_errors import dist_poly  # same folder: the trials' own distance

REACH_MM = 2.5


def inverse(m):
    """Inverse of a 3 × 3 matrix (rows)."""
    (a, b, c), (d, e, f), (g, h, i) = m
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    adj = [
        [e * i - f * h, c * h - b * i, b * f - c * e],
        [f * g - d * i, a * i - c * g, c * d - a * f],
        [d * h - e * g, b * g - a * h, a * e - b * d],
    ]
    return [[v / det for v in row] for row in adj]


def apply(m, p):
    x = m[0][0] * p[0] + m[0][1] * p[1] + m[0][2]
    y = m[1][0] * p[0] + m[1][1] * p[1] + m[1][2]
    w = m[2][0] * p[0] + m[2][1] * p[1] + m[2][2]
    return (x / w, y / w)


def coverage(scenes, dump):
    """(pieces, pieces on nothing, cracks, set of (seed, crack index) without a piece)."""
    pieces = on_nothing = cracks = 0
    missing = set()
    for line in open(dump):
        row = json.loads(line)
        seed = row["seed"]
        to_mm = inverse(row["surface_to_image"])
        scene = json.load(open(os.path.join(scenes, f"scene-{seed}.json")))
        feats = [f for f in scene["features"] if "path" in f]
        touches = [apply(to_mm, (p[0], p[1])) for p in row["pieces"]]
        pieces += len(touches)
        on_nothing += sum(
            all(dist_poly(p, f["path"]) > REACH_MM + f["width_mm"] / 2 for f in feats)
            for p in touches
        )
        for k, f in enumerate(f for f in feats if f["kind"] == "crack"):
            cracks += 1
            if not any(dist_poly(p, f["path"]) <= REACH_MM + f["width_mm"] / 2 for p in touches):
                missing.add((int(seed), k))
    return pieces, on_nothing, cracks, missing


def main():
    args = sys.argv[1:]
    against = None
    if "--against" in args:
        k = args.index("--against")
        against = args[k + 1]
        del args[k : k + 2]
    if len(args) != 2:
        sys.exit(__doc__)
    scenes, dump = args
    results = [("pieces", coverage(scenes, dump))]
    if against:
        results.append(("against", coverage(scenes, against)))
    for name, (n, nothing, cracks, missing) in results:
        print(f"{name}: {n} pieces, {nothing} on no crack or print; "
              f"{len(missing)} of {cracks} cracks without a piece")
    if against:
        new, old = results[0][1][3], results[1][1][3]
        print("gain a piece:", sorted(old - new))
        print("lose their piece:", sorted(new - old))


if __name__ == "__main__":
    main()
