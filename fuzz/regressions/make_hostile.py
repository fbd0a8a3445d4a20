#!/usr/bin/env python3
"""Writes the hand-made hostile inputs of fuzz/regressions/<target>/hostile-* (committed).

Each file is one attack on a reader: truncated payloads, lying headers, zlib bombs, dimensions
of 2^31, negative sizes, non-numeric fields. fuzz/regressions/expected-messages.tsv lists the
message each must be rejected with (checked by the fuzz_regressions test), and
docs/hostile-inputs.md shows the actual messages. Run from anywhere:
    python3 fuzz/regressions/make_hostile.py
"""
import os
import struct
import zlib

ROOT = os.path.dirname(os.path.abspath(__file__))


def put(target, name, data):
    folder = os.path.join(ROOT, target)
    os.makedirs(folder, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(folder, "hostile-" + name), "wb") as f:
        f.write(data)


def vol_header(x, y, z, version, extra=""):
    return f"X: {x}\nY: {y}\nZ: {z}\nVoxel-Size: 1\n{extra}Version: {version}\n.\n"


def raw_prefix(x, y, z, type_code, big_endian=False, header_bytes=0):
    return struct.pack("<iiiBBB", x, y, z, type_code, 1 if big_endian else 0, header_bytes)


# ---- .vol
put("vol", "truncated-v2.vol", vol_header(4, 4, 4, 2) + "abc")
put("vol", "trailing-v2.vol", vol_header(2, 2, 1, 2) + "\x01\x00\x01\x00EXTRA")
put("vol", "dims-2p31.vol", vol_header(2**31, 2**31, 2**31, 2) + "\x01")
put("vol", "negative-dim.vol", vol_header(-4, 4, 4, 2) + "\x00" * 64)
put("vol", "non-numeric-dim.vol", vol_header("four", 4, 4, 2) + "\x00" * 64)
put("vol", "dim-overflows-int64.vol", vol_header(99999999999999999999999, 1, 1, 2) + "\x00")
put("vol", "lying-header-v3.vol", vol_header(2000, 2000, 2000, 3).encode() + zlib.compress(b"\x01" * 64))
# A zlib bomb: 32 MiB of zeros in 32 KiB, for a header announcing 16 voxels.
put("vol", "zlib-bomb.vol", vol_header(4, 2, 2, 3).encode() + zlib.compress(b"\x00" * (32 << 20), 9))
put("vol", "zlib-short.vol", vol_header(4, 4, 4, 3).encode() + zlib.compress(b"\x01" * 60))
put("vol", "zlib-corrupt.vol", vol_header(4, 4, 4, 3).encode() + b"\x78\x9c" + b"\xff" * 30)
put("vol", "zlib-cut.vol", vol_header(4, 4, 4, 3).encode() + zlib.compress(b"\x01" * 64)[:-6])
put("vol", "no-end-line.vol", "X: 4\nY: 4\nZ: 4\nVersion: 2\n")
put("vol", "version-4.vol", vol_header(1, 1, 1, 4) + "\x01")
put("vol", "voxel-size-2.vol", "X: 1\nY: 1\nZ: 1\nVoxel-Size: 2\nVersion: 2\n.\n\x01\x00")
put("vol", "duplicate-key.vol", "X: 1\nX: 2\nY: 1\nZ: 1\nVersion: 2\n.\n\x01")
put("vol", "binary-garbage.vol", bytes(range(256)) * 4)

# ---- .longvol
put("longvol", "truncated-v2.longvol", vol_header(2, 2, 2, 2).replace("Voxel-Size: 1", "Lvoxel-Size: 8") + "\x01" * 60)
put("longvol", "dims-2p31.longvol", vol_header(2**31 - 1, 2**31 - 1, 1, 3).encode() + zlib.compress(b"\x00" * 8))
put("longvol", "lying-header-v3.longvol", vol_header(1000, 1000, 1000, 3).encode() + zlib.compress(b"\x00" * 800))

