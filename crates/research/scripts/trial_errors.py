#!/usr/bin/env python3
"""Where the detection trials' errors come from: every candidate a fused mission touched, scored
against its scene's truth (standard library only).

    cargo run --release -p crackbot-mission --example trial_scenes -- 9000 120 SCENES --printed-cracks
    cargo run --release -p crackbot-lab -- mission trials --trials 120 --seed 9000 \\
        --printed-cracks --speedup 1 --jobs 2 --out RUN
    python3 crates/research/scripts/trial_errors.py SCENES RUN [RUN ...]

For each touched candidate: what its judged stroke crossed (cracks and printed decoys, mm along
the stroke, with their widths), screws and bumps within 4.5 mm of the stroke (distance from
their edge, and height), the print check's ratio and what the mission decided. The reports are
matched to cracks as `crackbot_mission::experiments::score` does (within 5 mm plus half the
crack's width, once per crack). Prints a count per (truth, outcome, one or several lines
crossed, something standing near) and one line per error; cracks that no stroke crossed are
listed with the nearest candidates (a long candidate near a missed crack is often two cracks
merged into one piece); then the errors counted by where they come from (vision: second
reports, cracks never crossed; the finger: cracks rejected, other things confirmed); last, the
fused score as the trials count it (the mean over trials of correct / (reports + missed))
next to what it would be on the same strokes with a finger that is never wrong (a crack it
rejected found where no other report claimed it; a print, relief or bare plate it confirmed
dropped, its crack missed where that report had claimed one): what vision and the plan allow.
Written for `crates/research/EXPERIMENTS.md`, "Raised passes stop over what stands under them",
and given the bound for "What vision and the plan allow: the score with a finger that is never
wrong"; most sections since use it.

With `PASSES=1` it also prints one line per judged pass over a candidate: `pass SEED CANDIDATE
TRUTH WIDTH CLASS CONFIDENCE DOUBT DIP` (what the pass's own stroke crossed nearest its middle,
that crack's or print's width, the recognition verdict, its confidence and doubt, the proximity
dip's confidence, 0 without a dip); `RATIOS=1` one line per candidate with its print ratio.
"""
import collections
import glob
import json
import math
import os
import sys

MATCH_MM = 5.0
NEAR_MM = 4.5
PRINT_RATIO = 0.88


def seg_inter(p, q, a, b):
    """Where segment p→q crosses segment a→b, as a fraction of p→q, or None."""
    r = (q[0] - p[0], q[1] - p[1])
    s = (b[0] - a[0], b[1] - a[1])
    den = r[0] * s[1] - r[1] * s[0]
    if abs(den) < 1e-12:
        return None
    t = ((a[0] - p[0]) * s[1] - (a[1] - p[1]) * s[0]) / den
    u = ((a[0] - p[0]) * r[1] - (a[1] - p[1]) * r[0]) / den
    return t if 0.0 <= t <= 1.0 and 0.0 <= u <= 1.0 else None


def dist_seg(pt, a, b):
    d = (b[0] - a[0], b[1] - a[1])
    l2 = d[0] ** 2 + d[1] ** 2
    t = 0 if l2 == 0 else max(0, min(1, ((pt[0] - a[0]) * d[0] + (pt[1] - a[1]) * d[1]) / l2))
    return math.hypot(pt[0] - a[0] - t * d[0], pt[1] - a[1] - t * d[1])


def dist_poly(pt, path):
    return min(dist_seg(pt, path[i], path[i + 1]) for i in range(len(path) - 1))


def crossings(p, q, feats):
    """Cracks and decoys the segment p→q crosses: (mm along it, feature index, kind, width)."""
    length = math.hypot(q[0] - p[0], q[1] - p[1])
    out = []
    for fi, f in enumerate(feats):
        if f["kind"] not in ("crack", "decoy"):
            continue
        path = f["path"]
        for i in range(len(path) - 1):
            t = seg_inter(p, q, path[i], path[i + 1])
            if t is not None:
                out.append((t * length, fi, f["kind"], f["width_mm"]))
    return sorted(out), length


def nearest_middle(xs, length):
    """The crossing of `xs` nearest the middle of a stroke `length` mm long, or None."""
    return min(xs, key=lambda c: abs(c[0] - length / 2)) if xs else None


def standing_near(p, q, feats):
    out = []
    for f in feats:
        if f["kind"] == "screw":
            d = dist_seg(f["centre"], p, q) - f["head_diameter_mm"] / 2
        elif f["kind"] == "bump":
            d = dist_seg(f["centre"], p, q) - f["radius_mm"]
        else:
            continue
        if d < NEAR_MM:
            out.append((f["kind"], round(d, 1), round(f["height_mm"], 1)))
    return out


