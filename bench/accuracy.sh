#!/usr/bin/env bash
# The accuracy suite in one command: builds dsreg (Release, in build/), runs bench/accuracy.py
# (dsreg with its defaults and the 3D Slicer pipeline on every case, see its header) and writes
# the table into docs/accuracy.md; every figure also goes to build/accuracy.json.
#   bench/accuracy.sh [ARGS for bench/accuracy.py, e.g. --cases thin]
# Needs Debian's /usr/bin/python3 with python3-vtk9 and numpy: scripts/install-deps.sh --bench.
# About 10 minutes on the project's 2 cores; one case at a time.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh" --dev --bench
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$root/build" -j2 --target dsreg >/dev/null
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
/usr/bin/python3 "$root/bench/accuracy.py" --dsreg "$root/build/dsreg" --json "$root/build/accuracy.json" \
    --write-docs "$root/docs/accuracy.md" "$@"
echo "table written to docs/accuracy.md, figures to build/accuracy.json"
