"""Helpers of the Python package's tests."""

import json

import numpy as np

import dsreg


def ellipsoid(shape=(24, 20, 18), radii=(9.3, 7.1, 6.2), center=None):
    """A bool ellipsoid indexed [i, j, k], Fortran order."""
    center = np.array(shape) / 2 - 0.3 if center is None else np.asarray(center)
    i, j, k = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
    inside = ((i - center[0]) / radii[0]) ** 2 + ((j - center[1]) / radii[1]) ** 2 + ((k - center[2]) / radii[2]) ** 2 <= 1
    return np.asfortranarray(inside)


def write_raw(path, mask):
    """`mask` as a uint8 .raw file, x fastest (Fortran order of [i, j, k])."""
    mask.astype(np.uint8).ravel(order="F").tofile(path)
    return ",".join(str(n) for n in mask.shape)


def cli_mesh(cli, tmp_path, *args):
    """The mesh and report `dsreg regularize ARGS -o out.ply --report r.json` writes."""
    out, report = tmp_path / "cli.ply", tmp_path / "cli.json"
    cli("regularize", *args, "-o", out, "--report", report, "--quiet")
    return dsreg.read_mesh(out), json.loads(report.read_text())
