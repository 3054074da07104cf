#!/usr/bin/env bash
# Installs the system packages tagsplat needs on Debian 12 (Rust toolchain assumed present):
# the Vulkan loader and headers, Mesa's drivers (lavapipe, the CPU device CI tests on), the
# Khronos validation layer the tests use as an oracle, and the shader tools and shaderc
# libraries build.rs compiles shaders/ with. Idempotent: packages already installed are
# skipped, and when none is missing it touches neither the network nor apt's lists.
set -euo pipefail

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

if [ "${#missing[@]}" -eq 0 ]; then
    echo "setup.sh: all ${#packages[@]} system packages already installed, nothing to do"
    exit 0
fi

as_root=()
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        as_root=(sudo)
    else
        echo "setup.sh: not root and no sudo; as root, install: ${missing[*]}" >&2
        exit 1
    fi
fi

export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup.sh: installed ${#missing[@]} missing package(s): ${missing[*]}"