# ---- .pgm3d
put("pgm3d", "bad-magic.pgm3d", "P5-2D\n2 2 2\n255\n" + "\x01" * 8)
put("pgm3d", "maxval-zero.pgm3d", "P5-3D\n2 2 2\n0\n" + "\x00" * 8)
put("pgm3d", "maxval-70000.pgm3d", "P5-3D\n2 2 2\n70000\n" + "\x00" * 16)
put("pgm3d", "value-above-maxval.pgm3d", "P2-3D\n2 1 1\n10\n5 11\n")
put("pgm3d", "non-numeric-value.pgm3d", "P2-3D\n2 1 1\n10\n5 x1\n")
put("pgm3d", "negative-dim.pgm3d", "P2-3D\n-2 1 1\n10\n5 1\n")
put("pgm3d", "dims-2p31.pgm3d", "P5-3D\n2147483648 2147483648 2147483648\n255\n\x00")
put("pgm3d", "lying-ascii-header.pgm3d", "P2-3D\n1000 1000 1000\n255\n1 2 3 4\n")
put("pgm3d", "truncated-p5.pgm3d", "P5-3D\n4 4 4\n65535\n" + "\x00" * 100)
put("pgm3d", "trailing-p2.pgm3d", "P2-3D\n2 1 1\n10\n5 1 7\n")

# ---- .raw (15-byte layout prefix, then the file; see fuzz_targets.hpp)
put("raw", "negative-dim", raw_prefix(-1, 4, 4, 0) + b"\x00" * 16)
put("raw", "dims-2p31", raw_prefix(2**31 - 1, 2**31 - 1, 2**31 - 1, 9) + b"\x00" * 8)
put("raw", "truncated-int16", raw_prefix(4, 4, 4, 3) + b"\x00" * 127)
put("raw", "header-beyond-file", raw_prefix(1, 1, 1, 0, header_bytes=200) + b"\x01" * 10)

# ---- polynomials
put("polynomial", "huge-power", "(x+y+z)^1000000")
put("polynomial", "degree-65", "(x+y)^33*(z-1)^32")
put("polynomial", "syntax", "x^2+*y")
put("polynomial", "implicit-product", "2x+y")
put("polynomial", "nested-20000", "(" * 20000 + "x" + ")" * 20000)
put("polynomial", "overflowing-coefficient", "1e999*x")
put("polynomial", "power-tower", "x^2^3")

# ---- normals files (surface: fuzz_targets.cpp, normals_target_surface)
put("normals", "nan-normal", "0 0 0 -x nan 0 0\n")
put("normals", "zero-normal", "0 0 0 -x 0 0 0\n")
put("normals", "voxel-2p63", "9223372036854775807 0 0 -x -1 0 0\n")
put("normals", "negative-voxel", "-1 0 0 -x -1 0 0\n")
put("normals", "non-numeric", "0 0 0 -x minus-one 0 0\n")
put("normals", "long-line", "0 0 0 -x -1 0 0 " + "9" * 5000 + "\n")
put("normals", "duplicate", "0 0 0 -x -1 0 0\n0 0 0 -x -1 0 0\n")
put("normals", "missing-surfels", "0 0 0 -x -1 0 0\n")
put("normals", "not-a-surfel", "1 1 1 +x 1 0 0\n")

# ---- meshes
put("obj", "index-out-of-range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
put("obj", "nan-vertex.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
put("obj", "pentagon.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n")
put("obj", "index-2p31.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2147483648\n")
put("obj", "unknown-statement.obj", "v 0 0 0\nfoo 1 2 3\n")
put("off", "counts-2p31.off", "OFF\n2147483647 2147483647 0\n0 0 0\n")
put("off", "negative-count.off", "OFF\n-3 1 0\n0 0 0\n")
put("off", "truncated.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n")
put("off", "non-numeric.off", "OFF\n3 1 0\n0 0 zero\n1 0 0\n0 1 0\n3 0 1 2\n")
put("ply", "vertex-count-2p32.ply",
    "ply\nformat binary_little_endian 1.0\nelement vertex 4294967296\nproperty float x\nproperty float y\n"
    "property float z\nend_header\n" + "\x00" * 12)
put("ply", "truncated-binary.ply",
    "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
    "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + "\x00" * 50)
put("ply", "list-count-255.ply",
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n255 0 1 2\n")
put("ply", "negative-count.ply",
    "ply\nformat ascii 1.0\nelement vertex -3\nproperty float x\nproperty float y\nproperty float z\nend_header\n")
put("ply", "no-end-header.ply", "ply\nformat ascii 1.0\nelement vertex 3\n")
put("stl", "triangle-count-2p31.stl", b"\x00" * 80 + struct.pack("<I", 2**31 - 1) + b"\x00" * 50)
put("stl", "truncated-ascii.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n")
put("stl", "nan-ascii.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 nan\nvertex 1 0 0\nvertex 0 1 0\n"
    "endloop\nendfacet\nendsolid t\n")
