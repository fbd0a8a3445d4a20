#!/usr/bin/python3
"""The peer a user would pick: 3D Slicer's binary-labelmap-to-closed-surface conversion, in Debian's VTK.

Benchmark-only (never a dependency of dsreg). It runs the steps of Slicer's conversion rule with
Slicer's defaults (smoothing factor 0.5, no decimation): pad the mask by one background voxel,
vtkDiscreteFlyingEdges3D on the object value, vtkWindowedSincPolyDataFilter (20 iterations,
pass band 10^(-4 * smoothing), boundary and feature-edge smoothing off, non-manifold smoothing
on, normalized coordinates), then vtkPolyDataNormals (consistency on, splitting off).

Coordinates are dsreg's: voxel (i, j, k) is centred at origin + spacing * (i, j, k), so the
output lands on dsreg's meshes of the same volume (spacing 1, origin 0 for .vol files).

  bench/slicer_pipeline.py INPUT -o OUT.{ply,obj,stl,vtk} [--min A] [--max B] [--smoothing 0.5]
                           [--raw-dims X,Y,Z --raw-type uint8] [--spacing SX,SY,SZ] [--json T.json]
                           [--each-label]

--each-label: a label map, as Slicer converts a segmentation: each non-zero value is a segment,
cropped to its extent and converted on its own (the steps above), written to OUT-<value>.EXT;
the timings are summed over the segments.

INPUT: DGtal .vol (versions 2 and 3), .longvol, a .raw volume (with --raw-dims), NumPy .npy
(indexed [i, j, k]) or NIfTI (.nii, .nii.gz, through nibabel; its voxel grid only: the mesh is
in voxel-grid coordinates scaled by the spacing). The object is MIN <= value <= MAX (default:
value > 0), as in dsreg. --json writes the wall time of each step and of the whole pipeline.
Run it with Debian's /usr/bin/python3 (python3-vtk9, python3-numpy).
"""
import argparse
import json
import sys
import time
import zlib

import numpy as np
import vtk
from vtk.util import numpy_support


def read_dgtal_vol(path, value_bytes):
    """Values of a .vol (1 byte) or .longvol (8 bytes little-endian) file, indexed [i, j, k]."""
    with open(path, "rb") as f:
        data = f.read()
    header = {}
    offset = 0
    while True:
        end = data.index(b"\n", offset)
        line = data[offset:end].decode("ascii").strip()
        offset = end + 1
        if line == ".":
            break
        key, _, value = line.partition(":")
        header[key.strip()] = value.strip()
    dims = tuple(int(header[k]) for k in ("X", "Y", "Z"))
    payload = data[offset:]
    if header.get("Version", "2") == "3":
        payload = zlib.decompress(payload)
    dtype = np.uint8 if value_bytes == 1 else np.dtype("<u8")
    values = np.frombuffer(payload, dtype=dtype, count=dims[0] * dims[1] * dims[2])
    return values.reshape(dims[::-1]).transpose(2, 1, 0), (1.0, 1.0, 1.0)


def read_volume(args):
    path = args.input
    lower = path.lower()
    if lower.endswith(".vol"):
        return read_dgtal_vol(path, 1)
    if lower.endswith(".longvol") or lower.endswith(".lvol"):
        return read_dgtal_vol(path, 8)
    if lower.endswith(".npy"):
        return np.load(path), (1.0, 1.0, 1.0)
    if lower.endswith(".nii") or lower.endswith(".nii.gz"):
        import nibabel

        image = nibabel.load(path)
        return np.asanyarray(image.dataobj), tuple(float(s) for s in image.header.get_zooms()[:3])
    if lower.endswith(".raw"):
        if not args.raw_dims:
            sys.exit(f"{path}: a .raw volume needs --raw-dims X,Y,Z")
        dims = tuple(int(d) for d in args.raw_dims.split(","))
        values = np.fromfile(path, dtype=np.dtype(args.raw_type), count=dims[0] * dims[1] * dims[2])
        return values.reshape(dims[::-1]).transpose(2, 1, 0), (1.0, 1.0, 1.0)
    sys.exit(f"{path}: unknown volume format")


def object_mask(values, minimum, maximum):
    inside = values >= minimum if minimum is not None else values > 0
    if maximum is not None:
        inside &= values <= maximum
    return inside


def padded_image(mask):
    """The mask as a vtkImageData of unsigned chars (1 = object), padded by one background voxel,
    with index (0,0,0) of the unpadded mask at the origin and unit spacing (as Slicer, which
    works in IJK and transforms the surface afterwards)."""
    padded = np.zeros(tuple(n + 2 for n in mask.shape), dtype=np.uint8)
    padded[1:-1, 1:-1, 1:-1] = mask
    image = vtk.vtkImageData()
    image.SetDimensions(*padded.shape)
    image.SetOrigin(-1.0, -1.0, -1.0)
    image.SetSpacing(1.0, 1.0, 1.0)
    flat = np.ascontiguousarray(padded.transpose(2, 1, 0)).ravel()  # x fastest
    array = numpy_support.numpy_to_vtk(flat, deep=True, array_type=vtk.VTK_UNSIGNED_CHAR)
    image.GetPointData().SetScalars(array)
    return image


