#!/usr/bin/python3
"""Edges and faces of a rotated cube: the normal error of a mesh near the cube's edges and on its
flat faces, and its mean vertex distance, for dsreg's fields (II, AT) and the Slicer pipeline.

Two cubes of side 2 in the frame X = 0.8x + 0.6y, Y = -0.48x + 0.64y + 0.6z, Z = 0.36x - 0.48y +
0.8z, digitized in [-1.8, 1.8]^3 at h = 0.04 (50 voxels across):

- sharp: the cube max(|X|, |Y|, |Z|) <= 1 (issue 12's "rotated cube", item 4), digitized as the
  superquadric X^64 + Y^64 + Z^64 = 1 (its edges are rounded over 0.4 voxel, less than the
  digitization's own staircase); the meshes are measured against the sharp cube itself, here
  (distance to its surface; normal of the face the centroid is nearest to);
- rounded: the superquadric of degree 16 (edges rounded over about 1.5 voxels along the diagonal,
  a few voxels in all), measured against that surface by `dsreg eval --face-errors`.

A face centroid with rotated coordinates |X| >= |Y| >= |Z| is sqrt((1 - |X|)^2 + (1 - |Y|)^2) / h
voxels from the nearest edge: "near an edge" below 2 voxels, "on a face" from 5 voxels on (the
regions of tests/test_ambrosio_tortorelli.cpp).

  /usr/bin/python3 bench/rotated_cube.py [--dsreg build/dsreg] [--cube sharp|rounded|both] [--json out.json] [-- extra dsreg options]

Every mesh of one cube comes from the same digitized .vol.
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
BOX, H = 1.8, 0.04
ORIGIN = -1.84  # centre of voxel (0, 0, 0) of the digitization of [-BOX, BOX]^3 at H
ROTATION = np.array([[0.8, 0.6, 0.0], [-0.48, 0.64, 0.6], [0.36, -0.48, 0.8]])
DEGREES = {"sharp": 64, "rounded": 16}

FIELDS = {
    "II (default field)": [],
    "AT (--normals at)": ["--normals", "at"],
}
if os.environ.get("CUBE_FIELDS"):  # study: name=options;name=options
    FIELDS = {item.split("=", 1)[0]: item.split("=", 1)[1].split() for item in os.environ["CUBE_FIELDS"].split(";")}


def superquadric(degree):
    return (f"(0.8*x+0.6*y)^{degree}+(-0.48*x+0.64*y+0.6*z)^{degree}+(0.36*x-0.48*y+0.8*z)^{degree}-1")


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{' '.join(command)}: {result.stderr}")
    return result.stdout


def edge_distance(centroids):
    """Voxels from each point (physical) to the nearest cube edge, in the cube's frame."""
    rotated = np.sort(np.abs(centroids @ ROTATION.T), axis=1)
    return np.hypot(1 - rotated[:, 2], 1 - rotated[:, 1]) / H


def summary(distance_h, normal_deg, angle, to_edge):
    """The mesh's means and its per-face normal errors `angle` (NaN: not measured) by region."""
    valid = ~np.isnan(angle)
    near, face = valid & (to_edge < 2), valid & (to_edge >= 5)
    return {"distance_h": float(distance_h), "normal_deg": float(normal_deg),
            "near_edge_deg": float(angle[near].mean()), "faces_deg": float(angle[face].mean()),
            "near_edge_faces": int(near.sum()), "face_faces": int(face.sum())}


