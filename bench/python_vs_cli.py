#!/usr/bin/python3
"""The cost of a dsreg.regularize call against the dsreg command on the same volume.

Each case is run alternately, --repeat times: the command (a whole process: start, read, run,
write the mesh), the same job from Python in this process (regularize(...) then Mesh.write(...),
the input already in memory for arrays) and, for the cases with a file, 3D Slicer's conversion
of that file (bench/slicer_pipeline.py, a process too). Prints one Markdown row per case: median
wall time and CPU time (user + system, all threads) of each, the ratios, and the load average.
Run with Debian's Python and the package on the path, e.g.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_vs_cli.py --dsreg build-release/dsreg

OpenMP's wait policy: like the command (which runs itself again with OMP_WAIT_POLICY=passive),
the package loads OpenMP with the passive policy unless OMP_WAIT_POLICY is set; set it to compare
(an empty value gives libgomp's default, spinning).
"""

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import dsreg

BENCH = Path(__file__).resolve().parent
DATA = BENCH.parent.parent / "shared" / "data"


def children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def time_cli(dsreg_cli, args, out):
    wall, cpu = time.perf_counter(), children_cpu()
    subprocess.run([dsreg_cli, "regularize", *map(str, args), "-o", out, "-q"], check=True)
    return time.perf_counter() - wall, children_cpu() - cpu


def time_slicer(args, out):
    wall, cpu = time.perf_counter(), children_cpu()
    subprocess.run([sys.executable, BENCH / "slicer_pipeline.py", *map(str, args), "-o", out], check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - wall, children_cpu() - cpu


def time_python(job, out):
    wall, cpu = time.perf_counter(), time.process_time()
    job().write(out)
    return time.perf_counter() - wall, time.process_time() - cpu


def cases(folder: Path):
    """(name, command-line arguments, Python job, Slicer arguments or None) of each case."""
    yield ("goursat h=0.25, shape", ["--shape", "goursat", "--h", "0.25", "--radius", "1.89"],
           lambda: dsreg.regularize(None, shape="goursat", h=0.25, radius=1.89), None)
    bunny = DATA / "bunny-128.vol"
    if bunny.exists():
        yield "bunny-128.vol, file", [bunny, "--radius", "6"], lambda: dsreg.regularize(bunny, radius=6), [bunny]
        values, affine = dsreg.read_volume(bunny)
        yield ("bunny-128, float32 array", [bunny, "--radius", "6"],
               lambda: dsreg.regularize(values, affine=affine, radius=6), [bunny])
    mask, affine = dsreg.digitize("goursat", 0.1)
    raw = folder / "goursat-0.1.raw"
    mask.astype(np.uint8).ravel(order="F").tofile(raw)
    raw_args = [raw, "--raw-dims", ",".join(map(str, mask.shape)), "--spacing", "0.1,0.1,0.1"]
    yield ("goursat h=0.1, bool array (CLI: .raw)", raw_args + ["--radius", "1.39"],
           lambda: dsreg.regularize(mask, affine=affine, radius=1.39), raw_args)
    c_order = np.ascontiguousarray(mask)
    yield ("goursat h=0.1, C-order bool array", raw_args + ["--radius", "1.39"],
           lambda: dsreg.regularize(c_order, affine=affine, radius=1.39), raw_args)
    # A label map in a NIfTI file with an oblique, mirrored affine (labels 1 and 2), as nibabel writes it.
    import nibabel

    labels = mask.astype(np.int16) * 2
    labels[: mask.shape[0] // 8] += 1
    rotation = np.linalg.qr(np.array([[0.9, -0.3, 0.2], [0.3, 0.95, 0.1], [-0.2, 0.0, 0.98]]))[0]
    oblique = np.eye(4)
    oblique[:3, :3] = rotation @ np.diag([-0.1, 0.1, 0.1])
    oblique[:3, 3] = (12.0, -30.0, 5.0)
    nii = folder / "labels.nii.gz"
    nibabel.save(nibabel.Nifti1Image(labels, oblique), nii)
    nii_values, nii_affine = dsreg.read_volume(nii)
    yield ("goursat h=0.1 label map, oblique .nii.gz: read_volume arrays, --label 2 --space ras",
           [nii, "--label", "2", "--space", "ras", "--radius", "1.39"],
           lambda: dsreg.regularize(nii_values, affine=nii_affine, label=2, space="ras", radius=1.39),
           [nii, "--min", "2", "--max", "2"])
    yield ("same, file path", [nii, "--label", "2", "--space", "ras", "--radius", "1.39"],
           lambda: dsreg.regularize(nii, label=2, space="ras", radius=1.39), None)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dsreg", default="build-release/dsreg", help="the dsreg command to compare with")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--only", default="", help="run only the cases whose name contains this text")
    args = parser.parse_args()
    print(f"OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY', '(unset)')}, {os.cpu_count()} cores", file=sys.stderr)
    print("| case | CLI wall s | Python wall s | wall ratio | CLI CPU s | Python CPU s | CPU ratio | Slicer wall s "
          "| Slicer CPU s | Python / Slicer wall | load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        out = folder / "out.ply"
        for name, cli_args, job, slicer_args in cases(folder):
            if args.only not in name:
                continue
            load = os.getloadavg()[0]
            job()  # warm: page cache, first-touch of the allocator
            cli, python, slicer = [], [], []
            for _ in range(args.repeat):
                cli.append(time_cli(args.dsreg, cli_args, out))
                python.append(time_python(job, out))
                if slicer_args:
                    slicer.append(time_slicer(slicer_args, out))
            cw, cc, pw, pc = (statistics.median(t[n] for t in times) for times in (cli, python) for n in (0, 1))
            row = f"| {name} | {cw:.3f} | {pw:.3f} | {pw / cw:.2f} | {cc:.2f} | {pc:.2f} | {pc / cc:.2f} | "
            if slicer:
                sw, sc = (statistics.median(t[n] for t in slicer) for n in (0, 1))
                row += f"{sw:.3f} | {sc:.2f} | {pw / sw:.2f} | "
            else:
                row += "– | – | – | "
            print(row + f"{load:.1f}–{os.getloadavg()[0]:.1f} |", flush=True)


if __name__ == "__main__":
    main()
