#!/usr/bin/python3
"""Compares two binary PLY meshes written by dsreg with the same vertex order: prints
`faces_equal max rms` — whether the face sections are byte for byte the same, then the largest and
the root-mean-square vertex distance, in voxels of size H.

    bench/ply_distance.py REFERENCE.ply OTHER.ply H
"""
import sys

import numpy as np


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    if "format binary_little_endian 1.0" not in header:
        sys.exit(f"{path}: not a binary little-endian PLY")
    vertices, types, section = 0, [], None
    for line in header:
        words = line.split()
        if line.startswith("element"):
            section = words[1]
            if section == "vertex":
                vertices = int(words[2])
        elif line.startswith("property") and section == "vertex":
            types.append("<f8" if words[1] == "double" else "<f4")
    record = np.dtype([(f"p{i}", t) for i, t in enumerate(types)])
    table = np.frombuffer(data, dtype=record, count=vertices, offset=end)
    xyz = np.stack([table["p0"], table["p1"], table["p2"]], axis=1).astype(np.float64)
    return xyz, data[end + vertices * record.itemsize:]


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    a, faces_a = read_ply(sys.argv[1])
    b, faces_b = read_ply(sys.argv[2])
    h = float(sys.argv[3])
    if a.shape != b.shape:
        print(f"different vertex counts {a.shape[0]} {b.shape[0]}")
        return
    d = np.linalg.norm(a - b, axis=1) / h
    print(f"{'yes' if faces_a == faces_b else 'no'} {d.max():.2e} {np.sqrt((d ** 2).mean()):.2e}")


if __name__ == "__main__":
    main()
