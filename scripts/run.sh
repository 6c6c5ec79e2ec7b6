#!/usr/bin/env bash
# Installs, builds and runs the main job on the built-in default scene (a river on the
# procedural valley):
#   - with a display (DISPLAY or WAYLAND_DISPLAY set): the interactive viewer;
#   - without one: a headless render (EGL, software OpenGL) of 180 frames at 1280x720
#     to out/default/frames/frame_NNNNN.png, render timings to out/default/render_stats.json,
#     and, when ffmpeg is installed, the same frames as out/default/default.mp4.
# METARIVER_HEADLESS=1 forces the headless render. Extra arguments go to `metariver view`
# or `metariver render` (e.g. --preset paper-bowl, --frames 60, --size 640x360).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
bin=./build/default/apps/metariver
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ -z "${METARIVER_HEADLESS:-}" ]; then
  if "$bin" view "$@"; then exit 0; fi
  echo "metariver: the viewer could not run here; rendering headless instead" >&2
fi
out=out/default
rm -rf "$out"
mkdir -p "$out"
"$bin" render --frames 180 --steps 2 --warmup 120 --size 1280x720 \
  --out "$out/frames" --stats "$out/render_stats.json" "$@"
if command -v ffmpeg >/dev/null 2>&1; then
  ffmpeg -nostdin -loglevel error -y -framerate 30 -i "$out/frames/frame_%05d.png" \
    -c:v libx264 -preset veryfast -crf 20 -pix_fmt yuv420p "$out/default.mp4"
  echo "video: $(pwd)/$out/default.mp4"
fi
echo "results: $(pwd)/$out (frames/frame_*.png, render_stats.json$(command -v ffmpeg >/dev/null 2>&1 && echo ', default.mp4'))"
