"""The Python package and the command line are one implementation: the same input and options
give the same mesh and report, and every flag of `dsreg regularize` is a keyword option of
dsreg.regularize or deliberately not one."""

import json
import re

import numpy as np
import pytest

import dsreg
from helpers import cli_mesh, ellipsoid, write_raw

MASK = ellipsoid()


def assert_same_as_cli(mesh, cli_result):
    """Same mesh and report as the command line's, up to the rounding of parallel sums (OpenMP
    combines the threads' partial sums in the order they finish: the command line itself varies
    in the 13th digit from run to run)."""
    cli_mesh_, cli_report = cli_result
    np.testing.assert_array_equal(mesh.faces, cli_mesh_.faces)
    np.testing.assert_allclose(mesh.vertices, cli_mesh_.vertices, rtol=0, atol=1e-9)
    np.testing.assert_allclose(mesh.face_normals, cli_mesh_.face_normals, atol=1e-6)  # PLY keeps floats
    for key in ("counts", "parameters", "grid"):
        assert mesh.report[key] == cli_report[key], key
    for key in ("energy_before", "energy_after"):
        assert mesh.report[key] == pytest.approx(cli_report[key], rel=1e-9), key
    assert mesh.report["solve"]["solver"] == cli_report["solve"]["solver"]
    assert mesh.report["solve"]["relative_residual"] == pytest.approx(cli_report["solve"]["relative_residual"], rel=1e-3)


@pytest.mark.parametrize(
    "options, flags",
    [
        ({}, []),
        ({"radius": 3.5, "ii_kernel": "ball"}, ["--radius", "3.5", "--ii-kernel", "ball"]),
        ({"normals": "trivial", "solver": "cholmod", "gamma": 0.1}, ["--normals", "trivial", "--solver", "cholmod", "--gamma", "0.1"]),
        ({"clamp": True, "connectivity": 6}, ["--clamp", "--connectivity", "6"]),
        ({"metric": "area", "ii_extrapolate": True}, ["--metric", "area", "--ii-extrapolate"]),
        ({"normals": "at", "at_eps": "1:0.5"}, ["--normals", "at", "--at-eps", "1:0.5"]),
    ],
)
def test_raw_file_and_array_give_the_command_lines_mesh(cli, tmp_path, options, flags):
    raw = tmp_path / "mask.raw"
    dims = write_raw(raw, MASK)
    expected = cli_mesh(cli, tmp_path, raw, "--raw-dims", dims, *flags)
    assert_same_as_cli(dsreg.regularize(MASK, **options), expected)
    from_file = dsreg.regularize(raw, raw_dims=MASK.shape, **options)
    assert_same_as_cli(from_file, expected)
    assert from_file.report["input"] == str(raw)
    if options.get("normals") == "at":
        assert "v" in from_file.vertex_scalars
        assert from_file.report["at"]["total_rounds"] == expected[1]["at"]["total_rounds"]


def test_spacing_and_value_range_as_on_the_command_line(cli, tmp_path):
    values = np.where(MASK, 40, 7).astype(np.int16)
    values[:3] = 300
    raw = tmp_path / "ct.raw"
    values.ravel(order="F").tofile(raw)
    dims = ",".join(map(str, values.shape))
    expected = cli_mesh(cli, tmp_path, raw, "--raw-dims", dims, "--raw-type", "int16", "--spacing", "0.7,0.7,1.25",
                        "--min", "20", "--max", "100")
    assert_same_as_cli(dsreg.regularize(values, spacing=(0.7, 0.7, 1.25), min=20, max=100), expected)
    assert_same_as_cli(dsreg.regularize(raw, raw_dims=values.shape, raw_type="int16", spacing=(0.7, 0.7, 1.25),
                                        min=20, max=100), expected)


def test_shared_volume_read_by_read_volume(cli, tmp_path, shared_data):
    path = shared_data / "bunny-64.vol"
    values, affine = dsreg.read_volume(path)
    assert values.dtype == np.float32 and values.flags["F_CONTIGUOUS"]
    np.testing.assert_array_equal(affine, np.eye(4))
    expected = cli_mesh(cli, tmp_path, path)
    assert_same_as_cli(dsreg.regularize(values, affine=affine), expected)
    assert_same_as_cli(dsreg.regularize(path), expected)


