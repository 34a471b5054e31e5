#!/usr/bin/env python3
"""An independent "ROS 2 arm" over DDS, played by Eclipse Cyclone DDS's Python binding.

Tests use it to prove that crackbot's ROS 2 backend (ros2-client on RustDDS) drives a real DDS peer
from another implementation. No ROS installation is involved: the arm speaks ROS 2's DDS
conventions directly, so it doubles as documentation for anyone writing the arm side:

* a ROS topic `/a/b` is the DDS topic `rt/a/b`;
* a ROS message `pkg/msg/Name` is the DDS type `pkg::msg::dds_::Name_`, a final struct in plain
  (XCDR1) CDR with the message's fields in order (nested messages inline, `string` as a CDR string,
  unbounded arrays as sequences).

The arm reads PoseStamped targets (best-effort, keep-last, volatile reader: it matches best-effort
and reliable writers), follows the latest one with a first-order lag, and publishes where its tool
is, either as a PoseStamped or as a TFMessage on `rt/tf` (reliable writers, which match best-effort
and reliable readers). Fault options make it misbehave for tests; their clocks start at the first
target. Prints READY on stdout when its entities exist. Run it with scripts/dds_arm.sh. Cyclone
picks its network interface itself; CYCLONEDDS_URI (Cyclone's own configuration) can override that.
"""
import argparse
import math
import signal
import sys
import threading
import time
from cyclonedds.core import InstanceState, Policy, Qos, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from ros2_idl import (  # the shared ROS 2 types (scripts/ros2_idl.py)
    Header, Point, Pose, PoseStamped, Quaternion, TFMessage, Time, Transform, TransformStamped,
    Vector3, Wrench, WrenchStamped,
)


FLOOD_HZ = 20_000  # pose samples a second under --flood-after


def dds_topic(ros_topic):
    """ROS 2 topic name -> DDS topic name: `/crackbot/target` -> `rt/crackbot/target`."""
    return "rt/" + ros_topic.lstrip("/")


def stamp_now():
    ns = time.time_ns()  # ROS stamps are wall-clock (system) time
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--domain", type=int, default=0, help="DDS domain id (ROS_DOMAIN_ID is not read)")
    p.add_argument("--target-topic", default="/crackbot/target", help="ROS topic of PoseStamped targets")
    p.add_argument("--pose-topic", default="/crackbot/tool_pose", help="ROS topic of the PoseStamped tool pose")
    p.add_argument("--pose-source", choices=["pose", "tf"], default="pose",
                   help="publish the tool pose as PoseStamped on --pose-topic, or as TFMessage on /tf")
    p.add_argument("--base-frame", default="base_link")
    p.add_argument("--tool-frame", default="tool0", help="child_frame_id of the /tf transform")
    p.add_argument("--wrench-topic", help="also publish a WrenchStamped (frame --tool-frame) on this ROS topic")
    p.add_argument("--force-n", type=float, default=0.0, help="force along z of that wrench, N")
    p.add_argument("--rate", type=float, default=250.0, help="simulation and publishing rate, Hz")
    p.add_argument("--lag-ms", type=float, default=20.0, help="first-order lag of the arm, ms")
    p.add_argument("--start", help="x,y,z metres: publish from there at once (default: start at the first target)")
    p.add_argument("--plate", metavar="PX,PY,PZ,NX,NY,NZ",
                   help="a rigid plate: a point on it and its normal (towards the arm), metres, base frame; "
                        "the tool stops on it, and the wrench's force grows 2 N per 0.1 mm the arm "
                        "would have gone into it")
    p.add_argument("--seconds", type=float, help="exit after this long (default: run until killed)")
    p.add_argument("--record", help="append `t_wall_s x y z frame_id` per received target to this file")
    for fault, what in [("nan", "publish NaN positions"), ("wrong-frame", "publish frame_id wrong_frame"),
                        ("silent", "stop publishing the pose"), ("flood", "publish the pose at 20 kHz in bursts"),
                        ("drift", "add an offset growing 10 mm/s along x to the published pose")]:
        p.add_argument(f"--{fault}-after", type=float, metavar="S", help=f"S s after the first target: {what}")
    return p.parse_args()


