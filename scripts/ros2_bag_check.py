"""Checks a mission's ROS 2 bag against what the mission left beside it, with two readers
independent of crackbot's Rust writer:

  * `rosbags` (pure Python: rosbag2 reader, CDR decoder), its typestore ROS 2 Humble's standard
    messages plus crackbot_msgs built from the package's own .msg files;
  * the `mcap` reader with `mcap-ros2-support`, decoding every message from the ros2msg
    definitions stored in the bag.

    python scripts/ros2_bag_check.py --msgs ros/crackbot_msgs/msg BAG_DIR MISSION_DIR [--json]

Checked: every message of every topic decodes (both readers, zero errors) and the bag's
metadata counts are the messages read; one report, equal to report.json; one stroke and one
verdict per pass of the report, in its order, with its samples and class; per pass exactly its
`samples` stroke samples; the frame decodes to the bytes of frame.png; header stamps and log
times never go back within a topic. Exits 1 with the failures listed, 0 with a summary.
"""

import argparse
import json
import math
import sys
from collections import Counter, defaultdict
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore


def typestore(msgs: Path):
    store = get_typestore(Stores.ROS2_HUMBLE)
    add = {}
    for p in sorted(msgs.glob("*.msg")):
        add.update(get_types_from_msg(p.read_text(), f"crackbot_msgs/msg/{p.stem}"))
    store.register(add)
    return store


def stamp_ns(msg) -> int | None:
    header = getattr(msg, "header", None)
    t = header.stamp if header is not None else getattr(msg, "stamp", None)
    return None if t is None else t.sec * 1_000_000_000 + t.nanosec


def read_rosbags(bag: Path, store, fails: list[str]):
    """Every message decoded by rosbags: {topic: [(log time, message)]}."""
    out = defaultdict(list)
    errors = 0
    with Reader(bag) as reader:
        meta = {c.topic: c.msgcount for c in reader.connections}
        for conn, t, raw in reader.messages():
            try:
                out[conn.topic].append((t, store.deserialize_cdr(raw, conn.msgtype)))
            except Exception as e:  # noqa: BLE001 - every failure is counted and named
                errors += 1
                if errors <= 5:
                    fails.append(f"rosbags: {conn.topic} at {t}: {e}")
    for topic, n in meta.items():
        if len(out[topic]) != n and errors == 0:
            fails.append(f"{topic}: metadata says {n} messages, {len(out[topic])} read")
    return out, errors


def read_mcap_ros2(bag: Path, fails: list[str]) -> tuple[Counter, int]:
    counts, errors = Counter(), 0
    (path,) = sorted(bag.glob("*.mcap"))
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        if header.profile != "ros2":
            fails.append(f"mcap profile {header.profile!r}, not 'ros2'")
        for schema, channel, message in reader.iter_messages():
            if channel.message_encoding != "cdr" or schema.encoding != "ros2msg":
                fails.append(f"{channel.topic}: {channel.message_encoding}/{schema.encoding}")
        f.seek(0)
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        it = reader.iter_decoded_messages()
        while True:
            try:
                _, channel, _, _ = next(it)
            except StopIteration:
                break
            except Exception as e:  # noqa: BLE001
                errors += 1
                if errors <= 5:
                    fails.append(f"mcap-ros2-support: {e}")
                continue
            counts[channel.topic] += 1
    return counts, errors


def check_mission(by_topic, mission: Path, fails: list[str]) -> None:
    report = json.loads((mission / "report.json").read_text())
    reports = by_topic.get("/crackbot/mission/report", [])
    if len(reports) != 1:
        fails.append(f"{len(reports)} reports, 1 expected")
    else:
        r = reports[0][1]
        if json.loads(r.report_json) != report:
            fails.append("/crackbot/mission/report's report_json is not report.json")
        if (len(r.cracks), len(r.candidates), r.passes) != (
            len(report["cracks"]), len(report["candidates"]), len(report["passes"])):
            fails.append("the report's cracks, candidates or passes differ from report.json")
    passes = report["passes"]
    strokes = [m for _, m in by_topic.get("/crackbot/strokes", [])]
    verdicts = [m for _, m in by_topic.get("/crackbot/verdicts", [])]
    if [s.id for s in strokes] != [p["id"] for p in passes]:
        fails.append(f"strokes {[s.id for s in strokes]} against passes {[p['id'] for p in passes]}")
    if [v.stroke for v in verdicts] != [p["id"] for p in passes]:
        fails.append("one verdict per pass, in order: not so")
    for v, p in zip(verdicts, passes):
        if v.count != p["samples"] or v.surface != (p.get("class") or ""):
            fails.append(f"verdict of pass {p['id']}: {v.surface}/{v.count} against {p.get('class')}/{p['samples']}")
    per_slide = Counter(m.slide for _, m in by_topic.get("/crackbot/stroke/samples", []))
    for p in passes:
        if per_slide[p["id"]] != p["samples"]:
            fails.append(f"pass {p['id']}: {per_slide[p['id']]} stroke samples, report says {p['samples']}")
    images = by_topic.get("/crackbot/camera/image/compressed", [])
    frame = (mission / "frame.png").read_bytes()
    if len(images) != 1 or bytes(images[0][1].data) != frame or images[0][1].format != "png":
        fails.append("the camera frame is not frame.png")


def check_monotonic(by_topic, fails: list[str]) -> None:
    for topic, msgs in by_topic.items():
        times = [t for t, _ in msgs]
        stamps = [s for s in (stamp_ns(m) for _, m in msgs) if s is not None]
        if any(b < a for a, b in zip(times, times[1:])):
            fails.append(f"{topic}: log times go back")
        if any(b < a for a, b in zip(stamps, stamps[1:])):
            fails.append(f"{topic}: header stamps go back")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--msgs", type=Path, required=True)
    ap.add_argument("bag", type=Path)
    ap.add_argument("mission", type=Path)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    fails: list[str] = []
    by_topic, rosbags_errors = read_rosbags(a.bag, typestore(a.msgs), fails)
    mcap_counts, mcap_errors = read_mcap_ros2(a.bag, fails)
    counts = {t: len(m) for t, m in by_topic.items()}
    if dict(mcap_counts) != counts:
        fails.append(f"the two readers count differently: {dict(mcap_counts)} against {counts}")
    check_mission(by_topic, a.mission, fails)
    check_monotonic(by_topic, fails)
    tactile = [m for _, m in by_topic.get("/crackbot/tactile", [])]
    if not tactile or not all(0 <= m.p <= 1023 for m in tactile):
        fails.append("no tactile samples, or one outside 0-1023")
    summary = {
        "topics": counts,
        "messages": sum(counts.values()),
        "rosbags_errors": rosbags_errors,
        "mcap_ros2_errors": mcap_errors,
        "sliding_samples_with_position": sum(1 for m in tactile if m.slide and not math.isnan(m.along_mm)),
        "failures": fails,
    }
    if a.json:
        print(json.dumps(summary))
    else:
        for f in fails:
            print("FAIL", f)
        print(f"{summary['messages']} messages on {len(counts)} topics; decode errors: rosbags {rosbags_errors}, mcap-ros2-support {mcap_errors}")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
