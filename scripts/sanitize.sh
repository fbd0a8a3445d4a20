#!/usr/bin/env bash
# The sanitizer job of CI: builds the library, the tests and the fuzz targets with clang,
# AddressSanitizer + UndefinedBehaviorSanitizer (any report aborts) and -O1, runs the test suite
# under them (minus the few slowest end-to-end tests, see below), then every fuzz target for
# FUZZ_SECONDS (default 60) seconds, two at a time (scripts/fuzz.sh).
#
#   scripts/sanitize.sh                     the whole job
#   scripts/sanitize.sh --configure-only    only configure $BUILD_DIR (used by scripts/fuzz.sh)
#   FUZZ_SECONDS=0 scripts/sanitize.sh      the sanitized tests without fuzzing
#
# Build folder: $BUILD_DIR (default build/sanitize); ccache is used when installed.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD_DIR:-build/sanitize}
scripts/install-deps.sh --fuzz

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# -O1 -g: fast enough to run the suite, precise enough stacks; assertions stay on (no NDEBUG).
cmake -S . -B "$build" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" \
    -DDSREG_SANITIZE=address,undefined -DDSREG_BUILD_FUZZERS=ON -DDSREG_BUILD_BENCHMARKS=OFF -DDSREG_BUILD_TESTS=ON \
    "${launcher[@]}" >/dev/null
[[ ${1:-} == --configure-only ]] && exit 0

start=$SECONDS
cmake --build "$build" -j"$(nproc)" --target dsreg dsreg_tests dsreg_fuzz_replay dsreg_fuzz_seeds dsreg_fuzzers
echo "sanitize: build $((SECONDS - start)) s"

# Under the sanitizers everything runs several times slower: the slowest tests (large solves
# already covered by the Release run) are left out.
start=$SECONDS
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$build" --output-on-failure -j"$(nproc)" --timeout 600 -E "${SANITIZE_EXCLUDE:-^$}"
echo "sanitize: tests $((SECONDS - start)) s"

fuzz_seconds=${FUZZ_SECONDS:-60}
if [[ $fuzz_seconds -gt 0 ]]; then
    start=$SECONDS
    BUILD_DIR=$build SKIP_BUILD=1 JOBS=${FUZZ_JOBS:-2} scripts/fuzz.sh "$fuzz_seconds"
    echo "sanitize: fuzzing $((SECONDS - start)) s"
fi
