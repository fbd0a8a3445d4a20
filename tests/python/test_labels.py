"""Label maps from numpy arrays (multi_label=True, labels=[...]): the same complex, label
surfaces and report as `dsreg regularize FILE --multi-label` on the same data saved as .npy or
NIfTI; any dtype and strides; each label's surface closed and outward; world placement by an
oblique affine; non-integer values refused."""

import json

import nibabel as nib
import numpy as np
import pytest

import dsreg
from test_nifti import AFFINES, signed_volume

SHAPE = (18, 16, 14)
VALUES = (3, 7, 12)  # not compact: the labels keep their values


def sectors(shape=SHAPE, radius=6.5, dtype=np.int16):
    """A ball cut in three sectors around the z axis (values 3, 7, 12) in background 0,
    indexed [i, j, k], Fortran order. The sectors meet along the axis: a junction curve."""
    centre = np.array(shape) / 2 - 0.4
    i, j, k = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
    ball = (i - centre[0]) ** 2 + (j - centre[1]) ** 2 + (k - centre[2]) ** 2 <= radius**2
    angle = np.arctan2(j - centre[1], i - centre[0]) + np.pi
    sector = np.minimum((angle / (2 * np.pi / 3)).astype(int), 2)
    labels = np.zeros(shape, dtype)
    labels[ball] = np.array(VALUES, dtype)[sector[ball]]
    return np.asfortranarray(labels)


def cli_labels(cli, tmp_path, path, *args):
    """The complex, {value: label mesh} and report of `dsreg regularize PATH --multi-label ARGS`."""
    out, report = tmp_path / "cli.ply", tmp_path / "cli.json"
    cli("regularize", path, "--multi-label", *args, "-o", out, "--report", report, "--quiet")
    report = json.loads(report.read_text())
    meshes = {entry["label"]: dsreg.read_mesh(entry["mesh"]) for entry in report["labels"]}
    return dsreg.read_mesh(out), meshes, report


def assert_same_mesh(mesh, expected, atol=0.0):
    np.testing.assert_array_equal(mesh.faces, expected.faces)
    if atol == 0:
        np.testing.assert_array_equal(mesh.vertices, expected.vertices)
    else:
        np.testing.assert_allclose(mesh.vertices, expected.vertices, rtol=0, atol=atol)
    np.testing.assert_allclose(mesh.face_normals, expected.face_normals, rtol=0, atol=1e-6)
    if expected.face_labels is None:
        assert mesh.face_labels is None
    else:
        np.testing.assert_array_equal(mesh.face_labels, expected.face_labels)


def assert_same_labels(result, complex_mesh, label_meshes, atol=0.0):
    assert_same_mesh(result, complex_mesh, atol)
    assert sorted(result.label_meshes) == sorted(label_meshes)
    for value, mesh in label_meshes.items():
        assert_same_mesh(result.label_meshes[value], mesh, atol)


def label_entries(report):
    """The report's per-label lines without the file names."""
    return [{k: v for k, v in entry.items() if k != "mesh"} for entry in report["labels"]]


@pytest.fixture(scope="module")
def npy_run(tmp_path_factory):
    """The label map saved as .npy, and the command line's results on it."""
    folder = tmp_path_factory.mktemp("npy")
    path = folder / "labels.npy"
    np.save(path, sectors())
    return path, folder


def test_array_gives_the_command_lines_complex_and_label_meshes(cli, npy_run):
    path, folder = npy_run
    complex_mesh, label_meshes, report = cli_labels(cli, folder, path)
    assert sorted(label_meshes) == list(VALUES)
    result = dsreg.regularize(sectors(), multi_label=True)
    assert_same_labels(result, complex_mesh, label_meshes)
    assert set(np.unique(result.face_labels)) == {0, *VALUES}
    assert label_entries(result.report) == label_entries(report)
    assert result.report["label_complex"] == report["label_complex"]
    assert result.report["counts"] == report["counts"]
    assert report["validity"]["repair"] and result.report["validity"]["repair"]  # label maps are repaired by default
    for value, mesh in result.label_meshes.items():
        assert mesh.report["label"] == value and mesh.report["faces"] == len(mesh.faces)


