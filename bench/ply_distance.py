#!/usr/bin/python3
"""Compares two binary PLY meshes written by dsreg with the same vertex order: prints
`faces_equal max rms normal_max tangential_max` — whether the face sections are byte for byte the
same, the largest and the root-mean-square vertex distance, then the largest component of the
difference along the reference's vertex normal (the mean of its faces' u: how far the surface is)
and across it (a slide along the surface), in voxels of size H.

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
    e = (b - a) / h
    d = np.linalg.norm(e, axis=1)
    n = vertex_normals(faces_a, a.shape[0])
    along = (e * n).sum(axis=1)
    across = np.linalg.norm(e - along[:, None] * n, axis=1)
    print(f"{'yes' if faces_a == faces_b else 'no'} {d.max():.2e} {np.sqrt((d ** 2).mean()):.2e} "
          f"{np.abs(along).max():.2e} {across.max():.2e}")


def vertex_normals(faces, vertices):
    """The mean of the field u of each vertex's faces, normalized (dsreg's PLY faces: 4 indices and u)."""
    record = np.dtype([("n", "u1"), ("v", "<i4", 4), ("u", "<f4", 3)])
    table = np.frombuffer(faces, dtype=record)
    if table.size == 0 or (table["n"] != 4).any():
        sys.exit("ply_distance.py: expected dsreg's quad faces with the field u")
    normals = np.zeros((vertices, 3))
    for k in range(4):
        np.add.at(normals, table["v"][:, k], table["u"].astype(np.float64))
    return normals / np.linalg.norm(normals, axis=1)[:, None]


if __name__ == "__main__":
    main()
