#!/usr/bin/env bash
# End-to-end checks of dsreg-mpi under mpirun (2 ranks) and of the block-wise streaming mode of
# dsreg regularize: the same mesh as dsreg regularize, in the same order; per-block fragments
# and their manifest; errors reach every rank (exit 1, the message printed once, no output).
: "${DSREG_SERIAL:?set DSREG_SERIAL to the dsreg executable}"
: "${DSREG_MPI:?set DSREG_MPI to the dsreg-mpi executable}"
: "${MPIEXEC:?set MPIEXEC to mpirun}"
launcher=$(mktemp -d)
DSREG="$launcher/dsreg-mpi-2"  # what expect_error runs: dsreg-mpi on 2 ranks
printf '#!/bin/sh\nexec "%s" --oversubscribe -np 2 "%s" "$@"\n' "$MPIEXEC" "$DSREG_MPI" >"$DSREG"
chmod +x "$DSREG"
OUTPUTS='out*'
source "$(dirname "$0")/cli_harness.sh"
trap 'rm -rf "$work" "$launcher"' EXIT

vertices() { grep '^v ' "$1"; }
faces() { grep '^f ' "$1"; }
# Largest coordinate difference between the vertices of two OBJ files with the same vertex order.
max_difference() {
    paste -d ' ' <(vertices "$1") <(vertices "$2") |
        awk '{for (i = 2; i <= 4; ++i) {d = $i - $(i + 4); if (d < 0) d = -d; if (d > m) m = d}} END {printf "%.3g\n", m + 0}'
}
below() { awk -v a="$1" -v b="$2" 'BEGIN {exit !(a < b)}'; }

# Block-wise runs have a fixed radius and none of the thin-part weights, the noise fairness and
# the shrink correction (plan_block_run): the serial runs they are compared with get the same options.
blockwise="--radius 2.5 --alpha-reach 0 --shrink-correction 0 --noise-fairness 0"
# dsreg-mpi writes the mesh dsreg regularize writes (same faces, vertices within 1e-6 voxel).
"$DSREG_SERIAL" regularize --shape goursat --h 0.5 $blockwise --solver cholmod -o "$work/serial.obj" -q
log=$("$DSREG" --shape goursat --h 0.5 --radius 2.5 --max-error 1e-7 -o "$work/mpi.obj" --report "$work/mpi.json" \
      --fragments "$work/fragments" -v 2>&1)
check "dsreg-mpi exits 0" test $? -eq 0
check "same faces, same order" cmp -s <(faces "$work/serial.obj") <(faces "$work/mpi.obj")
check "same vertex count" test "$(vertices "$work/serial.obj" | wc -l)" -eq "$(vertices "$work/mpi.obj" | wc -l)"
difference=$(max_difference "$work/serial.obj" "$work/mpi.obj")
check "vertices within 1e-6 voxel ($difference)" below "$difference" 5e-7
check "one summary line, from rank 0" test "$(grep -c '2 ranks, largest rank peak' <<<"$log")" -eq 1
check "stage lines once" test "$(grep -c '^dsreg-mpi: normals' <<<"$log")" -eq 1
check "report names the ranks" grep -q '"ranks": 2' "$work/mpi.json"
check "report has per-rank peaks" grep -q '"peak_memory_bytes"' "$work/mpi.json"
check "manifest written" test -s "$work/fragments/manifest.json"
check "one fragment per block" test "$(ls "$work/fragments"/block-*.ply | wc -l)" -eq 2
fragment_faces=$(grep -o '"faces": [0-9]*' "$work/fragments/manifest.json" | awk '{s += $2} END {print s}')
check "fragments hold every face once" test "$fragment_faces" -eq "$(faces "$work/serial.obj" | wc -l)"

# Errors: on every rank alike, printed once.
expect_error "missing input" "nothing.vol" "$work/nothing.vol" -o "$work/out.obj"
check "error printed once" test "$("$DSREG" "$work/nothing.vol" -o "$work/out.obj" 2>&1 | grep -c 'dsreg-mpi: error')" -eq 1
expect_error "AT normals refused" "--normals at" --shape sphere9 --h 1 --normals at -o "$work/out.obj"
expect_error "clamp refused" "--clamp" --shape sphere9 --h 1 --clamp -o "$work/out.obj"
expect_error "streaming refused" "--block-size" --shape sphere9 --h 1 --block-size 8 -o "$work/out.obj"
expect_error "dsreg-mpi refuses --labels" "--labels" --shape sphere9 --h 1 --labels 1 -o "$work/out.obj"
expect_error "max-memory refused" "--max-memory" --shape sphere9 --h 1 --max-memory 4G -o "$work/out.obj"
expect_error "thin-part weights refused" "--alpha-reach" --shape sphere9 --h 1 --alpha-reach 12 -o "$work/out.obj"
expect_error "noise fairness refused" "--noise-fairness" --shape sphere9 --h 1 --noise-fairness 12 -o "$work/out.obj"
expect_error "bad flag" "--no-such-flag" --shape sphere9 --no-such-flag -o "$work/out.obj"
expect_error "missing output folder" "no/such" --shape sphere9 --h 1 -o "$work/no/such/out.obj"

