#!/usr/bin/env bash
# Soak test (issue 13; not in CI): three long runs, each reporting every 1000 frames
# (`--report-every`): the default river (`run`), the paper's Nile scene (`run --preset
# paper-nile` on ../shared's nile.png) and the viewer's render path (`render`: the same
# renderer, headless, to an MP4, on the paper's bowl). Checks for each: exit 0; resident memory flat (the
# largest VmRSS after warm-up at most 1 % above the VmRSS at the end of warm-up, the first
# 10 % of the frames); no non-finite particle or surface value; the counters add up at
# every report (balance 0: active = emitted - sunk [- respawned for PBF], or the spawn
# schedule). Prints a Markdown table; the logs stay in out/soak/.
#
# Usage: scripts/soak.sh [FRAMES]     (default 100000; about an hour on 2 cores)
#   METARIVER_BUILD_DIR=build/default  the build to use (bash scripts/build.sh makes it)
#   SOAK_RUNS="river paper render"     which runs
set -euo pipefail
cd "$(dirname "$0")/.."
frames="${1:-100000}"
every=1000
build="${METARIVER_BUILD_DIR:-build/default}"
exe="$build/apps/metariver"
out=out/soak
runs="${SOAK_RUNS:-river paper render}"
nile=../shared/heightmaps/metawater/nile.png
[ -x "$exe" ] || { echo "soak: $exe not built (bash scripts/build.sh)"; exit 2; }
mkdir -p "$out"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"

for r in $runs; do
  case "$r" in
    river) args=(run --frames "$frames") ;;
    paper) [ -f "$nile" ] || { echo "soak: $nile missing"; exit 2; }
           args=(run --preset paper-nile --heightmap "$nile" --frames "$frames") ;;
    # The render path under test, not the river's simulation (run soaks that): the
    # paper's bowl, cheap to simulate, its surface still rebuilt and uploaded every frame.
    render) args=(render --preset paper-bowl --frames "$frames" --size 160x96 --out "$out/render.mp4" --no-progress) ;;
    *) echo "soak: unknown run '$r'"; exit 2 ;;
  esac
  echo "soak: $r: $exe ${args[*]} --report-every $every"
  start=$(date +%s)
  rc=0
  "$exe" "${args[@]}" --report-every "$every" >"$out/$r.log" 2>"$out/$r.err" || rc=$?
  echo "rc=$rc seconds=$(( $(date +%s) - start ))" >"$out/$r.status"
done

python3 - "$frames" $runs <<'PY'
import re, sys
frames = int(sys.argv[1]); runs = sys.argv[2:]
warm = frames // 10
fail = False
print()
print("| run | frames | wall | VmRSS at warm-up end | max VmRSS after | growth | non-finite | counters (balance) | end: active / total, emitted, sunk, respawned | result |")
print("|---|---|---|---|---|---|---|---|---|---|")
for r in runs:
    st = dict(kv.split("=") for kv in open(f"out/soak/{r}.status").read().split())
    rows = []
    for line in open(f"out/soak/{r}.log"):
        if line.startswith("report "):
            rows.append({k: int(v) for k, v in (kv.split("=") for kv in line.split()[1:])})
    ok = int(st["rc"]) == 0 and rows and rows[-1]["frame"] >= frames
    base = next((x["rss_kb"] for x in rows if x["frame"] >= warm), None)
    after = max((x["rss_kb"] for x in rows if x["frame"] >= warm), default=None)
    growth = (after - base) / base * 100 if base else float("nan")
    nonfinite = sum(x["nonfinite"] for x in rows)
    unbalanced = [x for x in rows if x["balance"] != 0]
    ok = ok and growth < 1.0 and nonfinite == 0 and not unbalanced
    fail |= not ok
    e = rows[-1] if rows else {}
    print(f"| {r} | {e.get('frame', 0):,} | {int(st['seconds'])/60:.0f} min | {base/1024 if base else 0:.1f} MiB | "
          f"{after/1024 if after else 0:.1f} MiB | {growth:+.2f} % | {nonfinite} | "
          f"{'0 at every report' if not unbalanced else f'{len(unbalanced)} reports off'} | "
          f"{e.get('active')} / {e.get('total')}, {e.get('emitted')}, {e.get('sunk')}, {e.get('respawned')} | "
          f"{'ok' if ok else 'FAILED (exit ' + st['rc'] + ')'} |")
sys.exit(1 if fail else 0)
PY
