#!/usr/bin/env bash
# The ctests of the Python package and the Blender add-on (tests/CMakeLists.txt).
# Usage: run_ctest.sh pytest|example|blender LIBRARY OUT_DIR
#   pytest : /usr/bin/python3 -m pytest python/tests, METARIVER_LIBRARY=LIBRARY
#   example: pip install --no-build-isolation --no-deps --target OUT_DIR/site python/ (copies
#            LIBRARY into the package), then examples/python/example.py in a fresh process
#            whose only path to the package is PYTHONPATH=OUT_DIR/site
#   blender: blender -b --factory-startup --python tests/blender/bake_test.py -- OUT_DIR
# A missing numpy, pytest or blender skips (exit 77), or fails under METARIVER_REQUIRE_ALL=1.
set -euo pipefail
mode=$1 lib=$2 out=$3
repo=$(cd "$(dirname "$0")/../.." && pwd)
py=/usr/bin/python3
missing() {
  if [ "${METARIVER_REQUIRE_ALL:-}" = 1 ]; then echo "METARIVER_REQUIRE_ALL=1 and $1 is missing" >&2; exit 1; fi
  echo "skipped: $1 is missing (scripts/install-deps.sh installs it)"; exit 77
}
"$py" -c "import numpy" 2>/dev/null || missing "numpy for $py (python3-numpy)"
rm -rf "$out" && mkdir -p "$out"
case $mode in
  pytest)
    "$py" -c "import pytest" 2>/dev/null || missing "pytest for $py (python3-pytest)"
    cd "$repo/python"
    METARIVER_LIBRARY=$lib exec "$py" -m pytest -q -p no:cacheprovider tests ;;
  example)
    # from a copy of python/ (beside a link to CMakeLists.txt, the version's source): pip's
    # build writes build/ and *.egg-info next to setup.py, not into the checkout
    mkdir -p "$out/src"
    cp -r "$repo/python" "$out/src/python"
    rm -rf "$out/src/python/build" "$out/src/python/"*.egg-info
    ln -s "$repo/CMakeLists.txt" "$out/src/CMakeLists.txt"
    METARIVER_LIBRARY=$lib "$py" -m pip install -q --root-user-action=ignore --no-build-isolation --no-deps --target "$out/site" "$out/src/python"
    test -f "$out/site/metariver/libmetariver.so"
    cd "$out"
    exec env -i PATH=/usr/bin:/bin HOME="$out" PYTHONPATH="$out/site" "$py" "$repo/examples/python/example.py" ;;
  blender)
    command -v blender >/dev/null 2>&1 || missing "blender"
    export METARIVER_LIBRARY=$lib
    exec blender -b --factory-startup --python-exit-code 1 --python "$repo/tests/blender/bake_test.py" -- "$out" ;;
  *) echo "run_ctest.sh: unknown mode '$mode' (pytest, example, blender)" >&2; exit 2 ;;
esac
