#!/usr/bin/env python3
"""Writes frames.json, the golden vectors of the crackbot sensor wire format.

An independent implementation of the format in crates/protocol (COBS, CRC-32C, layout), in plain
Python with no dependencies, so that the Rust encoder, the Rust decoder and the firmware are all
checked against something they did not produce. Run from anywhere:

    python3 crates/protocol/golden/generate.py          # (re)write frames.json
    python3 crates/protocol/golden/generate.py --check  # fail if frames.json differs

The output is checked in; tests in crates/protocol and firmware/ read it, and the test script
runs --check so the file can never drift from this reference implementation.
"""
import json
import os
import sys
import random
import struct

VERSION = 1
ADC_MAX = 1023  # 10-bit ADC, as on the authors' Arduino Mega
PERIOD_US = 2500  # 400 Hz


def crc32c(data: bytes) -> int:
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ (0x82F63B78 if crc & 1 else 0)
    return crc ^ 0xFFFFFFFF


assert crc32c(b"123456789") == 0xE3069283


def cobs_encode(data: bytes) -> bytes:
    out = bytearray([0])
    code_at, code = 0, 1
    for byte in data:
        if byte == 0:
            out[code_at] = code
            code_at, code = len(out), 1
            out.append(0)
        else:
            out.append(byte)
            code += 1
            if code == 0xFF:
                out[code_at] = code
                code_at, code = len(out), 1
                out.append(0)
    out[code_at] = code
    return bytes(out)


def payload(seq, ts, channels, flags, version=VERSION):
    body = struct.pack("<BBHI4H", version, flags, seq, ts, *channels)
    return body + struct.pack("<I", crc32c(body))


def wire(p: bytes) -> bytes:
    return b"\x00" + cobs_encode(p) + b"\x00"


def saturation_flags(channels):
    flags = 0
    for i, v in enumerate(channels):
        if v == 0 or v >= ADC_MAX:
            flags |= 1 << i
    return flags


def frame_obj(seq, ts, channels, flags):
    return {"seq": seq, "timestamp_us": ts, "channels": list(channels), "flags": flags}


def main():
    rng = random.Random(20261121)
    valid = []

    def add(name, seq, ts, channels, flags):
        valid.append({"name": name, "frame": frame_obj(seq, ts, channels, flags),
                      "wire": wire(payload(seq, ts, channels, flags)).hex()})

    # What the firmware sends for these ADC readings, ticking at 400 Hz from t = 0 µs.
    firmware_adc = [
        (660, 440, 720, 500),  # values in the range of the authors' recordings
        (661, 441, 721, 510),
        (0, 441, 722, 520),  # D1 at the lower rail
        (662, 1023, 723, 530),  # D2 at the upper rail
        (663, 442, 1023, 787),
        (664, 443, 724, 1023),  # P saturated (surface too close)
        (0, 0, 0, 0),
        (1023, 1023, 1023, 1023),
        (512, 256, 128, 64),
        (1, 2, 3, 1022),
    ]
    firmware = []
    for i, ch in enumerate(firmware_adc):
        f = frame_obj(i, i * PERIOD_US, ch, saturation_flags(ch))
        firmware.append({"adc": list(ch), "frame": f,
                         "wire": wire(payload(i, i * PERIOD_US, ch, f["flags"])).hex()})

    # Edge cases of the format.
    add("all zero", 0, 0, (0, 0, 0, 0), 0)
    add("all ones", 0xFFFF, 0xFFFFFFFF, (0xFFFF,) * 4, 0x1F)
    add("sequence wrap", 0xFFFF, 163_837_500, (600, 450, 700, 300), 0)
    add("timestamp wrap", 12, 0xFFFFFFFF - 1000, (600, 450, 700, 300), 0)
    add("overrun flag", 42, 105_000, (640, 430, 710, 400), 0x10)
    add("every saturation flag", 7, 17_500, (0, 1023, 0, 1023), 0x0F)
    add("16-bit channel values", 300, 750_000, (0x00FF, 0xFF00, 0x0100, 0x8000), 0)
    for k in range(8):
        seq = rng.randrange(0, 1 << 16)
        ts = rng.randrange(0, 1 << 32)
        ch = tuple(rng.randrange(0, 1024) for _ in range(4))
        add(f"random {k}", seq, ts, ch, rng.choice([0, 0x10]) | saturation_flags(ch))

    # Byte strings that must be rejected, with the error they must give.
    good = payload(5, 12_500, (650, 445, 715, 480), 0)
    enc = cobs_encode(good)
    bad_crc = bytearray(good)
    bad_crc[8] ^= 0x01
    bad_version = payload(5, 12_500, (650, 445, 715, 480), 0, version=2)
    reserved = payload(5, 12_500, (650, 445, 715, 480), 0x20)
    invalid = [
        {"name": "bit flip in a channel", "wire": wire(bytes(bad_crc)).hex(), "error": "crc"},
        {"name": "unknown protocol version", "wire": wire(bad_version).hex(), "error": "version"},
        {"name": "reserved flag bit", "wire": wire(reserved).hex(), "error": "version"},
        {"name": "truncated (last 3 bytes lost)", "wire": (b"\x00" + enc[:-3] + b"\x00").hex(),
         "error": "truncated"},
        {"name": "two frames glued (delimiter lost)",
         "wire": (b"\x00" + enc + enc + b"\x00").hex(), "error": "overlong"},
        {"name": "COBS code pointing past the end",
         "wire": (b"\x00" + bytes([0x30]) + enc[1:] + b"\x00").hex(), "error": "cobs"},
    ]
    doc = {
        "comment": "Golden vectors of the crackbot sensor wire format, written by generate.py "
                   "(independent Python implementation). Do not edit by hand.",
        "protocol_version": VERSION,
        "wire_len": 23,
        "sample_period_us": PERIOD_US,
        "adc_max": ADC_MAX,
        "valid": valid,
        "firmware_sequence": firmware,
        "invalid": invalid,
    }
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "frames.json")
    text = json.dumps(doc, indent=1) + "\n"
    if "--check" in sys.argv[1:]:
        with open(out) as fh:
            if fh.read() != text:
                sys.exit(f"{out} differs from what generate.py produces: regenerate it and review the diff")
        print(f"{out}: matches the Python reference ({len(valid)} valid, {len(firmware)} firmware, "
              f"{len(invalid)} invalid vectors)")
        return
    with open(out, "w") as fh:
        fh.write(text)
    print(f"wrote {out}: {len(valid)} valid, {len(firmware)} firmware, {len(invalid)} invalid")


if __name__ == "__main__":
    main()
