#!/usr/bin/python3
"""The accuracy suite: dsreg with its default settings and the 3D Slicer pipeline, side by side.

Every case is a volume file, so both tools see exactly the same voxels: the named shapes at
h = 0.5, 0.25 and 0.1, thin shapes (tubes, shells, plates of 1.5-4 voxels), noisy digitizations
and the real volumes of ../shared/data. For each, `dsreg regularize IN.vol -o OUT.ply` (no option,
or the options given with --dsreg-args) and bench/slicer_pipeline.py, then `dsreg eval`:

  * shapes: mean vertex distance to the true surface (units of h), mean face-normal error
    (degrees), relative volume error, against the implicit shape (--voxel-coordinates);
  * every case: the voxel centres classified like the input (object voxels; voxels next to the
    surface, both sides), self-intersecting triangle pairs (CGAL) and, for dsreg, faces folded
    against its field u (eval --volume IN.vol).

The reference figures are those the issue gives for the DGtal tools (DGtalTools
volSurfaceRegularization / DGtal DigitalSurfaceRegularization, DGtal_REFERENCE below); the target
is each figure of dsreg <= the best of Slicer's (same run) and DGtal's.

  /usr/bin/python3 bench/accuracy.py [--dsreg build/dsreg] [--cases REGEX] [--dsreg-args "..."]
                                     [--write-docs docs/accuracy.md] [--json results.json] [--keep DIR]
                                     [--resume]

With --write-docs the Markdown table replaces the lines between the markers
"<!-- accuracy-suite:begin -->" and "<!-- accuracy-suite:end -->" of that file. Run it with
Debian's /usr/bin/python3 (python3-vtk9, numpy); one case at a time (the machine's cores go to
each tool in turn). bench/accuracy.sh builds dsreg and runs this with the docs table. The JSON file
is rewritten after every case; with --resume the cases already in it are not run again (a run cut
short goes on where it stopped, and runs of a few --cases each add up to one table).
"""
import argparse
import datetime
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DATA = os.path.join(REPO, "..", "shared", "data")

# Rotation (0.8, 0.6, 0; -0.48, 0.64, 0.6; 0.36, -0.48, 0.8): no axis of the shapes below is a grid axis.
CUBE = "(0.8*x+0.6*y)^16+(-0.48*x+0.64*y+0.6*z)^16+(0.36*x-0.48*y+0.8*z)^16-1"


def torus(big, small, tilted=False):
    """Torus of tube radius `small` around a circle of radius `big` (tilted: the circle turned)."""
    planar = "((0.8*x+0.6*y)^2+(-0.48*x+0.64*y+0.6*z)^2)" if tilted else "(x^2+y^2)"
    return f"(x^2+y^2+z^2+{big * big:g}-{small * small:g})^2-{4 * big * big:g}*{planar}"


def plate(thickness):
    """A turned flat plate: superellipse of radius 4 and degree 8 in its plane, |z'| <= thickness/2."""
    z = f"({0.36 * 2 / thickness:.7g}*x-{0.48 * 2 / thickness:.7g}*y+{0.8 * 2 / thickness:.7g}*z)"
    return f"((0.2*x+0.15*y)^2+(-0.12*x+0.16*y+0.15*z)^2)^4+{z}^8-1"


# An ellipsoidal shell 0.5 thick along its axes: between the ellipsoids of semi-axes (3, 2, 1.5)
# and (3.5, 2.5, 2).
SHELL = "(0.1111111*x^2+0.25*y^2+0.4444444*z^2-1)*(0.0816327*x^2+0.16*y^2+0.25*z^2-1)"

