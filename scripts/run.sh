#!/usr/bin/env bash
# Installs, builds and runs the main job on the built-in default scene: a river on the
# procedural valley, simulated headless; the water surface of every frame goes to
# out/default/*.obj and the run's statistics to out/default/stats.json.
# Extra arguments are passed to `metariver run` (e.g. --frames 1200 --preset paper-bowl).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
out=out/default
rm -rf "$out"
./build/default/apps/metariver run --frames 600 --obj-dir "$out" --stats "$out/stats.json" "$@"
echo "results: $(pwd)/$out (terrain.obj, surface_*.obj, stats.json)"
