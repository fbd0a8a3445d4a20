"""dsreg.Mesh: a polygon mesh as numpy arrays."""

import os
from typing import Dict, Optional

import numpy as np

from . import _dsreg


def _points(name: str, values, rows: Optional[int] = None) -> np.ndarray:
    array = np.ascontiguousarray(values, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3 or (rows is not None and array.shape[0] != rows):
        expected = f"({rows}, 3)" if rows is not None else "(n, 3)"
        raise ValueError(f"{name}: an array of shape {expected} is needed (got shape {array.shape})")
    return array


def _faces(values, vertex_count: int) -> np.ndarray:
    array = np.asarray(values)
    if array.ndim != 2 or array.shape[1] not in (3, 4) or (array.size and array.dtype.kind not in "iu"):
        raise ValueError(
            f"faces: an integer array of shape (m, 4) or (m, 3) is needed (got shape {array.shape}, dtype {array.dtype})"
        )
    array = np.ascontiguousarray(array, dtype=np.int64)
    if array.size and (array.min() < 0 or array.max() >= vertex_count):
        raise ValueError(f"faces: vertex indices must be in [0, {vertex_count}) (got {array.min()} to {array.max()})")
    return array


class Mesh:
    """A polygon mesh whose faces all have 4 vertices (quads) or all 3 (triangles).

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
        Vertex positions, in the space regularize() was asked for (``space=``, the command line's
        --space): by default the world of the input's affine (LPS for a file, as the command
        line writes it; for an array, the space of its ``affine``, or ``origin`` + ``spacing`` ⊙
        (i, j, k)), in physical units; or voxel coordinates (voxel centres at integers).
    faces : numpy.ndarray, (m, 4) or (m, 3) int64
        Vertex indices of each face, counter-clockwise seen from outside (the right-hand normal
        points out of the object).
    face_normals : numpy.ndarray, (m, 3) float64, or None
        One unit vector per face: for a result of dsreg.regularize, the normal field u the
        vertices were aligned with.
    vertex_scalars : dict of str to numpy.ndarray (n,) float64
        Named per-vertex values, e.g. ``"v"``, the feature map of ``normals="at"`` (near 0 on
        sharp edges, 1 elsewhere).
    coordinate_system : str
        "LPS" or "RAS" when the vertices are in a named world space (medical files, arrays given
        with an affine), else "" (voxel coordinates, DGtal files, shapes, plain arrays).
        ``write`` records it where 3D Slicer reads it ("SPACE=LPS"); ``read_mesh`` restores it.
    report : dict
        For a result of dsreg.regularize, the command line's ``--report`` content: counts, grid,
        parameters, solve, energies, per-stage seconds, peak memory. Empty otherwise.
    """

    def __init__(self, vertices, faces, face_normals=None, vertex_scalars=None, report=None, coordinate_system=""):
        self.vertices = _points("vertices", vertices)
        self.faces = _faces(faces, len(self.vertices))
        self.face_normals = None if face_normals is None else _points("face_normals", face_normals, len(self.faces))
        self.vertex_scalars: Dict[str, np.ndarray] = {}
        for name, values in (vertex_scalars or {}).items():
            array = np.ascontiguousarray(values, dtype=np.float64)
            if array.shape != (len(self.vertices),):
                raise ValueError(f"vertex_scalars[{name!r}]: {len(self.vertices)} values are needed (got shape {array.shape})")
            self.vertex_scalars[name] = array
        self.report = dict(report or {})
        if coordinate_system not in ("", "LPS", "RAS"):
            raise ValueError(f"coordinate_system: 'LPS', 'RAS' or '' (got {coordinate_system!r})")
        self.coordinate_system = coordinate_system

    @classmethod
    def _from_arrays(cls, arrays: dict, report=None) -> "Mesh":
        """A Mesh of the C++ module's arrays (taken as they are: already checked)."""
        mesh = cls.__new__(cls)
        mesh.vertices = arrays["vertices"]
        mesh.faces = arrays["faces"]
        normals = arrays["face_normals"]
        mesh.face_normals = normals if len(normals) else None
        mesh.vertex_scalars = dict(arrays["vertex_scalars"])
        mesh.report = dict(report or {})
        mesh.coordinate_system = arrays.get("coordinate_system", "")
        return mesh

    def _arrays(self):
        """(vertices, faces as int32, face normals or (0, 3), scalars) for the C++ module, checked
        again: the attributes may have been replaced since construction."""
        vertices = _points("vertices", self.vertices)
        if len(vertices) >= 2**31:
            raise ValueError(f"vertices: at most 2^31 - 1 are supported (got {len(vertices)})")
        faces = _faces(self.faces, len(vertices)).astype(np.int32)
        normals = np.zeros((0, 3)) if self.face_normals is None else _points("face_normals", self.face_normals, len(faces))
        return vertices, faces, normals, list(self.vertex_scalars.items())

    def triangles(self) -> "Mesh":
        """The mesh with each quad split along its shorter diagonal into two triangles (the
        command line's ``--triangulate``), orientation kept; face normals are repeated for both
        halves. A triangle mesh is returned as it is."""
        mesh = Mesh._from_arrays(_dsreg.triangulate(*self._arrays()), self.report)
        mesh.coordinate_system = self.coordinate_system
        return mesh

    def write(self, path) -> None:
        """Write the mesh to `path`, in the format of its extension (the command line's -o):

        - ``.obj``, ``.off``: vertices and faces (quads stay quads);
        - ``.ply``: binary, with the face normals as nx ny nz and the vertex scalars;
        - ``.stl``: binary triangles (quads split along their shorter diagonal);
        - ``.vtk`` (legacy, binary), ``.vtp`` (VTK XML): 3D Slicer's model formats, quads kept,
          face normals as cell data "u", vertex scalars as point data.

        coordinate_system ("LPS"/"RAS") is recorded as 3D Slicer records it. The file is written under a temporary name and renamed when complete. Raises OSError if
        it cannot be written, ValueError for an unknown extension.
        """
        _dsreg.write_mesh(os.fspath(path), *self._arrays(), self.coordinate_system)

    def __repr__(self) -> str:
        kind = {3: "triangles", 4: "quads"}.get(self.faces.shape[1], "faces")
        return f"<dsreg.Mesh: {len(self.vertices)} vertices, {len(self.faces)} {kind}>"
