#!/usr/bin/env bash
# Reading a large NIfTI label map: dsreg (1-byte mask, streaming) against ITK's own reader (the
# whole image in its buffer), in the same run: wall time (hyperfine), CPU time and peak memory
# (/usr/bin/time). Figures in docs/benchmarks.md.
#   bench/medical_read.sh [BUILD_DIR] [N]     default build, 512
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
n=${2:-512}
tool=$build/bench/dsreg_bench_medical_read
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$tool" write "$work/labels.nii.gz" "$n" >/dev/null
"$tool" write "$work/labels.nii" "$n" >/dev/null
echo "load: $(cat /proc/loadavg)"
ls -l "$work"/labels.nii* | awk '{print $5, $9}'
for file in labels.nii.gz labels.nii; do
    for mode in itk dsreg values; do
        /usr/bin/time -f "$file $mode: %e s wall, %U s user, %S s system, %M KiB peak" "$tool" "$mode" "$work/$file" >/dev/null
    done
done
if command -v hyperfine >/dev/null; then
    hyperfine -N --warmup 1 --runs "${RUNS:-5}" "$tool itk $work/labels.nii.gz" "$tool dsreg $work/labels.nii.gz"
fi
