#!/usr/bin/env bash
# The Python package's checks: builds the wheel (profile `fronts`: maturin cannot build in the
# `test` profile) and the `tagsplat` program the tests compare against (profile `test`), installs
# it into a venv of its own, checks the stubs against the module, and runs tests/python.
# Idempotent: the venv and the builds are reused; run it again after any change.
#     scripts/test_python.sh [pytest arguments]
# The wheel is left in target/wheels/ (tagsplat-<version>-cp311-abi3-<platform>.whl).
set -euo pipefail
cd "$(dirname "$0")/.."

venv=.tools/python-venv
# Pinned, so every run and CI tests with the same tools.
tools=(maturin==1.9.6 numpy==2.2.6 pytest==8.4.2 mypy==1.18.2)
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
# The tools installed last are listed in the venv; a different list reinstalls.
if [ "$(cat "$venv/tools.txt" 2>/dev/null)" != "${tools[*]}" ]; then
    "$venv/bin/python" -m pip install --quiet "${tools[@]}"
    echo "${tools[*]}" >"$venv/tools.txt"
fi

cargo build --profile test --bin tagsplat
"$venv/bin/maturin" build --profile fronts --manifest-path tools/python/Cargo.toml \
    --out target/wheels --interpreter "$venv/bin/python"
version=$(sed -n 's/^version = "\(.*\)"/\1/p' tools/python/Cargo.toml | head -n 1)
wheel=$(ls -t target/wheels/tagsplat-"$version"-cp311-abi3-*.whl | head -n 1)
"$venv/bin/python" -m pip install --quiet --force-reinstall --no-deps "$wheel"

# The stubs (tools/python/python/tagsplat/_tagsplat.pyi) against the built module.
# (tagsplat covers its submodule tagsplat._tagsplat.)
(cd tests/python && "../../$venv/bin/python" -m mypy.stubtest tagsplat)

. scripts/env.sh
export TAGSPLAT_VALIDATION=1 TAGSPLAT_CLI="$PWD/target/debug/tagsplat"
"$venv/bin/python" -m pytest tests/python -q "$@"