# name, shape (named or polynomial), h, box (for polynomials), noise (share of the voxels next to
# the surface flipped), group, what it is.
SHAPE_CASES = [
    *[(f"{s} h={h}", s, h, 10, 0.0, "named", "") for s in ("sphere9", "ellipsoid", "torus", "goursat", "leopold", "rcube")
      for h in (0.5, 0.25, 0.1)],
    ("rotated cube", CUBE, 0.04, 1.8, 0.0, "named", "cube of side 2 (50 voxels), degree 16, turned off the axes"),
    ("thin torus 2.4", torus(3, 0.6), 0.25, 4, 0.0, "thin", "tube radius 2.4 voxels"),
    ("thin tube 1.5", torus(3, 0.375), 0.25, 3.6, 0.0, "thin", "tube radius 1.5 voxels (3 across)"),
    ("tilted tube 2", torus(3, 0.5, tilted=True), 0.25, 4, 0.0, "thin", "tube radius 2 voxels, turned"),
    ("shell 2", SHELL, 0.25, 4, 0.0, "thin", "ellipsoidal shell 2 voxels thick"),
    ("plate 3", plate(0.75), 0.25, 4.5, 0.0, "thin", "turned plate 3 voxels thick"),
    ("plate 2", plate(0.5), 0.25, 4.5, 0.0, "thin", "turned plate 2 voxels thick"),
    ("plate 1.5", plate(0.375), 0.25, 4.5, 0.0, "thin", "turned plate 1.5 voxels thick"),
    ("noisy goursat h=0.25", "goursat", 0.25, 10, 0.1, "noisy", "10 % of the voxels next to the surface flipped"),
    ("noisy sphere9 h=0.5", "sphere9", 0.5, 10, 0.2, "noisy", "20 % flipped"),
    ("noisy thin torus 2.4", torus(3, 0.6), 0.25, 4, 0.05, "noisy", "5 % flipped"),
]
FILE_CASES = [("bunny-64.vol", []), ("bunny-128.vol", []), ("Al.100.vol", []), ("cat10.vol", []), ("lobster.vol", [])]

# The figures the issue gives for the DGtal tools (distance in units of h, normal error in degrees);
# goursat h=0.25: docs/accuracy.md (DGtalTools volSurfaceRegularization).
DGTAL_REFERENCE = {
    "leopold h=0.25": (0.36, 10.6),
    "rotated cube": (0.23, None),
    "sphere9 h=0.25": (0.018, 0.41),
    "goursat h=0.5": (0.113, 2.12),
    "goursat h=0.25": (0.071, 0.65),
    "goursat h=0.1": (0.034, 0.24),
}


def run(command, **kwargs):
    result = subprocess.run(command, capture_output=True, text=True, **kwargs)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)}: exit {result.returncode}\n{result.stderr}")
    return result.stdout


def timed(command):
    """Runs the command; returns its CPU time (user + system of the child, seconds) and wall time."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    run(command)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), wall


def read_vol(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"\n.\n")
    header = dict(line.split(": ", 1) for line in data[:end].decode("ascii").splitlines())
    dims = tuple(int(header[k]) for k in ("X", "Y", "Z"))
    payload = data[end + 3:]
    if header.get("Version") == "3":
        payload = zlib.decompress(payload)
    return np.frombuffer(payload, dtype=np.uint8).reshape(dims[::-1]).copy(), dims  # [z, y, x]


def write_vol(path, values, dims):
    header = (f"Center-X: 0\nCenter-Y: 0\nCenter-Z: 0\nX: {dims[0]}\nY: {dims[1]}\nZ: {dims[2]}\n"
              "Voxel-Size: 1\nAlpha-Color: 0\nVoxel-Endian: 0\nInt-Endian: 0123\nVersion: 3\n.\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii") + zlib.compress(np.ascontiguousarray(values).tobytes()))


def add_noise(path, share, seed):
    """Flips `share` of the voxels next to the surface (6-neighbour of the other kind, the border
    counting as background), with a fixed seed: the same noisy volume on every run."""
    values, dims = read_vol(path)
    inside = np.pad(values > 0, 1)
    next_to_surface = np.zeros_like(inside)
    for axis in range(3):
        for step in (1, -1):
            next_to_surface |= inside != np.roll(inside, step, axis=axis)
    next_to_surface = next_to_surface[1:-1, 1:-1, 1:-1]
    flip = next_to_surface & (np.random.default_rng(seed).random(values.shape) < share)
    write_vol(path, np.where(flip, 1 - (values > 0), values > 0).astype(np.uint8), dims)


def evaluate(dsreg, mesh, volume, shape=None, h=None, box=None, volume_args=()):
    """dsreg eval against the input's voxels (and the shape): one flat dict of figures."""
    figures = {}
    against_volume = json.loads(run([dsreg, "eval", mesh, "--volume", volume, "--json", *volume_args]))
    c, v = against_volume["voxel_classification"], against_volume["validity"]
    figures.update(object_share=c["object_share"], boundary_share=c["boundary_share"],
                   intersecting_pairs=v["intersecting_pairs"] + v["degenerate_triangles"],
                   folded_faces=v["folded_faces"])
    if shape is not None:
        e = json.loads(run([dsreg, "eval", mesh, "--shape", shape, "--h", str(h), "--box", str(box),
                            "--voxel-coordinates", "--json"]))
        figures.update(distance_h=e["vertex_distance_h"]["mean"], distance_h_max=e["vertex_distance_h"]["linf"],
                       normal_deg=e["normal_angle_deg"]["mean"], volume_error=e["relative_volume_error"])
    return figures


