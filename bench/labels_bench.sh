#!/bin/bash
# Time and memory of --multi-label against the number of labels (docs/benchmarks.md): random
# blobs packed in a ball (dsreg_bench_labels blobs), each case in its own process; one binary
# ball with as many faces in the same grid (--ball-faces); 3D Slicer's conversion of the same
# label map, segment by segment (bench/slicer_pipeline.py --each-label). Each run reads the
# volume and writes its meshes (dsreg: -o and one file per label). In a grid too small for that
# ball, the binary object is a ball with a concentric cavity, a shell a few voxels thick whose
# normals are cheap (small integral-invariant balls): so a thick ball of as many faces is also
# run, in the smallest cubic grid that holds it ("thick ball"). CPU seconds (user + system)
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
printf "| labels | faces | junction vertices | dsreg --multi-label CPU s | peak MiB | binary ball: faces | CPU s | peak MiB | thick ball: grid, faces | CPU s | peak MiB | Slicer per segment: CPU s | peak MiB |\n"
printf "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
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
    # A digital sphere has about 6π r² faces (bench_labels.cpp's ball_values): the grid of a ball of
    # $faces faces, with the 0.48 margin ball_values keeps from the grid's faces.
    side=$(python3 -c "import math,sys; print(max(int(sys.argv[2]), math.ceil(2 * math.sqrt(int(sys.argv[1]) / (6 * math.pi)) / 0.96) + 2))" "$faces" "$nx")
    /usr/bin/time -f "%U %S %M" -o "$work/time" "$bench" blobs --ball-faces "$faces" --dims "$side,$side,$side" \
        --out "$work/meshes" > "$work/thick.json"
    read -r tu ts tm < "$work/time"
    rm -rf "$work/meshes"/*
    /usr/bin/time -f "%U %S %M" -o "$work/time" /usr/bin/python3 "$(dirname "$0")/slicer_pipeline.py" "$work/blobs.raw" \
        --raw-dims "$dims" --raw-type uint16 --each-label -o "$work/slicer.ply" --json "$work/slicer.json" > /dev/null
    read -r su ss sm < "$work/time"
    python3 - "$work" "$lu" "$ls" "$lm" "$bu" "$bs" "$bm" "$su" "$ss" "$sm" "$tu" "$ts" "$tm" "$side" <<'PY'
import json, sys
work = sys.argv[1]
lu, ls, lm, bu, bs, bm, su, ss, sm, tu, ts, tm = map(float, sys.argv[2:14])
side = int(sys.argv[14])
labels = json.load(open(f"{work}/labels.json"))
binary = json.load(open(f"{work}/binary.json"))
thick = json.load(open(f"{work}/thick.json"))
print(f"| {labels['labels']} | {labels['faces']} | {labels['junction_vertices']} | {lu + ls:.1f} | {lm / 1024:.0f} "
      f"| {binary['faces']} | {bu + bs:.1f} | {bm / 1024:.0f} | {side}³, {thick['faces']} | {tu + ts:.1f} | {tm / 1024:.0f} "
      f"| {su + ss:.1f} | {sm / 1024:.0f} |")
stages = lambda r: json.dumps({k: round(v, 2) for k, v in r.get("cpu", {}).items()})
print(f"  stages (CPU s): labels {stages(labels)} binary {stages(binary)} thick ball {stages(thick)}", file=sys.stderr)
PY
    rm -f "$work"/slicer-*.ply
done
