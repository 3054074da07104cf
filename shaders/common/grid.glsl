// Flat workgroup index of a 1-D grid that the host folded into x and y
// (Recorder::dispatch_1d) to stay under maxComputeWorkGroupCount[0].
#ifndef COMMON_GRID_GLSL
#define COMMON_GRID_GLSL

uint flat_workgroup_id() {
    return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
}

#endif