def run_case(args, work, name, make_volume, shape=None, h=None, box=None, volume_args=()):
    volume = os.path.join(work, "in.vol")
    make_volume(volume)
    dsreg_mesh, slicer_mesh, report = (os.path.join(work, f) for f in ("dsreg.ply", "slicer.ply", "report.json"))
    dsreg_cpu, dsreg_wall = timed([args.dsreg, "regularize", volume, "-o", dsreg_mesh, "--report", report, "-q",
                                   *volume_args, *args.dsreg_args.split()])
    slicer_cpu, slicer_wall = timed(["/usr/bin/python3", os.path.join(HERE, "slicer_pipeline.py"), volume,
                                     "-o", slicer_mesh, *volume_args])
    with open(report) as f:
        surfels = json.load(f)["counts"]["surfels"]
    result = {"case": name, "surfels": surfels,
              "dsreg": evaluate(args.dsreg, dsreg_mesh, volume, shape, h, box, volume_args),
              "slicer": evaluate(args.dsreg, slicer_mesh, volume, shape, h, box, volume_args)}
    result["dsreg"].update(cpu_seconds=dsreg_cpu, wall_seconds=dsreg_wall)
    result["slicer"].update(cpu_seconds=slicer_cpu, wall_seconds=slicer_wall)
    if args.keep:
        target = os.path.join(args.keep, re.sub(r"[^A-Za-z0-9.=-]+", "_", name))
        shutil.copytree(work, target, dirs_exist_ok=True)
    return result


def cases(args):
    for name, shape, h, box, noise, group, note in SHAPE_CASES:
        def make(path, shape=shape, h=h, box=box, noise=noise):
            run([args.dsreg, "digitize", "--shape", shape, "--h", str(h), "--box", str(box), "-o", path])
            if noise > 0:
                add_noise(path, noise, seed=12)
        yield name, group, note, make, dict(shape=shape, h=h, box=box)
    for file, volume_args in FILE_CASES:
        source = os.path.join(DATA, file)
        if os.path.exists(source):
            yield file, "real", "", lambda path, source=source: shutil.copyfile(source, path), dict(volume_args=volume_args)


def target(result):
    """The figures dsreg must reach: the best of Slicer's and DGtal's (None where not given)."""
    slicer = result["slicer"]
    dgtal = DGTAL_REFERENCE.get(result["case"], (None, None))
    best = {}
    for key, index in (("distance_h", 0), ("normal_deg", 1)):
        values = [v for v in (slicer.get(key), dgtal[index]) if v is not None]
        best[key] = min(values) if values else None
    return best


def verdict(result):
    """'yes' when every figure meets the target, else the figures that miss it."""
    d, best = result["dsreg"], target(result)
    misses = [key for key in ("distance_h", "normal_deg") if best[key] is not None and d[key] > best[key]]
    if d["object_share"] < 0.99:
        misses.append("voxels")
    if d["intersecting_pairs"] > 0 or (d["folded_faces"] or 0) > 0:
        misses.append("valid")
    return "yes" if not misses else "no: " + ", ".join(misses)


