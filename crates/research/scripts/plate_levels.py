#!/usr/bin/env python3
"""How dark and how bright each plate reads, real against simulated (standard library only): for
every folder of recordings in crackbot's CSV (`crackbot tactile convert`, `crackbot sim
dataset`), the mean over each plate's recordings (`crack_<plate>_complete_<r>.csv`) of the
median and the 2 % / 98 % quantiles of D1, D2 and P. Surface-type and width plates alike.

    crackbot tactile convert ../shared/data/tactile/type --out real
    crackbot sim dataset --experiment recognition --seed 23 --out sim23
    python3 crates/research/scripts/plate_levels.py real sim23 [DIR ...]

Used in `crates/sim/docs/calibration.md` ("6–7.4 mm adopted for recognition") to find which
plate the simulated finger reads unlike the real one.
"""
import csv
import glob
import os
import re
import statistics
import sys

# The surface types first, in the paper's order; any other plate (the width plates) after them.
SURFACE_TYPES = ["nocrack", "crack", "bump", "pattern"]
RECORDING = re.compile(r"crack_(.+)_complete_\d+\.csv$")
CHANNELS = ["d1", "d2", "p"]


def quantile(values, q):
    """The `q` quantile of `values` (nearest rank below)."""
    ordered = sorted(values)
    return ordered[int(q * (len(ordered) - 1))]


def levels(path):
    """Median, 2 % and 98 % quantiles of each channel of one recording."""
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"{path}: no samples")
    out = []
    for ch in CHANNELS:
        try:
            v = [float(r[ch]) for r in rows]
        except (KeyError, ValueError) as e:
            raise SystemExit(f"{path}: column {ch}: {e}")
        out += [statistics.median(v), quantile(v, 0.02), quantile(v, 0.98)]
    return out


def plates_of(folder):
    """The recordings of `folder` by plate name (`crack_<plate>_complete_<r>.csv`)."""
    plates = {}
    for path in sorted(glob.glob(os.path.join(folder, "crack_*_complete_*.csv"))):
        m = RECORDING.search(os.path.basename(path))
        if m:
            plates.setdefault(m.group(1), []).append(path)
    return plates


def main(folders):
    if not folders:
        raise SystemExit(__doc__)
    for folder in folders:
        if not os.path.isdir(folder):
            raise SystemExit(f"{folder}: not a folder of recordings")
    found = {folder: plates_of(folder) for folder in folders}
    names = {name for plates in found.values() for name in plates}
    if not names:
        raise SystemExit("no crack_<plate>_complete_<r>.csv recordings in " + ", ".join(folders))
    order = [p for p in SURFACE_TYPES if p in names] + sorted(names - set(SURFACE_TYPES))
    header = " ".join(f"{c + '_' + s:>7}" for c in CHANNELS for s in ("med", "q2", "q98"))
    for plate in order:
        print(f"== {plate}")
        print(f"{'folder':>10}", header)
        for folder in folders:
            label = f"{os.path.basename(folder.rstrip('/')):>10}"
            files = found[folder].get(plate)
            if not files:
                print(label, f" (no crack_{plate} recordings)")
                continue
            per_recording = [levels(f) for f in files]
            means = [statistics.mean(col) for col in zip(*per_recording)]
            print(label, " ".join(f"{m:7.0f}" for m in means))


if __name__ == "__main__":
    main(sys.argv[1:])
