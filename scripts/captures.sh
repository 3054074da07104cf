#!/usr/bin/env bash
# Trains the paper's two capture sizes on generated data, two frames each with a short schedule
# (enough to pass every stage that sizes buffers by the views: the first mesh, frame 0, the
# silhouette term and the graph of frame 1), and prints what each run reports: the time to frame
# 0's first iteration and where it went, the peak host and device memory, the estimate.
#
#   scripts/captures.sh [OUT]     generated data and runs under OUT (default /tmp/tagsplat-captures)
#
# 42 views at 1080² run at full size; 30 views at 3000 × 4000 at --scale 0.25 (and are refused at
# full size on a device whose largest buffer is under 367 MiB, lavapipe's included).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/setup.sh
. scripts/env.sh
cargo build --release --features cli
tagsplat=${CARGO_TARGET_DIR:-target}/release/tagsplat
OUT=${1:-/tmp/tagsplat-captures}
mkdir -p "$OUT"
cat >"$OUT/short.toml" <<'TOML'
[canonical]
iterations = 20
densify_from = 5
densify_until = 15
densify_every = 5
[temporal]
iterations = 10
min_iterations = 5
colour_iterations = 2
[temporal.graph]
iterations = 10
min_iterations = 5
TOML

# capture NAME SYNTH_ARGS... -- TRAIN_ARGS...
capture() {
    local name=$1 data=$OUT/$1 synth=() train=()
    shift
    while [[ $# -gt 0 && $1 != -- ]]; do synth+=("$1"); shift; done
    [[ $# -gt 0 ]] && shift
    train=("$@")
    [[ -f $data/dataset.json ]] || "$tagsplat" synth --out "$data" --frames 2 "${synth[@]}"
    rm -rf "$data-run"
    echo "== $name: tagsplat train --data $data --out $data-run --config $OUT/short.toml ${train[*]}"
    "$tagsplat" train --data "$data" --out "$data-run" --config "$OUT/short.toml" "${train[@]}" >/dev/null
    grep -v " config |" "$data-run/run.log"
    grep -E '"(dataset_s|mesh_s|views_s|first_iteration_s|peak_host_bytes|peak_device_bytes|device_bytes|host_bytes)"' \
        "$data-run/report.json"
}

capture views42-1080 --views 42 --resolution 1080
capture views30-3000x4000 --views 30 --width 3000 --height 4000 --samples 2 -- --scale 0.25
echo "== views30-3000x4000 at full size:"
"$tagsplat" dataset info --data "$OUT/views30-3000x4000" | grep -E "^memory|refused"
