"""dsreg.regularize on numpy arrays: every dtype, memory order and stride give the mesh of the
same binary volume; bad input raises ValueError with a message naming the problem."""

import numpy as np
import pytest

import dsreg
from helpers import ellipsoid

MASK = ellipsoid()


@pytest.fixture(scope="module")
def reference():
    """The mesh of the bool, Fortran-ordered mask (the layout dsreg reads as it is)."""
    return dsreg.regularize(MASK)


def assert_same_mesh(mesh, reference):
    np.testing.assert_array_equal(mesh.faces, reference.faces)
    np.testing.assert_array_equal(mesh.vertices, reference.vertices)
    np.testing.assert_array_equal(mesh.face_normals, reference.face_normals)


def test_result_arrays(reference):
    counts = reference.report["counts"]
    assert reference.vertices.shape == (counts["vertices"], 3) and reference.vertices.dtype == np.float64
    assert reference.faces.shape == (counts["surfels"], 4) and reference.faces.dtype == np.int64
    assert reference.face_normals.shape == (counts["surfels"], 3)
    np.testing.assert_allclose(np.linalg.norm(reference.face_normals, axis=1), 1.0, rtol=1e-12)
    assert counts["object_voxels"] == MASK.sum()
    assert reference.report["grid"]["dims"] == list(MASK.shape)


def test_vertices_are_in_index_space_by_default(reference):
    """Without an affine, voxel (i, j, k) is centred at (i, j, k): the vertices lie on the
    ellipsoid the mask digitizes, within a voxel (its level ρ = 1 ± 1/radius)."""
    center, radii = np.array(MASK.shape) / 2 - 0.3, np.array([9.3, 7.1, 6.2])
    rho = np.linalg.norm((reference.vertices - center) / radii, axis=1)
    assert np.max(np.abs(rho - 1) * radii.min()) < 1.0
    assert np.mean(np.abs(rho - 1) * radii.min()) < 0.3


DTYPES = ["bool", "uint8", "int8", "uint16", "int16", "uint32", "int32", "uint64", "int64",
          "float16", "float32", "float64", ">i2", ">u4", ">f4", ">f8", "<f8"]


@pytest.mark.parametrize("dtype", DTYPES)
def test_every_dtype(dtype, reference):
    """Object voxels valued 3 (0.75 for floats), background 0: value > 0 selects the object."""
    value = 0.75 if np.dtype(dtype).kind == "f" else (True if dtype == "bool" else 3)
    values = np.where(MASK, value, 0).astype(dtype)
    assert_same_mesh(dsreg.regularize(values), reference)


@pytest.mark.parametrize("dtype", ["int16", "float32", ">f8", "uint64"])
def test_min_and_max_select_a_label(dtype):
    """min=/max= as the command line's --min/--max: labels 1, 2, 3; the object is label 2."""
    labels = np.zeros(MASK.shape, dtype=dtype)
    labels[MASK] = 2
    labels[:4] = 1
    labels[:, :, -3:] = 3
    only_two = dsreg.regularize(labels == 2)
    assert_same_mesh(dsreg.regularize(labels, min=2, max=2), only_two)
    assert only_two.report["parameters"]["min"] is None
    assert dsreg.regularize(labels, min=2, max=2).report["parameters"]["min"] == 2


def test_negative_values_are_background_by_default():
    values = np.where(MASK, 1.0, -1.0)
    assert_same_mesh(dsreg.regularize(values), dsreg.regularize(MASK))


@pytest.mark.parametrize(
    "layout",
    ["C order", "transposed view", "reversed axis", "every other voxel", "slice of a 4-D array", "broadcast"],
)
def test_any_memory_layout(layout):
    """Each view is read through its strides; the result equals that of a Fortran-ordered copy."""
    big = ellipsoid((30, 26, 22), (12.2, 9.4, 8.3))
    views = {
        "C order": np.ascontiguousarray(big),
        "transposed view": np.ascontiguousarray(big.transpose(1, 0, 2)).transpose(1, 0, 2),
        "reversed axis": big[::-1, :, ::-1],
        "every other voxel": big[::2, 1::2, ::2],
        "slice of a 4-D array": np.stack([big, ~big], axis=1)[:, 0],
        "broadcast": np.broadcast_to(big[:, :, 11:12], big.shape),
    }
    view = views[layout]
    assert not view.flags["F_CONTIGUOUS"]
    assert_same_mesh(dsreg.regularize(view), dsreg.regularize(np.asfortranarray(view)))


def test_nested_lists_are_arrays():
    small = ellipsoid((8, 8, 8), (3.1, 3.1, 3.1))
    assert_same_mesh(dsreg.regularize(small.tolist()), dsreg.regularize(small))


def test_spacing_and_origin_place_the_grid(reference):
    """Voxel (i, j, k) centred at origin + spacing * (i, j, k): the origin translates the mesh
    (up to the solver's tolerance, 5e-5 voxel), an isotropic spacing scales it (with the default
    radius, 5 voxels)."""
    spacing, origin = np.array([0.5, 2.0, 1.25]), np.array([10.0, -3.0, 7.5])
    placed = dsreg.regularize(MASK, spacing=spacing, origin=origin)
    at_zero = dsreg.regularize(MASK, spacing=spacing)
    np.testing.assert_array_equal(placed.faces, at_zero.faces)
    np.testing.assert_allclose(placed.vertices, at_zero.vertices + origin, rtol=0, atol=1e-3)
    assert placed.report["grid"]["spacing"] == spacing.tolist()
    assert placed.report["grid"]["origin"] == origin.tolist()
    iso = dsreg.regularize(MASK, spacing=2.0)
    np.testing.assert_allclose(iso.vertices, 2.0 * reference.vertices, rtol=0, atol=1e-3)


