#!/usr/bin/env bash
# Builds dsreg (Release) and regularizes the built-in goursat shape: no input file needed.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release -DDSREG_BUILD_TESTS=OFF -DDSREG_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build/release --target dsreg -j"$(nproc)"
mkdir -p out
build/release/dsreg regularize --shape goursat --h 0.25 -o out/goursat.obj --input-mesh out/goursat-digital.obj \
    --report out/goursat.json --html out/goursat.html --verbose
echo "Wrote out/goursat.obj (regularized), out/goursat-digital.obj (digital surface), out/goursat.json (report)"
echo "and out/goursat.html (open it in a browser: the result in 3D)."
