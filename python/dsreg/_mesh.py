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


_INNER, _OUTER = "inner_label", "outer_label"  # the face integers of a label complex (the command line's names)


def _face_labels(values, face_count: int) -> np.ndarray:
    array = np.asarray(values)
    if array.shape != (face_count, 2) or (array.size and array.dtype.kind not in "iu"):
        raise ValueError(
            f"face_labels: an integer array of shape ({face_count}, 2) is needed (got shape {array.shape}, dtype {array.dtype})"
        )
    array = np.ascontiguousarray(array, dtype=np.int64)
    if array.size and (array.min() < -(2**31) or array.max() >= 2**31):
        raise ValueError("face_labels: the label values must fit 32-bit integers (the files' face properties)")
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
        parameters, solve, energies, per-stage seconds, peak memory; for a label map also
        ``"labels"`` (per label: faces, area, volume against the voxel volume, components,
        genus) and ``"label_complex"``. Empty otherwise.
    face_labels : numpy.ndarray, (m, 2) int64, or None
        For a label complex (``regularize(..., multi_label=True)`` or ``labels=[...]``, or a
        complex file the command line wrote): the label values (inner_label, outer_label) on
        the two sides of each face, 0 for the background; the face's right-hand normal (and
        its face_normals row) points from the inner label to the outer one. None otherwise.
        ``write`` stores them as the command line does: integer PLY face properties
        inner_label and outer_label, VTK/VTP cell data of those names.
    label_meshes : dict of int to Mesh
        For a label complex returned by regularize: the closed surface of each label (keyed by
        its value, increasing), oriented outward (counter-clockwise seen from outside the
        label), with the complex's vertex positions bit for bit where labels touch (each
        label's vertices are copies of the complex's rows); its face_normals are the complex's,
        flipped where the label is the outer one. What ``dsreg regularize --multi-label -o
        out.ply`` writes to out-<label>.ply. Empty otherwise.
    """

    def __init__(self, vertices, faces, face_normals=None, vertex_scalars=None, report=None, coordinate_system="",
                 face_labels=None):
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
        self.face_labels = None if face_labels is None else _face_labels(face_labels, len(self.faces))
        self.label_meshes: Dict[int, "Mesh"] = {}

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
        integers = arrays.get("face_integers", {})
        mesh.face_labels = None
        if _INNER in integers and _OUTER in integers:
            mesh.face_labels = np.column_stack([integers[_INNER], integers[_OUTER]]).astype(np.int64)
        mesh.label_meshes = {int(value): cls._from_arrays(label) for value, label in arrays.get("label_meshes", [])}
        return mesh

    def _face_integers(self, face_count: int):
        """The face labels as the C++ module's named int32 face integers, checked again."""
        if self.face_labels is None:
            return []
        labels = _face_labels(self.face_labels, face_count)
        return [(_INNER, labels[:, 0].astype(np.int32)), (_OUTER, labels[:, 1].astype(np.int32))]

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
        halves, and so are face_labels; label_meshes are split too. A triangle mesh is returned
        as it is."""
        arrays = self._arrays()
        mesh = Mesh._from_arrays(_dsreg.triangulate(*arrays, self._face_integers(len(arrays[1]))), self.report)
        mesh.coordinate_system = self.coordinate_system
        mesh.label_meshes = {value: label.triangles() for value, label in self.label_meshes.items()}
        return mesh

    def write(self, path) -> None:
        """Write the mesh to `path`, in the format of its extension (the command line's -o):

        - ``.obj``, ``.off``: vertices and faces (quads stay quads);
        - ``.ply``: binary, with the face normals as nx ny nz and the vertex scalars;
        - ``.stl``: binary triangles (quads split along their shorter diagonal);
        - ``.vtk`` (legacy, binary), ``.vtp`` (VTK XML): 3D Slicer's model formats, quads kept,
          face normals as cell data "u", vertex scalars as point data.

        face_labels, if any, are written as the integer face properties (PLY) or cell data
        (VTK, VTP) inner_label and outer_label, as the command line writes a label complex (the
        other formats cannot hold them). coordinate_system ("LPS"/"RAS") is recorded as 3D Slicer records it. The file is written under a temporary name and renamed when complete. Raises OSError if
        it cannot be written, ValueError for an unknown extension.
        """
        arrays = self._arrays()
        _dsreg.write_mesh(os.fspath(path), *arrays, self.coordinate_system, self._face_integers(len(arrays[1])))

    def __repr__(self) -> str:
        kind = {3: "triangles", 4: "quads"}.get(self.faces.shape[1], "faces")
        labels = f", {len(self.label_meshes)} label meshes" if self.label_meshes else ""
        return f"<dsreg.Mesh: {len(self.vertices)} vertices, {len(self.faces)} {kind}{labels}>"
