#!/usr/bin/env bash
# End-to-end timings of `dsreg regularize` (read, surface, normals, solve, write) with per-stage
# wall time and peak memory taken from the --report JSON, the process's CPU time (user + system,
# all threads, from /usr/bin/time or bash's `times`) and the load average when the case started.
# Prints one Markdown table row per case.
#   bench/end_to_end.sh [DSREG] [SOLVER]     (defaults: build/release/dsreg, the CLI default solver)
#   DSREG_BENCH_LARGE=1   also goursat h = 0.05 (~10^6 surfels)
#   DSREG_BENCH_GROWTH=1  instead: the growth series, goursat h = 0.5 … DSREG_BENCH_MIN_H (default 0.035)
# OMP_WAIT_POLICY=passive: on cores shared with other jobs, spinning OpenMP threads wait for
# descheduled ones (see docs/solvers.md, "Shared cores"); it costs nothing on an idle machine.
set -euo pipefail
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
dsreg=${1:-build/release/dsreg}
solver=${2:-}
data=$(cd "$(dirname "$0")/.." && pwd)/../shared/data
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

field() { grep -o "\"$1\": [0-9-][0-9.e+-]*" "$work/r.json" | head -1 | awk '{print $2}'; }

run_case() {  # run_case NAME ARGS...
    local name=$1; shift
    local load; load=$(cut -d' ' -f1 /proc/loadavg)
    local cpu
    if [[ -x /usr/bin/time ]]; then
        /usr/bin/time -f '%U %S' -o "$work/time" "$dsreg" regularize "$@" ${solver:+--solver "$solver"} \
            -o "$work/out.ply" --report "$work/r.json" -q
        cpu=$(awk '{printf "%.2f", $1 + $2}' "$work/time")
    else
        "$dsreg" regularize "$@" ${solver:+--solver "$solver"} -o "$work/out.ply" --report "$work/r.json" -q
        cpu=n/a
    fi
    printf '| %s | %s | %s | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | **%.2f** | %s | %.0f | %s |\n' "$name" \
        "$(field surfels)" "$(grep -o '"solver": "[a-z_]*"' "$work/r.json" | tail -1 | cut -d'"' -f4)" \
        "$(field iterations)" "$(field read)$(field digitize)" "$(field surface)" "$(field normals)" \
        "$(field assembly)" "$(field solve)" "$(field write)" "$(field total_seconds)" "$cpu" \
        "$(awk -v b="$(field peak_memory_bytes)" 'BEGIN { print b / 1048576 }')" "$load"
}

echo "| case | surfels | solver | iterations | read/digitize s | surface s | normals s | assembly s | solve s | write s | total s (wall) | CPU s | peak MiB | load |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
if [[ ${DSREG_BENCH_GROWTH:-0} == 1 ]]; then
    for h in 0.5 0.25 0.1 0.05 0.035 0.025 0.02 0.015; do
        awk -v h="$h" -v m="${DSREG_BENCH_MIN_H:-0.035}" 'BEGIN { exit !(h >= m) }' || break
        run_case "goursat h=$h" --shape goursat --h "$h"   # II radius 3·h^(1/3) (the shape default)
    done
    exit 0
fi
run_case "goursat h=0.25, II r=7.56 vx" --shape goursat --h 0.25 --radius 1.89
[[ -f $data/bunny-128.vol ]] && run_case "bunny-128.vol, II r=6" "$data/bunny-128.vol" --radius 6
run_case "goursat h=0.1, II r=13.9 vx" --shape goursat --h 0.1 --radius 1.39
[[ ${DSREG_BENCH_LARGE:-0} == 1 ]] && run_case "goursat h=0.05, II r=22 vx" --shape goursat --h 0.05 --radius 1.105
exit 0
