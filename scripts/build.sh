#!/usr/bin/env bash
# Installs missing Debian packages, configures and builds metariver (preset "default").
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset default >/dev/null
cmake --build --preset default -j"$(nproc)"