def test_shape_as_on_the_command_line(cli, tmp_path):
    expected = cli_mesh(cli, tmp_path, "--shape", "goursat", "--h", "0.5", "--normals", "exact")
    mesh = dsreg.regularize(None, shape="goursat", h=0.5, normals="exact")
    assert_same_as_cli(mesh, expected)
    assert mesh.report["input"] == "goursat at h=0.5"


def test_digitize_is_the_command_lines_digitization(cli, tmp_path):
    """digitize + regularize(mask, affine) is the --shape run with the file defaults' radius."""
    mask, affine = dsreg.digitize("goursat", 0.5)
    expected = cli_mesh(cli, tmp_path, "--shape", "goursat", "--h", "0.5", "--radius", "2.5")
    mesh = dsreg.regularize(mask, affine=affine, radius=2.5)
    np.testing.assert_array_equal(mesh.faces, expected[0].faces)
    np.testing.assert_allclose(mesh.vertices, expected[0].vertices, rtol=0, atol=1e-9)
    assert mesh.report["counts"] == expected[1]["counts"]


def test_digitize_is_the_gauss_digitization():
    """Voxel (i, j, k) is inside iff F(affine @ (i, j, k, 1)) <= 0, for F = x² + y² + z² − 4.1."""
    mask, affine = dsreg.digitize("x^2+y^2+z^2-4.1", 0.5, box=3)
    assert mask.dtype == bool and mask.flags["F_CONTIGUOUS"]
    i, j, k = np.meshgrid(*[np.arange(n) for n in mask.shape], indexing="ij")
    centres = np.stack([i, j, k, np.ones_like(i)], axis=-1) @ affine.T
    np.testing.assert_array_equal(mask, (centres[..., :3] ** 2).sum(axis=-1) - 4.1 <= 0)
    np.testing.assert_array_equal(np.diag(affine)[:3], [0.5, 0.5, 0.5])


def test_evaluate_is_dsreg_eval(cli, tmp_path):
    mesh = dsreg.regularize(None, shape="goursat", h=0.5)
    path = tmp_path / "g.ply"
    mesh.write(path)
    expected = json.loads(cli("eval", path, "--shape", "goursat", "--h", "0.5", "--json").stdout)
    report = dsreg.evaluate(mesh, "goursat", 0.5)
    assert report.pop("mesh") is None and expected.pop("mesh") == str(path)
    assert report.keys() == expected.keys()
    for key in report:
        assert report[key] == pytest.approx(expected[key], rel=1e-9), key
    assert dsreg.evaluate(path, "goursat", h=0.5, volume_cells=32)["vertex_distance"] == pytest.approx(expected["vertex_distance"])
    with pytest.raises(ValueError, match="--wall-margin must be non-negative"):
        dsreg.evaluate(mesh, "goursat", wall_margin=-1.0)


def test_evaluate_volume_voxel_coordinates_and_face_errors_are_dsreg_eval(cli, tmp_path):
    """volume=, min=, voxel_coordinates= and face_errors= are the flags of `dsreg eval`: the same
    report and the same CSV, through the library's one evaluation."""
    vol, ply = tmp_path / "g.vol", tmp_path / "g.ply"
    cli("digitize", "--shape", "goursat", "--h", "0.5", "-o", vol)
    cli("regularize", vol, "-o", ply, "-q")  # in the voxel frame of the .vol, with the field u

    expected = json.loads(cli("eval", ply, "--volume", vol, "--min", "1", "--json").stdout)
    report = dsreg.evaluate(ply, volume=vol, min=1)
    assert report.pop("mesh") is None and expected.pop("mesh") == str(ply)
    assert report == expected
    assert report["validity"]["folded_faces"] is not None  # the PLY's face normals are the field
    assert report["voxel_classification"]["boundary_share"] > 0.9

    cli_csv, py_csv = tmp_path / "cli.csv", tmp_path / "py.csv"
    expected = json.loads(
        cli("eval", ply, "--shape", "goursat", "--h", "0.5", "--voxel-coordinates", "--face-errors", cli_csv, "--json").stdout
    )
    report = dsreg.evaluate(ply, "goursat", 0.5, voxel_coordinates=True, face_errors=py_csv)
    assert report["normal_angle_deg"] == pytest.approx(expected["normal_angle_deg"], rel=1e-9)
    assert report["normal_angle_deg"]["mean"] < 10  # mapped to the shape's frame: close to the truth
    assert py_csv.read_text() == cli_csv.read_text()
    rows = np.genfromtxt(py_csv, delimiter=",", names=True)
    assert len(rows) == len(dsreg.read_mesh(ply).faces)
    assert np.nanmean(rows["normal_angle_deg"]) == pytest.approx(report["normal_angle_deg"]["mean"], rel=1e-6)

    with pytest.raises(ValueError, match="--min and --max only apply to --volume"):
        dsreg.evaluate(ply, "goursat", min=1)
    with pytest.raises(ValueError, match="--volume gives the truth as voxels"):
        dsreg.evaluate(ply, "goursat", volume=vol)