def read_obj(path):
    """Vertices (voxel coordinates) and polygons (0-based index lists) of an OBJ file."""
    vertices, faces = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append([float(t) for t in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return np.array(vertices), faces


def sharp_cube_truth(points):
    """Distance to the sharp cube's surface and the outward normal of the face nearest to each point."""
    q = points @ ROTATION.T
    a = np.abs(q)
    largest = a.max(axis=1)
    outside = np.linalg.norm(np.maximum(a - 1, 0), axis=1)
    distance = np.where(largest > 1, outside, 1 - largest)
    axis = a.argmax(axis=1)
    normal = np.zeros_like(q)
    rows = np.arange(len(q))
    normal[rows, axis] = np.sign(q[rows, axis])
    return distance, normal @ ROTATION


def face_normals(vertices, faces):
    """A quad's normal is the mean of the unit normals of its triangles abc and acd (paper, note 5)."""
    normals = []
    for f in faces:
        p = vertices[f]
        n = np.zeros(3)
        for k in range(1, len(f) - 1):
            t = np.cross(p[k] - p[0], p[k + 1] - p[0])
            n += t / np.linalg.norm(t)
        normals.append(n / np.linalg.norm(n))
    return np.array(normals)


def sharp_regions(mesh):
    vertices, faces = read_obj(mesh)
    vertices = ORIGIN + H * vertices  # voxel coordinates -> the shape's
    distance, _ = sharp_cube_truth(vertices)
    centroids = np.array([vertices[f].mean(axis=0) for f in faces])
    _, truth = sharp_cube_truth(centroids)
    cosine = np.clip(np.sum(face_normals(vertices, faces) * truth, axis=1), -1, 1)
    angle = np.degrees(np.arccos(cosine))
    return summary(np.mean(distance) / H, np.mean(angle), angle, edge_distance(centroids))


def rounded_regions(dsreg, mesh, work):
    errors = os.path.join(work, "faces.csv")
    report = json.loads(run([dsreg, "eval", mesh, "--shape", superquadric(DEGREES["rounded"]), "--box", str(BOX),
                             "--h", str(H), "--voxel-coordinates", "--json", "--face-errors", errors]))
    with open(errors) as f:
        rows = np.array([[float(v) for v in row] for row in list(csv.reader(f))[1:]])
    return summary(report["vertex_distance_h"]["mean"], report["normal_angle_deg"]["mean"], rows[:, 3],
                   edge_distance(rows[:, :3]))


def measure_cube(kind, dsreg, extra, work):
    volume = os.path.join(work, f"{kind}.vol")
    run([dsreg, "digitize", "--shape", superquadric(DEGREES[kind]), "--box", str(BOX), "--h", str(H), "-o", volume])
    regions = sharp_regions if kind == "sharp" else (lambda mesh: rounded_regions(dsreg, mesh, work))
    results = {}
    for name, options in FIELDS.items():
        mesh = os.path.join(work, "dsreg.obj")
        run([dsreg, "regularize", volume, "-o", mesh, *options, *extra])
        results[name] = regions(mesh)
    mesh = os.path.join(work, "slicer.obj")
    run(["/usr/bin/python3", os.path.join(HERE, "slicer_pipeline.py"), volume, "-o", mesh])
    results["Slicer pipeline"] = regions(mesh)
    return results


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dsreg", default=os.path.join(os.path.dirname(HERE), "build", "dsreg"))
    parser.add_argument("--cube", choices=["sharp", "rounded", "both"], default="both")
    parser.add_argument("--json")
    parser.add_argument("extra", nargs="*", help="options added to every dsreg run")
    args = parser.parse_args()
    kinds = ["sharp", "rounded"] if args.cube == "both" else [args.cube]
    results = {}
    with tempfile.TemporaryDirectory() as work:
        for kind in kinds:
            results[kind] = measure_cube(kind, args.dsreg, args.extra, work)
    print("| cube | mesh | mean distance (h) | mean normal error | near edges (< 2 voxels) | flat faces (>= 5 voxels) |")
    print("|---|---|---|---|---|---|")
    for kind, by_mesh in results.items():
        for name, r in by_mesh.items():
            print(f"| {kind} | {name} | {r['distance_h']:.3f} | {r['normal_deg']:.2f}° | {r['near_edge_deg']:.2f}° "
                  f"({r['near_edge_faces']} faces) | {r['faces_deg']:.2f}° ({r['face_faces']} faces) |")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
