#!/usr/bin/env bash
# Installs the Debian 12 packages dsreg needs, if any is missing.
#   scripts/install-deps.sh          build and run dsreg (ITK reads the medical image formats;
#                                    libgdcm-tools completes GDCM's CMake package, which ITK loads)
#   scripts/install-deps.sh --dev    also the test and benchmark libraries, and nibabel, VTK and
#                                    numpy for Debian's /usr/bin/python3 (tests/medical_interop_test.py)
#   scripts/install-deps.sh --bench  also Debian's VTK and NumPy for Python 3 (bench/slicer_pipeline.py,
#                                    the 3D Slicer peer, and bench/accuracy.sh; benchmarks only)
#   scripts/install-deps.sh --fuzz   also clang with its sanitizer/libFuzzer runtimes and OpenMP
#                                    (scripts/sanitize.sh, scripts/fuzz.sh); implies --dev
#   scripts/install-deps.sh --python also what `pip install --no-build-isolation .` needs offline
#                                    (docs/python.md); with --dev, the Python tests' packages too
#   scripts/install-deps.sh --viewer also Chromium, which opens the HTML pages headless (the
#                                    viewer's browser test, scripts/render.sh), and Python's PIL,
#                                    with which the test reads the screenshots
#   scripts/install-deps.sh --mpi    also OpenMPI and PETSc (3.18, with hypre), for dsreg-mpi and
#                                    its tests (docs/scaling.md)
# libjs-three is a build dependency: three.js is inlined into dsreg's HTML pages (docs/viewer.md).
set -euo pipefail
packages=(build-essential cmake pkg-config libeigen3-dev libsuitesparse-dev libopenblas-dev zlib1g-dev
          libcli11-dev nlohmann-json3-dev libcgal-dev libjs-three libinsighttoolkit5-dev libgdcm-tools libtiff-dev libhdf5-dev)
dev=(libgtest-dev libgmock-dev libbenchmark-dev python3 python3-numpy python3-nibabel python3-vtk9)
bench=(python3 python3-vtk9 python3-numpy)
python=(python3-dev python3-numpy python3-venv python3-setuptools python3-wheel pybind11-dev)
python_dev=(python3-pytest python3-meshio)
with_dev=false with_python=false
for option in "$@"; do
    case $option in
        --dev) packages+=("${dev[@]}"); with_dev=true ;;
        --bench) packages+=("${bench[@]}") ;;
        --fuzz) packages+=("${dev[@]}" clang libclang-rt-14-dev libomp-dev) ;;
        --python) packages+=("${python[@]}"); with_python=true ;;
        --viewer) packages+=(chromium python3-pil) ;;
        --mpi) packages+=(openmpi-bin libopenmpi-dev petsc-dev) ;;
        *) echo "usage: $0 [--dev] [--bench] [--fuzz] [--python] [--viewer] [--mpi]" >&2; exit 2 ;;
    esac
done
$with_dev && $with_python && packages+=("${python_dev[@]}")

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "Installing Debian packages: ${missing[*]}" >&2
sudo_cmd=()
[[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