def help_flags(cli, command):
    """The long names of the flags `dsreg COMMAND --help` lists."""
    text = cli(command, "--help").stdout
    return set(re.findall(r"^\s+(?:-\w,)?--([a-z][a-z0-9-]*)", text, flags=re.MULTILINE))


def test_every_regularize_flag_is_a_keyword_or_excluded(cli):
    flags = help_flags(cli, "regularize")
    keywords = {k.replace("_", "-") for k in dsreg.regularize_keywords()}
    excluded = set(dsreg.EXCLUDED_REGULARIZE_FLAGS)
    assert not keywords & excluded
    assert flags == keywords | excluded, (
        f"flags of `dsreg regularize` that are neither keywords nor excluded: {sorted(flags - keywords - excluded)}; "
        f"keywords or exclusions that are no flags: {sorted((keywords | excluded) - flags)}"
    )
    for keyword in ("ii_kernel", "radius", "min", "max", "raw_dims", "clamp", "normals", "solver", "max_memory"):
        assert keyword in dsreg.regularize_keywords()
        assert f"{keyword} :" in dsreg.regularize.__doc__  # help(dsreg.regularize) lists it


def test_every_eval_flag_is_a_keyword_or_argument(cli):
    flags = help_flags(cli, "eval")
    keywords = {f.name for f in dsreg._EVALUATION_FLAGS.values() if f.name not in dsreg.EXCLUDED_EVALUATION_FLAGS}
    assert flags == keywords | set(dsreg.EXCLUDED_EVALUATION_FLAGS)


def test_file_options_write_what_the_command_line_writes(cli, tmp_path):
    """report=, input_mesh=, html=, export_normals= write their files as the flags do;
    triangulate=True returns the triangles the command line writes."""
    raw = tmp_path / "mask.raw"
    dims = write_raw(raw, MASK)
    cli("regularize", raw, "--raw-dims", dims, "--triangulate", "-o", tmp_path / "cli.ply",
        "--input-mesh", tmp_path / "cli-digital.obj", "--export-normals", tmp_path / "cli-u.txt", "-q")
    files = {name: tmp_path / f"py.{name}" for name in ("json", "obj", "html", "txt")}
    stages = []
    mesh = dsreg.regularize(MASK, triangulate=True, report=files["json"], input_mesh=files["obj"], html=files["html"],
                            export_normals=files["txt"], progress=lambda stage, fraction: stages.append(stage))
    assert stages[-2:] == ["write", "write"]
    written = json.loads(files["json"].read_text())
    assert written["counts"] == mesh.report["counts"] and written["outputs"]["html"] == str(files["html"])
    assert mesh.report["parameters"]["triangulate"] is True and "write" in mesh.report["seconds"]
    expected = dsreg.read_mesh(tmp_path / "cli.ply")
    np.testing.assert_array_equal(mesh.faces, expected.faces)
    np.testing.assert_allclose(mesh.vertices, expected.vertices, atol=1e-9)
    digital, cli_digital = dsreg.read_mesh(files["obj"]), dsreg.read_mesh(tmp_path / "cli-digital.obj")
    np.testing.assert_array_equal(digital.vertices, cli_digital.vertices)
    assert files["txt"].read_text().splitlines()[1:] == (tmp_path / "cli-u.txt").read_text().splitlines()[1:]
    assert files["html"].read_text().startswith("<!DOCTYPE html>")
    with pytest.raises(ValueError, match="--input-mesh .*unsupported mesh format"):
        dsreg.regularize(MASK, input_mesh=tmp_path / "digital.xyz")
