#!/usr/bin/env bash
# End-to-end timings of `dsreg regularize` (read, surface, normals, solve, write) with per-stage
# wall time and peak memory taken from the --report JSON. Prints one Markdown table row per case.
#   bench/end_to_end.sh [DSREG] [SOLVER]     (defaults: build/release/dsreg, the CLI default solver)
set -euo pipefail
dsreg=${1:-build/release/dsreg}
solver=${2:-}
data=$(cd "$(dirname "$0")/.." && pwd)/../shared/data
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

field() { grep -o "\"$1\": [0-9][0-9.e+-]*" "$work/r.json" | head -1 | awk '{print $2}'; }

run_case() {  # run_case NAME ARGS...
    local name=$1; shift
    "$dsreg" regularize "$@" ${solver:+--solver "$solver"} -o "$work/out.ply" --report "$work/r.json" -q
    printf '| %s | %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.0f |\n' "$name" "$(field surfels)" \
        "$(grep -o '"solver": "[a-z_]*"' "$work/r.json" | cut -d'"' -f4)" \
        "$(field read)$(field digitize)" "$(field surface)" "$(field normals)" "$(field assembly)" "$(field solve)" \
        "$(field total_seconds)" "$(awk -v b="$(field peak_memory_bytes)" 'BEGIN { print b / 1048576 }')"
}

echo "| case | surfels | solver | read/digitize s | surface s | normals s | assembly s | solve s | total s | peak MiB |"
echo "|---|---|---|---|---|---|---|---|---|---|"
run_case "goursat h=0.25, II r=7.56 vx" --shape goursat --h 0.25 --radius 1.89
[[ -f $data/bunny-128.vol ]] && run_case "bunny-128.vol, II r=6" "$data/bunny-128.vol" --radius 6
run_case "goursat h=0.1, II r=13.9 vx" --shape goursat --h 0.1 --radius 1.39
[[ ${DSREG_BENCH_LARGE:-0} == 1 ]] && run_case "goursat h=0.05, II r=22 vx" --shape goursat --h 0.05 --radius 1.105
exit 0