def markdown(results, meta):
    def number(value, pattern):
        return "—" if value is None else pattern % value

    tool_seconds = sum(r[t]["wall_seconds"] for r in results for t in ("dsreg", "slicer"))
    lines = [f"Run {meta['date']} on commit {meta['commit']}, dsreg options: `{meta['dsreg_args'] or 'none (defaults)'}`; "
             f"load average {meta['load_before']:.1f} before, {meta['load_after']:.1f} after; "
             f"{tool_seconds:.0f} s of dsreg and Slicer wall time in all. `bench/accuracy.sh` reproduces it.",
             "",
             "Each cell: dsreg / Slicer pipeline (flying edges + windowed sinc). Distance: mean vertex distance to "
             "the true surface in units of h; normal: mean face-normal error; object, boundary: voxel centres "
             "classified like the input among its object voxels, among the voxels next to its surface (both "
             "sides); self-int. / folded: dsreg's self-intersecting triangle pairs (CGAL) / dsreg's faces folded "
             "against u ; Slicer's self-intersecting triangle pairs; target: the "
             "best of Slicer and the DGtal figure (in brackets) where given.",
             "",
             "| case | surfels | distance (h) [DGtal] | normal (°) [DGtal] | object % | boundary % | self-int. / folded | dsreg / Slicer CPU s | meets target |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        d, s = r["dsreg"], r["slicer"]
        dgtal = DGTAL_REFERENCE.get(r["case"], (None, None))
        ref = lambda v, p: "" if v is None else f" [{p % v}]"
        distance = number(d.get("distance_h"), "%.3f") + " / " + number(s.get("distance_h"), "%.3f") + ref(dgtal[0], "%.3g")
        normal = number(d.get("normal_deg"), "%.2f") + " / " + number(s.get("normal_deg"), "%.2f") + ref(dgtal[1], "%.3g")
        if "distance_h" not in d:
            distance = normal = "—"
        lines.append(f"| {r['case']} | {r['surfels']} | {distance} | {normal} | "
                     f"{100 * d['object_share']:.2f} / {100 * s['object_share']:.2f} | "
                     f"{100 * d['boundary_share']:.2f} / {100 * s['boundary_share']:.2f} | "
                     f"{d['intersecting_pairs']} / {d['folded_faces']} ; {s['intersecting_pairs']} | "
                     f"{d['cpu_seconds']:.2f} / {s['cpu_seconds']:.2f} | {verdict(r)} |")
    met = sum(verdict(r) == "yes" for r in results)
    lines += ["", f"{met} of {len(results)} cases meet every target."]
    return "\n".join(lines) + "\n"


def write_json(path, meta, results):
    with open(path + ".tmp", "w") as f:
        json.dump({"meta": meta, "results": results}, f, indent=1)
    os.replace(path + ".tmp", path)


def write_docs(path, table):
    with open(path) as f:
        text = f.read()
    begin, end = "<!-- accuracy-suite:begin -->", "<!-- accuracy-suite:end -->"
    if begin not in text or end not in text:
        sys.exit(f"{path}: no {begin} … {end} markers")
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    with open(path + ".tmp", "w") as f:
        f.write(head + begin + "\n" + table + end + tail)
    os.replace(path + ".tmp", path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dsreg", default=os.path.join(REPO, "build", "dsreg"))
    parser.add_argument("--cases", default=".", help="regular expression on the case names")
    parser.add_argument("--dsreg-args", default="", help="options for dsreg regularize (default: none)")
    parser.add_argument("--write-docs", help="replace the table between the markers of this Markdown file")
    parser.add_argument("--json", help="write every figure here")
    parser.add_argument("--keep", help="copy each case's volume and meshes into this folder")
    parser.add_argument("--resume", action="store_true", help="keep the cases already in the --json file")
    args = parser.parse_args()
    if args.resume and not args.json:
        parser.error("--resume needs --json")

    start = time.perf_counter()
    meta = {"date": datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M UTC"),
            "commit": run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"]).strip(),
            "dsreg_args": args.dsreg_args, "load_before": os.getloadavg()[0]}
    done, done_meta = {}, None
    if args.resume and os.path.exists(args.json):
        with open(args.json) as f:
            stored = json.load(f)
        done, done_meta = {r["case"]: r for r in stored["results"]}, stored["meta"]
    results = []
    for name, group, note, make, where in cases(args):
        if name in done:
            results.append(done[name])
            continue
        if not re.search(args.cases, name):
            continue
        with tempfile.TemporaryDirectory() as work:
            result = run_case(args, work, name, make, **where)
        result.update(group=group, note=note)
        results.append(result)
        d, s = result["dsreg"], result["slicer"]
        print(f"{name:24s} dsreg {d.get('distance_h', float('nan')):.3f}h {d.get('normal_deg', float('nan')):6.2f}° "
              f"obj {100 * d['object_share']:6.2f}% bnd {100 * d['boundary_share']:6.2f}% si {d['intersecting_pairs']} "
              f"fold {d['folded_faces']} | slicer {s.get('distance_h', float('nan')):.3f}h "
              f"{s.get('normal_deg', float('nan')):6.2f}° obj {100 * s['object_share']:6.2f}% si {s['intersecting_pairs']}"
              f" | {verdict(result)}", flush=True)
        if args.json:  # the cases kept from the file but not reached yet too
            reached = {r["case"] for r in results}
            write_json(args.json, meta, results + [r for r in done.values() if r["case"] not in reached])
    meta.update(seconds=time.perf_counter() - start, load_after=os.getloadavg()[0])
    if done_meta and all(r["case"] in done for r in results):
        meta = done_meta  # nothing run now: the table is the stored run's
    if args.json:
        write_json(args.json, meta, results)
    table = markdown(results, meta)
    if args.write_docs:
        write_docs(args.write_docs, table)
    else:
        print(table)


if __name__ == "__main__":
    main()
