#!/usr/bin/env bash
# Installs the Debian 12 packages dsreg needs, if any is missing.
#   scripts/install-deps.sh          build and run dsreg
#   scripts/install-deps.sh --dev    also the test and benchmark libraries
set -euo pipefail
packages=(build-essential cmake pkg-config libeigen3-dev libsuitesparse-dev libopenblas-dev zlib1g-dev
          libcli11-dev nlohmann-json3-dev)
if [[ ${1:-} == --dev ]]; then packages+=(libgtest-dev libgmock-dev libbenchmark-dev); fi

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
