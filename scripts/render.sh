#!/usr/bin/env bash
# Makes the pictures of README.md and docs/ from dsreg's own HTML pages: each picture is a
# screenshot by headless Chromium (WebGL on SwiftShader) of a page written by
# `dsreg regularize --html` (docs/viewer.md), so that one script remakes them all.
#
#   scripts/render.sh                                 every picture of docs/images/ (PNG)
#   scripts/render.sh PAGE PNG [FRAGMENT] [WxH|N]     one screenshot of a page, e.g.
#       scripts/render.sh out/goursat.html g.png "colour=deviation&panels=0&background=none" 480
#
# FRAGMENT sets the page's state (docs/viewer.md: colour, layer, surface, digital, wireframe,
# features, up, azimuth, elevation, panels, background=none for a transparent background).
# Uses $DSREG, else build/release/dsreg (built when missing, as scripts/demo.sh does); installs
# Chromium when missing (scripts/install-deps.sh --viewer). The pictures of the shared data
# (../shared/data/bunny-128.vol) are skipped when it is not there. The README's convergence plots
# (SVG) come from `dsreg convergence` (docs/convergence.md), not from here.
set -euo pipefail
cd "$(dirname "$0")/.."

# screenshot PAGE PNG FRAGMENT SIZE: the page at #FRAGMENT in a window of SIZE (WxH, or N for NxN).
screenshot() {
    local page=$1 png=$2 fragment=${3:-} size=${4:-480}
    [[ $size == *x* ]] || size=${size}x${size}
    local profile
    profile=$(mktemp -d)
    # A fresh profile; no background networking (the page itself loads nothing).
    chromium --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader \
        --no-first-run --disable-background-networking --disable-component-update --disable-sync \
        --disable-quic --hide-scrollbars --user-data-dir="$profile" --window-size="${size/x/,}" \
        --default-background-color=00000000 --screenshot="$png" \
        "file://$(realpath "$page")#$fragment" >/dev/null 2>&1 || { rm -rf "$profile"; echo "render: $page: chromium failed" >&2; return 1; }
    rm -rf "$profile"
    [[ -s $png ]] || { echo "render: $page: no screenshot" >&2; return 1; }
    echo "render: $png"
}

command -v chromium >/dev/null || scripts/install-deps.sh --viewer

if [[ $# -ge 2 ]]; then
    screenshot "$@"
    exit 0
fi
[[ $# -eq 0 ]] || { echo "usage: $0 [PAGE PNG [FRAGMENT] [WxH|N]]" >&2; exit 2; }

dsreg=${DSREG:-build/release/dsreg}
if [[ ! -x $dsreg ]]; then
    scripts/install-deps.sh
    cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release -DDSREG_BUILD_TESTS=OFF -DDSREG_BUILD_BENCHMARKS=OFF >/dev/null
    cmake --build build/release --target dsreg -j"$(nproc)"
fi
pages=$(mktemp -d)
trap 'rm -rf "$pages"' EXIT
images=docs/images
clean="panels=0&background=none"  # the mesh alone, on a transparent background

# README: goursat at h = 0.25 (the demo), digital and regularized.
"$dsreg" regularize --shape goursat --h 0.25 -o "$pages/goursat.ply" --html "$pages/goursat.html" -q
screenshot "$pages/goursat.html" "$images/goursat-regularized.png" "$clean&azimuth=30&elevation=25" 400
screenshot "$pages/goursat.html" "$images/goursat-digital.png" "$clean&azimuth=30&elevation=25&surface=0&digital=1" 400

# docs/ambrosio-tortorelli.md: a turned cube and a turned can, II and AT normals, feature map.
CUBE="(0.8*x+0.6*y)^16+(-0.48*x+0.64*y+0.6*z)^16+(0.36*x-0.48*y+0.8*z)^16-1"
CAN="((0.8*x+0.6*y)^2+(-0.48*x+0.64*y+0.6*z)^2)^8+(0.36*x-0.48*y+0.8*z)^16-1"
turned="azimuth=20&elevation=25"
for shape in cube can; do
    polynomial=$CUBE
    [[ $shape == can ]] && polynomial=$CAN
    "$dsreg" regularize --shape "$polynomial" --box 1.8 --h 0.04 --radius 0.12 -o "$pages/$shape-ii.ply" \
        --html "$pages/$shape-ii.html" -q
    "$dsreg" regularize --shape "$polynomial" --box 1.8 --h 0.04 --radius 0.12 --normals at -o "$pages/$shape-at.ply" \
        --html "$pages/$shape-at.html" -q
    [[ $shape == cube ]] && screenshot "$pages/cube-ii.html" "$images/at-cube-digital.png" "$clean&$turned&surface=0&digital=1" 360
    screenshot "$pages/$shape-ii.html" "$images/at-$shape-ii.png" "$clean&$turned" 360
    screenshot "$pages/$shape-at.html" "$images/at-$shape-at.png" "$clean&$turned&features=0" 360
    screenshot "$pages/$shape-at.html" "$images/at-$shape-features.png" "$clean&$turned&colour=features" 360
done

# README and docs/ambrosio-tortorelli.md: bunny-128, and the viewer itself (docs/viewer.md).
bunny=../shared/data/bunny-128.vol
if [[ -f $bunny ]]; then
    side="up=-y&azimuth=90&elevation=-30"
    "$dsreg" regularize "$bunny" --radius 6 -o "$pages/bunny.ply" --html "$pages/bunny.html" -q
    screenshot "$pages/bunny.html" "$images/bunny-regularized.png" "$clean&$side" 400
    screenshot "$pages/bunny.html" "$images/bunny-digital.png" "$clean&$side&surface=0&digital=1" 400
    screenshot "$pages/bunny.html" "$images/viewer.png" "$side&colour=deviation" 1100x600
    "$dsreg" regularize "$bunny" --radius 3 -o "$pages/bunny-ii.ply" --html "$pages/bunny-ii.html" -q
    "$dsreg" regularize "$bunny" --radius 3 --normals at -o "$pages/bunny-at.ply" --html "$pages/bunny-at.html" -q
    screenshot "$pages/bunny-ii.html" "$images/at-bunny-ii.png" "$clean&$side" 360
    screenshot "$pages/bunny-at.html" "$images/at-bunny-at.png" "$clean&$side&features=0" 360
    screenshot "$pages/bunny-at.html" "$images/at-bunny-features.png" "$clean&$side&colour=features" 360
else
    echo "render: $bunny not found: the bunny pictures are left as they are" >&2
fi
