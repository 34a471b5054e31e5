#!/usr/bin/env python3
"""Writes vectors.json, the golden vectors of the crackbot manipulator link (crates/link).

An independent implementation of the packet format, the postcard encoding of the messages, the
HMAC-SHA256-128 tag and the anti-replay window, written from the crate documentation in plain
Python with the standard library only (struct, hmac, hashlib), so that the Rust encoder, decoder
and window are checked against something they did not produce. Run from anywhere:

    python3 crates/link/golden/generate.py          # (re)write vectors.json
    python3 crates/link/golden/generate.py --check  # fail if vectors.json differs

The output is checked in; crates/link/tests/golden.rs reads it, and scripts/test.sh runs --check
so the file can never drift from this reference implementation.
"""
import hashlib
import hmac
import json
import os
import struct
import sys

WIRE_VERSION = 1
MAGIC = b"CL"
HEADER_LEN = 34
TAG_LEN = 16
MAX_PAYLOAD = 256
FLAG_SIGNED = 0x01
FLAG_ACK_REQUESTED = 0x02
KINDS = {"Data": 0, "Ack": 1, "Challenge": 2, "Response": 3}
WINDOW = 128
MAX_JUMP = 1024

# The message definitions, byte for byte the text whose SHA-256 the packets carry.
SCHEMA = """\
crackbot-link schema 2
Message = enum {
  0 Heartbeat
  1 MoveTo(MoveTo)
  2 Slide(Slide)
  3 Stop
  4 State(State)
  5 Error(ErrorReport)
  6 Done { slide_id: u32 }
}
MoveTo = struct { pose: Pose, speed_mm_s: f32, valid_until_us: u64 }
Slide = struct { id: u32, start: Point2, end: Point2, speed_mm_s: f32, contact: Contact, valid_until_us: u64 }
State = struct { controller_time_us: u64, pose: Pose, velocity: Velocity, mode: Mode, slide_progress: f32 }
ErrorReport = struct { seq: u32, code: ErrorCode, text: string<=64 }
Pose = struct { x_mm: f32, y_mm: f32, z_mm: f32 }
Point2 = struct { x_mm: f32, y_mm: f32 }
Velocity = struct { x_mm_s: f32, y_mm_s: f32, z_mm_s: f32 }
Contact = enum { 0 DepthMm(f32), 1 ForceN(f32) }
Mode = enum { 0 Idle, 1 Moving, 2 Sliding { id: u32 }, 3 Stopped, 4 Fault { code: u16 } }
ErrorCode = enum { 0 OutsideWorkspace, 1 OverSpeedLimit, 2 InvalidCommand, 3 Busy, 4 Faulted, 5 Unsupported, 6 Other, 7 Expired }
"""
SCHEMA_HASH = hashlib.sha256(SCHEMA.encode()).digest()[:8]

# The same definitions as data for the encoder: a struct is a list of (field, type); an enum a
# list of (variant, None | type | list of fields), the variant index being the position.
TYPES = {
    "Message": ("enum", [
        ("Heartbeat", None),
        ("MoveTo", "MoveTo"),
        ("Slide", "Slide"),
        ("Stop", None),
        ("State", "State"),
        ("Error", "ErrorReport"),
        ("Done", [("slide_id", "u32")]),
    ]),
    "MoveTo": ("struct", [("pose", "Pose"), ("speed_mm_s", "f32"), ("valid_until_us", "u64")]),
    "Slide": ("struct", [("id", "u32"), ("start", "Point2"), ("end", "Point2"),
                         ("speed_mm_s", "f32"), ("contact", "Contact"), ("valid_until_us", "u64")]),
    "State": ("struct", [("controller_time_us", "u64"), ("pose", "Pose"),
                         ("velocity", "Velocity"), ("mode", "Mode"), ("slide_progress", "f32")]),
    "ErrorReport": ("struct", [("seq", "u32"), ("code", "ErrorCode"), ("text", "string64")]),
    "Pose": ("struct", [("x_mm", "f32"), ("y_mm", "f32"), ("z_mm", "f32")]),
    "Point2": ("struct", [("x_mm", "f32"), ("y_mm", "f32")]),
    "Velocity": ("struct", [("x_mm_s", "f32"), ("y_mm_s", "f32"), ("z_mm_s", "f32")]),
    "Contact": ("enum", [("DepthMm", "f32"), ("ForceN", "f32")]),
    "Mode": ("enum", [("Idle", None), ("Moving", None), ("Sliding", [("id", "u32")]),
                      ("Stopped", None), ("Fault", [("code", "u16")])]),
    "ErrorCode": ("enum", [(n, None) for n in ["OutsideWorkspace", "OverSpeedLimit",
                                               "InvalidCommand", "Busy", "Faulted",
                                               "Unsupported", "Other", "Expired"]]),
}
UINT_BITS = {"u16": 16, "u32": 32, "u64": 64}


