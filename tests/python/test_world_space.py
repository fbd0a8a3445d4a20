"""One placement of voxels in the world for the command line and the Python package: a NIfTI
label map written by nibabel with an oblique, mirrored affine gives the same mesh through
`dsreg regularize FILE --space S`, dsreg.regularize(FILE, space=S), the arrays of
dsreg.read_volume(FILE) and nibabel's own array and img.affine, in LPS, RAS and voxel
coordinates."""

import json

import nibabel as nib
import numpy as np
import pytest

import dsreg
from test_nifti import AFFINES, signed_volume, world_sphere_mask

LPS_TO_RAS = np.diag([-1.0, -1.0, 1.0, 1.0])
SHAPE = (26, 24, 22)


@pytest.fixture(scope="module")
def label_map(tmp_path_factory):
    """(path, affine): label 2 a world ball, label 1 a slab, in an int16 NIfTI saved by nibabel."""
    affine = AFFINES["oblique, mirrored"]
    labels = np.zeros(SHAPE, np.int16)
    labels[world_sphere_mask(affine, SHAPE, nib.affines.apply_affine(affine, np.array(SHAPE) / 2 - 0.3), 7.5)] = 2
    labels[:3] = 1
    path = tmp_path_factory.mktemp("nifti") / "labels.nii.gz"
    nib.save(nib.Nifti1Image(labels, affine), path)
    return path, nib.load(path).affine


def cli_run(cli, tmp_path, path, space):
    out, report = tmp_path / f"cli-{space}.vtk", tmp_path / f"cli-{space}.json"
    cli("regularize", path, "--label", "2", "--space", space, "-o", out, "--report", report, "--quiet")
    return dsreg.read_mesh(out), json.loads(report.read_text())


def assert_same_mesh(mesh, expected, atol=1e-9):
    np.testing.assert_array_equal(mesh.faces, expected.faces)
    np.testing.assert_allclose(mesh.vertices, expected.vertices, rtol=0, atol=atol)
    np.testing.assert_allclose(mesh.face_normals, expected.face_normals, atol=1e-6)
    assert mesh.coordinate_system == expected.coordinate_system


def test_read_volume_gives_nibabels_array_and_affine(label_map):
    path, nib_affine = label_map
    values, lps = dsreg.read_volume(path)
    np.testing.assert_array_equal(values, np.asanyarray(nib.load(path).dataobj))
    np.testing.assert_allclose(lps, LPS_TO_RAS @ nib_affine, atol=1e-5)
    _, ras = dsreg.read_volume(path, space="ras")
    np.testing.assert_allclose(ras, nib_affine, atol=1e-5)
    np.testing.assert_allclose(dsreg.read_volume(path, space="voxel")[1], np.eye(4), atol=1e-12)


@pytest.mark.parametrize("space", ["lps", "ras", "voxel"])
def test_file_arrays_and_nibabel_give_the_command_lines_mesh(cli, tmp_path, label_map, space):
    path, nib_affine = label_map
    expected, report = cli_run(cli, tmp_path, path, space)
    assert expected.coordinate_system == {"lps": "LPS", "ras": "RAS", "voxel": ""}[space]
    assert signed_volume(expected) > 0  # counter-clockwise seen from outside in every space

    from_file = dsreg.regularize(path, label=2, space=space)
    assert_same_mesh(from_file, expected)
    assert from_file.report["space"] == report["space"]

    values, lps_affine = dsreg.read_volume(path)
    from_arrays = dsreg.regularize(values, affine=lps_affine, label=2, space=space)
    assert_same_mesh(from_arrays, expected)
    np.testing.assert_allclose(from_arrays.report["space"]["index_to_output"], report["space"]["index_to_output"],
                               atol=1e-12)

    # The index-to-output affine of the report is what read_volume gives for that space.
    np.testing.assert_allclose(dsreg.read_volume(path, space=space)[1], report["space"]["index_to_output"], atol=1e-12)

    # nibabel's array and RAS affine (float32 sform, rounded like ITK's reading of it).
    from_nibabel = dsreg.regularize(np.asanyarray(nib.load(path).dataobj), affine=nib_affine, affine_space="ras",
                                    label=2, space=space)
    assert_same_mesh(from_nibabel, expected, atol=1e-5)  # ~1e-6 relative: the float32 affine only


def test_affine_space_is_the_default_output_space(label_map):
    path, nib_affine = label_map
    data = np.asanyarray(nib.load(path).dataobj)
    ras = dsreg.regularize(data, affine=nib_affine, affine_space="ras", label=2)
    assert ras.coordinate_system == "RAS"
    lps = dsreg.regularize(data, affine=LPS_TO_RAS @ nib_affine, label=2)
    assert lps.coordinate_system == "LPS"
    np.testing.assert_allclose(ras.vertices, lps.vertices * [-1, -1, 1], atol=1e-9)
    with pytest.raises(ValueError, match="affine_space"):
        dsreg.regularize(data, affine=nib_affine, affine_space="voxel", label=2)
