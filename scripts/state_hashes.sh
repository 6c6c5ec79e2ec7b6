#!/usr/bin/env bash
# Prints the state hash (particle positions, velocities and activity after N frames) of the
# scenes whose behaviour a refactor must keep: the default river, the springs valley, the
# paper's scenes (the PNG ones from the paper's heightmaps when HEIGHTMAPS has them), the
# Bullet engine mode and the default river on three real DEMs. Compare two builds' output
# with diff: equal lines mean the same particles bit for bit.
#   bash scripts/state_hashes.sh [METARIVER_BINARY] [HEIGHTMAPS_DIR]
# Defaults: build/default/apps/metariver and ../shared/heightmaps (beside the repository).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
bin="${1:-$here/build/default/apps/metariver}"
maps="${2:-$here/../shared/heightmaps}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
row() {  # name frames args...
  local name="$1" frames="$2"; shift 2
  "$bin" run "$@" --frames "$frames" --stats "$tmp/s.json" --no-progress >/dev/null 2>"$tmp/err" ||
    { echo "$name FAILED: $(tail -1 "$tmp/err")"; return; }
  python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print(sys.argv[2], s["state_hash"], s["particles_active"], s["triangles"], s["vertices"])' \
    "$tmp/s.json" "$name"
}
row default 600
row springs-valley 300 --preset springs-valley
row paper-bowl 300 --preset paper-bowl
[ -f "$maps/metawater/strict17.png" ] && row paper-full 300 --preset paper-full --heightmap "$maps/metawater/strict17.png"
[ -f "$maps/metawater/nile.png" ] && row paper-nile 300 --preset paper-nile --heightmap "$maps/metawater/nile.png"
[ -f "$maps/metawater/strict17.png" ] && row paper-engine 300 --preset paper-engine --heightmap "$maps/metawater/strict17.png"
[ -f "$maps/metawater/nile.png" ] && row paper-nile-engine 300 --preset paper-nile-engine --heightmap "$maps/metawater/nile.png"
for dem in alps pyrenees andes_peru; do
  row "default-$dem" 300 --heightmap "$here/assets/heightmaps/real/$dem.png"
done