class Arm:
    def __init__(self, args):
        self.args = args
        self.stop = threading.Event()
        self.lock = threading.Lock()  # guards self.target, written by the receiving thread
        self.target = None  # ((x, y, z), (qx, qy, qz, qw)) of the latest valid target
        self.first_target_at = None  # time.monotonic() of the first valid target
        self.received = []  # time.time() of every received target, for the summary
        self.bad, self.bad_logged_at = 0, 0.0
        self.record = open(args.record, "a") if args.record else None

        self.dp = DomainParticipant(args.domain)
        # Reader: best-effort matches both best-effort and reliable writers. The depth only sizes the
        # local queue between two take()s, so that --record sees every target; it plays no part in
        # matching.
        reader_qos = Qos(Policy.Reliability.BestEffort, Policy.Durability.Volatile, Policy.History.KeepLast(64))
        self.reader = DataReader(self.dp, Topic(self.dp, dds_topic(args.target_topic), PoseStamped), qos=reader_qos)
        # Writers: reliable matches both best-effort and reliable readers; keep-last-1 never blocks.
        # XCDR1 (cdrv0) is what ROS 2 and RustDDS speak.
        writer_qos = Qos(Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100)),
                         Policy.Durability.Volatile, Policy.History.KeepLast(1),
                         Policy.DataRepresentation(use_cdrv0_representation=True))
        if args.pose_source == "pose":
            topic = Topic(self.dp, dds_topic(args.pose_topic), PoseStamped)
        else:
            topic = Topic(self.dp, "rt/tf", TFMessage)
        self.pose_writer = DataWriter(self.dp, topic, qos=writer_qos)
        self.wrench_writer = None
        if args.wrench_topic:
            topic = Topic(self.dp, dds_topic(args.wrench_topic), WrenchStamped)
            self.wrench_writer = DataWriter(self.dp, topic, qos=writer_qos)

    def receive(self):
        """Receiving thread: waits for targets, records each one and keeps the latest valid one."""
        waitset = WaitSet(self.dp)
        waitset.attach(ReadCondition(self.reader, SampleState.Any | ViewState.Any | InstanceState.Any))
        while not self.stop.is_set():
            waitset.wait(duration(milliseconds=100))  # releases the GIL while it blocks
            try:
                samples = self.reader.take(N=64)
            except Exception as e:  # a sample that does not deserialize: drop the batch, keep going
                self.reject(f"undecodable target ({e})")
                continue
            now = time.time()
            for s in samples:
                if not s.sample_info.valid_data:  # e.g. a writer went away: no data in it
                    continue
                p, q = s.pose.position, s.pose.orientation
                self.received.append(now)
                if self.record:
                    self.record.write(f"{now:.6f} {p.x!r} {p.y!r} {p.z!r} {s.header.frame_id}\n")
                    self.record.flush()
                values = (p.x, p.y, p.z, q.x, q.y, q.z, q.w)
                if not all(math.isfinite(v) for v in values):
                    self.reject(f"non-finite target {values}")
                    continue
                with self.lock:
                    self.target = ((p.x, p.y, p.z), (q.x, q.y, q.z, q.w))
                    if self.first_target_at is None:
                        self.first_target_at = time.monotonic()

    def reject(self, why):
        """Logs a skipped target to stderr, at most once a second."""
        self.bad += 1
        if time.monotonic() - self.bad_logged_at >= 1.0:
            self.bad_logged_at = time.monotonic()
            print(f"dds_arm: skipped {why} ({self.bad} skipped so far)", file=sys.stderr, flush=True)

    def on_plate(self, pose):
        """The pose held on the plate's side, and the contact force, N: 2 N per 0.1 mm the arm
        would have gone into the plate (the force arises only where the tool meets it)."""
        if not self.args.plate:
            return pose, 0.0
        v = [float(x) for x in self.args.plate.split(",")]
        point, normal = v[:3], v[3:]
        n = math.sqrt(sum(c * c for c in normal))
        normal = [c / n for c in normal]
        depth = -sum((p - q) * c for p, q, c in zip(pose, point, normal))  # > 0: inside the plate
        if depth <= 0:
            return pose, 0.0
        return [p + depth * c for p, c in zip(pose, normal)], depth * 20000.0

    def publish(self, position, orientation, frame_id):
        header = Header(stamp=stamp_now(), frame_id=frame_id)
        if self.args.pose_source == "pose":
            self.pose_writer.write(PoseStamped(header, Pose(Point(*position), Quaternion(*orientation))))
        else:
            transform = Transform(Vector3(*position), Quaternion(*orientation))
            self.pose_writer.write(TFMessage([TransformStamped(header, self.args.tool_frame, transform)]))

    def run(self):
        a = self.args
        pose = [float(v) for v in a.start.split(",")] if a.start else None
        orientation = (0.0, 0.0, 0.0, 1.0)
        receiver = threading.Thread(target=self.receive, daemon=True)
        receiver.start()
        print("READY", flush=True)
        t_start = last = next_step = time.monotonic()
        while not self.stop.is_set():
            now = time.monotonic()
            if a.seconds is not None and now - t_start >= a.seconds:
                break
            dt, last = now - last, now
            with self.lock:
                target, first_at = self.target, self.first_target_at
            if target is not None:
                orientation = target[1]  # the orientation is copied, not lagged
                if pose is None:
                    pose = list(target[0])  # no --start: begin at the first target
                alpha = 1.0 - math.exp(-dt / (a.lag_ms / 1000.0)) if a.lag_ms > 0 else 1.0
                pose = [p + alpha * (t - p) for p, t in zip(pose, target[0])]
            force_n = a.force_n
            if pose is not None:
                pose, contact = self.on_plate(pose)
                force_n += contact

            # Faults, timed from the first target.
            since = now - first_at if first_at is not None else -1.0
            active = {f: since >= s for f, s in [("nan", a.nan_after), ("wrong_frame", a.wrong_frame_after),
                                                 ("silent", a.silent_after), ("flood", a.flood_after),
                                                 ("drift", a.drift_after)] if s is not None}
            position = list(pose) if pose is not None else None
            if position is not None and active.get("drift"):
                position[0] += 0.010 * (since - a.drift_after)
            if position is not None and active.get("nan"):
                position = [math.nan] * 3
            frame_id = "wrong_frame" if active.get("wrong_frame") else a.base_frame

            publishing = position is not None and not active.get("silent")
            if publishing:
                self.publish(position, orientation, frame_id)
            if self.wrench_writer:
                force = Vector3(0.0, 0.0, force_n if pose is not None else a.force_n)
                self.wrench_writer.write(WrenchStamped(Header(stamp_now(), a.tool_frame),
                                                       Wrench(force, Vector3(0.0, 0.0, 0.0))))

            if publishing and active.get("flood"):
                # 20 kHz worth each step, back to back with a fresh stamp on each. Not truly unbounded:
                # the rest of the step is left to the receiving thread and the system under test.
                for _ in range(int(FLOOD_HZ / a.rate)):
                    self.publish(position, orientation, frame_id)
            next_step = max(next_step + 1.0 / a.rate, now)
            self.stop.wait(max(0.0, next_step - time.monotonic()))
        self.stop.set()
        receiver.join(timeout=1.0)  # its waits last at most 100 ms
        self.summary()

    def summary(self):
        times = list(self.received)
        gaps = sorted(b - a for a, b in zip(times, times[1:]))
        rate = (len(times) - 1) / (times[-1] - times[0]) if len(gaps) and times[-1] > times[0] else 0.0
        p99 = gaps[min(len(gaps) - 1, math.ceil(0.99 * len(gaps)) - 1)] * 1000 if gaps else 0.0
        print(f"dds_arm: {len(times)} targets received, mean rate {rate:.1f} Hz, p99 gap {p99:.1f} ms, "
              f"{self.bad} skipped", file=sys.stderr, flush=True)
        if self.record:
            self.record.close()


def main():
    # Hand the GIL over every 0.5 ms instead of 5 ms, so that the receiving thread stamps targets
    # on time even while the main thread floods.
    sys.setswitchinterval(0.0005)
    arm = Arm(parse_args())
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: arm.stop.set())
    arm.run()


if __name__ == "__main__":
    main()
