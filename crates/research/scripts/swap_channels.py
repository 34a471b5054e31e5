#!/usr/bin/env python3
"""Which of the finger's channels keep the deployed models from reading simulated slides: each
simulated recording (width or recognition plates) gets some of its channels replaced by a real
recording's, stroke by stroke, and a deployed model then reads the hybrids (standard library
only).

    crackbot sim dataset --experiment width --seed 7 --out sim-w7
    crackbot tactile convert ../shared/data/tactile/width --out real-width
    python3 crates/research/scripts/swap_channels.py sim-w7 real-width hybrid-p --channels p
    crackbot tactile eval --model models/tactile/width.ctm --test hybrid-p --json

Simulated recording `STEM_complete_R` (e.g. `crack_mm2`, `crack_bump`) takes its channels from
the real `STEM_complete_<(R-1) mod 3 + 1>`. A stroke is the first run of rows with one (slide,
direction): the few rows of a later run of the same pair (the direction column flickering at a
turn) keep their simulated values. Each
real stroke is stretched linearly in time onto the simulated stroke of the same slide and
direction (the two take about as long), so the real signal's events keep their order but not
their exact time. `--channels d1,d2,d3,p` replaces all four: the control, which shows what the
stretching alone costs. Used for `crates/sim/docs/calibration.md`, "The proximity channel
carries the width gap" (2026-11-27).
"""
import argparse
import csv
import glob
import os
import sys

COLUMNS = ["x_mm", "d1", "d2", "d3", "p", "direction", "slide", "label", "repetition"]
CHANNELS = {"d1": 1, "d2": 2, "d3": 3, "p": 4}


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows or rows[0] != COLUMNS:
        sys.exit(f"{path}: expected the header {','.join(COLUMNS)}")
    try:
        return [[float(v) for v in r] for r in rows[1:]]
    except ValueError as e:
        sys.exit(f"{path}: {e}")


def strokes(rows):
    """(slide, direction) → (first row, one past the last row) of its first run."""
    out = {}
    start = 0
    for i in range(1, len(rows) + 1):
        if i == len(rows) or rows[i][5:7] != rows[start][5:7]:
            out.setdefault((rows[start][6], rows[start][5]), (start, i))
            start = i
    return out


def stretched(values, n):
    """`values` resampled linearly onto `n` points."""
    if n == 1 or len(values) == 1:
        return [values[0]] * n
    out = []
    for k in range(n):
        t = k * (len(values) - 1) / (n - 1)
        i = min(int(t), len(values) - 2)
        out.append(values[i] + (t - i) * (values[i + 1] - values[i]))
    return out


def cell(v):
    """A CSV cell for a non-position column: integers as integers, anything else unrounded."""
    return int(v) if v == int(v) else f"{v:g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sim", help="folder of simulated width recordings (CSV)")
    ap.add_argument("real", help="folder of the real width recordings as CSV")
    ap.add_argument("out", help="folder for the hybrids (created)")
    ap.add_argument("--channels", default="p", help="comma-separated: d1, d2, d3, p")
    a = ap.parse_args()
    try:
        cols = [CHANNELS[c.strip()] for c in a.channels.split(",")]
    except KeyError as e:
        sys.exit(f"--channels: unknown channel {e} (d1, d2, d3, p)")
    sims = sorted(glob.glob(os.path.join(a.sim, "*_complete_*.csv")))
    if not sims:
        sys.exit(f"{a.sim}: no *_complete_*.csv recordings")
    os.makedirs(a.out, exist_ok=True)
    reals = {}  # each real recording read once, with its strokes
    for path in sims:
        name = os.path.basename(path)
        stem, rep = name.rsplit("_", 1)
        real_path = os.path.join(a.real, f"{stem}_{(int(rep.split('.')[0]) - 1) % 3 + 1}.csv")
        if not os.path.exists(real_path):
            sys.exit(f"{real_path}: no such real recording for {name}")
        if real_path not in reals:
            rows = read(real_path)
            reals[real_path] = (rows, strokes(rows))
        real, real_strokes = reals[real_path]
        sim = read(path)
        for key, (s, e) in strokes(sim).items():
            if key not in real_strokes:
                continue
            rs, re_ = real_strokes[key]
            for c in cols:
                values = stretched([r[c] for r in real[rs:re_]], e - s)
                for k, v in enumerate(values):
                    sim[s + k][c] = round(v)
        with open(os.path.join(a.out, name), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(COLUMNS)
            for r in sim:
                w.writerow([f"{r[0]:.4f}"] + [cell(v) for v in r[1:]])
    print(f"wrote {len(sims)} hybrids to {a.out} (channels {a.channels} from {a.real})")


if __name__ == "__main__":
    main()
