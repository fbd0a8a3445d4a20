#!/usr/bin/env bash
# What the validity check and repair find, do and cost (docs/validity.md). Each case runs four times:
#   default            (checked and repaired)      -> repaired.obj
#   --no-repair        (the mesh as solved)        -> solved.obj
#   --clamp --triangulate                          -> clamp.stl
#   --triangulate      (default, triangles)        -> tri.stl
# and prints one Markdown row per case: surfels; self-intersecting triangle pairs / faces folded
# against u of the solved mesh and of the repaired one (dsreg's report); the same counts of the
# files as written, read back and checked again by dsreg_bench_mesh_validity (CGAL; STL rounds to
# 32-bit floats); rounds and region of the repair; the share of the run's wall time spent in the
# "validity" stage (check + repair, same run) and its seconds; how far the repair moved the
# vertices (mean over all vertices and max, voxels); for --shape cases the mean vertex distance
# to the true surface (units of h) before -> after; the load average at the start of the case.
# lobster.vol has no --clamp run: the reversible solve of its 264K surfels alone takes longer than
# the rest of the script (box QP, docs/clamped.md).
#   bench/validity.sh [BUILD]   (default: build; needs BUILD/dsreg and BUILD/bench/dsreg_bench_mesh_validity,
#                                configure with -DDSREG_BUILD_BENCHMARKS=ON)
#   DSREG_BENCH_VOLUMES="cat10 bunny-64"   only these volumes of ../shared/data (default: all five)
#   DSREG_BENCH_SHAPES="torus disc"        only these shapes (leopold torus disc rcube; "" for none)
set -euo pipefail
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
dsreg=$build/dsreg
checker=$build/bench/dsreg_bench_mesh_validity
data=$root/../shared/data
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python=/usr/bin/python3

eval_args=()  # set by the caller: the ground truth for `dsreg eval` (empty: none)
run_case() {  # run_case NAME ARGS...
    local name=$1; shift
    local load; load=$(cut -d' ' -f1 /proc/loadavg)
    "$dsreg" regularize "$@" -o "$work/repaired.obj" --report "$work/repaired.json" -q
    "$dsreg" regularize "$@" --no-repair -o "$work/solved.obj" -q
    rm -f "$work/clamp.stl" "$work/clamp.json"
    [[ $name == lobster.vol ]] || "$dsreg" regularize "$@" --clamp --triangulate -o "$work/clamp.stl" --report "$work/clamp.json" -q
    "$dsreg" regularize "$@" --triangulate -o "$work/tri.stl" -q
    "$checker" "$work/repaired.obj" "$work/tri.stl" $([[ -f $work/clamp.stl ]] && echo "$work/clamp.stl") >"$work/files.jsonl"
    if ((${#eval_args[@]})); then
        "$dsreg" eval "$work/solved.obj" "${eval_args[@]}" --json >"$work/eval_solved.json"
        "$dsreg" eval "$work/repaired.obj" "${eval_args[@]}" --json >"$work/eval_repaired.json"
    else
        rm -f "$work"/eval_*.json
    fi
    "$python" - "$work" "$name" "$load" <<'EOF'
import json, os, sys
import numpy as np
work, name, load = sys.argv[1:4]
r = json.load(open(f"{work}/repaired.json"))
v = r["validity"]
files = [json.loads(line) for line in open(f"{work}/files.jsonl")]
def vertices(path):
    return np.array([line.split()[1:4] for line in open(path) if line.startswith("v ")], dtype=float)
# Vertex positions in world units; the voxel side is the smallest spacing of the grid.
voxel = min(r["grid"]["spacing"])
moved = np.linalg.norm(vertices(f"{work}/repaired.obj") - vertices(f"{work}/solved.obj"), axis=1) / voxel
def counts(m): return f"{m['intersecting_pairs']} / {m['folded_faces']}"
def file_counts(f): return f"{f['intersecting_pairs']}" + (f" / {f['folded_faces']}" if f["field"] else "")
distance = "—"
if os.path.exists(f"{work}/eval_solved.json"):
    d = lambda which: json.load(open(f"{work}/eval_{which}.json"))["vertex_distance_h"]["mean"]
    distance = f"{d('solved'):.3f} -> {d('repaired'):.3f}"
clamp = "—"
if os.path.exists(f"{work}/clamp.json"):
    vc = json.load(open(f"{work}/clamp.json"))["validity"]
    clamp = f"{counts(vc['before'])} -> {counts(vc['after'])} · {file_counts(files[2])}"
share = r["seconds"]["validity"] / r["total_seconds"]
print(f"| {name} | {r['counts']['surfels']} | {counts(v['before'])} | {counts(v['after'])} | "
      f"{file_counts(files[0])} · {file_counts(files[1])} | {clamp} | "
      f"{v['rounds']} | {v['region_vertices']} | {100 * share:.0f} % ({r['seconds']['validity']:.2f} of {r['total_seconds']:.2f} s) | "
      f"{moved.mean():.4f} / {moved.max():.2f} | {distance} | {load} |")
EOF
}

echo "| case | surfels | solved: pairs / folded | repaired: pairs / folded | files: repaired.obj · tri.stl pairs | --clamp: solved -> repaired · clamp.stl | rounds | region vertices | validity stage: share of run (s) | vertex moved, mean / max (voxels) | distance to truth (h), solved -> repaired | load |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for f in ${DSREG_BENCH_VOLUMES:-cat10 bunny-64 Al.100 bunny-128 lobster}; do
    [[ -f $data/$f.vol ]] || continue
    run_case "$f.vol" "$data/$f.vol"
done
# Thin shapes (Gauss digitizations, as `dsreg digitize` writes them): leopold's arms, a torus of
# tube radius 0.6 (2.4 voxels), a disc 0.8 thick at its centre (3.2 voxels, thinning to its rim),
# the cube rotated off the axes.
declare -A shapes=([leopold]=leopold [torus]="(x^2+y^2+z^2+16-0.36)^2-64*(x^2+y^2)" [disc]="x^2+y^2+100*z^2-16" [rcube]=rcube)
declare -A names=([leopold]="leopold" [torus]="torus r=0.6" [disc]="disc 0.8 thick" [rcube]="rcube")
for key in ${DSREG_BENCH_SHAPES-leopold torus disc rcube}; do
    eval_args=(--shape "${shapes[$key]}" --h 0.25)
    [[ $key == leopold || $key == rcube ]] || eval_args+=(--box 5)
    run_case "${names[$key]} h=0.25" "${eval_args[@]}"
done
exit 0
