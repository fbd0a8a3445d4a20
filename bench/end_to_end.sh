#!/usr/bin/env bash
# End-to-end timings of `dsreg regularize` (read, surface, normals, solve, validity, write) with per-stage
# wall time and peak memory taken from the --report JSON, the process's CPU time (user + system,
# all threads, from /usr/bin/time) and the load average when the case started; and, in the same
# run, 3D Slicer's labelmap -> closed surface pipeline on the same volume (bench/slicer_pipeline.py,
# Debian's VTK: python3-vtk9), so that every figure is also a ratio. Prints one Markdown table row
# per case.
#   bench/end_to_end.sh [DSREG] [SOLVER]     (defaults: build/release/dsreg, the CLI default solver)
#   DSREG_BENCH_LARGE=1   also goursat h = 0.05 (~10^6 surfels)
#   DSREG_BENCH_CLAMP=0   without the lobster.vol --clamp case
#   DSREG_BENCH_VOLUMES="lobster"  only these volumes of ../shared/data (default: all five)
#   DSREG_BENCH_GOURSAT=0 without the goursat cases
#   DSREG_BENCH_SPARSE=0  without the small object in a large image (a ball of 60 voxels in 512³)
#   DSREG_BENCH_GROWTH=1  instead: the growth series, goursat h = 0.5 … DSREG_BENCH_MIN_H (default 0.035)
# The real volumes are those of ../shared/data (read-only, never copied); the goursat cases are
# digitized to a .vol first (`dsreg digitize`) so that both pipelines read the same file.
# OMP_WAIT_POLICY=passive: on cores shared with other jobs, spinning OpenMP threads wait for
# descheduled ones (see docs/solvers.md, "Shared cores"); it costs nothing on an idle machine.
set -euo pipefail
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
dsreg=${1:-build/release/dsreg}
solver=${2:-}
here=$(cd "$(dirname "$0")" && pwd)
data=$here/../../shared/data
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
[[ -x /usr/bin/time ]] || { echo "end_to_end.sh: needs /usr/bin/time (Debian package time)" >&2; exit 1; }
slicer=1
/usr/bin/python3 -c "import vtk" 2>/dev/null || { slicer=0; echo "end_to_end.sh: no python3-vtk9: Slicer columns left empty" >&2; }

field() { grep -o "\"$1\": [0-9-][0-9.e+-]*" "$work/r.json" | head -1 | awk '{print $2}'; }

# slicer_case VOLUME [--min A]: sets slicer_wall, slicer_cpu (seconds, whole process).
slicer_case() {
    slicer_wall=; slicer_cpu=
    [[ $slicer == 1 && -n $1 ]] || return 0
    /usr/bin/time -f '%U %S %e' -o "$work/stime" /usr/bin/python3 "$here/slicer_pipeline.py" "$@" -o "$work/s.ply" >/dev/null
    slicer_cpu=$(awk '{printf "%.2f", $1 + $2}' "$work/stime")
    slicer_wall=$(awk '{printf "%.2f", $3}' "$work/stime")
}

ratio() { [[ -n $2 ]] && awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f×", a / b }' || echo "–"; }

run_case() {  # run_case NAME SLICER_INPUT ARGS...   (SLICER_INPUT empty: no Slicer run)
    local name=$1 slicer_input=$2; shift 2
    local load; load=$(cut -d' ' -f1 /proc/loadavg)
    /usr/bin/time -f '%U %S %e' -o "$work/time" "$dsreg" regularize "$@" ${solver:+--solver "$solver"} \
        -o "$work/out.ply" --report "$work/r.json" -q
    local cpu wall
    cpu=$(awk '{printf "%.2f", $1 + $2}' "$work/time")
    wall=$(awk '{printf "%.2f", $3}' "$work/time")
    slicer_case $slicer_input
    local surfels peak
    surfels=$(field surfels); peak=$(field peak_memory_bytes)
    printf '| %s | %s | %s | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | **%s** | %s | %.0f | %.2f | %s | %s | %s | %s | %s |\n' "$name" \
        "$surfels" "$(grep -o '"solver": "[a-z_]*"' "$work/r.json" | tail -1 | cut -d'"' -f4)" \
        "$(field iterations)" "$(field read)$(field digitize)" "$(field surface)" "$(field normals)" \
        "$(field assembly)" "$(field solve)" "$(field validity)" "$(field write)" "$wall" "$cpu" \
        "$(awk -v b="$peak" 'BEGIN { print b / 1048576 }')" "$(awk -v b="$peak" -v s="$surfels" 'BEGIN { print b / 1024 / s }')" \
        "${slicer_wall:-–}" "${slicer_cpu:-–}" "$(ratio "$wall" "$slicer_wall")" "$(ratio "$cpu" "$slicer_cpu")" "$load"
}

goursat_vol() {  # goursat_vol H: a .vol of goursat at step H in $work
    "$dsreg" digitize --shape goursat --h "$1" -o "$work/goursat-$1.vol" >/dev/null
    echo "$work/goursat-$1.vol"
}

echo "| case | surfels | solver | iterations | read s | surface s | normals s | assembly s | solve s | validity s | write s | total s (wall) | CPU s | peak MiB | KiB/surfel | Slicer wall s | Slicer CPU s | wall ratio | CPU ratio | load |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
if [[ ${DSREG_BENCH_GROWTH:-0} == 1 ]]; then
    for h in 0.5 0.25 0.1 0.05 0.035 0.025 0.02 0.015; do
        awk -v h="$h" -v m="${DSREG_BENCH_MIN_H:-0.035}" 'BEGIN { exit !(h >= m) }' || break
        run_case "goursat h=$h" "" --shape goursat --h "$h"   # II radius 3·h^(1/3) (the shape default)
    done
    exit 0
fi
for f in ${DSREG_BENCH_VOLUMES:-cat10 bunny-64 Al.100 bunny-128 lobster}; do
    [[ -f $data/$f.vol ]] && run_case "$f.vol" "$data/$f.vol" "$data/$f.vol"
done
[[ -f $data/lobster.vol && ${DSREG_BENCH_CLAMP:-1} == 1 ]] && run_case "lobster.vol --clamp" "$data/lobster.vol" "$data/lobster.vol" --clamp
if [[ ${DSREG_BENCH_SPARSE:-1} == 1 ]]; then
    # An organ-sized object in a CT-sized image: what scales with the image, not the surface.
    "$dsreg" digitize --shape "x^2+y^2+z^2-9" --box 12.8 --h 0.05 -o "$work/ball-in-512.vol" >/dev/null
    run_case "ball r=60 vx in 512³" "$work/ball-in-512.vol" "$work/ball-in-512.vol"
    rm -f "$work/ball-in-512.vol"
fi
[[ ${DSREG_BENCH_GOURSAT:-1} == 1 ]] || exit 0
g=$(goursat_vol 0.25); run_case "goursat h=0.25 .vol, II r=7.56 vx" "$g" "$g" --radius 7.56
g=$(goursat_vol 0.1); run_case "goursat h=0.1 .vol, II r=13.9 vx" "$g" "$g" --radius 13.9
if [[ ${DSREG_BENCH_LARGE:-0} == 1 ]]; then
    g=$(goursat_vol 0.05); run_case "goursat h=0.05 .vol, II r=22 vx" "$g" "$g" --radius 22.1
fi
exit 0
