#!/bin/bash
# Time and memory of --multi-label against the number of labels (docs/benchmarks.md): random
# blobs packed in a ball (dsreg_bench_labels blobs), each case in its own process; one binary
# ball with as many faces in the same grid (--ball-faces); 3D Slicer's conversion of the same
# label map, segment by segment (bench/slicer_pipeline.py --each-label). Each run reads the
# volume and writes its meshes (dsreg: -o and one file per label). CPU seconds (user + system)
# and peak memory from /usr/bin/time; OMP_NUM_THREADS=1 so that CPU time is not inflated by
# threads waiting for a core on a shared machine.
#
#   bench/labels_bench.sh BUILD_DIR DIMS RADIUS N...      e.g. bench/labels_bench.sh build 256,256,256 100 1 10 30 100 300
set -euo pipefail
build=$1; dims=$2; radius=$3; shift 3
bench="$build/bench/dsreg_bench_labels"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1
IFS=, read -r nx ny nz <<< "$dims"
echo "# $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD) load $(cut -d' ' -f1-3 /proc/loadavg) dims $dims radius $radius"
printf "| labels | faces | junction vertices | dsreg --multi-label CPU s | peak MiB | binary ball: faces | CPU s | peak MiB | Slicer per segment: CPU s | peak MiB |\n"
printf "|---|---|---|---|---|---|---|---|---|---|\n"
for n in "$@"; do
    mkdir -p "$work/meshes"
    /usr/bin/time -f "%U %S %M" -o "$work/time" "$bench" blobs --labels "$n" --dims "$dims" --radius "$radius" \
        --input-file "$work/blobs.raw" --out "$work/meshes" > "$work/labels.json"
    read -r lu ls lm < "$work/time"
    rm -rf "$work/meshes"/*
    faces=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['faces'])" "$work/labels.json")
    /usr/bin/time -f "%U %S %M" -o "$work/time" "$bench" blobs --ball-faces "$faces" --dims "$dims" \
        --out "$work/meshes" > "$work/binary.json"
    read -r bu bs bm < "$work/time"
    rm -rf "$work/meshes"/*
    /usr/bin/time -f "%U %S %M" -o "$work/time" /usr/bin/python3 "$(dirname "$0")/slicer_pipeline.py" "$work/blobs.raw" \
        --raw-dims "$dims" --raw-type uint16 --each-label -o "$work/slicer.ply" --json "$work/slicer.json" > /dev/null
    read -r su ss sm < "$work/time"
    python3 - "$work" "$lu" "$ls" "$lm" "$bu" "$bs" "$bm" "$su" "$ss" "$sm" <<'PY'
import json, sys
work = sys.argv[1]
lu, ls, lm, bu, bs, bm, su, ss, sm = map(float, sys.argv[2:])
labels = json.load(open(f"{work}/labels.json"))
binary = json.load(open(f"{work}/binary.json"))
print(f"| {labels['labels']} | {labels['faces']} | {labels['junction_vertices']} | {lu + ls:.1f} | {lm / 1024:.0f} "
      f"| {binary['faces']} | {bu + bs:.1f} | {bm / 1024:.0f} | {su + ss:.1f} | {sm / 1024:.0f} |")
print("  stages (CPU s): labels " + json.dumps({k: round(v, 2) for k, v in labels.get("cpu", {}).items()})
      + " binary " + json.dumps({k: round(v, 2) for k, v in binary.get("cpu", {}).items()}), file=sys.stderr)
PY
    rm -f "$work"/slicer-*.ply
done
