#!/usr/bin/env bash
# The figures of docs/scaling.md: dsreg-mpi on several ranks and the block-wise streaming mode,
# each against the whole-volume CHOLMOD solve of the same goursat digitization. One Markdown row
# per run: peak memory (the largest rank's, from the report), wall and CPU time (all processes,
# /usr/bin/time), iterations, whether the faces are the same in the same order, the largest and
# the root-mean-square vertex distance to the reference (bench/ply_distance.py), the load average.
#   bench/scaling.sh mpi [BUILD]         H (0.1), NPS ("1 2 4"): dsreg-mpi
#   bench/scaling.sh streaming [BUILD]   H (0.1), BLOCK (64), HALOS ("32 64"), SWEEPS ("0"), COARSE ("0"), ALPHA (1e-3)
# Every run has one OpenMP thread (the whole-volume run too). BUILD defaults to build/release.
# Block-wise runs (dsreg-mpi, --block-size) use the fixed-radius normal field and neither the
# thin-part weights nor the shrink correction (plan_block_run): the reference and the whole-volume
# run get the same options (--radius 3·h^(1/3), goursat's default radius, --alpha-reach 0
# --shrink-correction 0), and every run --no-check (the validity repair would differ between runs).
# The streaming rows also give the largest error along the reference's vertex normals and across
# them (bench/ply_distance.py).
# REFERENCE_DIR: keeps the CHOLMOD reference there, reused for the same H and ALPHA (the costliest
# run: 3 GiB at h = 0.1). As root, OpenMPI needs OMPI_ALLOW_RUN_AS_ROOT(_CONFIRM)=1 (set here);
# ranks beyond the cores need --oversubscribe (passed).
set -euo pipefail
mode=${1:?usage: bench/scaling.sh mpi|streaming [BUILD]}
build=${2:-build/release}
here=$(cd "$(dirname "$0")" && pwd)
h=${H:-0.1}
alpha=${ALPHA:-1e-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_WAIT_POLICY=passive

json() { /usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
mib() { awk -v b="$1" 'BEGIN { printf "%.0f", b / 1048576 }'; }

# timed OUTPUT.ply COMMAND...: runs COMMAND -o OUTPUT.ply --report OUTPUT.json -q; wall and CPU in OUTPUT.time
timed() {
    local out=$1; shift
    /usr/bin/time -f '%e %U %S' -o "${out%.ply}.time" "$@" -o "$out" --report "${out%.ply}.json" -q
}
wall() { awk '{printf "%.1f", $1}' "${1%.ply}.time"; }
cpu() { awk '{printf "%.1f", $2 + $3}' "${1%.ply}.time"; }

load=$(cut -d' ' -f1 /proc/loadavg)
echo "# $(date -u '+%F %H:%M UTC'), commit $(git -C "$here" rev-parse --short HEAD), load $load, goursat h=$h alpha=$alpha"
radius=$(awk -v h="$h" 'BEGIN { printf "%.17g", 3 * exp(log(h) / 3) }')
shape=(--shape goursat --h "$h" --alpha "$alpha" --no-check)
whole=(--radius "$radius" --alpha-reach 0 --shrink-correction 0 --noise-fairness 0)
reference=${REFERENCE_DIR:-$work}/reference_fixed_h${h}_alpha$alpha.ply
[[ -s $reference ]] || timed "$reference" "$build/dsreg" regularize "${shape[@]}" "${whole[@]}" --solver cholmod
for suffix in ply json time; do ln -sf "${reference%.ply}.$suffix" "$work/ref.$suffix"; done
ref_faces=$(json "$work/ref.json" "r['counts']['surfels']")
echo "reference (cholmod): $ref_faces surfels, peak $(mib "$(json "$work/ref.json" "r['peak_memory_bytes']")") MiB," \
     "$(wall "$work/ref.ply") s wall, $(cpu "$work/ref.ply") s CPU"
# The whole-volume run the others are measured against: the default solver, one thread.
export OMP_NUM_THREADS=1
timed "$work/serial.ply" "$build/dsreg" regularize "${shape[@]}" "${whole[@]}"
serial_peak=$(json "$work/serial.json" "r['peak_memory_bytes']")
ratio() { awk -v a="$1" -v b="$serial_peak" 'BEGIN { printf "%.2f", a / b }'; }

case $mode in
mpi)
    echo "| run | largest peak MiB | / serial | wall s | CPU s | iterations | same faces | max error voxel | rms voxel | load |"
    echo "|---|---|---|---|---|---|---|---|---|---|"
    row() {  # row NAME OUTPUT.ply PEAK
        local name=$1 out=$2 peak=$3
        read -r same max rms _ < <("$here/ply_distance.py" "$work/ref.ply" "$out" "$h")
        printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$(mib "$peak")" \
            "$(ratio "$peak")" "$(wall "$out")" "$(cpu "$out")" \
            "$(json "${out%.ply}.json" "r['solve']['iterations']")" "$same" "$max" "$rms" "$(cut -d' ' -f1 /proc/loadavg)"
    }
    row "dsreg regularize (amg, 1 thread)" "$work/serial.ply" "$serial_peak"
    for np in ${NPS:-1 2 4}; do
        timed "$work/np$np.ply" mpirun --oversubscribe -np "$np" "$build/dsreg-mpi" "${shape[@]}"
        peak=$(json "$work/np$np.json" "max(p['peak_memory_bytes'] for p in r['blocks']['per_rank'])")
        row "dsreg-mpi, $np ranks" "$work/np$np.ply" "$peak"
    done
    ;;
streaming)
    block=${BLOCK:-64}
    echo "| block | halo | sweeps | coarse | peak MiB | / whole | wall s | CPU s | same faces | max error voxel | rms voxel | max along normals | max across | reported bound voxel | load |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    read -r same max rms along across < <("$here/ply_distance.py" "$work/ref.ply" "$work/serial.ply" "$h")
    echo "| whole volume | | | | $(mib "$serial_peak") | 1.00 | $(wall "$work/serial.ply") | $(cpu "$work/serial.ply") | $same | $max | $rms | $along | $across | | $load |"
    for halo in ${HALOS:-32 64}; do
        for sweeps in ${SWEEPS:-0}; do
            for coarse in ${COARSE:-0}; do
                out=$work/b${halo}_${sweeps}_$coarse.ply
                started_load=$(cut -d' ' -f1 /proc/loadavg)
                timed "$out" "$build/dsreg" regularize "${shape[@]}" --block-size "$block" --block-halo "$halo" \
                    --schwarz-sweeps "$sweeps" --coarse-spacing "$coarse" --max-error 1e-7
                read -r same max rms along across < <("$here/ply_distance.py" "$work/ref.ply" "$out" "$h")
                peak=$(json "${out%.ply}.json" "r['peak_memory_bytes']")
                printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %.2e | %s |\n' "$block" "$halo" \
                    "$sweeps" "$coarse" "$(mib "$peak")" "$(ratio "$peak")" "$(wall "$out")" "$(cpu "$out")" "$same" "$max" \
                    "$rms" "$along" "$across" "$(json "${out%.ply}.json" "r['blocks']['error_bound_voxels']")" "$started_load"
            done
        done
    done
    ;;
*) echo "bench/scaling.sh: unknown mode '$mode' (mpi or streaming)" >&2; exit 1 ;;
esac