@pytest.mark.parametrize(
    "mask, options, message",
    [
        (np.zeros((5, 6, 7), bool), {}, "mask 5x6x7 bool: the object is empty: no voxel has value > 0; its values range from 0 to 0"),
        (np.full((4, 4, 4), 5, np.int16), {"min": 6}, "no voxel has value >= 6; its values range from 5 to 5"),
        (np.ones((5, 6), bool), {}, "mask: a 3-D array indexed [i, j, k] is needed (got 2-D, shape (5, 6))"),
        (np.ones((5, 6, 7, 2), bool), {}, "got 4-D"),
        (np.ones((0, 6, 7), bool), {}, "every dimension must be positive"),
        (np.ones((4, 4, 4), complex), {}, "dtype complex128 is not supported"),
        (MASK, {"spacing": (1.0, np.nan, 1.0)}, "--spacing: every voxel size must be positive and finite"),
        (MASK, {"spacing": (1.0, -2.0, 1.0)}, "--spacing: every voxel size must be positive and finite"),
        (MASK, {"spacing": (1.0, 2.0)}, "spacing: three values"),
        (MASK, {"origin": (0.0, np.inf, 0.0)}, "origin: every coordinate must be finite"),
        (MASK, {"affine": np.eye(3)}, "affine: a 4 x 4 voxel-to-world matrix is needed"),
        (MASK, {"affine": np.diag([1.0, 1.0, np.nan, 1.0])}, "affine: every entry must be finite"),
        (MASK, {"affine": np.diag([1.0, 0.0, 1.0, 1.0])}, "affine: column 1 is zero"),
        (MASK, {"affine": [[1, 0.5, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}, "affine: the direction cosines are not orthonormal"),
        (MASK, {"affine": np.eye(4), "spacing": 2.0}, "affine gives the spacing and the origin"),
        (MASK, {"radius": -1.0}, "--radius must be positive"),
        (MASK, {"normals": "sobel"}, "--normals: sobel not in {ii,trivial,ctrivial,exact,at}"),
        (MASK, {"normals": "exact"}, "--normals exact needs an implicit --shape"),
        (MASK, {"alpha": 0.0}, "--alpha 0: must be positive"),
        (MASK, {"shape": "goursat"}, "give either an array, a volume file or --shape, not several"),
        (MASK, {"at_alpha": 0.1}, "--at-alpha only applies to --normals at"),
        (MASK, {"connectivity": 8}, "--connectivity: 8 not in {6,26}"),
        (MASK, {"max_voxels": 100}, "exceed the limit of 100"),
    ],
)
def test_bad_input_raises_value_error(mask, options, message):
    with pytest.raises(ValueError) as error:
        dsreg.regularize(mask, **options)
    assert message in str(error.value)


@pytest.mark.parametrize(
    "options, message",
    [
        ({"radious": 3.0}, "unexpected keyword argument 'radious'; did you mean radius="),
        ({"output": "out.ply"}, "Mesh.write(path) writes it"),
        ({"quiet": True}, "progress= receives the stages"),
        ({"clamp": "yes"}, "clamp= takes True or False"),
        ({"radius": True}, "radius= takes a value"),
        ({"raw_dims": (1, 2)}, "raw_dims= takes 3 values"),
        ({"radius": [3.0]}, "radius= takes a number or a string"),
        ({"progress": 3}, "progress= takes a callable"),
    ],
)
def test_bad_keywords_raise_type_error(options, message):
    with pytest.raises(TypeError) as error:
        dsreg.regularize(MASK, **options)
    assert message in str(error.value)


def test_missing_file_raises_os_error(tmp_path):
    with pytest.raises(FileNotFoundError) as error:
        dsreg.regularize(tmp_path / "missing.vol")
    assert "missing.vol: cannot open: no such file" in str(error.value)
    (tmp_path / "folder").mkdir()  # a folder is read as a DICOM series, as on the command line
    with pytest.raises(ValueError, match="no DICOM image series in this folder"):
        dsreg.read_volume(tmp_path / "folder")
    (tmp_path / "x.xyz").write_text("")
    with pytest.raises(ValueError, match="cannot tell the volume format"):
        dsreg.read_volume(tmp_path / "x.xyz")


def test_keep_voxels_puts_every_voxel_centre_back():
    """keep_voxels=True is --keep-voxels: single voxels added on the ellipsoid's extremes (bumps
    the smoothing takes away, leaving their centres outside) come back inside the mesh."""
    mask = MASK.copy()
    for axis in range(3):
        for end in (np.argmax, np.argmin):
            index = list(np.unravel_index(end(np.where(mask, np.indices(mask.shape)[axis], -1 if end is np.argmax else 10**6)), mask.shape))
            index[axis] += 1 if end is np.argmax else -1
            mask[tuple(index)] = True
    result = dsreg.regularize(mask, keep_voxels=True)
    validity = result.report["validity"]
    assert validity["wrong_voxels_before"] > 0, validity
    assert validity["wrong_voxels_after"] == 0 and validity["bounded_vertices"] > 0
    assert validity["after"]["valid"]
    # By default they are counted, and put back only when 1 % of the object's voxels are outside:
    # here 9 of 1 715 object voxels (0.5 %), which are left.
    default = dsreg.regularize(mask).report["validity"]
    assert default["wrong_voxels_before"] == validity["wrong_voxels_before"] and not default["voxels_put_back"]
    assert dsreg.regularize(mask, no_keep_voxels=True).report["validity"]["wrong_voxels_before"] == -1
