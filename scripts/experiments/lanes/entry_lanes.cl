// trace_range (native_trace's entry point) over kernels/traverse_lanes.h: a stream of rays
// through sixteen lanes for their nearest hits (from 0 to infinity, as the dumps' primary and
// diffuse rays are), a lane whose ray is done taking the next.
#define COUNT_OVERFLOW 4
void trace_range(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                 global const GpuRay* rays, uint first, uint end, global GpuHit* hits,
                 volatile global uint* counters, uint passes) {
    SceneSurfaces surf = {0};
    LaneMemory M;
    lanes_init(&M);
    int id[LANES];
    uint next = first;
    for (int l = 0; l < LANES && next < end; ++l, ++next) {
        GpuRay r = rays[next];
        id[l] = next;
        lanes_set_ray(&M, l, r.origin.xyz, r.direction.xyz);
    }
    for (;;) {
        int16 done = lanes_walk(&M, nodes, tris, &surf, &counters[COUNT_OVERFLOW]);
        if (!lanes_any(done)) break;
        int done_[LANES];
        vstore16(done, 0, done_);
        for (int l = 0; l < LANES; ++l) {
            if (!done_[l]) continue;
            hits[id[l]] = lanes_hit(&M, l);
            if (next < end) {
                GpuRay r = rays[next];
                id[l] = next++;
                lanes_set_ray(&M, l, r.origin.xyz, r.direction.xyz);
            }
        }
    }
}
