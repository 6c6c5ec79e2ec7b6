#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (what CI runs):
#   1. the suite (preset default);
#   2. the whole suite under AddressSanitizer + UBSan (preset asan, clang); the long
#      simulation runs (ctest label "long") at the preset's METARIVER_LONG_SCALE, a quarter
#      of their particles or frames (at full size under ASan they alone would take about
#      17 minutes; the default suite runs them at full size, preset asan-long-full too);
#   3. every libFuzzer target, from the same asan build, for METARIVER_FUZZ_SECONDS each
#      (default 60; scripts/fuzz.sh), FUZZ_JOBS (default: the number of cores) at a time;
#   4. the solver, field and surface tests under ThreadSanitizer (preset tsan).
# METARIVER_CI_QUICK=1 runs step 1 only. Any failure stops it with a non-zero exit.
set -euo pipefail
cd "$(dirname "$0")/.."
step() { echo; echo "=== $* ($(date +%T))"; }
step "build (preset default)"
bash scripts/build.sh
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
step "the suite (preset default)"
ctest --preset default
[ "${METARIVER_CI_QUICK:-0}" = 1 ] && exit 0

step "ASan + UBSan suite (label long at METARIVER_LONG_SCALE, the preset's)"
cmake --preset asan >/dev/null
cmake --build --preset asan -j"$(nproc)"
ctest --preset asan

step "fuzzing, ${METARIVER_FUZZ_SECONDS:-60} s per target"
# One target per core (a libFuzzer run is one thread): on 2 cores four minutes become two.
FUZZ_JOBS="${FUZZ_JOBS:-$(nproc)}" FUZZ_PRESET=asan bash scripts/fuzz.sh "${METARIVER_FUZZ_SECONDS:-60}"

step "ThreadSanitizer: solver, field and surface tests"
cmake --preset tsan >/dev/null
cmake --build --preset tsan -j"$(nproc)"
ctest --preset tsan
step "done"
