#!/bin/bash
# The validity stage of two dsreg binaries, alternately on each case (docs/benchmarks.md, "A leaner
# repair"): the real volumes of ../shared/data that the solve folds, a noisy goursat (10 % of the
# voxels next to the surface flipped, as in bench/accuracy.py) and the 100-blob label map of
# bench/labels_bench.sh (one OpenMP thread). One Markdown row per run: rounds, the check's and the
# local solves' seconds and the stage's (report), wall, CPU and peak memory (/usr/bin/time), the
# energy after the repair, whether the result is valid, the load average.
#   bench/validity_ab.sh OLD_DSREG NEW_DSREG [BUILD_WITH_BENCHMARKS] [REPEATS]
set -euo pipefail
old=$1; new=$2; build=${3:-$(dirname "$new")}; repeats=${4:-2}
here=$(cd "$(dirname "$0")" && pwd)
data=$here/../../shared/data
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMP_WAIT_POLICY=passive

"$new" digitize --shape goursat --h 0.25 --box 10 -o "$work/noisy-goursat.vol" > /dev/null
/usr/bin/python3 -c "import sys; sys.path.insert(0, sys.argv[1]); import accuracy; accuracy.add_noise(sys.argv[2], 0.1, seed=12)" \
    "$here" "$work/noisy-goursat.vol"
"$build/bench/dsreg_bench_labels" blobs --labels 100 --dims 128,128,128 --radius 50 --input-file "$work/blobs.raw" \
    --out "$work" > /dev/null

row() {  # row NAME BINARY ARGS...
    local name=$1 binary=$2; shift 2
    /usr/bin/time -f "%e %U %S %M" -o "$work/time" "$binary" regularize "$@" -o "$work/out.ply" --report "$work/report.json" -q
    /usr/bin/python3 - "$name" "$binary" "$work" "$(cut -d' ' -f1 /proc/loadavg)" <<'PY'
import json, sys
name, binary, work, load = sys.argv[1:]
wall, user, system, peak = open(f"{work}/time").read().split()
r = json.load(open(f"{work}/report.json"))
v = r["validity"]
print(f"| {name} | {binary} | {v['rounds']} | {v['seconds']['check']:.2f} | {v['seconds']['solve']:.2f} "
      f"| {r['seconds']['validity']:.2f} | {float(wall):.2f} | {float(user) + float(system):.2f} | {int(peak) / 1024:.0f} "
      f"| {v['energy_after']['total']:.1f} | {v['after']['valid']} | {load} |")
PY
}

echo "# $(date -u '+%F %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "| case | binary | rounds | check s | local solves s | validity stage s | run wall s | run CPU s | peak MiB | E after | valid | load |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for ((k = 0; k < repeats; ++k)); do
    for file in lobster.vol bunny-64.vol Al.100.vol bunny-128.vol; do
        [[ -f $data/$file ]] || continue
        for binary in "$old" "$new"; do row "$file" "$binary" "$data/$file"; done
    done
    for binary in "$old" "$new"; do row "noisy goursat h=0.25" "$binary" "$work/noisy-goursat.vol"; done
    for binary in "$old" "$new"; do
        OMP_NUM_THREADS=1 row "100-label blobs (1 thread)" "$binary" "$work/blobs.raw" --raw-dims 128,128,128 \
            --raw-type uint16 --multi-label
    done
done
