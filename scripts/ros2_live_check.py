#!/usr/bin/env python3
"""Subscribes to a running crackbot mission's live ROS 2 topics with Eclipse Cyclone DDS's Python
binding, an implementation independent of the robot's (ros2-client on RustDDS); no ROS
installation. ROS 2's DDS conventions: the ROS topic `/a/b` is the DDS topic `rt/a/b`, the
message `pkg/msg/Name` the DDS type `pkg::msg::dds_::Name_` (plain CDR, fields in order).

    python scripts/ros2_live_check.py --domain D [--late SECONDS] [--timeout SECONDS]

Prints READY once its readers exist, then waits for the mission's report (or the timeout) and
prints one JSON object: the samples, verdicts, strokes and statuses received, and, with --late,
what a second set of readers created SECONDS after READY got: the first status it read (a late
joiner gets the last one published before it joined, the topic being transient local) and the
report.
"""
import argparse
import json
import sys
import time
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration


from ros2_idl import Header, MissionReport, MissionStatus, Stroke, TactileSample, Verdict


def ns(h: Header) -> int:
    return h.stamp.sec * 1_000_000_000 + h.stamp.nanosec


def stream_qos() -> Qos:
    # Best effort: matches the best-effort writer; deep history so a burst is not overwritten.
    return Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100000))


def latched_qos() -> Qos:
    # Reliable, transient local: a late joiner gets what the writer keeps.
    return Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.TransientLocal,
               Policy.History.KeepLast(100000))


class Readers:
    def __init__(self, dp: DomainParticipant, tactile: bool):
        t = lambda name, ty: Topic(dp, f"rt/crackbot/{name}", ty)
        self.tactile = DataReader(dp, t("tactile", TactileSample), qos=stream_qos()) if tactile else None
        self.verdicts = DataReader(dp, t("verdicts", Verdict), qos=latched_qos())
        self.strokes = DataReader(dp, t("strokes", Stroke), qos=latched_qos())
        self.status = DataReader(dp, t("mission/status", MissionStatus), qos=latched_qos())
        self.report = DataReader(dp, t("mission/report", MissionReport), qos=latched_qos())
        self.got = {"tactile": [], "verdicts": [], "strokes": [], "status": [], "report": []}

    def poll(self) -> None:
        for name in self.got:
            r = getattr(self, name)
            if r is None:
                continue
            for s in r.take(N=100000):
                if hasattr(s, "header"):
                    self.got[name].append((time.time_ns(), s))


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--domain", type=int, required=True)
    ap.add_argument("--late", type=float, default=None)
    ap.add_argument("--timeout", type=float, default=120.0)
    a = ap.parse_args()
    dp = DomainParticipant(a.domain)
    early = Readers(dp, tactile=True)
    print("READY", flush=True)
    start = time.monotonic()
    late, late_at = None, None
    done_at = None
    while time.monotonic() - start < a.timeout:
        early.poll()
        if late is None and a.late is not None and early.got["status"] and time.monotonic() - start >= a.late:
            late_at = time.time_ns()
            late = Readers(DomainParticipant(a.domain), tactile=False)
        if late is not None:
            late.poll()
        if early.got["report"] and (late is None or late.got["report"]) and done_at is None:
            done_at = time.monotonic()
        if done_at is not None and time.monotonic() - done_at > 0.5:
            break
        time.sleep(0.005)
    tactile = [s for _, s in early.got["tactile"]]
    out = {
        "tactile": len(tactile),
        "tactile_sliding": sum(1 for s in tactile if s.slide > 0),
        "tactile_stamps_monotonic": all(ns(b.header) >= ns(a.header) for a, b in zip(tactile, tactile[1:])),
        "verdicts": [v.stroke for _, v in early.got["verdicts"]],
        "verdict_classes": [v.surface for _, v in early.got["verdicts"]],
        "strokes": [s.id for _, s in early.got["strokes"]],
        "stages": [s.stage for _, s in early.got["status"]],
        "report": None,
    }
    if early.got["report"]:
        r = early.got["report"][-1][1]
        out["report"] = {"cracks": len(r.cracks), "candidates": len(r.candidates), "passes": r.passes,
                         "json": json.loads(r.report_json)}
    if late is not None:
        first = late.got["status"][0][1] if late.got["status"] else None
        out["late"] = {
            "joined_ns": late_at,
            "first_status": None if first is None else {"stage": first.stage, "stamp_ns": ns(first.header)},
            "report": bool(late.got["report"]),
            "verdicts": [v.stroke for _, v in late.got["verdicts"]],
        }
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
