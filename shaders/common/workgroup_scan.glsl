// Workgroup-wide exclusive sum of one uint per invocation, for any subgroup size.
// Needs: GL_KHR_shader_subgroup_arithmetic, and MAX_SUBGROUPS >= gl_NumSubgroups defined
// before inclusion. Every invocation of the workgroup must call it (it has barriers).
#ifndef COMMON_WORKGROUP_SCAN_GLSL
#define COMMON_WORKGROUP_SCAN_GLSL

shared uint wg_scan_partials[MAX_SUBGROUPS];
shared uint wg_scan_total;

// Returns the sum of `value` over lower invocation indices; `total` gets the sum over all.
uint workgroup_exclusive_add(uint value, out uint total) {
    uint inclusive = subgroupInclusiveAdd(value);
    if (gl_SubgroupInvocationID == gl_SubgroupSize - 1u) {
        wg_scan_partials[gl_SubgroupID] = inclusive;
    }
    barrier();
    // Subgroup 0 scans the per-subgroup sums; there can be more of them than lanes
    // (lavapipe: 8 lanes, 32 subgroups in 256 invocations), so it walks them in chunks.
    if (gl_SubgroupID == 0u) {
        uint carry = 0u;
        for (uint base = 0u; base < gl_NumSubgroups; base += gl_SubgroupSize) {
            uint i = base + gl_SubgroupInvocationID;
            uint partial = i < gl_NumSubgroups ? wg_scan_partials[i] : 0u;
            uint prefix = subgroupExclusiveAdd(partial);
            if (i < gl_NumSubgroups) {
                wg_scan_partials[i] = carry + prefix;
            }
            carry += subgroupAdd(partial);
        }
        if (gl_SubgroupInvocationID == 0u) {
            wg_scan_total = carry;
        }
    }
    barrier();
    total = wg_scan_total;
    uint result = wg_scan_partials[gl_SubgroupID] + inclusive - value;
    barrier(); // The shared arrays may be reused by the next call.
    return result;
}

#endif