@pytest.mark.parametrize(
    "layout",
    ["C order", "transposed view", "every other voxel of a larger array", "reversed axis view", "uint8", "int64",
     "float32", "big-endian uint16"],
)
def test_every_layout_and_dtype_gives_the_same_result(layout):
    labels = sectors()
    expected = dsreg.regularize(labels, multi_label=True)
    if layout == "C order":
        array = np.ascontiguousarray(labels)
    elif layout == "transposed view":
        array = np.ascontiguousarray(labels.transpose(2, 0, 1)).transpose(1, 2, 0)
    elif layout == "every other voxel of a larger array":
        larger = np.full((2 * SHAPE[0], SHAPE[1], 3 * SHAPE[2]), 99, np.int32)
        larger[::2, :, ::3] = labels
        array = larger[::2, :, ::3]
    elif layout == "reversed axis view":
        array = np.flip(np.flip(labels, 1).copy(), 1)
    elif layout == "big-endian uint16":
        array = labels.astype(">u2")
    else:
        array = labels.astype(layout)
    assert layout in ("uint8", "int64", "float32", "big-endian uint16") or not array.flags.f_contiguous
    result = dsreg.regularize(array, multi_label=True)
    assert_same_labels(result, expected, expected.label_meshes)


def edge_face_counts(mesh):
    """How many faces hold each (undirected) edge."""
    quads = mesh.faces
    edges = np.stack([quads, np.roll(quads, -1, axis=1)], axis=-1).reshape(-1, 2)
    _, counts = np.unique(np.sort(edges, axis=1), axis=0, return_counts=True)
    return counts


def test_each_label_mesh_is_closed_outward_and_shares_the_complexs_vertices():
    labels = sectors()
    result = dsreg.regularize(labels, multi_label=True, spacing=(0.8, 1.0, 1.3))
    complex_vertices = {tuple(v) for v in result.vertices}
    for value, mesh in result.label_meshes.items():
        assert np.all(edge_face_counts(mesh) == 2), f"label {value}: an edge not in exactly two faces"
        voxel_volume = np.count_nonzero(labels == value) * 0.8 * 1.0 * 1.3
        volume = signed_volume(mesh)
        assert volume > 0, f"label {value}: faces inward"
        assert abs(volume / voxel_volume - 1) < 0.08, (value, volume, voxel_volume)
        assert volume == pytest.approx(mesh.report["volume"], rel=1e-9)
        assert mesh.report["voxel_volume"] == pytest.approx(voxel_volume, rel=1e-12)
        # The same positions, bit for bit, where the labels touch: rows of the complex.
        assert {tuple(v) for v in mesh.vertices} <= complex_vertices
        # Every face of the complex on this label's boundary is one of its faces.
        on_boundary = np.count_nonzero((result.face_labels == value).any(axis=1))
        assert len(mesh.faces) == on_boundary
    # Each face of the complex separates two different labels.
    assert np.all(result.face_labels[:, 0] != result.face_labels[:, 1])


def test_an_oblique_affine_places_the_labels_as_the_command_line_does_a_nifti(cli, tmp_path):
    affine = AFFINES["oblique"]
    path = tmp_path / "labels.nii.gz"
    nib.save(nib.Nifti1Image(sectors(), affine), path)
    complex_mesh, label_meshes, report = cli_labels(cli, tmp_path, path, "--space", "ras")
    assert complex_mesh.coordinate_system == "RAS"

    # dsreg's reading of the file: the same values and LPS affine, so the same mesh.
    values, lps = dsreg.read_volume(path)
    from_arrays = dsreg.regularize(values, affine=lps, multi_label=True, space="ras")
    assert_same_labels(from_arrays, complex_mesh, label_meshes, atol=1e-10)  # the two routes to the affine differ by round-off; the repair solves carry it
    assert from_arrays.coordinate_system == "RAS"
    for mesh in from_arrays.label_meshes.values():
        assert mesh.coordinate_system == "RAS" and signed_volume(mesh) > 0
    np.testing.assert_allclose(from_arrays.report["space"]["index_to_output"], report["space"]["index_to_output"],
                               atol=1e-12)

    # nibabel's array and RAS affine (its float32 sform: rounded like ITK's reading of it).
    image = nib.load(path)
    from_nibabel = dsreg.regularize(np.asanyarray(image.dataobj), affine=image.affine, affine_space="ras",
                                    multi_label=True)
    assert_same_labels(from_nibabel, complex_mesh, label_meshes, atol=1e-5)


