#!/bin/bash
# The GPU PBF step and field on a lent GPU machine (the workplace's `device` tool), in one short run.
#
#   bash scripts/device_gpu.sh prepare   # here: build, bundle the two programs and their
#                                       # libraries into .devrun/, fetch glvnd's EGL into .gl/
#   then the device tool: run `bash scripts/device_gpu.sh run` with carry [".devrun", ".gl"]
#
# `run` (on the GPU machine, which has NVIDIA's driver but none of our Debian libraries):
# unpacks the bundle, runs the GPU twin tests (tests/gpu/, gpu_tests) on the real
# GPU, then `metariver bench --scenario w3 --gpu` at nx = 32, 46, 58, 100 (CPU rows on 2
# threads of that host beside them) and 126, 160, 200, 250 (GPU only: 1 to 7.8 million
# particles), and `bench --scenario w1 --gpu` (the field of the peers' metaball workload
# on the GPU beside ours). Into $OUT: gpu.txt (the machine), tests.txt and gpu_all.json (every bench
# JSON by file name). Both folders are in .git/info/exclude; the bundle is ~15 MB.
set -euo pipefail
cd "$(dirname "$0")/.."

case "${1:-}" in
prepare)
    cmake --build --preset default --target metariver gpu_tests
    grep -qx '/.devrun/' .git/info/exclude || echo /.devrun/ >> .git/info/exclude
    grep -qx '/.gl/' .git/info/exclude || echo /.gl/ >> .git/info/exclude
    stage=$(mktemp -d)
    mkdir -p "$stage/devrun/lib" .devrun .gl
    # Every shared library both programs load, but glibc's and the C++ runtime (the GPU
    # machine's are newer, and NVIDIA's driver may need them).
    { ldd build/default/apps/metariver; ldd build/default/tests/gpu_tests; } | awk '$3 ~ /^\// {print $3}' | sort -u |
        grep -v -E '/(libc|libm|libdl|libpthread|librt|libstdc\+\+|libgcc_s)\.so|ld-linux' |
        xargs -I{} cp -L {} "$stage/devrun/lib/"
    strip -o "$stage/devrun/metariver" build/default/apps/metariver
    strip -o "$stage/devrun/gpu_tests" build/default/tests/gpu_tests
    tar czf .devrun/bundle.tgz -C "$stage" devrun
    rm -rf "$stage"
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    mkdir -p /tmp/amd64/partial
    apt-get $o update > /dev/null
    (cd .gl && apt-get $o download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
    ls -la .devrun .gl
    ;;
run)
    : "${OUT:?run on the device machine, where OUT is set}"
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
    tar xzf .devrun/bundle.tgz -C /tmp
    export LD_LIBRARY_PATH=/tmp/devrun/lib
    B=/tmp/devrun/metariver
    mkdir -p /tmp/j
    { nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv; lscpu | grep -E 'Model name|^CPU\(s\)'; } |
        tee "$OUT/gpu.txt" || true
    timeout 120 /tmp/devrun/gpu_tests > "$OUT/tests.txt" 2>&1 || true
    grep -E 'OK|FAIL|Failure|Expected|actual|Which|Skipped' "$OUT/tests.txt" || true
    for nx in 32 46 58 100; do
        timeout 120 $B bench --scenario w3 --gpu --nx $nx --threads 2 --warmup 3 --frames 20 --json /tmp/j/w3_$nx.json || true
    done
    for nx in 126 160 200 250; do
        timeout 120 $B bench --scenario w3 --gpu --nx $nx --warmup 3 --frames 20 --json /tmp/j/w3_$nx.json || true
    done
    # W1's field (the peers' metaball workload, five sizes) on the GPU beside ours on 2 threads.
    timeout 120 $B bench --scenario w1 --gpu --threads 2 --json /tmp/j/w1.json || true
    python3 -c "
import glob, json
print(json.dumps({f: json.load(open(f)) for f in sorted(glob.glob('/tmp/j/*.json'))}))" > "$OUT/gpu_all.json"
    ;;
*)
    echo "usage: bash scripts/device_gpu.sh prepare|run" >&2
    exit 2
    ;;
esac
