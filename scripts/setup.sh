#!/usr/bin/env bash
# Installs the system packages tagsplat needs on Debian 12 (Rust toolchain assumed present):
# the Vulkan loader and headers, Mesa's drivers (lavapipe, the CPU device CI tests on), the
# Khronos validation layer the tests use as an oracle, and the shader tools and shaderc
# libraries build.rs compiles shaders/ with. Idempotent: packages already installed are
# skipped, and when none is missing it touches neither the network nor apt's lists.
# Then, optionally, the Khronos glTF validator (npm `gltf-validator`, under .tools/) that the
# GLB tests run: when npm or the network is missing it warns and the tests say they skipped it.
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

# The glTF validator: optional, never fatal.
validator_version=2.0.0-dev.3.10
validator_dir="$root/.tools/gltf-validator"
validator_package="$validator_dir/node_modules/gltf-validator/package.json"
if [ -f "$validator_package" ] && grep -q "\"version\": \"$validator_version\"" "$validator_package"; then
    echo "setup.sh: gltf-validator $validator_version already installed"
    exit 0
fi
if ! command -v npm >/dev/null 2>&1 && can_install; then
    apt_install nodejs npm || true
fi
if command -v npm >/dev/null 2>&1 && npm install --prefix "$validator_dir" --no-audit --no-fund --loglevel=error \
        "gltf-validator@$validator_version" >/dev/null; then
    echo "setup.sh: installed gltf-validator $validator_version into $validator_dir"
else
    echo "setup.sh: WARNING: could not install the glTF validator (no npm or no network);" \
        "the GLB validation tests will report that they SKIPPED it" >&2
fi
