#!/usr/bin/env bash
# Runs the default scene (the PBF river) with only --heightmap on every map of the set
# and prints one markdown row per map from the stats of `metariver run`:
#   sound: the sound-water table (issue 9): particle-steps, tunneled, guarded,
#          respawned, max speed, final speed p95, spray fraction; plus the still pool.
#   river: the river table (issue 10): scale, particles, channel coverage,
#          outflow/inflow (main outlet), steady, time to outlet, spray, tunneled,
#          guarded, frame median.
#   gallery: the river rendered headless at the last frame, an oblique view and a view
#          from above side by side, one JPEG per map in GALLERY_DIR (default
#          docs/images/gallery), and one markdown row per map naming it.
# Maps: the procedural terrains, the tunneling test's torture terrains and random maps
# (scripts/torture_maps.py), the paper's maps in ../shared and the real DEMs in assets/heightmaps/real.
# Usage: bash scripts/map_table.sh sound|river|gallery [FRAMES] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
MODE=${1:?usage: map_table.sh sound|river|gallery [FRAMES] [OUT_DIR]}
case "$MODE" in
  sound) DEFAULT_FRAMES=1800 ;;
  river | gallery) DEFAULT_FRAMES=7200 ;;
  *) echo "mode: sound, river or gallery" >&2; exit 2 ;;
esac
B=${METARIVER:-build/default/apps/metariver}  # METARIVER=path: another build
FRAMES=${2:-$DEFAULT_FRAMES}
OUT=${3:-out/${MODE}_table}
SHARED=../shared/heightmaps
mkdir -p "$OUT"
python3 scripts/torture_maps.py "$OUT/maps"
row() {  # name, stats file
  python3 - "$MODE" "$1" "$2" <<'PY'
import json, sys
mode, name, path = sys.argv[1:4]
j = json.load(open(path)); p = j["plausibility"]; t = j["terrain"]
size = f"{t['columns']} x {t['rows']}"
if mode == "sound":
    print(f"| {name} | {size} | {j['particles_active']} | {j['particle_steps']:,} | {j['tunneled']} | {j['guarded']} | "
          f"{j['respawned']} | {p['max_speed']:.1f} | {p['final_speed']['p95']:.3f} | {p['spray_fraction']:.4f} |")
else:
    main = [o for o in p.get("outlets", []) if o.get("main")]
    steady = "yes" if p.get("outflow_steady") else "no"
    print(f"| {name} | {size} | {t.get('area_scale', 0):g} | {j['particles_active']} | {p['channel_coverage']:.2f} | "
          f"{p['outflow_over_inflow']:.3f} | {steady} | {p['time_to_outlet_s']:.1f} | {p['spray_fraction']:.4f} | "
          f"{j['tunneled']} | {j['guarded']} | {j['stage_ms']['total']['median']:.1f} |")
PY
}
GALLERY=${GALLERY_DIR:-docs/images/gallery}
if [ "$MODE" = gallery ]; then
  mkdir -p "$GALLERY"
  echo "| map | at $((FRAMES / 60)) s: oblique, and from above |"
  echo "|---|---|"
elif [ "$MODE" = sound ]; then
  echo "| map | size | active | particle-steps | tunneled | guarded | respawned | max speed m/s | final speed p95 m/s | spray fraction |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
else
  echo "| map | size | area scale m | active | channel coverage | outflow / inflow | steady | time to outlet s | spray | tunneled | guarded | frame ms |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
fi
# NO_SURFACE=1: the default scene with surface = false (the same physics, no field or
# mesh: the frame ms column is then the simulation alone).
BASE=()
if [ "${NO_SURFACE:-0}" = 1 ] && [ "$MODE" != gallery ]; then printf 'surface = false\n' > "$OUT/no_surface.toml"; BASE=(--scene "$OUT/no_surface.toml"); fi
run_map() {  # name, extra args...
  local name=$1; shift
  if [ ${#BASE[@]} -gt 0 ] && [[ " $* " != *" --scene "* ]]; then set -- "${BASE[@]}" "$@"; fi
  local file; file=$(echo "$name" | tr '/ ,()' '_____')
  if [ "$MODE" = gallery ]; then
    local view cam
    for view in oblique top; do
      cam=(); [ $view = top ] && cam=(--camera top)
      "$B" render --frames 1 --warmup $((FRAMES - 1)) --size 480x270 --no-progress --out "$OUT/$file.$view" \
        "${cam[@]}" "$@" >/dev/null 2>"$OUT/last_stderr.txt" || { echo "| $name | failed: $(tail -1 "$OUT/last_stderr.txt") |"; return; }
    done
    ffmpeg -loglevel error -y -i "$OUT/$file.oblique/frame_00000.png" -i "$OUT/$file.top/frame_00000.png" \
      -filter_complex hstack -q:v 5 "$GALLERY/$file.jpg"
    echo "| $name | ![$name]($(realpath --relative-to=docs "$GALLERY")/$file.jpg) |"
    return
  fi
  local s="$OUT/$file.json"
  "$B" run --frames "$FRAMES" --stats "$s" "$@" >/dev/null 2>"$OUT/last_stderr.txt" || { echo "| $name | failed: $(tail -1 "$OUT/last_stderr.txt") |"; return; }
  row "$name" "$s"
}
run_map "valley (default scene)"
for src in strict bowl flat; do
  extra=""; [ "${NO_SURFACE:-0}" = 1 ] && extra='surface = false\n'
  printf "name = \"%s\"\n${extra}[terrain]\nsource = \"%s\"\n" "$src" "$src" > "$OUT/$src.toml"
  run_map "procedural $src" --scene "$OUT/$src.toml"
done
for f in "$OUT"/maps/spikes.png "$OUT"/maps/cliffs.png "$OUT"/maps/random_*.png; do run_map "$(basename "$f")" --heightmap "$f"; done
for f in "$SHARED"/metawater/*.png assets/heightmaps/real/*.png; do
  [ -f "$f" ] && run_map "$(basename "$(dirname "$f")")/$(basename "$f")" --heightmap "$f"
done
if [ "$MODE" = sound ]; then
  cp scripts/still_pool.toml "$OUT/pool.toml"
  FRAMES=900 run_map "still pool (defaults, 900 frames)" --scene "$OUT/pool.toml"
  printf '[collision]\ndamping = 0.02\n' | cat "$OUT/pool.toml" - > "$OUT/pool_still.toml"
  FRAMES=900 run_map "still pool, collision.damping 0.02 (900 frames)" --scene "$OUT/pool_still.toml"
fi