def slicer_closed_surface(image, smoothing, spacing, origin, times):
    start = time.perf_counter()
    surface = vtk.vtkDiscreteFlyingEdges3D()
    surface.SetInputData(image)
    surface.ComputeGradientsOff()
    surface.ComputeNormalsOff()
    surface.SetValue(0, 1)
    surface.Update()
    result = surface.GetOutput()
    times["flying_edges"] = time.perf_counter() - start

    if smoothing > 0:
        start = time.perf_counter()
        smoother = vtk.vtkWindowedSincPolyDataFilter()
        smoother.SetInputData(result)
        smoother.SetNumberOfIterations(20)
        smoother.SetPassBand(10.0 ** (-4.0 * smoothing))
        smoother.BoundarySmoothingOff()
        smoother.FeatureEdgeSmoothingOff()
        smoother.NonManifoldSmoothingOn()
        smoother.NormalizeCoordinatesOn()
        smoother.Update()
        result = smoother.GetOutput()
        times["windowed_sinc"] = time.perf_counter() - start

    start = time.perf_counter()
    transform = vtk.vtkTransform()
    transform.Translate(*origin)
    transform.Scale(*spacing)
    placed = vtk.vtkTransformPolyDataFilter()
    placed.SetInputData(result)
    placed.SetTransform(transform)
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputConnection(placed.GetOutputPort())
    normals.ConsistencyOn()
    normals.SplittingOff()
    normals.Update()
    times["transform_and_normals"] = time.perf_counter() - start
    return normals.GetOutput()


def write_mesh(polydata, path):
    lower = path.lower()
    if lower.endswith(".ply"):
        writer = vtk.vtkPLYWriter()
        writer.SetFileTypeToBinary()
    elif lower.endswith(".obj"):
        writer = vtk.vtkOBJWriter()
    elif lower.endswith(".stl"):
        writer = vtk.vtkSTLWriter()
        writer.SetFileTypeToBinary()
    elif lower.endswith(".vtk"):
        writer = vtk.vtkPolyDataWriter()
    else:
        sys.exit(f"{path}: unknown mesh format (.ply .obj .stl .vtk)")
    writer.SetFileName(path)
    writer.SetInputData(polydata)
    if not writer.Write():
        sys.exit(f"{path}: cannot write the mesh")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input")
    parser.add_argument("-o", "--output", required=True)
    parser.add_argument("--min", type=float)
    parser.add_argument("--max", type=float)
    parser.add_argument("--smoothing", type=float, default=0.5, help="Slicer's smoothing factor (default 0.5)")
    parser.add_argument("--raw-dims")
    parser.add_argument("--raw-type", default="uint8")
    parser.add_argument("--spacing", help="voxel size SX,SY,SZ (overrides the file's)")
    parser.add_argument("--origin", default="0,0,0", help="centre of voxel (0,0,0) (default 0,0,0)")
    parser.add_argument("--json", help="write the step timings here")
    parser.add_argument("--each-label", action="store_true", help="convert each label of a label map on its own")
    args = parser.parse_args()

    process_start = time.perf_counter()
    times = {}
    start = time.perf_counter()
    values, spacing = read_volume(args)
    if args.spacing:
        spacing = tuple(float(s) for s in args.spacing.split(","))
    origin = tuple(float(s) for s in args.origin.split(","))
    mask = object_mask(values, args.min, args.max)
    times["read"] = time.perf_counter() - start

    if args.each_label:
        triangles, vertices = each_label(values, spacing, origin, args, times)
    else:
        start = time.perf_counter()
        image = padded_image(mask)
        times["pad"] = time.perf_counter() - start
        polydata = slicer_closed_surface(image, args.smoothing, spacing, origin, times)
        start = time.perf_counter()
        write_mesh(polydata, args.output)
        times["write"] = time.perf_counter() - start
        triangles, vertices = polydata.GetNumberOfPolys(), polydata.GetNumberOfPoints()
    times["pipeline"] = sum(times[k] for k in ("pad", "flying_edges", "windowed_sinc", "transform_and_normals") if k in times)
    times["total"] = time.perf_counter() - process_start
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"seconds": times, "triangles": triangles, "vertices": vertices}, f, indent=2)


def label_output(path, value):
    stem, dot, extension = path.rpartition(".")
    return f"{stem}-{value}.{extension}"


def each_label(values, spacing, origin, args, times):
    """Every segment on its own, cropped to its extent: Slicer's conversion of a segmentation."""
    start = time.perf_counter()
    labels = [int(v) for v in np.unique(values) if v != 0]
    times["read"] += time.perf_counter() - start
    triangles = vertices = 0
    for value in labels:
        start = time.perf_counter()
        mask = values == value
        extent = [np.nonzero(mask.any(axis=tuple(a for a in range(3) if a != d)))[0] for d in range(3)]
        low = [int(e[0]) for e in extent]
        high = [int(e[-1]) + 1 for e in extent]
        image = padded_image(mask[low[0]:high[0], low[1]:high[1], low[2]:high[2]])
        times["pad"] = times.get("pad", 0.0) + time.perf_counter() - start
        shifted = tuple(o + s * l for o, s, l in zip(origin, spacing, low))
        step = {}
        polydata = slicer_closed_surface(image, args.smoothing, spacing, shifted, step)
        for key, seconds in step.items():
            times[key] = times.get(key, 0.0) + seconds
        start = time.perf_counter()
        write_mesh(polydata, label_output(args.output, value))
        times["write"] = times.get("write", 0.0) + time.perf_counter() - start
        triangles += polydata.GetNumberOfPolys()
        vertices += polydata.GetNumberOfPoints()
    return triangles, vertices


if __name__ == "__main__":
    main()
