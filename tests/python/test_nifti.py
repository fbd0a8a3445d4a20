"""NIfTI volumes through nibabel: the mesh comes out in the world frame of img.affine, oblique
and mirrored affines included, outward-oriented, on the object's surface."""

import nibabel as nib
import numpy as np
import pytest

import dsreg


def rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = np.radians(degrees)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


def affine_of(direction, spacing, origin):
    affine = np.eye(4)
    affine[:3, :3] = direction @ np.diag(spacing)
    affine[:3, 3] = origin
    return affine


AFFINES = {
    "axis-aligned": affine_of(np.eye(3), (0.9, 1.1, 1.4), (-12.0, 5.0, 30.0)),
    "oblique": affine_of(rotation((1, 2, 3), 37), (0.9, 1.1, 1.4), (-12.0, 5.0, 30.0)),
    "radiological (mirrored x)": affine_of(np.diag([-1.0, 1.0, 1.0]), (2.0, 2.0, 2.0), (90.0, -126.0, -72.0)),
    "oblique, mirrored": affine_of(rotation((0, 1, 1), -20) @ np.diag([1.0, -1.0, 1.0]), (1.0, 0.8, 1.2), (3.0, 2.0, 1.0)),
}


def world_sphere_mask(affine, shape, center, radius):
    """Voxels whose centre (affine @ (i, j, k, 1)) lies in the ball of `center` and `radius`."""
    i, j, k = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
    centres = np.stack([i, j, k], axis=-1) @ affine[:3, :3].T + affine[:3, 3]
    return np.linalg.norm(centres - center, axis=-1) <= radius


def nifti_round_trip(tmp_path, mask, affine, dtype=np.uint8):
    path = tmp_path / "mask.nii.gz"
    nib.save(nib.Nifti1Image(mask.astype(dtype), affine), path)
    return nib.load(path)


def signed_volume(mesh):
    """Volume enclosed by the mesh (divergence theorem): positive iff faces are counter-clockwise
    seen from outside."""
    t = mesh.triangles()
    a, b, c = (t.vertices[t.faces[:, n]] for n in range(3))
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


@pytest.mark.parametrize("name", list(AFFINES))
def test_sphere_in_world_coordinates(tmp_path, name):
    """A ball defined in world coordinates, saved and loaded with nibabel: the mesh of
    regularize(img.get_fdata(), affine=img.affine, affine_space="ras") lies on that ball's sphere,
    faces outward, in RAS."""
    affine = AFFINES[name]
    shape = (36, 34, 30)
    center = nib.affines.apply_affine(affine, np.array(shape) / 2 - 0.4)
    radius = 11.0
    mask = world_sphere_mask(affine, shape, center, radius)
    img = nifti_round_trip(tmp_path, mask, affine)
    np.testing.assert_allclose(img.affine, affine, atol=1e-5)  # NIfTI stores it in float32

    mesh = dsreg.regularize(img.get_fdata(), affine=img.affine, affine_space="ras")
    assert mesh.coordinate_system == "RAS"
    voxel = np.abs(np.linalg.det(affine[:3, :3])) ** (1 / 3)
    distance = np.abs(np.linalg.norm(mesh.vertices - center, axis=1) - radius)
    assert distance.max() < 0.75 * voxel and distance.mean() < 0.2 * voxel, (distance.max(), distance.mean())
    # Outward: positive enclosed volume, close to the ball's; normals point away from the centre.
    assert signed_volume(mesh) == pytest.approx(4 / 3 * np.pi * radius**3, rel=0.03)
    centroids = mesh.vertices[mesh.faces].mean(axis=1)
    outward = np.einsum("ij,ij->i", mesh.face_normals, centroids - center)
    assert np.mean(outward > 0) > 0.99
    np.testing.assert_allclose(np.linalg.norm(mesh.face_normals, axis=1), 1, rtol=1e-9)
    # The grid holds the placement in LPS, as ITK reads the file.
    direction = np.array(mesh.report["grid"]["direction"])
    lps_to_ras = np.diag([-1.0, -1.0, 1.0])
    np.testing.assert_allclose(lps_to_ras @ direction @ np.diag(mesh.report["grid"]["spacing"]), img.affine[:3, :3], atol=1e-6)


