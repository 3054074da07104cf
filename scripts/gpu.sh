#!/usr/bin/env bash
# A GPU check in one call, for a machine lent for minutes that has a GPU but no Rust toolchain
# (docs/gpu.md records the last one). Two halves:
#
#   BENCH=DIR bash scripts/gpu.sh pack   here: builds the release program and the test
#                                        binaries, strips them and packs them into .gpu/
#                                        (git-ignored) with DIR/fox_walk and Debian's Vulkan
#                                        loader and validation layer
#   bash scripts/gpu.sh run OUT          there, in the repo root with .gpu carried: the tests
#                                        (validation on), the benches as JSON, fox_walk; writes
#                                        OUT/gpu.log and OUT/gpu-results.tar.gz
#
# QUICK=1 with `run` skips the tests and shrinks the benches and fox_walk to a minute or two
# on lavapipe: a dry run of the script itself. The device machine returns at most 8 files,
# hence one archive for the results.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
PACK=.gpu

pack() {
    : "${BENCH:?set BENCH to the folder that holds the benchmark sequences}"
    bash scripts/setup.sh
    . scripts/env.sh
    rm -rf "$PACK" && mkdir -p "$PACK/tests" "$PACK/debs"
    cargo build --release --features cli
    cp target/release/tagsplat "$PACK/"
    cargo test --release --no-run --message-format=json |
        python3 -c 'import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m["profile"]["test"]:
        print(m["executable"])' | while read -r test; do
        cp "$test" "$PACK/tests/"
    done
    # The test binaries read their fixtures through the path they were built at.
    pwd >"$PACK/built_at"
    strip "$PACK/tagsplat" "$PACK"/tests/*
    tar -C "$PACK" -cJf "$PACK/tests.tar.xz" tests && rm -r "$PACK/tests"
    cp -r "$BENCH/fox_walk" "$PACK/fox_walk"
    (cd "$PACK/debs" && apt-get download libvulkan1 vulkan-validationlayers)
    du -sh "$PACK"
}

# The Vulkan loader and validation layer from the packed debs, unpacked beside the system
# (unpacking into / can break a lent machine), and the NVIDIA driver where the machine has one.
vulkan_env() {
    for deb in "$PACK"/debs/*.deb; do dpkg -x "$deb" /tmp/vk; done
    export LD_LIBRARY_PATH=/tmp/vk/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export VK_LAYER_PATH=/tmp/vk/usr/share/vulkan/explicit_layer.d
    local icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
    if [ -f "$icd" ]; then
        export VK_DRIVER_FILES=$icd VK_ICD_FILENAMES=$icd
    else
        . scripts/env.sh
    fi
    export TAGSPLAT_ANY_GPU=1
}

# The tests, each binary in turn, with validation on; their fixtures are reached through the
# path they were built at (`built_at`), linked to this checkout where it is missing.
run_tests() {
    local built
    built=$(cat "$PACK/built_at")
    if [ ! -e "$built" ]; then
        mkdir -p "$(dirname "$built")" && ln -s "$PWD" "$built"
    fi
    mkdir -p /tmp/gpu-tests && tar -C /tmp/gpu-tests -xJf "$PACK/tests.tar.xz"
    for test in /tmp/gpu-tests/tests/*; do
        echo "== test $(basename "$test")"
        TAGSPLAT_VALIDATION=1 "$test" 2>&1 | grep -E '^test result|FAILED|panicked|SKIPPED' || true
    done
}

# bench NAME ARGS...: `tagsplat bench ARGS... --json` into $results/NAME.json, its time logged.
bench() {
    local name=$1
    shift
    echo "== bench $name: $*"
    local started=$SECONDS
    "$PACK/tagsplat" bench "$@" --json >"$results/$name.json" || echo "FAILED: $name"
    echo "   $((SECONDS - started)) s"
}

run() {
    local out=${1:?usage: gpu.sh run OUT}
    results=$(mktemp -d)
    mkdir -p "$out"
    {
        vulkan_env
        nvidia-smi -L 2>/dev/null || true
        "$PACK/tagsplat" devices
        local big=1000000 many=6000000 sort_n=4194304 wide=(--width 1920 --height 1080) frames=()
        if [ "${QUICK:-0}" = 1 ]; then
            big=20000 many=40000 sort_n=262144 wide=(--width 320 --height 180) frames=(--frames 0..1)
        else
            run_tests
        fi
        for variant in onesweep subgroups lanes; do
            bench "sort-$variant" sort --n "$sort_n" --bits 32 --variant "$variant"
        done
        bench splat splat
        bench render-1m render --gaussians "$big" "${wide[@]}" --views 2 --sh-degree 2
        bench render-6m render --gaussians "$many" "${wide[@]}" --views 2 --sh-degree 2
        bench train train
        bench train-1-in-flight train --in-flight 1
        bench train-1080p train "${wide[@]}"
        bench mesh mesh
        rm -rf /tmp/gpu-fox_walk
        bench sequence-fox_walk sequence --data "$PACK/fox_walk" --out /tmp/gpu-fox_walk "${frames[@]}"
    } 2>&1 | tee "$out/gpu.log"
    tar -C "$results" -czf "$out/gpu-results.tar.gz" .
}

case ${1:-} in
pack) pack ;;
run) run "${2:-}" ;;
*) echo "usage: BENCH=DIR gpu.sh pack | gpu.sh run OUT" >&2 && exit 2 ;;
esac
