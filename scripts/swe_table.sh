#!/usr/bin/env bash
# The shallow-water river on every map of the particle river's table (docs/river.md): the
# procedural terrains, the torture and random maps (scripts/torture_maps.py), the paper's maps
# in ../shared and the real DEMs at their real scale (--real-scale, the sea below the
# sidecar's zero as swe.sea_level). Each map runs `metariver run --stats` with solver = "swe",
# swe.init = "steady" (frame 0 is the river), swe.time_scale = "auto" and the automatic
# discharge, and prints one markdown row from the stats' swe block (docs/shallow-water.md,
# "The river on any map").
# Usage: bash scripts/swe_table.sh [FRAMES] [OUT_DIR]   (METARIVER=path: another build;
# ONLY=regex: only the maps whose name matches, e.g. ONLY='flat|western' )
set -euo pipefail
cd "$(dirname "$0")/.."
B=${METARIVER:-build/default/apps/metariver}
FRAMES=${1:-1200}
OUT=${2:-out/swe_table}
SHARED=../shared/heightmaps
PY=${PYTHON:-/usr/bin/python3}
mkdir -p "$OUT"
"$PY" scripts/torture_maps.py "$OUT/maps"
SWE='solver = "swe"\n\n[swe]\ninit = "steady"\ntime_scale = "auto"\n'
row() {  # name, stats file, wall seconds
  "$PY" - "$1" "$2" "$3" <<'PY'
import json, sys
name, path, wall = sys.argv[1], sys.argv[2], float(sys.argv[3])
j = json.load(open(path)); s = j["swe"]; t = j["terrain"]; i = s["init"]
spin = f"{i['simulated_s']:.3g} s in {i['wall_ms'] / 1000:.1f} s" + ("" if i["converged"] else " (cap)")
print(f"| {name} | {t['columns']} x {t['rows']} | {t['area_scale']:.4g} | {s['discharge_m3_s']:.3g} | {spin} | "
      f"{j['plausibility']['channel_coverage']:.2f} | {s['outflow_over_inflow']:.3f} | {s['storage_change_over_inflow']:.4f} | "
      f"{'yes' if s['steady'] else 'no'} | {s['balance_error_relative_per_min']:.1e} | "
      f"{j['stage_ms']['simulate']['median']:.2f} | {j['stage_ms']['total']['median']:.2f} | {s['wet_fraction']:.3f} |")
PY
}
echo "| map | size | cell m | discharge m^3/s | spin-up (simulated, wall) | coverage | out / in | storage change / in | steady | balance error / min | simulate ms | frame ms | wet |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
run_map() {  # name, scene lines (after [swe]'s), extra args...
  local name=$1 lines=$2; shift 2
  [ -n "${ONLY:-}" ] && ! [[ "$name" =~ $ONLY ]] && return
  local file; file=$(echo "$name" | tr '/ ,()' '_____')
  printf "$SWE$lines" > "$OUT/$file.toml"
  local t0; t0=$(date +%s.%N)
  "$B" run --scene "$OUT/$file.toml" --frames "$FRAMES" --no-progress --stats "$OUT/$file.json" "$@" >/dev/null 2>"$OUT/last_stderr.txt" ||
    { echo "| $name | failed: $(tail -1 "$OUT/last_stderr.txt") |"; return; }
  row "$name" "$OUT/$file.json" "$(echo "$(date +%s.%N) - $t0" | bc)"
}
run_map "valley (default scene)" ""
for src in strict bowl flat; do run_map "procedural $src" "[terrain]\nsource = \"$src\"\n"; done
for f in "$OUT"/maps/spikes.png "$OUT"/maps/cliffs.png "$OUT"/maps/random_*.png; do run_map "$(basename "$f")" "" --heightmap "$f"; done
for f in "$SHARED"/metawater/*.png; do [ -f "$f" ] && run_map "metawater/$(basename "$f")" "" --heightmap "$f"; done
for f in assets/heightmaps/real/*.png; do
  sea=$("$PY" -c "import json,sys; m=json.load(open(sys.argv[1]))['metres_min']; print(-m if m < 0 else 'none')" "${f%.png}.json")
  [ "$sea" = none ] && sea='"none"'
  run_map "real/$(basename "$f") at real scale" "sea_level = $sea\n" --heightmap "$f" --real-scale
done
