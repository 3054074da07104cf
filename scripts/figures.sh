#!/usr/bin/env bash
# Measures the README's figures and keeps each as a result file in benches/results/ (the
# command's `--json` output: the figure with its command line, commit, date, device, driver and
# host), then rewrites the README's table from those files (`tagsplat figures`).
#
#   scripts/figures.sh micro          the sort, splatting, render-only, training-iteration, mesh and
#                                     BVH benches
#   scripts/figures.sh demo           the demo
#   scripts/figures.sh sequences      every benchmark sequence in $BENCH (all frames)
#   scripts/figures.sh NAME...        one benchmark sequence each (fox_walk, fox_run, ...)
#   scripts/figures.sh NAME+CONFIG    the same with --config benches/configs/CONFIG.toml (an
#                                     ablation row: fox_run_textured+anchor)
#   scripts/figures.sh table          only rewrite the README's table
#
# BENCH (required for sequences) is the folder that holds the benchmark sequences (see
# docs/benchmarks.md); their training runs go to
# $RUNS/NAME (default /tmp/tagsplat-figures), started afresh unless RESUME=1 (then an interrupted
# run goes on from its last complete frame). A measurement replaces its result file only when it
# succeeds. Measure on a quiet host: the figures include times.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/setup.sh
. scripts/env.sh
cargo build --release --features cli
tagsplat=${CARGO_TARGET_DIR:-target}/release/tagsplat
RUNS=${RUNS:-/tmp/tagsplat-figures}
mkdir -p benches/results "$RUNS"

# record NAME COMMAND...: runs `tagsplat COMMAND... --json` into benches/results/NAME.json.
record() {
    local name=$1
    shift
    local file=benches/results/$name.json
    echo "== $name: tagsplat $*"
    "$tagsplat" "$@" --json >"$file.tmp"
    mv "$file.tmp" "$file"
}

# sequence NAME or NAME+CONFIG: a benchmark sequence, with benches/configs/CONFIG.toml if named.
sequence() {
    : "${BENCH:?set BENCH to the folder that holds the benchmark sequences}"
    local name=${1%%+*} config=()
    [[ $1 == *+* ]] && config=(--config "benches/configs/${1#*+}.toml")
    [[ ${RESUME:-0} == 1 ]] || rm -rf "${RUNS:?}/$1"
    record "sequence-$1" bench sequence --data "$BENCH/$name" --out "$RUNS/$1" "${config[@]}"
}

for what in "${@:-table}"; do
    case $what in
    micro)
        record sort bench sort --n 4194304 --bits 32
        record splat bench splat
        record render bench render --gaussians 1000000 --width 1920 --height 1080 --views 2 --sh-degree 2
        record train bench train
        record mesh bench mesh
        record track bench track
        ;;
    demo)
        rm -rf "${RUNS:?}/demo"
        record demo demo --out "$RUNS/demo"
        ;;
    sequences)
        for dir in "$BENCH"/*/; do
            sequence "$(basename "$dir")"
        done
        ;;
    table) ;;
    *) sequence "$what" ;;
    esac
done
"$tagsplat" figures
