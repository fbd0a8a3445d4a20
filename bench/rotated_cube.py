#!/usr/bin/python3
"""Edges and faces of the rotated cube: the normal error of a mesh near the cube's edges and on its
flat faces, and its mean vertex distance, for dsreg's fields (II, AT) and the Slicer pipeline.

The cube of docs/ambrosio-tortorelli.md: the superquadric X^16 + Y^16 + Z^16 = 1 in the frame
X = 0.8x + 0.6y, Y = -0.48x + 0.64y + 0.6z, Z = 0.36x - 0.48y + 0.8z, in [-1.8, 1.8]^3 at
h = 0.04 (50 voxels across). A face centroid with rotated coordinates |X| >= |Y| >= |Z| is
sqrt((1 - |X|)^2 + (1 - |Y|)^2) / h voxels from the nearest edge: "near an edge" below 2 voxels,
"on a face" from 5 voxels on (the regions of tests/test_ambrosio_tortorelli.cpp).

  /usr/bin/python3 bench/rotated_cube.py [--dsreg build/dsreg] [--json out.json] [-- extra dsreg options]

Every mesh comes from the same digitized .vol; errors from `dsreg eval --face-errors`.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DEGREE = int(os.environ.get("CUBE_DEGREE", "16"))
CUBE = f"(0.8*x+0.6*y)^{DEGREE}+(-0.48*x+0.64*y+0.6*z)^{DEGREE}+(0.36*x-0.48*y+0.8*z)^{DEGREE}-1"
BOX, H = 1.8, 0.04
ROTATION = np.array([[0.8, 0.6, 0.0], [-0.48, 0.64, 0.6], [0.36, -0.48, 0.8]])

FIELDS = {
    "II (default field)": [],
    "AT (--normals at)": ["--normals", "at"],
}
if os.environ.get("CUBE_FIELDS"):  # study: name=options;name=options
    FIELDS = {item.split("=", 1)[0]: item.split("=", 1)[1].split() for item in os.environ["CUBE_FIELDS"].split(";")}


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{' '.join(command)}: {result.stderr}")
    return result.stdout


def name_of(mesh):
    return os.path.basename(mesh)


def regions(dsreg, mesh, work):
    errors = os.path.join(work, "faces.csv")
    report = json.loads(run([dsreg, "eval", mesh, "--shape", CUBE, "--box", str(BOX), "--h", str(H),
                             "--voxel-coordinates", "--json", "--face-errors", errors]))
    with open(errors) as f:
        rows = np.array([[float(v) for v in row] for row in list(csv.reader(f))[1:]])
    rotated = np.abs(rows[:, :3] @ ROTATION.T)
    rotated.sort(axis=1)
    to_edge = np.hypot(1 - rotated[:, 2], 1 - rotated[:, 1]) / H
    angle = rows[:, 3]
    valid = ~np.isnan(angle)
    near, face = valid & (to_edge < 2), valid & (to_edge >= 5)
    if os.environ.get("CUBE_DEBUG"):
        print(name_of(mesh), "near-edge percentiles 50/90/99:", np.percentile(angle[near], [50, 90, 99]), "max", angle[near].max(), file=sys.stderr)
    return {"distance_h": report["vertex_distance_h"]["mean"], "normal_deg": report["normal_angle_deg"]["mean"],
            "near_edge_deg": float(angle[near].mean()), "faces_deg": float(angle[face].mean()),
            "near_edge_faces": int(near.sum()), "face_faces": int(face.sum())}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dsreg", default=os.path.join(os.path.dirname(HERE), "build", "dsreg"))
    parser.add_argument("--json")
    parser.add_argument("extra", nargs="*", help="options added to every dsreg run")
    args = parser.parse_args()
    results = {}
    with tempfile.TemporaryDirectory() as work:
        volume = os.path.join(work, "cube.vol")
        run([args.dsreg, "digitize", "--shape", CUBE, "--box", str(BOX), "--h", str(H), "-o", volume])
        for name, options in FIELDS.items():
            mesh = os.path.join(work, "dsreg.ply")
            run([args.dsreg, "regularize", volume, "-o", mesh, "-q", *options, *args.extra])
            results[name] = regions(args.dsreg, mesh, work)
        mesh = os.path.join(work, "slicer.ply")
        run(["/usr/bin/python3", os.path.join(HERE, "slicer_pipeline.py"), volume, "-o", mesh])
        results["Slicer pipeline"] = regions(args.dsreg, mesh, work)
    print("| mesh | mean distance (h) | mean normal error | near edges (< 2 voxels) | flat faces (>= 5 voxels) |")
    print("|---|---|---|---|---|")
    for name, r in results.items():
        print(f"| {name} | {r['distance_h']:.3f} | {r['normal_deg']:.2f}° | {r['near_edge_deg']:.2f}° "
              f"({r['near_edge_faces']} faces) | {r['faces_deg']:.2f}° ({r['face_faces']} faces) |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
