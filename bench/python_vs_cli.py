#!/usr/bin/python3
"""The cost of a dsreg.regularize call against the dsreg command on the same volume.

Each case is run alternately, --repeat times: the command (a whole process: start, read, run,
write the mesh) and the same job from Python in this process (regularize(...) then
Mesh.write(...), the input already in memory for arrays). Prints one Markdown row per case:
median wall time and CPU time (user + system, all threads) of each, their ratio, and the load
average. Run with Debian's Python and the package on the path, e.g.

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

DATA = Path(__file__).resolve().parent.parent.parent / "shared" / "data"


def children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def time_cli(dsreg_cli, args, out):
    wall, cpu = time.perf_counter(), children_cpu()
    subprocess.run([dsreg_cli, "regularize", *map(str, args), "-o", out, "-q"], check=True)
    return time.perf_counter() - wall, children_cpu() - cpu


def time_python(job, out):
    wall, cpu = time.perf_counter(), time.process_time()
    job().write(out)
    return time.perf_counter() - wall, time.process_time() - cpu


def cases(folder: Path):
    """(name, command-line arguments, Python job) of each case."""
    yield ("goursat h=0.25, shape", ["--shape", "goursat", "--h", "0.25", "--radius", "1.89"],
           lambda: dsreg.regularize(None, shape="goursat", h=0.25, radius=1.89))
    bunny = DATA / "bunny-128.vol"
    if bunny.exists():
        yield "bunny-128.vol, file", [bunny, "--radius", "6"], lambda: dsreg.regularize(bunny, radius=6)
        values, affine = dsreg.read_volume(bunny)
        yield ("bunny-128, float32 array", [bunny, "--radius", "6"],
               lambda: dsreg.regularize(values, affine=affine, radius=6))
    mask, affine = dsreg.digitize("goursat", 0.1)
    raw = folder / "goursat-0.1.raw"
    mask.astype(np.uint8).ravel(order="F").tofile(raw)
    yield ("goursat h=0.1, bool array (CLI: .raw)",
           [raw, "--raw-dims", ",".join(map(str, mask.shape)), "--spacing", "0.1,0.1,0.1", "--radius", "1.39"],
           lambda: dsreg.regularize(mask, affine=affine, radius=1.39))
    c_order = np.ascontiguousarray(mask)
    yield ("goursat h=0.1, C-order bool array", [raw, "--raw-dims", ",".join(map(str, mask.shape)),
                                                  "--spacing", "0.1,0.1,0.1", "--radius", "1.39"],
           lambda: dsreg.regularize(c_order, affine=affine, radius=1.39))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dsreg", default="build-release/dsreg", help="the dsreg command to compare with")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY', '(unset)')}, {os.cpu_count()} cores", file=sys.stderr)
    print("| case | CLI wall s | Python wall s | wall ratio | CLI CPU s | Python CPU s | CPU ratio | load |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        out = folder / "out.ply"
        for name, cli_args, job in cases(folder):
            load = os.getloadavg()[0]
            job()  # warm: page cache, first-touch of the allocator
            cli, python = [], []
            for _ in range(args.repeat):
                cli.append(time_cli(args.dsreg, cli_args, out))
                python.append(time_python(job, out))
            cw, cc = (statistics.median(t[n] for t in cli) for n in (0, 1))
            pw, pc = (statistics.median(t[n] for t in python) for n in (0, 1))
            print(f"| {name} | {cw:.3f} | {pw:.3f} | {pw / cw:.2f} | {cc:.2f} | {pc:.2f} | {pc / cc:.2f} | "
                  f"{load:.1f}–{os.getloadavg()[0]:.1f} |", flush=True)


if __name__ == "__main__":
    main()