# dsreg regularize --block-size: the same faces, a report with the bound, fragments.
"$DSREG_SERIAL" regularize --shape goursat --h 0.7 $blockwise --solver cholmod -o "$work/whole.obj" -q
"$DSREG_SERIAL" regularize --shape goursat --h 0.7 --radius 2.5 --block-size 12 --block-halo 6 --schwarz-sweeps 1 \
    -o "$work/streamed.obj" --report "$work/streamed.json" --fragments "$work/streamed" -q
check "streaming exits 0" test $? -eq 0
check "streaming: same faces, same order" cmp -s <(faces "$work/whole.obj") <(faces "$work/streamed.obj")
check "streaming reports its bound" grep -q '"error_bound_voxels"' "$work/streamed.json"
check "streaming fragments" test -s "$work/streamed/manifest.json"
"$DSREG_SERIAL" regularize --shape goursat --h 0.7 --radius 2.5 --block-size 12 --block-halo 6 --coarse-spacing 4 \
    -o "$work/coarse.obj" --report "$work/coarse.json" -q
check "coarse correction: same faces" cmp -s <(faces "$work/whole.obj") <(faces "$work/coarse.obj")
coarse='import json,sys; c=json.load(open(sys.argv[1]))["blocks"]["coarse"]; sys.exit(0 if c["spacing_voxels"] == 4 and c["nodes"] > 0 and c["energy_after"] <= c["energy_before"] else 1)'
check "coarse correction reported, energy down" python3 -c "$coarse" "$work/coarse.json"
# The validity stage on the welded mesh (docs/validity.md): leopold's thin arms fold as solved.
repaired='import json,sys; v=json.load(open(sys.argv[1]))["validity"]; sys.exit(0 if v["repair"] and not v["before"]["valid"] and v["rounds"] > 0 and v["after"]["valid"] else 1)'
"$DSREG" --shape leopold --h 0.5 -o "$work/leo-mpi.obj" --report "$work/leo-mpi.json" -q
check "dsreg-mpi repairs the welded mesh" python3 -c "$repaired" "$work/leo-mpi.json"
"$DSREG_SERIAL" regularize --shape leopold --h 0.5 --block-size 24 --block-halo 12 -o "$work/leo-blocks.obj" \
    --report "$work/leo-blocks.json" -q
check "streaming repairs the welded mesh" python3 -c "$repaired" "$work/leo-blocks.json"
"$DSREG" --shape leopold --h 0.5 --no-check -o "$work/leo-raw.obj" --report "$work/leo-raw.json" -q
check "dsreg-mpi --no-check: no validity" grep -q '"validity": null' "$work/leo-raw.json"
DSREG=$DSREG_SERIAL
expect_error "fragments need blocks" "--fragments" regularize --shape sphere9 --h 1 --fragments "$work/out.d" -o "$work/out.obj"
expect_error "halo needs blocks" "--block-halo" regularize --shape sphere9 --h 1 --block-halo 4 -o "$work/out.obj"
expect_error "block size positive" "--block-size" regularize --shape sphere9 --h 1 --block-size 0 -o "$work/out.obj"
expect_error "coarse spacing not negative" "--coarse-spacing must be zero (off) or positive" regularize --shape sphere9 --h 1 --block-size 8 --coarse-spacing -4 -o "$work/out.obj"
expect_error "coarse spacing needs blocks" "--coarse-spacing only applies with --block-size" regularize --shape sphere9 --h 1 --coarse-spacing 8 -o "$work/out.obj"
expect_error "block size 1 or 3 values" "--block-size" regularize --shape sphere9 --h 1 --block-size 4,4 -o "$work/out.obj"
expect_error "streaming refuses AT" "--normals at" regularize --shape sphere9 --h 1 --block-size 8 --normals at -o "$work/out.obj"
expect_error "streaming refuses label maps" "--multi-label" regularize --shape sphere9 --h 1 --block-size 8 --multi-label -o "$work/out.obj"
expect_error "streaming refuses max-memory" "--max-memory" regularize --shape sphere9 --h 1 --block-size 8 --max-memory 4G -o "$work/out.obj"
finish
