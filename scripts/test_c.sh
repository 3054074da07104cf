#!/usr/bin/env bash
# The C ABI's tests: builds libtagsplat_c (whose build fails when the committed
# tools/capi/include/tagsplat.h is not what cbindgen generates) and the `tagsplat` program, makes
# a tiny dataset with it, then
#   - compiles tests/c/smoke.c as C99 and tests/c/header.cpp as C++17, warnings as errors;
#   - runs the smoke test under AddressSanitizer + LeakSanitizer (every call, every error path,
#     a short training run, cancels, a resume) and compares its meshes with the CLI's, byte for
#     byte;
#   - runs 1000 create/free cycles of every handle and a cancelled job under LeakSanitizer, and
#     (fewer, as valgrind is slow on lavapipe) under valgrind;
# with the Khronos validation layer on: any validation message fails. Idempotent; installs gcc,
# g++ and valgrind through apt when missing. CYCLES and VALGRIND_CYCLES override the counts.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

missing=()
command -v cc >/dev/null || missing+=(gcc)
command -v c++ >/dev/null || missing+=(g++)
command -v valgrind >/dev/null || missing+=(valgrind)
if ((${#missing[@]})); then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi

. scripts/env.sh
export TAGSPLAT_VALIDATION=1
# The header is checked, never rewritten, here.
unset TAGSPLAT_WRITE_HEADER

cargo build --profile test -p tagsplat-capi
cargo build --profile test --bin tagsplat
lib=target/debug
tagsplat=$lib/tagsplat
work=target/c-smoke
rm -rf "$work"
mkdir -p "$work"

step() { printf '== %s (%ds)\n' "$1" "$SECONDS"; }
# Runs a command with its stderr kept in $work/$1.log as well; a validation message fails.
logged() {
    local name=$1
    shift
    "$@" 2> >(tee "$work/$name.log" >&2)
    if grep -q '\[vulkan validation\]' "$work/$name.log"; then
        echo "FAILED: $name: the Vulkan validation layer reported messages (above)" >&2
        return 1
    fi
}

step "data: tagsplat synth, convert, and the CLI's training run"
"$tagsplat" synth --out "$work/data" --views 4 --frames 2 --resolution 64 --subdivisions 2 \
    --samples 1 --track-vertices 6 --track-surface 6 >/dev/null
"$tagsplat" convert --sequence "$work/data/meshes" --to "$work/gt.pc2" >/dev/null
cp tests/c/train.toml "$work/train.toml"
logged cli_train "$tagsplat" train --data "$work/data" --out "$work/cli_out" \
    --config "$work/train.toml" >/dev/null

step "compile: C99 and C++17, warnings as errors"
include=(-I tools/capi/include)
link=(-L "$lib" -ltagsplat_c "-Wl,-rpath,$PWD/$lib" -lpthread -lm)
# The leak checkers run with lavapipe and the validation layer kept loaded (the Vulkan loader
# unloads them with each instance; see tests/c/lsan.supp): the libraries the loader's manifests
# name, when they are these.
library_of() { sed -n 's/.*"library_path": *"\([^"]*\)".*/\1/p' "$1"; }
keep=()
if [[ "${VK_ICD_FILENAMES:-}" == *lvp_icd* ]]; then
    keep+=("$(library_of "$VK_ICD_FILENAMES")")
fi
layer=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
if [[ -f $layer ]]; then
    keep+=("$(library_of "$layer")")
fi
export SMOKE_KEEP_LOADED=$(IFS=:; echo "${keep[*]}")
c99=(cc -std=c99 -Wall -Wextra -Werror -pedantic -g "${include[@]}" tests/c/smoke.c)
"${c99[@]}" -o "$work/smoke" "${link[@]}" -ldl
"${c99[@]}" -fsanitize=address -fno-omit-frame-pointer -o "$work/smoke_asan" "${link[@]}" -ldl
c++ -std=c++17 -Wall -Wextra -Werror -pedantic "${include[@]}" -x c++ tests/c/header.cpp \
    -o "$work/header_cpp" -x none "$lib/libtagsplat_c.a" -lpthread -ldl -lm
"$work/header_cpp"

# LeakSanitizer reports leaks at exit; the validation layer's are suppressed (see the file).
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0
export LSAN_OPTIONS="suppressions=$PWD/tests/c/lsan.supp:print_suppressions=0"

step "smoke test under AddressSanitizer"
logged smoke "$work/smoke_asan" full "$work"

step "meshes: the C runs against the CLI's, byte for byte"
for out in c_out resume_out; do
    diff -r "$work/cli_out/meshes" "$work/$out/meshes"
    echo "$out/meshes: $(ls "$work/$out/meshes" | wc -l) files identical to cli_out/meshes"
done

step "leaks: ${CYCLES:=1000} create/free cycles of every handle under LeakSanitizer"
logged cycles_lsan "$work/smoke_asan" cycles "$CYCLES" "$work"

step "leaks: ${VALGRIND_CYCLES:=10} cycles under valgrind"
logged cycles_valgrind valgrind --quiet --leak-check=full --errors-for-leak-kinds=definite,indirect \
    --error-exitcode=1 --suppressions=tests/c/valgrind.supp \
    "$work/smoke" cycles "$VALGRIND_CYCLES" "$work"

step "C ABI tests passed"