def test_labels_keeps_some_and_the_rest_joins_the_background(cli, npy_run):
    path, folder = npy_run
    complex_mesh, label_meshes, _ = cli_labels(cli, folder, path, "--labels", "3,12")
    result = dsreg.regularize(sectors(), labels=[3, 12])
    assert sorted(result.label_meshes) == [3, 12]
    assert set(np.unique(result.face_labels)) == {0, 3, 12}
    # Equal to round-off: since label maps are repaired, the array and the .npy differ by 1.3e-13
    # (the repair's arithmetic in another order; the faces and labels are the same).
    assert_same_labels(result, complex_mesh, label_meshes, atol=1e-11)
    # The kept labels' voxels are those of a map without label 7.
    without_7 = sectors()
    without_7[without_7 == 7] = 0
    assert_same_labels(result, dsreg.regularize(without_7, multi_label=True), label_meshes, atol=1e-11)


def test_write_keeps_the_face_labels(tmp_path):
    result = dsreg.regularize(sectors(), multi_label=True)
    for extension in ("ply", "vtk", "vtp"):
        path = tmp_path / f"complex.{extension}"
        result.write(path)
        back = dsreg.read_mesh(path)
        np.testing.assert_array_equal(back.face_labels, result.face_labels)
        np.testing.assert_array_equal(back.faces, result.faces)
    triangles = result.triangles()
    np.testing.assert_array_equal(triangles.face_labels, np.repeat(result.face_labels, 2, axis=0))
    assert sorted(triangles.label_meshes) == list(VALUES)
    assert all(mesh.faces.shape[1] == 3 for mesh in triangles.label_meshes.values())
    # triangulate=True (--triangulate) splits the same way in the library.
    run = dsreg.regularize(sectors(), multi_label=True, triangulate=True)
    np.testing.assert_array_equal(run.faces, triangles.faces)
    np.testing.assert_array_equal(run.face_labels, triangles.face_labels)
    for value, mesh in run.label_meshes.items():
        np.testing.assert_array_equal(mesh.faces, triangles.label_meshes[value].faces)
        np.testing.assert_array_equal(mesh.vertices, triangles.label_meshes[value].vertices)


def test_progress_reports_the_label_stage():
    stages = []
    dsreg.regularize(sectors(), multi_label=True, progress=lambda stage, fraction: stages.append(stage))
    assert stages[0] == "read" and "labels" in stages
    assert stages.index("validity") < stages.index("labels")  # the complex is checked and repaired, then measured


def test_a_binary_run_has_no_labels():
    result = dsreg.regularize(sectors() > 0)
    assert result.face_labels is None and result.label_meshes == {}


def test_non_integer_values_are_refused():
    values = sectors().astype(np.float64)
    values[4, 5, 6] = 2.5
    with pytest.raises(ValueError, match=r"mask 18x16x14 float64: value 2\.5 of voxel #\d+ is not an integer"):
        dsreg.regularize(values, multi_label=True)
    values[4, 5, 6] = np.nan
    with pytest.raises(ValueError, match=r"(?i)value nan .*is not an integer"):
        dsreg.regularize(values, multi_label=True)
    with pytest.raises(ValueError, match=r"no voxel has a label"):
        dsreg.regularize(np.zeros(SHAPE, np.uint8), multi_label=True)
