#!/usr/bin/env bash
# Install.ExamplesBuildFromThePackage (tests/CMakeLists.txt): installs the build to a
# temporary prefix and, in temporary folders outside the tree, builds against it with
# find_package(metariver CONFIG) only:
#   1. the installed libraries share no code: every strong symbol (T, D, B, R) is defined in
#      one .so only, mr::Simulation::create and mr::SolverRegistry::builtin() in libmetariver.so;
#   2. examples/cpp builds and runs (no LD_LIBRARY_PATH): particles and surface triangles > 0;
#   3. examples/c, when the tree has it, builds and runs;
#   4. each component built links (metariver::render, metariver::export); one left out of
#      this build, and an unknown one, fail find_package with the package's message.
# A missing compiler or tool skips (exit 77); with METARIVER_REQUIRE_ALL=1 it fails instead.
# Usage: examples_test.sh BUILD_DIR SOURCE_DIR CMAKE CXX_COMPILER "COMPONENTS"
set -euo pipefail
build=$1 src=$2 cmake=$3 cxx=$4 components=${5:-}

skip() {
    if [ "${METARIVER_REQUIRE_ALL:-0}" = 1 ]; then
        echo "FAIL: METARIVER_REQUIRE_ALL=1, and this test would have skipped: $*"
        exit 1
    fi
    echo "SKIP: $*"
    exit 77
}
fail() { echo "FAIL: $*"; exit 1; }
need() { command -v "$1" >/dev/null || skip "$1 is not installed ($2)"; }
need "$cxx" "the C++ compiler the examples are built with"
need nm "binutils, for the symbol check"

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
"$cmake" --install "$build" --prefix "$prefix" >"$tmp/install.log" || { cat "$tmp/install.log"; fail "cmake --install"; }
config=$prefix/lib/cmake/metariver
for f in "$config/metariver-config.cmake" "$config/metariver-config-version.cmake" "$config/metariver-targets.cmake" \
         "$prefix/lib/libmetariver.so" "$prefix/include/metariver/metariver.h" "$prefix/include/metariver/scene.h"; do
    [ -e "$f" ] || fail "the install lacks $f"
done

# 1. One copy of every symbol.
libs=("$prefix"/lib/libmetariver*.so)
dups=$(for so in "${libs[@]}"; do nm -D --defined-only "$so" | awk '$2 ~ /^[TDBR]$/ {print $3}'; done | sort | uniq -d)
[ -z "$dups" ] || fail "defined in more than one installed library: $(echo "$dups" | head -5 | c++filt)"
for sym in 'mr::Simulation::create(' 'mr::SolverRegistry::builtin()'; do
    where=$(for so in "${libs[@]}"; do
        [ "$(nm -DC --defined-only "$so" | grep -cF " T $sym")" -gt 0 ] && basename "$so"
    done || true)
    [ "$where" = libmetariver.so ] || fail "$sym is defined in [$where], not in libmetariver.so alone"
done
echo "symbols: ${#libs[@]} libraries, no strong symbol defined twice"

# 2. and 3. The examples, each configured and built in a folder of its own.
build_example() {  # NAME [cmake args...]
    local name=$1
    shift
    "$cmake" -S "$src/examples/$name" -B "$tmp/$name" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release "$@" \
        >"$tmp/$name.log" 2>&1 || { cat "$tmp/$name.log"; fail "examples/$name: configure"; }
    "$cmake" --build "$tmp/$name" >>"$tmp/$name.log" 2>&1 || { cat "$tmp/$name.log"; fail "examples/$name: build"; }
}
build_example cpp -DCMAKE_CXX_COMPILER="$cxx"
out=$(env -u LD_LIBRARY_PATH "$tmp/cpp/river") || fail "examples/cpp: the program failed: $out"
echo "$out"
particles=$(echo "$out" | sed -n 's/^active particles: //p')
triangles=$(echo "$out" | sed -n 's/^surface triangles: //p')
[ "${particles:-0}" -gt 0 ] || fail "examples/cpp: no active particles"
[ "${triangles:-0}" -gt 0 ] || fail "examples/cpp: no surface triangles"
grep -q "^water at (.*): wet, " <<<"$out" || fail "examples/cpp: the water query found no water under the surface"

if [ -f "$src/examples/c/CMakeLists.txt" ]; then
    need cc "the C compiler examples/c is built with"
    build_example c
    exe=$(find "$tmp/c" -maxdepth 1 -type f -perm -u+x | head -1)
    [ -n "$exe" ] || fail "examples/c built no program"
    out=$(env -u LD_LIBRARY_PATH "$exe") || fail "examples/c: the program failed: $out"
    [ -n "$out" ] || fail "examples/c printed nothing"
    echo "$out"
fi

# 4. The components.
mkdir -p "$tmp/probe"
cat >"$tmp/probe/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(probe LANGUAGES CXX)
find_package(metariver CONFIG REQUIRED COMPONENTS ${WANT})
file(WRITE ${CMAKE_BINARY_DIR}/main.cpp "int main() { return 0; }\n")
add_executable(probe ${CMAKE_BINARY_DIR}/main.cpp)
list(TRANSFORM WANT PREPEND metariver::)
target_link_libraries(probe PRIVATE metariver::metariver ${WANT})
CMAKE
probe() {  # COMPONENTS (;-separated) -> configure and build; the log in $tmp/probe.log
    rm -rf "$tmp/probe/build"
    "$cmake" -S "$tmp/probe" -B "$tmp/probe/build" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_COMPILER="$cxx" \
        "-DWANT=$1" >"$tmp/probe.log" 2>&1 && "$cmake" --build "$tmp/probe/build" >>"$tmp/probe.log" 2>&1
}
expect_refused() {  # COMPONENT MESSAGE
    ! probe "$1" || fail "find_package(metariver COMPONENTS $1) succeeded; this build has: '$components'"
    grep -qF "$2" "$tmp/probe.log" || { cat "$tmp/probe.log"; fail "find_package(metariver COMPONENTS $1): no message '$2'"; }
    echo "component $1: refused, \"$(grep -oF "$2" "$tmp/probe.log" | head -1) ...\""
}
for c in render export; do
    if [[ ";$components;" == *";$c;"* ]]; then
        probe "$c" || { cat "$tmp/probe.log"; fail "find_package(metariver COMPONENTS $c) and linking metariver::$c"; }
        echo "component $c: found and linked"
    else
        expect_refused "$c" "component '$c' is not in this installation"
    fi
done
expect_refused nosuch "no component 'nosuch' (the components are render and export"
echo "PASS"
