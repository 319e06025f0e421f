#define COUNT_OVERFLOW 4  // src/cl/types.rs (the program prepends its generated constants)
// The wide traversal of kernels/traverse_wide.h as a plain function over a range of rays, to be
// compiled by clang for the host CPU (build.sh) instead of by PoCL. With passes = 2 each ray is
// traced twice in a row: the second walk finds its nodes and triangles in the cache.
void trace_range(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                 global const GpuRay* rays, uint first, uint end, global GpuHit* hits,
                 volatile global uint* counters, uint passes) {
    SceneSurfaces surf;
    for (uint i = first; i < end; ++i) {
        GpuRay r = rays[i];
        for (uint k = 0; k < passes; ++k) {
            hits[i] = trace_scene_wide(nodes, tris, 0, 0, &surf, r.origin.xyz, r.direction.xyz,
                                       r.origin.w, r.direction.w, false,
                                       &counters[COUNT_OVERFLOW]);
        }
    }
}
