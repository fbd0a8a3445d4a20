#!/usr/bin/env bash
# Block-wise runs of the medical formats (docs/scaling.md, "Formats by blocks"): an N³ uint8 label
# map (default 256, five nested ellipsoids, spacing 0.7 x 0.7 x 1) written as .h5, .nii, .nii.gz
# and .raw, then for each:
#   * the reads alone: read_volume (the whole mask) against read_volume_box of every B³ block in
#     turn (dsreg_bench_medical_read dsreg / boxes), peak memory and CPU time;
#   * the pipeline: dsreg regularize whole against --block-size B --block-halo H, peak memory (the
#     report's peak_memory_bytes), CPU time, and the surfels (the faces' equality
#     is tested in tests/test_medical_blocks.cpp).
# The header-only read gives the process's own memory (libraries, ITK's factories). One OpenMP
# thread everywhere.
#   bench/medical_blocks.sh [BUILD] [N] [B] [H]     default build/release 256 128 32
set -euo pipefail
build=${1:-build/release}
n=${2:-256}
b=${3:-128}
halo=${4:-32}
tool=$build/bench/dsreg_bench_medical_read
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1 OMP_WAIT_POLICY=passive
json() { /usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
cpu() { awk '{printf "%.1f", $2 + $3}' "$1"; }
peak_kib() { awk '{print $4}' "$1"; }

echo "# $(date -u '+%F %H:%M UTC'), commit $(git rev-parse --short HEAD), load $(cut -d' ' -f1-3 /proc/loadavg), ${n}³ uint8, blocks of $b, halo $halo"
mkdir "$work/h5" "$work/nii" "$work/gz" "$work/raw"
"$tool" write "$work/h5/labels.h5" "$n" >/dev/null
"$tool" write "$work/nii/labels.nii" "$n" >/dev/null
"$tool" write "$work/gz/labels.nii.gz" "$n" >/dev/null
# The .nii's payload (after vox_offset, a float32 at byte 108 of the NIfTI-1 header) is the raw file.
/usr/bin/python3 -c "import struct,sys; d=open(sys.argv[1],'rb').read(); open(sys.argv[2],'wb').write(d[int(struct.unpack('<f', d[108:112])[0]):])" \
    "$work/nii/labels.nii" "$work/raw/labels.raw"
raw_flags=(--raw-dims "$n,$n,$n" --raw-type uint8 --spacing 0.7,0.7,1)

echo "| file | read | peak MiB | CPU s |"
echo "|---|---|---|---|"
for file in h5/labels.h5 nii/labels.nii gz/labels.nii.gz; do
    for mode in dims dsreg boxes; do
        /usr/bin/time -f '%e %U %S %M' -o "$work/t" "$tool" "$mode" "$work/$file" "$b" >"$work/out"
        what="whole (read_volume)"
        [[ $mode == dims ]] && what="header alone (read_volume_dims)"
        [[ $mode == boxes ]] && what="every $b³ box (read_volume_box)"
        echo "| ${file#*/} | $what: $(head -1 "$work/out" | cut -d' ' -f1) | $(( $(peak_kib "$work/t") / 1024 )) | $(cpu "$work/t") |"
    done
done

echo
echo "| file | run | peak MiB | CPU s | surfels |"
echo "|---|---|---|---|---|"
for file in h5/labels.h5 nii/labels.nii gz/labels.nii.gz raw/labels.raw; do
    extra=()
    [[ $file == *.raw ]] && extra=("${raw_flags[@]}")
    for run in whole blocks; do
        flags=()
        [[ $run == blocks ]] && flags=(--block-size "$b" --block-halo "$halo")
        out=$work/$run.ply
        /usr/bin/time -f '%e %U %S %M' -o "$work/t" "$build/dsreg" regularize "$work/$file" "${extra[@]}" "${flags[@]}" \
            --no-check -o "$out" --report "$work/$run.json" -q
        surfels=$(json "$work/$run.json" "r['counts']['surfels']")
        echo "| ${file#*/} | $run | $(( $(json "$work/$run.json" "r['peak_memory_bytes']") / 1048576 )) | $(cpu "$work/t") | $surfels |"
    done
done
