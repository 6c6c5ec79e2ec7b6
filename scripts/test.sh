#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (what CI runs):
#   1. the suite (preset default);
#   2. the core alone (preset minimal: METARIVER_WITH_RENDER, _EXPORT and _BULLET off, so
#      that the library builds and passes its tests without their dependencies), without
#      the long runs (label long: the default suite has just run them on the same code);
#   3. the whole suite under AddressSanitizer + UBSan (preset asan, clang); the long
#      simulation runs (ctest label "long") at the preset's METARIVER_LONG_SCALE, a quarter
#      of their particles or frames (at full size under ASan they alone would take about
#      17 minutes; the default suite runs them at full size, preset asan-long-full too);
#   4. every libFuzzer target, from the same asan build, for METARIVER_FUZZ_SECONDS each
#      (default 60; scripts/fuzz.sh), FUZZ_JOBS (default: the number of cores) at a time;
#   5. the solver, field and surface tests under ThreadSanitizer (preset tsan).
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

step "the core alone (preset minimal, label long excluded)"
cmake --preset minimal >/dev/null
cmake --build --preset minimal -j"$(nproc)"
ctest --preset minimal

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
