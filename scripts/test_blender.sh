#!/usr/bin/env bash
# The Blender add-on's checks (tools/blender, tests/blender): installs Debian's Blender 3.4 and
# the numpy its Python imports when they are missing (as root: apt-get), installs the newest
# tagsplat wheel from target/wheels (built by scripts/test_python.sh) into .tools/blender-site,
# and runs tests/blender inside `blender -b` with the Khronos validation layer on.
# Idempotent; extra arguments go to tests/blender/run.py, e.g. `scripts/test_blender.sh -k track`.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v blender >/dev/null || ! dpkg -s python3-numpy >/dev/null 2>&1; then
    if [ "$(id -u)" != 0 ]; then
        echo "blender or python3-numpy is missing: run this as root, or apt-get install them" >&2
        exit 1
    fi
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        blender python3-numpy >/dev/null
fi

wheel=$(ls -t target/wheels/tagsplat-*-cp311-abi3-*.whl 2>/dev/null | head -n 1 || true)
if [ -z "$wheel" ]; then
    echo "no tagsplat wheel in target/wheels: build it with scripts/test_python.sh" >&2
    exit 1
fi
# The wheel's own files only (Blender's Python has Debian's numpy), replacing an older install;
# skipped when this very wheel (name, size, time) is installed already.
site=.tools/blender-site
installed="$(basename "$wheel") $(stat -c %s-%Y "$wheel")"
if [ "$(cat "$site/.wheel" 2>/dev/null)" != "$installed" ]; then
    python3 -m pip install --quiet --no-deps --upgrade --root-user-action=ignore \
        --disable-pip-version-check --target "$site" "$wheel"
    echo "$installed" >"$site/.wheel"
fi

. scripts/env.sh
export TAGSPLAT_VALIDATION=1
blender -b --factory-startup --python-exit-code 1 --python tests/blender/run.py -- \
    --package-folder "$PWD/$site" --cli "$PWD/target/debug/tagsplat" "$@"
