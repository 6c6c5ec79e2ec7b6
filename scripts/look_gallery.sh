#!/usr/bin/env bash
# The water's three looks side by side on the same scenes and frames (docs/rendering.md,
# "Gallery: three looks"): the paper's (Gouraud, no foam), the realistic water without
# flow detail and foam (the look before issue 11's flow detail), and the realistic water
# with both (today's default). Rendered headless by `metariver render`, 960x540, one JPEG
# per scene and look in GALLERY_DIR (default docs/images/looks).
# Usage: bash scripts/look_gallery.sh [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
B=${METARIVER:-build/default/apps/metariver}  # METARIVER=path: another build
OUT=${1:-out/look_gallery}
GALLERY=${GALLERY_DIR:-docs/images/looks}
SHARED=../shared/heightmaps
mkdir -p "$OUT" "$GALLERY"
cp scripts/still_pool.toml "$OUT/pool.toml"  # the still pool of docs/river.md
# name | frame shown (warm-up frames + 1) | camera YAW,PITCH,DISTANCE,TARGET (on the water:
# the particles' median position at that frame, from run --export) | scene options
scenes=(
  "pool|900|30,40,26,16,2,16|--scene $OUT/pool.toml"
  "river|1200|30,40,45,44,8,53|"
  "nile|1500|30,45,14,27,3.5,29|--preset paper-nile --heightmap $SHARED/metawater/nile.png"
  "pyrenees|1800|30,45,40,74,5,18|--heightmap assets/heightmaps/real/pyrenees.png --area-scale 3 --height-scale 15"
)
looks=(
  "paper|--water gouraud --no-foam"
  "before|--water realistic --no-flow --no-foam"
  "now|--water realistic"
)
for s in "${scenes[@]}"; do
  IFS='|' read -r name frame camera opts <<<"$s"
  for l in "${looks[@]}"; do
    IFS='|' read -r look lopts <<<"$l"
    # shellcheck disable=SC2086  # the options are words
    "$B" render $opts $lopts --frames 1 --warmup $((frame - 1)) --size 960x540 --camera "$camera" --no-progress \
      --out "$OUT/$name.$look" >/dev/null
    ffmpeg -loglevel error -y -i "$OUT/$name.$look/frame_00000.png" -q:v 4 "$GALLERY/${name}_$look.jpg"
    echo "$GALLERY/${name}_$look.jpg"
  done
done
