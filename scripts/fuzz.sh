#!/usr/bin/env bash
# Builds the libFuzzer targets (preset "fuzz": clang, ASan + UBSan, build/fuzz; or the
# preset in FUZZ_PRESET, e.g. asan, which CI builds anyway) and runs each on its seed
# corpus (fuzz/corpus/<target>/) for a bounded time. Any crash, leak,
# UBSan report, timeout (one input over 10 s) or out-of-memory (over 2 GiB) fails the
# script; the input that did it is kept in build/fuzz/run/<target>/ and named below.
#
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
#   SECONDS_PER_TARGET  default 60; targets: png_heightmap scene_toml image cli (default: all)
#   FUZZ_JOBS=2         run two targets at once (default 1)
#   FUZZ_PRESET=asan    build and run the targets of that preset's build (default fuzz)
# Prints per target: runs, executions per second, coverage (cov: edges, ft: features) and
# the corpus (inputs/size) from libFuzzer's final figures, and the time. Reproduce a failure:
#   build/fuzz/fuzz/fuzz_<target> build/fuzz/run/<target>/crash-...  (build/<preset>/ with FUZZ_PRESET)
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD"
secs="${1:-60}"
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(png_heightmap scene_toml image cli)
jobs="${FUZZ_JOBS:-1}"

preset="${FUZZ_PRESET:-fuzz}"
bin="$root/build/$preset/fuzz"
cmake --preset "$preset" >/dev/null
cmake --build "build/$preset" --target fuzzers -j"$(nproc)"

dict_of() {
  case "$1" in
    png_heightmap|image) echo "$root/fuzz/png.dict" ;;
    *) echo "$root/fuzz/$1.dict" ;;
  esac
}

run_one() {
  local t="$1" dir="$root/build/$preset/run/$1"
  rm -rf "$dir"
  mkdir -p "$dir/corpus" "$dir/cwd"
  # In an empty folder: the CLI target's relative paths name nothing there.
  (cd "$dir/cwd" && "$bin/fuzz_$t" "$dir/corpus" "$root/fuzz/corpus/$t" \
      -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
      -dict="$(dict_of "$t")" -use_value_profile=1 -print_final_stats=1 \
      -artifact_prefix="$dir/" >"$dir/log.txt" 2>&1)
}

summary() {
  local t="$1" rc="$2" log="$root/build/$preset/run/$1/log.txt"
  local done_line runs eps cov ft corp
  done_line="$(grep -E '^#[0-9]+[[:space:]]+(DONE|pulse|NEW|REDUCE|INITED)' "$log" | tail -n 1 || true)"
  runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")"
  eps="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")"
  cov="$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$done_line")"
  ft="$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$done_line")"
  corp="$(sed -n 's/.* corp: \([0-9]*\/[0-9]*[a-zA-Z]*\).*/\1/p' <<<"$done_line")"
  local result=ok
  [ "$rc" -ne 0 ] && result="FAILED (exit $rc)"
  printf '%-14s %10s %8s %7s %7s %12s %6s  %s\n' "$t" "${runs:-?}" "${eps:-?}" "${cov:-?}" "${ft:-?}" \
    "${corp:-?}" "${secs}s" "$result"
}

declare -A rcs
if [ "$jobs" -gt 1 ]; then
  declare -A pids
  for t in "${targets[@]}"; do
    while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
    run_one "$t" & pids[$t]=$!
  done
  for t in "${targets[@]}"; do
    if wait "${pids[$t]}"; then rcs[$t]=0; else rcs[$t]=$?; fi
  done
else
  for t in "${targets[@]}"; do
    if run_one "$t"; then rcs[$t]=0; else rcs[$t]=$?; fi
  done
fi

failed=0
echo
printf '%-14s %10s %8s %7s %7s %12s %6s  %s\n' target runs exec/s cov ft corpus time result
for t in "${targets[@]}"; do
  summary "$t" "${rcs[$t]}"
  if [ "${rcs[$t]}" -ne 0 ]; then
    failed=1
    echo "--- fuzz_$t: $(grep -m1 -E 'ERROR: |runtime error:|SUMMARY:' "$root/build/$preset/run/$t/log.txt" || echo "see log")"
    ls "$root/build/$preset/run/$t"/{crash,leak,timeout,oom,slow-unit}-* 2>/dev/null | sed 's/^/    input: /' || true
    echo "    log: build/$preset/run/$t/log.txt"
  fi
done
exit "$failed"
