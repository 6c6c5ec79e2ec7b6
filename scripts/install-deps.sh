#!/usr/bin/env bash
# Installs the Debian packages metariver needs, only those that are missing, and the
# Khronos glTF validator (npm) the export tests run.
# Usage: scripts/install-deps.sh            (build + test dependencies)
# The peers of `metariver bench --peers` (VTK, numpy, Node + three.js) are NOT installed here
# (CI stays fast); see docs/benchmarks.md: bash bench/peers/setup.sh. Neither is Blender
# (scripts/blender_import.py; docs/export.md).
set -euo pipefail
cd "$(dirname "$0")/.."
pkgs=(cmake ninja-build g++ pkg-config
      libtbb-dev libglm-dev libfmt-dev libtomlplusplus-dev libcli11-dev libstb-dev libturbojpeg0-dev
      libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev
      libbullet-dev
      libepoxy-dev libglfw3-dev libimgui-dev libegl-dev libgl1-mesa-dri libegl-mesa0 ffmpeg xvfb
      # the sanitizer build and the fuzz targets (scripts/fuzz.sh): clang, its runtimes
      clang libclang-rt-dev
      # export (docs/export.md): tinygltf, OpenVDB (its headers need Boost's), and the
      # outside readers the tests use: assimp, vdb_print
      libtinygltf-dev libopenvdb-dev libboost-iostreams-dev libassimp-dev libopenvdb-tools
      # the Python package (python/: pip install, pytest) and the Blender add-on's
      # headless test (blender/, docs/blender.md)
      python3-numpy python3-pytest python3-pip python3-setuptools python3-wheel blender)
# node + npm for the glTF validator, from Debian unless a node with npm is there already.
if ! command -v npm >/dev/null 2>&1; then pkgs+=(nodejs npm); fi
missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "metariver: installing missing packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The Khronos glTF validator, pinned, into build/npm (tests/io/export_test.cpp runs it
# through scripts/gltf_validate.cjs). Without the npm registry the test skips, saying so.
validator=2.0.0-dev.3.10
if ! grep -qs "\"version\": \"$validator\"" build/npm/node_modules/gltf-validator/package.json; then
  echo "metariver: installing gltf-validator@$validator (npm) into build/npm"
  mkdir -p build/npm
  npm install --prefix build/npm --no-audit --no-fund --loglevel=error "gltf-validator@$validator" ||
    echo "metariver: warning: npm could not install gltf-validator; the glTF validation test will skip"
fi
