#!/usr/bin/env bash
# The main benchmark: a GPU radix sort of 4 Mi pairs of 32-bit keys, measured against the
# bounds of the same run (see `tagsplat bench sort --help`). Extra arguments go to it, e.g.
# `scripts/bench.sh --json`. Runs on lavapipe unless TAGSPLAT_ANY_GPU=1 or VK_ICD_FILENAMES
# says otherwise (scripts/env.sh).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/setup.sh
. scripts/env.sh

cargo build --release --quiet
cargo run --release --quiet -- bench sort --n 4194304 --bits 32 "$@"
