#!/usr/bin/env bash
# Builds dsreg with its tests (Release) and dsreg-mpi, and runs the whole suite through CTest (the
# MPI tests under mpirun --oversubscribe: tests/CMakeLists.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --dev --viewer --mpi
cmake -S . -B build/test -DCMAKE_BUILD_TYPE=Release -DDSREG_REQUIRE_MPI=ON >/dev/null
cmake --build build/test -j"$(nproc)"
ctest --test-dir build/test --output-on-failure -j"$(nproc)"
