#!/usr/bin/env bash
# Installs what is missing, lints every target (which keeps the benchmarks compiling), then runs
# every test with the Khronos validation layer on; then the fronts' tests: the Python package, the C ABI and the Blender
# add-on (each script installs what it needs). Extra arguments go to `cargo test`, e.g.
# `scripts/test.sh -- --nocapture`.
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
# Lints too: every target of the workspace (the engine, the CLI, its tests, benchmarks and
# examples, the Python and C fronts) with every feature, and the library as embedders build it;
# a lint that is wrong for a piece of code is allowed there, with the reason beside it. Checking
# every target is also what keeps the benchmarks compiling (running them is scripts/bench.sh's
# job and `cargo bench`'s).
if ! cargo clippy --version >/dev/null 2>&1; then
    rustup component add clippy
fi
cargo clippy --workspace --all-targets --all-features -- -D warnings
cargo clippy --lib --no-default-features -- -D warnings

# Every upload and readback through staging buffers, as on a discrete GPU whose working memory
# the host cannot see (lavapipe's can be): the whole suite runs that path once. The direct path
# (host-visible memory mapped in place) runs in the kernel passes below.
TAGSPLAT_FORCE_STAGING=1 cargo test --lib --bins --tests "$@"

# The GPU kernels again, on the direct memory path, at lavapipe's other subgroup sizes (the run
# above used its default, 256-bit vectors: 8 lanes). tests/gpu.rs checks that the size took effect.
kernel_tests=(--test gpu --test sort --test splat --test raster --test loss --test silhouette
    --test regularize --test optim --test deform --test flow)
if [[ "${VK_ICD_FILENAMES:-}" == *lvp_icd* ]]; then
    echo "== GPU kernels at subgroup size 4 (LP_NATIVE_VECTOR_WIDTH=128)"
    LP_NATIVE_VECTOR_WIDTH=128 cargo test "${kernel_tests[@]}" "$@"
    if grep -qw avx512f /proc/cpuinfo; then
        echo "== GPU kernels at subgroup size 16 (LP_NATIVE_VECTOR_WIDTH=512)"
        LP_NATIVE_VECTOR_WIDTH=512 cargo test "${kernel_tests[@]}" "$@"
    else
        echo "SKIPPED: subgroup size 16 (LP_NATIVE_VECTOR_WIDTH=512) needs AVX-512, which this CPU lacks"
    fi
fi
# The public API's documentation: every public item documented, every intra-doc link resolved.
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --lib

# The fronts: the C library and the `tagsplat` program in the `test` profile, the wheel in
# `fronts`: the Python package (pytest, its stubs against
# the module), the C ABI (C99 and C++17, leak checkers) and the Blender add-on on the same wheel.
bash scripts/test_python.sh
bash scripts/test_c.sh
bash scripts/test_blender.sh
