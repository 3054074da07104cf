#!/usr/bin/env bash
# Installs what is missing, then runs every test with the Khronos validation layer on, and
# builds the benchmarks so they at least compile (running them is scripts/bench.sh's job and
# `cargo bench`'s). Extra arguments go to `cargo test`, e.g. `scripts/test.sh -- --nocapture`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

bash scripts/setup.sh
. scripts/env.sh
export TAGSPLAT_VALIDATION=1

# Formatting is part of the check (rustfmt.toml); a minimal toolchain profile may lack rustfmt.
if ! cargo fmt --version >/dev/null 2>&1; then
    rustup component add rustfmt
fi
cargo fmt --check

cargo test --lib --bins --tests "$@"
# The library builds without the command-line program's crates (how embedders take it).
cargo check --lib --no-default-features
cargo build --benches
