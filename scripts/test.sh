#!/usr/bin/env bash
# Builds dsreg with its tests, the Python module and dsreg-mpi (Release) and runs the whole suite
# through CTest: the Python package's tests included (a pip install into a fresh virtual
# environment), the MPI tests under mpirun --oversubscribe (tests/CMakeLists.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --dev --python --viewer --mpi
cmake -S . -B build/test -DCMAKE_BUILD_TYPE=Release -DDSREG_BUILD_PYTHON=ON -DDSREG_REQUIRE_MPI=ON >/dev/null
cmake --build build/test -j"$(nproc)"
ctest --test-dir build/test --output-on-failure -j"$(nproc)"
