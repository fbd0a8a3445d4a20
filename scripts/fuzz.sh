#!/usr/bin/env bash
# Runs every libFuzzer target of fuzz/ for SECONDS each (default 60), JOBS at a time (default 2).
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]
#
# Builds them first (clang, ASan + UBSan + libFuzzer, -O1) in $BUILD_DIR (default build/fuzz),
# unless SKIP_BUILD=1. Each target starts from the seed corpus written by the project's writers
# (dsreg_fuzz_seeds) plus the committed regression corpus fuzz/regressions/<target>/; new
# interesting inputs accumulate in $BUILD_DIR/corpus/<target>/ (kept between runs). A crash,
# leak, sanitizer report or time-out leaves its input in $BUILD_DIR/artifacts/<target>/ and makes
# this script fail: fix the bug, then commit the input to fuzz/regressions/<target>/ so that the
# normal test suite replays it (docs/fuzzing.md).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
[[ $seconds =~ ^[0-9]+$ ]] || { echo "usage: $0 [SECONDS] [TARGET...]" >&2; exit 2; }
build=${BUILD_DIR:-build/fuzz}
jobs=${JOBS:-2}
all_targets=(vol longvol pgm3d nifti nrrd metaimage npy tiff hdf5 dicom vtkimage raw polynomial normals obj off ply stl vtk vtp)
targets=("${@:-${all_targets[@]}}")

if [[ ${SKIP_BUILD:-0} != 1 ]]; then
    scripts/install-deps.sh --fuzz
    start=$SECONDS
    scripts/sanitize.sh --configure-fuzz "$build"
    cmake --build "$build" -j"$(nproc)" --target dsreg_fuzzers dsreg_fuzz_seeds
    echo "fuzz: build $((SECONDS - start)) s"
fi

# Leaks of third-party libraries (fuzz/lsan-suppressions.txt: ITK, HDF5) are suppressed; dsreg's own are findings.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan-suppressions.txt}
rm -rf "$build/seeds"
"$build/fuzz/dsreg_fuzz_seeds" "$build/seeds" >/dev/null

run_one() {  # run_one TARGET: fuzz it, log to $build/logs/TARGET.log; exit status 0 = no finding
    local target=$1
    local corpus=$build/corpus/$target artifacts=$build/artifacts/$target
    mkdir -p "$corpus" "$artifacts" "$build/logs"
    local extra=()
    [[ -d fuzz/regressions/$target ]] && extra+=("fuzz/regressions/$target")
    # -rss_limit_mb: a reader that allocates what a lying header says is a finding, not a slow run.
    # -timeout: one input taking more than 10 s is a finding (a hang).
    ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} \
        "$build/fuzz/dsreg_fuzz_$target" "$corpus" "$build/seeds/$target" "${extra[@]}" \
        -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10 -max_len=16384 \
        -print_final_stats=1 -artifact_prefix="$artifacts/" >"$build/logs/$target.log" 2>&1
}

echo "fuzzing ${#targets[@]} targets for ${seconds} s each, ${jobs} at a time (logs: $build/logs/)"
failed=()
pids=()
names=()
wait_one() {  # waits for the oldest running fuzzer
    local status=0
    wait "${pids[0]}" || status=$?
    local target=${names[0]}
    local runs
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/logs/$target.log" | grep -o '[0-9]*$' || echo "?")
    if [[ $status -eq 0 ]]; then
        echo "  $target: no finding ($runs runs)"
    else
        echo "  $target: FINDING (exit $status), see $build/logs/$target.log and $build/artifacts/$target/"
        grep -m5 -E 'ERROR|runtime error|broken promise|Test unit written' "$build/logs/$target.log" | sed 's/^/      /' || true
        failed+=("$target")
    fi
    pids=("${pids[@]:1}")
    names=("${names[@]:1}")
}
for target in "${targets[@]}"; do
    [[ -x $build/fuzz/dsreg_fuzz_$target ]] || { echo "no fuzz target $target in $build/fuzz" >&2; exit 2; }
    while [[ ${#pids[@]} -ge $jobs ]]; do wait_one; done
    run_one "$target" &
    pids+=($!)
    names+=("$target")
done
while [[ ${#pids[@]} -gt 0 ]]; do wait_one; done

if [[ ${#failed[@]} -gt 0 ]]; then
    echo "fuzzing found problems in: ${failed[*]}" >&2
    exit 1
fi
echo "fuzzing: no finding in ${#targets[@]} targets"
