#!/usr/bin/env bash
# Installs the system packages tagsplat needs on Debian 12 (Rust toolchain assumed present):
# the Vulkan loader and headers, Mesa's drivers (lavapipe, the CPU device CI tests on), the
# Khronos validation layer the tests use as an oracle, the shader tools and shaderc libraries
# build.rs compiles shaders/ with, and Chromium, which renders OUT/report.html headless in
# tests/report.rs. Idempotent: packages already installed are skipped, and when none is
# missing it touches neither the network nor apt's lists.
# Then, optionally, the Khronos glTF validator (npm `gltf-validator`) and Pixar's USD library
# (PyPI `usd-core`), under .tools/, that the GLB and USD tests run: when npm, python3-venv or
# the network is missing it warns and the tests say they skipped them.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

packages=(
    mesa-vulkan-drivers
    libvulkan1
    libvulkan-dev
    vulkan-tools
    glslang-tools
    glslc
    libshaderc-dev
    glslang-dev
    spirv-tools
    vulkan-validationlayers
    chromium
)

missing=()
for package in "${packages[@]}"; do
    # One status line per installed architecture; any fully installed one will do.
    status=$(dpkg-query -W -f='${Status}\n' "$package" 2>/dev/null || true)
    if ! grep -qx 'install ok installed' <<<"$status"; then
        missing+=("$package")
    fi
done

as_root=()
if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
fi
can_install() { [ "$(id -u)" -eq 0 ] || [ "${#as_root[@]}" -gt 0 ]; }
apt_updated=0
apt_install() {
    if [ "$apt_updated" -eq 0 ]; then
        "${as_root[@]}" apt-get update -qq
        apt_updated=1
    fi
    "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}

if [ "${#missing[@]}" -eq 0 ]; then
    echo "setup.sh: all ${#packages[@]} system packages already installed"
elif ! can_install; then
    echo "setup.sh: not root and no sudo; as root, install: ${missing[*]}" >&2
    exit 1
else
    apt_install "${missing[@]}"
    echo "setup.sh: installed ${#missing[@]} missing package(s): ${missing[*]}"
fi

# The glTF validator and Pixar's USD library (PyPI `usd-core`), both under .tools/: optional,
# never fatal here; the tests that use them say SKIPPED without them (and fail when CI=true).
install_gltf_validator() {
    local version=2.0.0-dev.3.10
    local dir="$root/.tools/gltf-validator"
    local package="$dir/node_modules/gltf-validator/package.json"
    if [ -f "$package" ] && grep -q "\"version\": \"$version\"" "$package"; then
        echo "setup.sh: gltf-validator $version already installed"
        return
    fi
    if ! command -v npm >/dev/null 2>&1 && can_install; then
        apt_install nodejs npm || true
    fi
    if command -v npm >/dev/null 2>&1 && npm install --prefix "$dir" --no-audit --no-fund \
            --loglevel=error "gltf-validator@$version" >/dev/null; then
        echo "setup.sh: installed gltf-validator $version into $dir"
    else
        echo "setup.sh: WARNING: could not install the glTF validator (no npm or no network);" \
            "the GLB validation tests will report that they SKIPPED it" >&2
    fi
}

install_usd_core() {
    local version=26.11
    local venv="$root/.tools/usd"
    if "$venv/bin/python" -c "import pxr.Usd as u; assert u.GetVersion() == (0, ${version%%.*}, ${version#*.})" 2>/dev/null; then
        echo "setup.sh: usd-core $version already installed"
        return
    fi
    if ! python3 -c "import ensurepip" 2>/dev/null && can_install; then
        apt_install python3-venv || true
    fi
    if python3 -m venv "$venv" >/dev/null && "$venv/bin/pip" install -q "usd-core==$version"; then
        echo "setup.sh: installed usd-core $version into $venv"
    else
        echo "setup.sh: WARNING: could not install usd-core (no python3-venv or no network);" \
            "the USD tests will report that they SKIPPED it" >&2
    fi
}

install_gltf_validator
install_usd_core
