#!/usr/bin/env bash
# The main job: `tagsplat demo` generates a deforming synthetic subject seen by 10 cameras,
# reconstructs its topology-consistent mesh sequence, tracks its ground-truth surface points and
# scores everything against the ground truth (minutes on a 2-core CPU through lavapipe). Extra
# arguments go to it, e.g. `scripts/demo.sh --out /tmp/demo --frames 10`. Runs on lavapipe
# unless TAGSPLAT_ANY_GPU=1 or VK_ICD_FILENAMES says otherwise (scripts/env.sh).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/setup.sh
. scripts/env.sh

cargo build --release --quiet
cargo run --release --quiet -- demo "$@"
