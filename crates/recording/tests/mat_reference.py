#!/usr/bin/env python3
"""Independent reference reader for the authors' MAT-files (level 5), using only the standard library.

Written separately from the Rust reader (crates/recording/src/mat.rs) to cross-check it: it walks the
top-level data elements, inflates miCOMPRESSED ones with `zlib`, finds the miMATRIX named
`synchronized_data` and prints, for every file given (or every .mat under ../shared/data/tactile):

    name rows cols sum_1 ... sum_9

where sum_c is the plain left-to-right float64 sum of column c over all rows (the same order of additions as
the Rust test, so the values must agree bit for bit; printed with repr(), Python's shortest round-trip form).
With --rows it also prints the first and last row of each file.

Usage: python3 crates/recording/tests/mat_reference.py [--rows] [FILE.mat ...]
"""

import os
import struct
import sys
import zlib

MI_TYPES = {
    1: "b", 2: "B", 3: "h", 4: "H", 5: "i", 6: "I", 7: "f", 9: "d", 12: "q", 13: "Q",
}
MI_MATRIX = 14
MI_COMPRESSED = 15


def tag(buf, pos, end):
    """Returns (type, size, data_start, next_pos) of the element at pos."""
    (word,) = struct.unpack_from(E + "I", buf, pos)
    if word >> 16:  # small data element: size in the upper half, data in the next 4 bytes
        return word & 0xFFFF, word >> 16, pos + 4, pos + 8
    mtype, size = struct.unpack_from(E + "II", buf, pos)
    start = pos + 8
    return mtype, size, start, start + ((size + 7) // 8) * 8


def matrix(buf, pos, end):
    """Parses the sub-elements of a miMATRIX whose data spans buf[pos:end]."""
    subs = []
    while pos < end:
        mtype, size, start, pos = tag(buf, pos, end)
        subs.append((mtype, buf[start:start + size]))
    flags = struct.unpack_from(E + "I", subs[0][1])[0]
    dims = struct.unpack(E + "%di" % (len(subs[1][1]) // 4), subs[1][1])
    name = subs[2][1].decode("ascii")
    dtype, data = subs[3]
    code = MI_TYPES[dtype]
    values = struct.unpack(E + "%d%s" % (len(data) // struct.calcsize(code), code), data)
    return flags & 0xFF, dims, name, [float(v) for v in values]


def read(path):
    global E
    buf = open(path, "rb").read()
    assert buf[:6] == b"MATLAB", "not a MAT-file"
    E = "<" if buf[126:128] == b"IM" else ">"
    pos = 128
    while pos + 8 <= len(buf):
        mtype, size = struct.unpack_from(E + "II", buf, pos)
        body = buf[pos + 8:pos + 8 + size]
        pos += 8 + size
        if mtype == MI_COMPRESSED:
            inner = zlib.decompress(body)
            mtype, size = struct.unpack_from(E + "II", inner, 0)
            body = inner[8:8 + size]
        else:
            pos = 128 + ((pos - 128 + 7) // 8) * 8
        if mtype != MI_MATRIX:
            continue
        cls, dims, name, values = matrix(body, 0, len(body))
        if name == "synchronized_data":
            assert cls == 6 and len(dims) == 2, (cls, dims)
            rows, cols = dims
            # Column-major: column c is values[c*rows:(c+1)*rows].
            return rows, cols, [values[c * rows:(c + 1) * rows] for c in range(cols)]
    raise SystemExit("%s: no synchronized_data" % path)


def main():
    args = sys.argv[1:]
    show_rows = "--rows" in args
    files = [a for a in args if a != "--rows"]
    if not files:
        root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../../shared/data/tactile")
        for sub in ("type", "width"):
            d = os.path.join(root, sub)
            files += [os.path.join(d, f) for f in sorted(os.listdir(d)) if f.endswith(".mat")]
    for f in files:
        rows, cols, columns = read(f)
        sums = []
        for col in columns:
            s = 0.0
            for v in col:
                s += v
            sums.append(s)
        print(os.path.basename(f), rows, cols, " ".join(repr(s) for s in sums))
        if show_rows:
            print("  first", [col[0] for col in columns])
            print("  last ", [col[-1] for col in columns])


if __name__ == "__main__":
    main()
