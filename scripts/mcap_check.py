"""Checks a mission's MCAP log against what the mission left beside it, with the Python `mcap`
package (foxglove/mcap, an implementation independent of the robot's Rust writer) and
`mcap-protobuf-support` decoding the Foxglove messages from the schemas stored in the file.

    python scripts/mcap_check.py MISSION_DIR [--json]

MISSION_DIR is the folder `crackbot run --out DIR` wrote: mission.mcap, report.json, frame.png
and slide-NNN.csv. Checked:
  * the file has a summary with chunk indexes (a viewer can seek), its chunks zstd-compressed;
  * every channel a fused mission writes is there, with its schema (name and encoding);
  * message counts agree with the report: one verdict per pass, one label per candidate, and for
    every pass exactly its `samples` on /slide, equal to its CSV recording sample for sample;
  * log times never go back within a channel, lie within the mission's span, and the samples'
    log times are their own `t_s` on one clock;
  * the camera frame decodes to the bytes of frame.png; /mission/report is report.json.
Exits 1 with the failures listed, 0 with a summary (JSON with --json).
"""

import argparse
import csv
import json
import sys
from collections import Counter, defaultdict
from pathlib import Path

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

FOXGLOVE = {
    "/camera/image": "foxglove.CompressedImage",
    "/camera/detections": "foxglove.ImageAnnotations",
    "/plan": "foxglove.SceneUpdate",
    "/tf": "foxglove.FrameTransform",
    "/log": "foxglove.Log",
}
JSON = {
    "/tactile": "crackbot.TactileSample",
    "/slide": "crackbot.StrokeSample",
    "/arm/pose": "crackbot.ArmPose",
    "/verdicts": "crackbot.PassRecord",
    "/feeling": "crackbot.Feeling",
    "/health": "crackbot.StreamHealth",
    "/mission/status": "crackbot.MissionStatus",
    "/mission/report": "crackbot.InspectReport",
}


def read(path):
    """Every message of the log (topic, log time, decoded), and its summary."""
    factory = DecoderFactory()
    decoders = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        messages = []
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.message_encoding == "json":
                decoded = json.loads(message.data)
            else:
                if channel.id not in decoders:
                    decoders[channel.id] = factory.decoder_for(channel.message_encoding, schema)
                decoded = decoders[channel.id](message.data)
            messages.append((channel.topic, message.log_time, decoded))
    return summary, messages


def check(mission_dir):
    failures = []
    fail = failures.append
    report = json.loads((mission_dir / "report.json").read_text())
    summary, messages = read(mission_dir / "mission.mcap")

    # Seekable: a summary with chunk indexes, zstd chunks.
    if summary is None or not summary.chunk_indexes:
        fail("no summary with chunk indexes")
    else:
        kinds = {c.compression for c in summary.chunk_indexes}
        if kinds != {"zstd"}:
            fail(f"chunks compressed with {kinds}, not zstd")

    # Channels and schemas.
    channels = {c.topic: c for c in summary.channels.values()} if summary else {}
    for topic, name in {**FOXGLOVE, **JSON}.items():
        c = channels.get(topic)
        if c is None:
            fail(f"no channel {topic}")
            continue
        schema = summary.schemas.get(c.schema_id)
        want = ("protobuf", "protobuf") if topic in FOXGLOVE else ("jsonschema", "json")
        got = (schema.encoding if schema else None, c.message_encoding)
        if schema is None or schema.name != name or got != want:
            fail(f"{topic}: schema {schema and schema.name} {got}, expected {name} {want}")

    by_topic = defaultdict(list)
    for topic, t, m in messages:
        by_topic[topic].append((t, m))
    counts = Counter(topic for topic, _, _ in messages)

    # Counts against the report.
    passes = report.get("passes", [])
    if counts["/verdicts"] != len(passes):
        fail(f"{counts['/verdicts']} verdicts, the report has {len(passes)} passes")
    detections = by_topic["/camera/detections"]
    if len(detections) != 1:
        fail(f"{len(detections)} detection messages, expected 1")
    elif len(detections[0][1].texts) != len(report.get("candidates", [])):
        fail(
            f"{len(detections[0][1].texts)} detections drawn, "
            f"the report has {len(report['candidates'])} candidates"
        )
    slide = defaultdict(list)
    for _, m in by_topic["/slide"]:
        slide[m["slide"]].append(m)
    for p in passes:
        got = slide.get(p["id"], [])
        if len(got) != p["samples"]:
            fail(f"pass {p['id']}: {len(got)} samples on /slide, the report says {p['samples']}")
            continue
        with open(p["recording"]) as f:
            rows = list(csv.DictReader(f))
        if len(rows) != len(got):
            fail(f"pass {p['id']}: {len(rows)} rows in {p['recording']}, {len(got)} on /slide")
            continue
        for r, m in zip(rows, got):
            same = all(float(r[k]) == m[k] for k in ("d1", "d2", "d3", "p"))
            if not same or abs(float(r["x_mm"]) - m["along_mm"]) > 1e-3:
                fail(f"pass {p['id']}: /slide differs from its recording: {m} vs {r}")
                break

    # Times: monotonic per channel, within the span, one clock for the samples.
    start = min(t for _, t, _ in messages)
    end = max(t for _, t, _ in messages)
    for topic, ms in by_topic.items():
        times = [t for t, _ in ms]
        if any(b < a for a, b in zip(times, times[1:])):
            fail(f"{topic}: log times go back")
        if times[0] < start or times[-1] > end:
            fail(f"{topic}: outside the mission's span")
    span_s = (end - start) / 1e9
    if span_s > report["elapsed_s"] + 1.0:
        fail(f"the log spans {span_s:.1f} s, the mission took {report['elapsed_s']:.1f} s")
    for topic in ("/tactile", "/slide", "/arm/pose"):
        offsets = [t - m["t_s"] * 1e9 for t, m in by_topic[topic]]
        if offsets and max(offsets) - min(offsets) > 2e3:
            fail(f"{topic}: log times are not the samples' t_s on one clock")

    # The frame and the report.
    frames = by_topic["/camera/image"]
    png = (mission_dir / "frame.png").read_bytes()
    if len(frames) != 1 or frames[0][1].format != "png" or frames[0][1].data != png:
        fail("the camera frame is not frame.png")
    reports = by_topic["/mission/report"]
    if len(reports) != 1 or reports[0][1] != report:
        fail("/mission/report is not report.json")

    return failures, {
        "channels": dict(sorted(counts.items())),
        "span_s": round(span_s, 3),
        "passes": len(passes),
        "candidates": len(report.get("candidates", [])),
        "bytes": (mission_dir / "mission.mcap").stat().st_size,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mission_dir", type=Path)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    try:
        failures, facts = check(args.mission_dir)
    except Exception as e:  # a file the reader refuses is a failure to report, with its reason
        failures, facts = [f"{type(e).__name__}: {e}"], {}
    if args.json:
        print(json.dumps({"ok": not failures, "failures": failures, **facts}))
    else:
        for f in failures:
            print("FAIL", f)
        for k, v in facts.items():
            print(f"{k}: {v}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
