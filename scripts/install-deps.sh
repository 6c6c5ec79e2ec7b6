#!/usr/bin/env bash
# Installs the Debian packages metariver needs, only those that are missing.
# Usage: scripts/install-deps.sh            (build + test dependencies)
# The peers of `metariver bench --peers` (VTK, numpy, Node + three.js) are NOT installed here
# (CI stays fast); see docs/benchmarks.md: bash bench/peers/setup.sh
set -euo pipefail
pkgs=(cmake ninja-build g++ pkg-config
      libtbb-dev libglm-dev libfmt-dev libtomlplusplus-dev libcli11-dev libstb-dev
      libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev
      libbullet-dev
      libepoxy-dev libglfw3-dev libimgui-dev libegl-dev libgl1-mesa-dri libegl-mesa0 ffmpeg xvfb)
missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "metariver: installing missing packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