def varint(n: int) -> bytes:
    """Unsigned LEB128, as postcard writes every u16, u32, u64 and length."""
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def f32(x: float) -> bytes:
    b = struct.pack("<f", x)
    assert struct.unpack("<f", b)[0] == x, f"{x} is not exactly an f32"
    return b


def encode(ty: str, v) -> bytes:
    """Postcard encoding of the JSON value v (serde's externally tagged form) of type ty."""
    if ty in UINT_BITS:
        assert isinstance(v, int) and 0 <= v < 1 << UINT_BITS[ty], (ty, v)
        return varint(v)
    if ty == "f32":
        return f32(v)
    if ty == "string64":
        b = v.encode("utf-8")
        assert len(b) <= 64
        return varint(len(b)) + b
    kind, spec = TYPES[ty]
    if kind == "struct":
        assert set(v) == {f for f, _ in spec}, (ty, v)
        return b"".join(encode(t, v[f]) for f, t in spec)
    names = [n for n, _ in spec]
    if isinstance(v, str):  # unit variant
        i = names.index(v)
        assert spec[i][1] is None
        return varint(i)
    ((name, inner),) = v.items()
    i = names.index(name)
    content = spec[i][1]
    if isinstance(content, str):  # newtype variant
        return varint(i) + encode(content, inner)
    assert isinstance(content, list)  # struct variant
    assert set(inner) == {f for f, _ in content}
    return varint(i) + b"".join(encode(t, inner[f]) for f, t in content)


def packet(key, kind, payload=b"", *, ack_requested=False, sender=1, link_id=1, epoch=1,
           counter=1, seq=0, schema=SCHEMA_HASH, version=WIRE_VERSION, flags_extra=0,
           length=None, signed=True, magic=MAGIC):
    flags = (FLAG_SIGNED if signed else 0) | (FLAG_ACK_REQUESTED if ack_requested else 0)
    flags |= flags_extra
    n = len(payload) if length is None else length
    head = struct.pack("<2sBBBBH8sIQIH", magic, version, flags, KINDS[kind], sender, link_id,
                       schema, epoch, counter, seq, n)
    assert len(head) == HEADER_LEN
    body = head + payload
    if signed:
        body += hmac.new(key, body, hashlib.sha256).digest()[:TAG_LEN]
    return body


class Window:
    """The anti-replay window, as the crate docs specify it."""

    def __init__(self, top=0, seen=1):
        self.top, self.seen = top, seen

    @classmethod
    def starting_at(cls, counter):
        return cls(counter, (1 << WINDOW) - 1)

    def check(self, c):
        if c > self.top:
            return "future" if c - self.top > MAX_JUMP else "fresh"
        back = self.top - c
        if back >= WINDOW:
            return "too_old"
        return "replay" if self.seen >> back & 1 else "fresh"

    def accept(self, c):
        if c > self.top:
            shift = c - self.top
            self.seen = 0 if shift >= WINDOW else (self.seen << shift) & ((1 << WINDOW) - 1)
            self.seen |= 1
            self.top = c
        elif self.top - c < WINDOW:
            self.seen |= 1 << (self.top - c)


