#!/usr/bin/env python3
"""Tile a recording (.npy, frames x nodes x 3, float64) to any number of frames, back and forth.

    scripts/tile_recording.py IN.npy OUT.npy FRAMES

The frames are played forwards, then backwards, then forwards again (0, 1, ..., n-1, n-2, ...,
1, 0, 1, ...), so that consecutive frames are always neighbours in the source: a long
recording without jumps, for benchmarks of memory and output size (scripts/bench_memory.sh).
Standard library only; the output is written frame by frame.
"""
import ast
import struct
import sys


def read_header(f):
    magic = f.read(6)
    if magic != b"\x93NUMPY":
        sys.exit(f"{f.name}: not a .npy file")
    major, _minor = f.read(2)
    (length,) = struct.unpack("<H" if major == 1 else "<I", f.read(2 if major == 1 else 4))
    header = ast.literal_eval(f.read(length).decode("latin1"))
    if header["descr"] != "<f8" or header["fortran_order"] or len(header["shape"]) != 3:
        sys.exit(f"{f.name}: expected a C-order float64 array frames x nodes x 3, got {header}")
    return header["shape"]


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    src, dst, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
    with open(src, "rb") as f:
        n, nodes, three = read_header(f)
        size = nodes * three * 8
        data = f.read(n * size)
    if n < 2 or len(data) != n * size:
        sys.exit(f"{src}: need at least 2 whole frames")
    period = 2 * (n - 1)
    head = "{'descr': '<f8', 'fortran_order': False, 'shape': (%d, %d, %d), }" % (frames, nodes, three)
    pad = (64 - (10 + len(head) + 1) % 64) % 64
    with open(dst, "wb") as out:
        out.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(head) + pad + 1) + head.encode() + b" " * pad + b"\n")
        for k in range(frames):
            i = k % period
            i = i if i < n else period - i
            out.write(data[i * size:(i + 1) * size])


if __name__ == "__main__":
    main()
