#!/usr/bin/env bash
# The Python package installs as a user installs it (docs/python.md): a fresh virtual environment
# made with Debian's Python and --system-site-packages, then `pip install --no-build-isolation .`
# offline in a snapshot of the source tree. The C++ module is taken from this build tree
# (DSREG_CMAKE_BUILD_DIR: built there by the test build already) instead of a second build of
# the library. Then the installed package must import from outside the source tree and run.
#   pip_install_test.sh SOURCE_DIR BUILD_DIR VENV PYTHON
set -euo pipefail
source_dir=$1 build_dir=$2 venv=$3 python=$4
snapshot=$(mktemp -d)
trap 'rm -rf "$snapshot"' EXIT

tar -C "$source_dir" --exclude='./build*' --exclude=./.git --exclude='*.egg-info' --exclude=__pycache__ -cf - . |
    tar -C "$snapshot" -xf -
rm -rf "$venv"
"$python" -m venv --system-site-packages "$venv"
(cd "$snapshot" && DSREG_CMAKE_BUILD_DIR=$build_dir PIP_NO_CACHE_DIR=1 PIP_NO_INDEX=1 PIP_DISABLE_PIP_VERSION_CHECK=1 \
    "$venv/bin/pip" install --no-build-isolation --quiet .)

cd /
"$venv/bin/python" - <<'PY'
import os, sys
import dsreg
location = os.path.dirname(dsreg.__file__)
assert location.startswith(sys.prefix), f"dsreg imported from {location}, not from the environment {sys.prefix}"
mask, affine = dsreg.digitize("sphere1", 0.25)
mesh = dsreg.regularize(mask, affine=affine)
assert mesh.faces.shape[1] == 4 and len(mesh.faces) == mesh.report["counts"]["surfels"], mesh
print(f"dsreg {dsreg.__version__} installed in {sys.prefix}: {mesh}")
PY