def claimed_cracks(report, feats):
    """Crack index → index of the report matched to it (as the trials score)."""
    cracks = [i for i, f in enumerate(feats) if f["kind"] == "crack"]
    claimed = {}
    for ri, r in enumerate(report["cracks"]):
        best = None
        for ci in cracks:
            if ci in claimed:
                continue
            d = dist_poly(r["position_mm"], feats[ci]["path"])
            if best is None or d < best[1]:
                best = (ci, d)
        if best and best[1] <= MATCH_MM + feats[best[0]]["width_mm"] / 2:
            claimed[best[0]] = ri
    return claimed


def second_or_off(report, feats, ri, ci, claimed):
    """Why confirmed report `ri`, whose stroke crossed crack `ci`, matched no crack: the crack
    was already claimed by another report (a second report: where that one lies, mm apart), or
    the report lies off it (how far)."""
    here = report["cracks"][ri]["position_mm"]
    if ci in claimed:
        first = report["cracks"][claimed[ci]]
        gap = math.dist(here, first["position_mm"])
        return f" (a second report of crack {ci}, the first candidate {first['candidate']}'s {gap:.1f} mm away)"
    return f" (the report {dist_poly(here, feats[ci]['path']):.1f} mm off crack {ci})"


def trial(scenes, folder, stats, errors, untouched, totals):
    seed = int(folder.rstrip("/").split("-")[-2])
    with open(os.path.join(folder, "report.json")) as f:
        report = json.load(f)
    scene = os.path.join(scenes, f"scene-{seed}.json")
    if not os.path.exists(scene):
        sys.exit(f"{scene}: no such scene (write the trials' scenes with the trial_scenes example)")
    with open(scene) as f:
        feats = json.load(f)["features"]
    claimed = claimed_cracks(report, feats)
    by_report = {ri: ci for ci, ri in claimed.items()}
    if os.environ.get("PASSES"):
        for p in report["passes"]:
            if p["candidate"] is None or p["class"] is None:
                continue
            xs, length = crossings(p["start_mm"], p["end_mm"], feats)
            near = nearest_middle(xs, length)
            dip = p["dip"]["confidence"] if p["dip"] else 0.0
            d = p["doubt"]
            # A tagged object since the report's doubts became an enum; text before.
            doubt = (d.get("kind", "?") if isinstance(d, dict) else (d or "none").split(" ")[0]) if d else "none"
            print(
                f"pass {seed} {p['candidate']} {near[2] if near else 'nothing'} "
                f"{near[3] if near else 0.0:.2f} {p['class'].replace(' ', '_')} "
                f"{p['confidence']:.3f} {doubt} {dip:.2f}"
            )
    passes = collections.defaultdict(list)
    for p in report["passes"]:
        if p["candidate"] is not None:
            passes[p["candidate"]].append(p)
    confirmed = {
        (ri, r["candidate"]) for ri, r in enumerate(report["cracks"]) if r.get("candidate")
    }
    rejected = {r["candidate"]: r for r in report["rejected"]}
    crossed = set()
    n_cracks = sum(f["kind"] == "crack" for f in feats)
    as_run = [len(claimed), len(report["cracks"]) - len(claimed), n_cracks - len(claimed)]
    # With a finger that is never wrong on the same strokes (correct, false, missed): the
    # cracks it rejected (and no other report claimed) found, the other things it confirmed gone.
    right_finger = list(as_run)
    found_by_right_finger = set()
    for cand, ps in passes.items():
        # A stroke made again beside the first one (its ends were not both sound surface) is
        # the one judged: the first has no class.
        ps = [p for p in ps if p["class"] is not None] or ps
        xs, length = crossings(ps[0]["start_mm"], ps[0]["end_mm"], feats)
        crossed.update(c[1] for c in xs)
        for p in passes[cand]:
            crossed.update(c[1] for c in crossings(p["start_mm"], p["end_mm"], feats)[0])
        crossed.update(c[1] for c in xs)
        near = nearest_middle(xs, length)
        truth = near[2] if near else "nothing"
        detail = ""
        standing = standing_near(ps[0]["start_mm"], ps[0]["end_mm"], feats)
        hit = [ri for ri, c in confirmed if c == cand]
        if hit:
            r = report["cracks"][hit[0]]
            decided, ratio = "confirmed", r["evidence"].get("height_ratio")
            matched = by_report.get(hit[0])
            if truth == "crack":
                result = (
                    "ok"
                    if matched == near[1]
                    else "duplicate or off the crack" if matched is None else "matched to another crack"
                )
                if matched is None:
                    detail = second_or_off(report, feats, hit[0], near[1], claimed)
            else:
                result = f"{truth} confirmed" + (" (matched to a crack)" if matched is not None else "")
                if matched is None:
                    right_finger[1] -= 1
                else:
                    right_finger[0] -= 1
                    right_finger[2] += 1
        elif cand in rejected:
            r = rejected[cand]
            decided, ratio = "rejected: " + r["felt"], r.get("height_ratio")
            result = "crack rejected" if truth == "crack" else "ok"
            if truth == "crack" and near[1] not in claimed:
                found_by_right_finger.add(near[1])
        else:
            continue
        if os.environ.get("RATIOS"):
            print(f"ratio {ratio} {seed} {cand} {truth} {'standing' if standing else '-'} {result}")
        key = (truth, result, "several lines" if len(xs) > 1 else "one line", "standing near" if standing else "")
        stats[key] += 1
        if result != "ok":
            dips = [p["dip"] and round(p["dip"]["centre_mm"], 1) for p in ps]
            errors.append(
                f"{seed} candidate {cand}: {truth}, {result}{detail}; {decided[:60]}; ratio "
                f"{ratio if ratio is None else round(ratio, 2)}; stroke {length:.1f} mm crosses "
                f"{[(round(c[0], 1), c[2], round(c[3], 2)) for c in xs]}; standing {standing}; "
                f"dip centres {dips}"
            )
    right_finger[0] += len(found_by_right_finger)
    right_finger[2] -= len(found_by_right_finger)
    totals.append((as_run, right_finger))
    for ci, f in enumerate(feats):
        if f["kind"] != "crack" or ci in claimed or ci in crossed:
            continue
        nearest = sorted(
            (round(dist_poly(c["centre_mm"], f["path"]), 1), c["id"], round(c["length_mm"], 1))
            for c in report["candidates"]
        )[:3]
        untouched.append(
            f"{seed} crack {ci} ({f['width_mm']:.2f} mm wide): no stroke crossed it; nearest "
            f"candidates (distance, id, length mm) {nearest}"
        )


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    scenes = sys.argv[1]
    stats, errors, untouched, totals = collections.Counter(), [], [], []
    folders = [d for run in sys.argv[2:] for d in sorted(glob.glob(os.path.join(run, "trial-*-fused")))]
    if not folders:
        sys.exit(f"no trial-*-fused folder in {sys.argv[2:]}")
    for d in folders:
        if os.path.exists(os.path.join(d, "report.json")):
            trial(scenes, d, stats, errors, untouched, totals)
    print("touched candidates by (truth, outcome, lines the stroke crossed, standing near):")
    for k, v in sorted(stats.items()):
        print(f"  {v:4d}  {', '.join(x for x in k if x)}")
    print("\nerrors:")
    for e in errors:
        print("  " + e)
    print("\ncracks no stroke crossed:")
    for u in untouched:
        print("  " + u)
    print("\nerror classes:")
    for line in error_classes(stats, len(untouched)):
        print("  " + line)
    print("\ncorrect detections (correct / false / missed):")
    for line in ceiling(totals):
        print("  " + line)


