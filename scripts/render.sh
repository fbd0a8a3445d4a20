#!/usr/bin/env bash
# Renders a mesh (OBJ/PLY/STL) to a PNG with f3d, off-screen under Xvfb.
#   scripts/render.sh MESH PNG [SIZE] [UP] [AZIMUTH]    (UP: +Z, -Y, +X ...; AZIMUTH in degrees)
# Installs Debian's f3d and xvfb when missing. Used to make the pictures of the README.
set -euo pipefail
[[ $# -ge 2 ]] || { echo "usage: $0 MESH PNG [SIZE] [UP] [AZIMUTH]" >&2; exit 2; }
mesh=$1 png=$2 size=${3:-480} up=${4:-+Z} azimuth=${5:-30}
need=()
command -v f3d >/dev/null || need+=(f3d)
command -v xvfb-run >/dev/null || need+=(xvfb xauth)
if [[ ${#need[@]} -gt 0 ]]; then
    sudo_cmd=(); [[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
    "${sudo_cmd[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${need[@]}" >/dev/null
fi
xvfb-run -a -s "-screen 0 1280x1024x24" f3d "$mesh" --output "$png" --resolution "$size,$size" \
    --up "$up" --camera-azimuth-angle "$azimuth" --camera-elevation-angle 25 --fxaa --no-background
