#!/usr/bin/env bash
# Builds dsreg with its tests and the Python module (Release) and runs the whole suite through
# CTest, the Python package's tests included (a pip install into a fresh virtual environment).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --dev --python --viewer
cmake -S . -B build/test -DCMAKE_BUILD_TYPE=Release -DDSREG_BUILD_PYTHON=ON >/dev/null
cmake --build build/test -j"$(nproc)"
ctest --test-dir build/test --output-on-failure -j"$(nproc)"
