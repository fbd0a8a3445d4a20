#!/usr/bin/env bash
# Reading a large NIfTI label map: dsreg (1-byte mask, streaming) against ITK's own reader (the
# whole image in its buffer), in the same run: CPU time and wall time (perf stat, RUNS runs each,
# interleaved), peak memory (/usr/bin/time). Figures in docs/benchmarks.md.
#   bench/medical_read.sh [BUILD_DIR] [N]     default build, 512
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
n=${2:-512}
runs=${RUNS:-5}
tool=$build/bench/dsreg_bench_medical_read
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Two folders: given labels.nii.gz, ITK's niftilib reads labels.nii instead when both are beside.
mkdir "$work/gz" "$work/plain"
"$tool" write "$work/gz/labels.nii.gz" "$n" >/dev/null
"$tool" write "$work/plain/labels.nii" "$n" >/dev/null
echo "commit $(git rev-parse --short HEAD), $(date -u '+%Y-%m-%d %H:%M UTC'), load: $(cut -d' ' -f1-3 /proc/loadavg)"
ls -l "$work"/*/labels.nii* | awk '{print $5, $9}'
for file in gz/labels.nii.gz plain/labels.nii; do
    for mode in itk dsreg values; do
        peak=$(/usr/bin/time -f "%M" "$tool" "$mode" "$work/$file" 2>&1 >/dev/null | tail -1)
        cpu=$(perf stat -r "$runs" -x, -e task-clock "$tool" "$mode" "$work/$file" 2>&1 >/dev/null | grep task-clock | cut -d, -f1)
        wall=$( { /usr/bin/time -f "%e" "$tool" "$mode" "$work/$file" >/dev/null; } 2>&1 | tail -1)
        echo "$file $mode: CPU $(printf '%.0f' "$cpu") ms (mean of $runs), wall $wall s, peak $((peak / 1024)) MiB"
    done
done
