# Environment for tagsplat's tests and benchmarks. Source it, do not execute it:
#     . scripts/env.sh
# Safe under `set -euo pipefail` in the sourcing shell; changes nothing the user already set.

# Run on lavapipe (Mesa's CPU Vulkan device) by default, as CI does, so results do not depend
# on whichever GPU the machine has. The loader then sees only the lavapipe ICD. Left alone when
# the user chose drivers (VK_ICD_FILENAMES, or VK_DRIVER_FILES of newer loaders) or asked for
# any device with TAGSPLAT_ANY_GPU=1 (then TAGSPLAT_DEVICE or the engine's policy picks).
if [ -z "${VK_ICD_FILENAMES+set}" ] && [ -z "${VK_DRIVER_FILES+set}" ] && [ "${TAGSPLAT_ANY_GPU:-}" != 1 ]; then
    export VK_ICD_FILENAMES="/usr/share/vulkan/icd.d/lvp_icd.$(uname -m).json"
fi

# LP_NUM_THREADS (lavapipe's worker threads) is deliberately left alone: unset, lavapipe uses
# one thread per CPU, which is what both tests and benchmarks want. Set it yourself to pin it.
