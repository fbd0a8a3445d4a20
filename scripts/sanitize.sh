#!/usr/bin/env bash
# The sanitizer job of CI: the test suite built with AddressSanitizer + UndefinedBehaviorSanitizer
# (any report aborts) at -O1, then every libFuzzer target for FUZZ_SECONDS (default 60) seconds,
# two at a time (scripts/fuzz.sh; clang, ASan + UBSan too). See docs/fuzzing.md.
#
#   scripts/sanitize.sh                       the whole job
#   scripts/sanitize.sh --configure-fuzz DIR  only configure the fuzz build in DIR (for scripts/fuzz.sh)
#   FUZZ_SECONDS=0 scripts/sanitize.sh        the sanitized tests without fuzzing
#   SANITIZE_EXCLUDE=REGEX                    tests to leave out (CTest -E); default: the solver
#                                             accuracy tests (Solvers.*, ClampedRegularization.ReDigitizes*),
#                                             4/5 of the suite's time, about solvers, not inputs, and
#                                             the browser test of the HTML pages (viewer_browser: about
#                                             the page's script, needs Chromium), all run by
#                                             scripts/test.sh; SANITIZE_EXCLUDE='^$' runs all
#
# dsreg-mpi is left out (-DDSREG_BUILD_MPI=OFF): this job checks dsreg's handling of inputs, and
# OpenMPI and PETSc are not built with the sanitizers; the block-wise code dsreg-mpi shares with
# dsreg (src/blocks, the streaming mode) is in the sanitized suite, scripts/test.sh runs the MPI tests.
#
# Build folders: $BUILD_DIR (default build/sanitize; the system compiler, gcc on Debian, which
# builds every part of the code base) and $FUZZ_BUILD_DIR (default build/fuzz; clang, only the
# stages the fuzz targets need). ccache is used when installed.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --fuzz
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# -O1 -g: fast enough to run the suite, precise enough stacks; assertions stay on (no NDEBUG).
common=(-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DDSREG_SANITIZE=address,undefined
        -DDSREG_BUILD_BENCHMARKS=OFF -DDSREG_BUILD_MPI=OFF "${launcher[@]}")

if [[ ${1:-} == --configure-fuzz ]]; then
    cmake -S . -B "$2" -DCMAKE_CXX_COMPILER=clang++ "${common[@]}" -DDSREG_BUILD_FUZZERS=ON -DDSREG_BUILD_TESTS=OFF >/dev/null
    exit 0
fi

build=${BUILD_DIR:-build/sanitize}
fuzz_build=${FUZZ_BUILD_DIR:-build/fuzz}
start=$SECONDS
cmake -S . -B "$build" "${common[@]}" -DDSREG_BUILD_TESTS=ON >/dev/null
cmake --build "$build" -j"$(nproc)" --target dsreg dsreg_tests dsreg_fuzz_replay dsreg_fuzz_seeds viewer_test_pages
echo "sanitize: build of the tests $((SECONDS - start)) s"

start=$SECONDS
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS=suppressions=$PWD/fuzz/lsan-suppressions.txt  # third-party leaks only (ITK's niftilib, NrrdIO and TIFF reader; HDF5)
ctest --test-dir "$build" --output-on-failure -j"$(nproc)" --timeout 900 \
    -E "${SANITIZE_EXCLUDE:-^(Solvers\.|ClampedRegularization\.ReDigitizes|viewer_browser$)}"
echo "sanitize: tests $((SECONDS - start)) s"

fuzz_seconds=${FUZZ_SECONDS:-60}
if [[ $fuzz_seconds -gt 0 ]]; then
    start=$SECONDS
    BUILD_DIR=$fuzz_build JOBS=${FUZZ_JOBS:-2} scripts/fuzz.sh "$fuzz_seconds"
    echo "sanitize: fuzz build and fuzzing $((SECONDS - start)) s"
fi