@pytest.mark.parametrize("name", list(AFFINES))
def test_affine_moves_the_grid_frame_mesh(tmp_path, name):
    """regularize(..., affine=A) is the mesh of the grid frame (spacing, origin of A) moved by A's
    directions: world = origin + D (p − origin), faces reversed (a, b, c, d) → (a, d, c, b) when D
    mirrors."""
    affine = AFFINES[name]
    spacing = np.linalg.norm(affine[:3, :3], axis=0)
    direction, origin = affine[:3, :3] / spacing, affine[:3, 3]
    shape = (28, 26, 24)
    mask = world_sphere_mask(np.diag([1.0, 1.0, 1.0, 1.0]), shape, np.array(shape) / 2, 9.5)
    world = dsreg.regularize(mask, affine=affine)
    grid = dsreg.regularize(mask, spacing=spacing, origin=origin)
    np.testing.assert_allclose(world.vertices, (grid.vertices - origin) @ direction.T + origin, rtol=0, atol=1e-9)
    mirrored = np.linalg.det(direction) < 0
    np.testing.assert_array_equal(world.faces, grid.faces[:, [0, 3, 2, 1]] if mirrored else grid.faces)
    np.testing.assert_allclose(world.face_normals, grid.face_normals @ direction.T, atol=1e-9)
    assert signed_volume(world) > 0 and signed_volume(world) == pytest.approx(signed_volume(grid), rel=1e-9)


def test_nifti_dtypes_and_dataobj(tmp_path):
    """A label map stored as int16 and float32 NIfTI: the label chosen with min=/max= from the
    array proxy (no float64 copy of get_fdata) gives the same mesh as the bool mask."""
    affine = AFFINES["oblique"]
    shape = (30, 28, 26)
    labels = np.zeros(shape, np.int16)
    labels[world_sphere_mask(affine, shape, nib.affines.apply_affine(affine, (15, 14, 13)), 8.0)] = 2
    labels[:5] = 1
    reference = dsreg.regularize(labels == 2, affine=affine)
    for dtype in (np.int16, np.float32):
        img = nifti_round_trip(tmp_path, labels, affine, dtype)
        mesh = dsreg.regularize(np.asanyarray(img.dataobj), affine=img.affine, min=2, max=2)
        np.testing.assert_array_equal(mesh.faces, reference.faces)
        np.testing.assert_allclose(mesh.vertices, reference.vertices, atol=1e-5)  # float32 affine of the file


def test_mesh_written_and_read_back(tmp_path):
    affine = AFFINES["oblique, mirrored"]
    mask = world_sphere_mask(affine, (24, 24, 24), nib.affines.apply_affine(affine, (12, 12, 12)), 7.0)
    mesh = dsreg.regularize(nifti_round_trip(tmp_path, mask, affine).get_fdata(), affine=affine)
    for extension in ("ply", "obj", "off"):
        path = tmp_path / f"mesh.{extension}"
        mesh.write(path)
        back = dsreg.read_mesh(path)
        np.testing.assert_array_equal(back.faces, mesh.faces)
        np.testing.assert_allclose(back.vertices, mesh.vertices, rtol=0, atol=1e-12)
    assert signed_volume(dsreg.read_mesh(tmp_path / "mesh.ply")) > 0


@pytest.mark.parametrize("name", list(AFFINES))
def test_digital_surface_is_on_voxel_corners_of_the_world_grid(tmp_path, name):
    """input_mesh= writes the digital surface in the world too: mapped back by the inverse
    affine, its vertices are voxel corners, (i ± 1/2, j ± 1/2, k ± 1/2)."""
    affine = AFFINES[name]
    mask = world_sphere_mask(affine, (20, 22, 24), nib.affines.apply_affine(affine, (10, 11, 12)), 6.5)
    dsreg.regularize(mask, affine=affine, input_mesh=tmp_path / "digital.ply")
    corners = nib.affines.apply_affine(np.linalg.inv(affine), dsreg.read_mesh(tmp_path / "digital.ply").vertices)
    np.testing.assert_allclose(corners - 0.5, np.round(corners - 0.5), atol=1e-9)
