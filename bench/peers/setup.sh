#!/usr/bin/env bash
# Installs what `metariver bench --peers` needs, only what is missing (idempotent, silent
# when everything is there). Not part of scripts/install-deps.sh: CI does not run peers.
#   Debian packages: python3-vtk9 python3-numpy (VTK peer, run with /usr/bin/python3),
#                    libbullet-dev (Bullet peer; the bench_w2_bullet target),
#                    nodejs npm (three.js peer; skipped when node and npm are already on PATH)
#   npm:             three@$THREE_VERSION into $METARIVER_PEERS_NODE (default <repo>/build/peers-node;
#                    never committed, build/ is ignored)
# Usage: bash bench/peers/setup.sh
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
REPO=$(cd "$HERE/../.." && pwd)
THREE_VERSION=${THREE_VERSION:-0.187.0}
NODE_DIR=${METARIVER_PEERS_NODE:-$REPO/build/peers-node}

pkgs=(python3-vtk9 python3-numpy libbullet-dev)
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then pkgs+=(nodejs npm); fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "bench/peers/setup.sh: installing ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

installed_three() {
  node -p "require('$NODE_DIR/node_modules/three/package.json').version" 2>/dev/null || true
}
if [ "$(installed_three)" != "$THREE_VERSION" ]; then
  echo "bench/peers/setup.sh: npm install three@$THREE_VERSION into $NODE_DIR"
  mkdir -p "$NODE_DIR"
  [ -f "$NODE_DIR/package.json" ] || echo '{"name":"metariver-peers","private":true}' > "$NODE_DIR/package.json"
  (cd "$NODE_DIR" && npm install --silent --no-audit --no-fund "three@$THREE_VERSION" >/dev/null)
  [ "$(installed_three)" = "$THREE_VERSION" ] || { echo "bench/peers/setup.sh: three@$THREE_VERSION did not install" >&2; exit 1; }
fi

# Fail loudly if a peer still does not load.
/usr/bin/python3 -c 'import numpy, vtkmodules.vtkFiltersCore' 2>/dev/null ||
  { echo "bench/peers/setup.sh: /usr/bin/python3 cannot import vtk/numpy" >&2; exit 1; }
[ -f /usr/include/bullet/btBulletDynamicsCommon.h ] ||
  { echo "bench/peers/setup.sh: Bullet headers missing (libbullet-dev)" >&2; exit 1; }
