#!/usr/bin/env bash
# The sound-water table (issue 9): the default PBF river, 1800 frames (30 s), on the
# paper's maps, the real DEMs, the procedural terrains and the tunneling test's torture
# terrains (spikes, cliffs), plus the still pool. One markdown row per map from the
# stats of `metariver run`. Usage: bash scripts/sound_water_table.sh [FRAMES] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
B=build/default/apps/metariver
FRAMES=${1:-1800}
OUT=${2:-out/sound_water}
SHARED=../shared/heightmaps
mkdir -p "$OUT"
python3 scripts/torture_maps.py "$OUT/maps"
row() {  # name, stats file
  python3 - "$1" "$2" <<'PY'
import json, sys
j = json.load(open(sys.argv[2])); p = j["plausibility"]
print(f"| {sys.argv[1]} | {j['terrain']['columns']} x {j['terrain']['rows']} | {j['particles_active']} | {j['particle_steps']:,} | "
      f"{j['tunneled']} | {j['guarded']} | {j['respawned']} | {p['max_speed']:.1f} | {p['final_speed']['p95']:.3f} | "
      f"{p['spray_fraction']:.4f} |")
PY
}
echo "| map | size | active | particle-steps | tunneled | guarded | respawned | max speed m/s | final speed p95 m/s | spray fraction |"
echo "|---|---|---|---|---|---|---|---|---|---|"
run_map() {  # name, extra args...
  local name=$1; shift
  local s="$OUT/$(echo "$name" | tr '/ ' '__').json"
  "$B" run --frames "$FRAMES" --stats "$s" "$@" >/dev/null 2>"$OUT/last_stderr.txt" || { echo "| $name | failed: $(tail -1 "$OUT/last_stderr.txt") |"; return; }
  row "$name" "$s"
}
run_map "valley (default scene)"
for src in strict bowl flat; do
  printf 'name = "%s"\n[terrain]\nsource = "%s"\n' "$src" "$src" > "$OUT/$src.toml"
  run_map "procedural $src" --scene "$OUT/$src.toml"
done
for f in "$OUT/maps/spikes.png" "$OUT/maps/cliffs.png"; do run_map "torture $(basename "$f")" --heightmap "$f"; done
for f in "$SHARED"/metawater/*.png "$SHARED"/real/*.png; do
  [ -f "$f" ] && run_map "$(basename "$(dirname "$f")")/$(basename "$f")" --heightmap "$f"
done
cat > "$OUT/pool.toml" <<'TOML'
name = "still pool"
solver = "pbf"
[terrain]
source = "bowl"
width = 33
height = 33
height_scale = 7.0
[particles]
count = 2500
spawn_center = [16.0, 6.0, 16.0]
spawn_half_extent = [5.0, 2.0, 5.0]
spawn_interval = 0
flow_rate = 0.0
source_shape = "box"
[sink]
kind = "none"
TOML
FRAMES=900 run_map "still pool (defaults, 900 frames)" --scene "$OUT/pool.toml"
printf '[collision]\ndamping = 0.02\n' | cat "$OUT/pool.toml" - > "$OUT/pool_still.toml"
FRAMES=900 run_map "still pool, collision.damping 0.02 (900 frames)" --scene "$OUT/pool_still.toml"