def error_classes(stats, untouched):
    """The errors by where they come from: vision's (a crack proposed twice, a crack never
    crossed) and the finger's (a crack rejected, something else confirmed)."""
    second, other_crack = "second reports of one crack (or off it)", "reports matched to another crack"
    rejected, confirmed = "cracks the finger rejected", "prints, relief or bare plate confirmed"
    by_result = {"duplicate or off the crack": second, "matched to another crack": other_crack,
                 "crack rejected": rejected}
    count = collections.Counter({"cracks no stroke crossed": untouched})
    for (_, result, *_), n in stats.items():
        if result != "ok":
            count[by_result.get(result, confirmed)] += n
    total = sum(count.values())
    vision = count[second] + untouched
    finger = count[rejected] + count[confirmed]
    lines = [f"{n:4d}  {k}" for k, n in count.most_common()]
    lines.append(f"{total:4d}  in all: vision's {vision}, the finger's {finger}, other {total - vision - finger}")
    return lines


def ceiling(totals):
    """The fused score as the trials count it (the mean over the trials of correct / (reports +
    missed), with the sums), and what it would be on the same strokes with a finger that is
    never wrong: what vision and the plan allow. `totals`: per trial, both (correct, false,
    missed)."""
    lines = []
    for label, which in (("as run", 0), ("with a finger never wrong", 1)):
        per_trial = [t[which] for t in totals]
        c, f, m = (sum(x[i] for x in per_trial) for i in range(3))
        mean = sum(x[0] / max(sum(x), 1) for x in per_trial) / max(len(per_trial), 1)
        lines.append(f"{label}: {c} / {f} / {m}, {100.0 * mean:.1f} %")
    return lines


if __name__ == "__main__":
    main()
