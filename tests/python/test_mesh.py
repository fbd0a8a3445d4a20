"""dsreg.Mesh: triangles(), write() in every format of the command line, read_mesh(), and
interchange with meshio (Debian's python3-meshio)."""

import copy

import meshio
import numpy as np
import pytest

import dsreg
from helpers import ellipsoid


@pytest.fixture(scope="module")
def mesh():
    return dsreg.regularize(ellipsoid(), normals="at")


def test_triangles_split_along_the_shorter_diagonal(mesh):
    triangles = mesh.triangles()
    assert triangles.faces.shape == (2 * len(mesh.faces), 3)
    np.testing.assert_array_equal(triangles.vertices, mesh.vertices)
    np.testing.assert_array_equal(triangles.face_normals[::2], mesh.face_normals)
    np.testing.assert_array_equal(triangles.face_normals[1::2], mesh.face_normals)
    v = mesh.vertices
    a, b, c, d = (mesh.faces[:, n] for n in range(4))
    ac_shorter = np.linalg.norm(v[a] - v[c], axis=1) <= np.linalg.norm(v[b] - v[d], axis=1)
    first = triangles.faces[::2]
    np.testing.assert_array_equal(first[ac_shorter], np.stack([a, b, c], axis=1)[ac_shorter])
    np.testing.assert_array_equal(first[~ac_shorter], np.stack([a, b, d], axis=1)[~ac_shorter])
    assert triangles.report == mesh.report
    assert triangles.triangles().faces.shape == triangles.faces.shape


@pytest.mark.parametrize("extension", ["obj", "off", "ply", "stl", "vtk", "vtp"])
@pytest.mark.parametrize("coordinate_system", ["", "LPS", "RAS"])
def test_write_and_read_every_format(tmp_path, mesh, extension, coordinate_system):
    path = tmp_path / f"m.{extension}"
    mesh = copy.copy(mesh)  # the module's fixture stays as it is
    mesh.coordinate_system = coordinate_system
    mesh.write(path)
    back = dsreg.read_mesh(str(path))
    assert back.coordinate_system == coordinate_system  # recorded where 3D Slicer reads it
    if extension == "stl":  # triangles, positions merged: same surface area
        assert back.faces.shape[1] == 3 and len(back.faces) == 2 * len(mesh.faces)
        area = lambda m: np.linalg.norm(np.cross(*(m.vertices[m.faces[:, n]] - m.vertices[m.faces[:, 0]] for n in (1, 2))), axis=1).sum() / 2
        assert area(back) == pytest.approx(area(mesh.triangles()), rel=1e-6)
        return
    np.testing.assert_array_equal(back.faces, mesh.faces)
    np.testing.assert_allclose(back.vertices, mesh.vertices, rtol=0, atol=1e-12)
    if extension in ("ply", "vtk", "vtp"):
        np.testing.assert_allclose(back.face_normals, mesh.face_normals, atol=1e-6)
        np.testing.assert_allclose(back.vertex_scalars["v"], mesh.vertex_scalars["v"], atol=1e-6)


def test_write_errors(tmp_path, mesh):
    with pytest.raises(FileNotFoundError):
        mesh.write(tmp_path / "missing-folder" / "m.obj")
    with pytest.raises(ValueError, match="unknown extension"):
        mesh.write(tmp_path / "m.xyz")
    assert not list(tmp_path.iterdir())  # nothing left behind
    with pytest.raises(OSError):
        dsreg.read_mesh(tmp_path / "absent.obj")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(ValueError, match="bad.obj"):
        dsreg.read_mesh(tmp_path / "bad.obj")


def test_constructed_mesh_is_checked():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    mesh = dsreg.Mesh(square, [[0, 1, 2, 3]])
    assert mesh.faces.dtype == np.int64 and mesh.face_normals is None and mesh.report == {}
    with pytest.raises(ValueError, match="vertex indices must be in"):
        dsreg.Mesh(square, [[0, 1, 2, 4]])
    with pytest.raises(ValueError, match="faces: an integer array"):
        dsreg.Mesh(square, [[0, 1, 2, 3, 0]])
    with pytest.raises(ValueError, match=r"vertices: an array of shape \(n, 3\)"):
        dsreg.Mesh(square[:, :2], [[0, 1, 2]])
    with pytest.raises(ValueError, match=r"face_normals: an array of shape \(1, 3\)"):
        dsreg.Mesh(square, [[0, 1, 2, 3]], face_normals=np.zeros((2, 3)))
    with pytest.raises(ValueError, match="vertex_scalars"):
        dsreg.Mesh(square, [[0, 1, 2, 3]], vertex_scalars={"w": [1.0, 2.0]})


@pytest.mark.parametrize("extension", ["obj", "ply", "off", "stl"])
def test_meshio_reads_what_dsreg_writes(tmp_path, mesh, extension):
    """meshio 5 reads OFF triangles only, and no binary PLY whose faces carry properties after
    their vertex list (dsreg's face normals): those are written as triangles / without normals
    (docs/python.md)."""
    written = {"off": mesh.triangles(), "ply": dsreg.Mesh(mesh.vertices, mesh.faces)}.get(extension, mesh)
    path = tmp_path / f"m.{extension}"
    written.write(path)
    other = meshio.read(path)
    if extension == "stl":
        assert sum(len(c.data) for c in other.cells if c.type == "triangle") == 2 * len(mesh.faces)
        return
    np.testing.assert_allclose(other.points, written.vertices, atol=1e-9)
    cell_type = {3: "triangle", 4: "quad"}[written.faces.shape[1]]
    np.testing.assert_array_equal(np.concatenate([c.data for c in other.cells if c.type == cell_type]), written.faces)


@pytest.mark.parametrize("extension", ["obj", "ply", "off", "stl", "vtk"])
def test_dsreg_reads_what_meshio_writes(tmp_path, mesh, extension):
    triangles = mesh.triangles()
    path = tmp_path / f"m.{extension}"
    meshio.write(path, meshio.Mesh(triangles.vertices, [("triangle", triangles.faces)]), **(
        {"binary": False} if extension in ("ply", "stl") else {}))
    if extension == "vtk":  # meshio writes an unstructured grid, not the PolyData of a mesh file: refused clearly
        with pytest.raises(ValueError, match="the dataset is UNSTRUCTURED_GRID, not POLYDATA"):
            dsreg.read_mesh(path)
        return
    back = dsreg.read_mesh(path)
    assert back.faces.shape == triangles.faces.shape
    if extension != "stl":
        np.testing.assert_array_equal(back.faces, triangles.faces)
    tolerance = 1e-6 if extension == "stl" else 1e-9  # STL stores float32
    np.testing.assert_allclose(np.sort(back.vertices, axis=0), np.sort(triangles.vertices, axis=0), atol=tolerance * 50)