def replay_sequence(window, counters):
    out = []
    for c in counters:
        v = window.check(c)
        if v == "fresh":
            window.accept(c)
        out.append({"counter": c, "verdict": v})
    return out


def main():
    key = hashlib.sha256(b"crackbot-link golden key").digest()
    other_key = hashlib.sha256(b"crackbot-link another key").digest()
    pose = {"x_mm": 120.5, "y_mm": -42.25, "z_mm": 15.0}
    messages = [
        ("heartbeat", "Heartbeat"),
        ("stop", "Stop"),
        ("move to", {"MoveTo": {"pose": pose, "speed_mm_s": 50.0, "valid_until_us": 1_500_000}}),
        ("move to, zeros and a negative zero",
         {"MoveTo": {"pose": {"x_mm": 0.0, "y_mm": -0.0, "z_mm": 0.0}, "speed_mm_s": 0.0,
                    "valid_until_us": 0}}),
        ("slide at a depth", {"Slide": {
            "id": 7, "start": {"x_mm": 10.0, "y_mm": 20.0}, "end": {"x_mm": 110.0, "y_mm": 20.0},
            "speed_mm_s": 5.0, "contact": {"DepthMm": 0.5}, "valid_until_us": 127}}),
        ("slide at a force, id at a varint boundary", {"Slide": {
            "id": 128, "start": {"x_mm": -1.5, "y_mm": 3.25}, "end": {"x_mm": 2.0, "y_mm": -7.75},
            "speed_mm_s": 12.5, "contact": {"ForceN": 1.25}, "valid_until_us": 128}}),
        ("slide with the largest id", {"Slide": {
            "id": 0xFFFFFFFF, "start": {"x_mm": 0.0, "y_mm": 0.0}, "end": {"x_mm": 1.0, "y_mm": 1.0},
            "speed_mm_s": 1.0, "contact": {"DepthMm": 0.0},
            "valid_until_us": 0xFFFFFFFFFFFFFFFF}}),
        ("state, idle", {"State": {
            "controller_time_us": 0, "pose": pose,
            "velocity": {"x_mm_s": 0.0, "y_mm_s": 0.0, "z_mm_s": 0.0},
            "mode": "Idle", "slide_progress": 0.0}}),
        ("state, moving", {"State": {
            "controller_time_us": 16383, "pose": pose,
            "velocity": {"x_mm_s": 25.0, "y_mm_s": -12.5, "z_mm_s": 0.125},
            "mode": "Moving", "slide_progress": 0.0}}),
        ("state, sliding", {"State": {
            "controller_time_us": 16384, "pose": pose,
            "velocity": {"x_mm_s": 5.0, "y_mm_s": 0.0, "z_mm_s": 0.0},
            "mode": {"Sliding": {"id": 300}}, "slide_progress": 0.375}}),
        ("state, stopped", {"State": {
            "controller_time_us": 3_600_000_000, "pose": pose,
            "velocity": {"x_mm_s": 0.0, "y_mm_s": 0.0, "z_mm_s": 0.0},
            "mode": "Stopped", "slide_progress": 1.0}}),
        ("state, fault, largest time", {"State": {
            "controller_time_us": 0xFFFFFFFFFFFFFFFF, "pose": pose,
            "velocity": {"x_mm_s": 0.0, "y_mm_s": 0.0, "z_mm_s": 0.0},
            "mode": {"Fault": {"code": 65535}}, "slide_progress": 0.0}}),
        ("error, outside the workspace", {"Error": {
            "seq": 42, "code": "OutsideWorkspace", "text": "x 950 mm beyond 900 mm"}}),
        ("error, over the speed limit, empty text", {"Error": {
            "seq": 0, "code": "OverSpeedLimit", "text": ""}}),
        ("error, text of 64 bytes with non-ASCII characters", {"Error": {
            "seq": 2**21, "code": "Other", "text": "é" * 31 + "µ"}}),
        ("error codes 2", {"Error": {"seq": 1, "code": "InvalidCommand", "text": "NaN"}}),
        ("error codes 3", {"Error": {"seq": 1, "code": "Busy", "text": "sliding"}}),
        ("error codes 4", {"Error": {"seq": 1, "code": "Faulted", "text": "axis 2"}}),
        ("error codes 5", {"Error": {"seq": 1, "code": "Unsupported", "text": "?"}}),
        ("error codes 7", {"Error": {"seq": 9, "code": "Expired", "text": "valid_until_us"}}),
        ("done", {"Done": {"slide_id": 7}}),
    ]

    valid = []

    def add(name, kind, payload, body, signed=True, **h):
        wire = packet(key, kind, payload, signed=signed, **h)
        header = {"ack_requested": h.get("ack_requested", False), "sender": h.get("sender", 1),
                  "link_id": h.get("link_id", 1), "epoch": h.get("epoch", 1),
                  "counter": h.get("counter", 1), "seq": h.get("seq", 0)}
        valid.append({"name": name, "signed": signed, "kind": kind, "header": header,
                      "body": body, "payload": payload.hex(), "wire": wire.hex()})

    for i, (name, m) in enumerate(messages):
        add(name, "Data", encode("Message", m), m, sender=1 + i % 2, link_id=1 + i,
            epoch=1_760_000_000 + i, counter=1000 + 37 * i, seq=1 + i, ack_requested=i % 3 == 0)
    add("unsigned data (the insecure baseline)", "Data", encode("Message", "Heartbeat"),
        "Heartbeat", signed=False, epoch=5, counter=6, seq=7)
    add("ack", "Ack", b"", None, sender=2, epoch=9, counter=77, seq=42)
    add("challenge", "Challenge", b"", None, epoch=0x01020304, counter=0x0506070809)
    add("response", "Response", struct.pack("<IQ", 0x01020304, 0x0506070809),
        {"epoch": 0x01020304, "counter": 0x0506070809}, sender=2, epoch=3, counter=1)
    add("largest header fields", "Ack", b"", None, sender=255, link_id=65535,
        epoch=0xFFFFFFFF, counter=0xFFFFFFFFFFFFFFFF, seq=0xFFFFFFFF)

    # What must be refused, and the error. "signed_link": decode with the key (true) or as an
    # unsigned link (false).
    hb = encode("Message", "Heartbeat")
    good = packet(key, "Data", hb, seq=3)
    flipped_tag = bytearray(good)
    flipped_tag[-1] ^= 0x80
    flipped_payload = bytearray(good)
    flipped_payload[HEADER_LEN] ^= 0x01  # Heartbeat (0) becomes MoveTo (1): tag must catch it
    flipped_header = bytearray(good)
    flipped_header[6] ^= 0x02  # link id 1 -> 3
    invalid = [
        ("empty datagram", b"", True, "truncated"),
        ("shorter than the header", good[:HEADER_LEN - 1], True, "truncated"),
        ("bad magic", packet(key, "Data", hb, magic=b"CK"), True, "magic"),
        ("wire version 2", packet(key, "Data", hb, version=2), True, "version"),
        ("reserved flag bit", packet(key, "Data", hb, flags_extra=0x04), True, "flags"),
        ("unknown kind", good[:4] + b"\x04" + good[5:], True, "kind"),
        ("tag cut short", good[:-1], True, "length"),
        ("a byte after the tag", good + b"\x00", True, "length"),
        ("payload length beyond the datagram", packet(key, "Data", hb, length=2), True, "length"),
        ("payload length over 256", packet(key, "Data", bytes(257)), True, "payload_too_long"),
        ("data without payload", packet(key, "Data", b""), True, "control"),
        ("ack with a payload", packet(key, "Ack", b"\x00", seq=1), True, "control"),
        ("ack requesting an ack", packet(key, "Ack", b"", ack_requested=True, seq=1), True,
         "control"),
        ("challenge with a sequence number", packet(key, "Challenge", b"", seq=1), True,
         "control"),
        ("response of 11 bytes", packet(key, "Response", bytes(11)), True, "control"),
        ("unknown message variant", packet(key, "Data", varint(7)), True, "payload"),
        ("message cut short", packet(key, "Data", encode("Message", messages[2][1])[:-1]), True,
         "payload"),
        ("error text of 65 bytes", packet(key, "Data", varint(5) + varint(1) + varint(6)
                                          + varint(65) + b"a" * 65), True, "payload"),
        ("error text not UTF-8", packet(key, "Data", varint(5) + varint(1) + varint(6)
                                        + varint(2) + b"\xc3\x28"), True, "payload"),
        ("trailing byte after the message", packet(key, "Data", hb + b"\x00"), True,
         "non_canonical"),
        ("overlong varint (Done, slide 1 as 81 00)", packet(key, "Data", b"\x06\x81\x00"), True,
         "non_canonical"),
        ("tag bit flipped", bytes(flipped_tag), True, "bad_tag"),
        ("payload bit flipped (Heartbeat to MoveTo)", bytes(flipped_payload), True, "bad_tag"),
        ("header bit flipped (link id)", bytes(flipped_header), True, "bad_tag"),
        ("signed with another key", packet(other_key, "Data", hb, seq=3), True, "bad_tag"),
        ("signed with an all-zero key", packet(bytes(32), "Data", hb, seq=3), True, "bad_tag"),
        ("signed with an empty key", packet(b"", "Data", hb, seq=3), True, "bad_tag"),
        ("tag of zeros", good[:-TAG_LEN] + bytes(TAG_LEN), True, "bad_tag"),
        ("unsigned on a signed link", packet(key, "Data", hb, signed=False), True, "unsigned"),
        ("signed on an unsigned link", good, False, "unexpected_tag"),
    ]
    invalid = [{"name": n, "wire": bytes(w).hex(), "signed_link": s, "error": e}
               for n, w, s, e in invalid]

    # The window: reordering, replays, the edges, a jump too far, a resynchronisation.
    replay = [
        {"name": "in order, reordered, replayed", "start": None,
         "steps": replay_sequence(Window(), [1, 2, 3, 5, 4, 4, 3, 6, 0, 10, 8, 9, 7, 10])},
        {"name": "window edges", "start": None,
         "steps": replay_sequence(Window(), [200, 73, 72, 73, 199, 327, 200, 201, 199, 328,
                                             201, 1352, 1353, 2377, 2378, 10**18])},
        {"name": "far jumps are refused and change nothing", "start": None,
         "steps": replay_sequence(Window(), [1, 2**64 - 1, 1026, 1025, 2, 3, 2**63])},
        {"name": "after a resynchronisation at 5000", "start": 5000,
         "steps": replay_sequence(Window.starting_at(5000),
                                  [5000, 4999, 4873, 4872, 5001, 6025, 6026, 5002])},
    ]

    doc = {
        "comment": "Golden vectors of the crackbot manipulator link, written by generate.py "
                   "(independent Python implementation). Do not edit by hand.",
        "wire_version": WIRE_VERSION,
        "header_len": HEADER_LEN,
        "tag_len": TAG_LEN,
        "max_payload": MAX_PAYLOAD,
        "window": WINDOW,
        "max_jump": MAX_JUMP,
        "schema_sha256": hashlib.sha256(SCHEMA.encode()).hexdigest(),
        "schema_hash": SCHEMA_HASH.hex(),
        "key": key.hex(),
        "valid": valid,
        "invalid": invalid,
        "replay": replay,
    }
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "vectors.json")
    text = json.dumps(doc, indent=1, ensure_ascii=False) + "\n"
    if "--check" in sys.argv[1:]:
        with open(out, encoding="utf-8") as fh:
            if fh.read() != text:
                sys.exit(f"{out} differs from what generate.py produces: regenerate it and "
                         "review the diff")
        print(f"{out}: matches the Python reference ({len(valid)} valid, {len(invalid)} invalid, "
              f"{len(replay)} replay sequences)")
        return
    with open(out, "w", encoding="utf-8") as fh:
        fh.write(text)
    print(f"wrote {out}: {len(valid)} valid, {len(invalid)} invalid, {len(replay)} replay sequences")


if __name__ == "__main__":
    main()
