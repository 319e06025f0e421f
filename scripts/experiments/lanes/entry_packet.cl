// trace_range (native_trace's entry point) over kernels/traverse_packet.h: the dump's rays
// (a square image's, in row order) in packets of PACKET_GROUPS 4×4 blocks of neighbouring
// pixels side by side, for their nearest hits; with PACKET_SCALAR each ray alone through
// traverse_wide instead, in the same order.
void trace_range(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                 global const GpuRay* rays, uint first, uint end, global GpuHit* hits,
                 volatile global uint* counters, uint passes) {
    SceneSurfaces surf = {0};
    uint side = (uint)sqrt((float)end);
    uint wide = 4u * PACKET_GROUPS;
    Packet P;
    int16 live[PACKET_GROUPS];
    for (int g = 0; g < PACKET_GROUPS; ++g) live[g] = (int16)(-1);
    for (uint by = 0; by + 4u <= side; by += 4u) {
        for (uint bx = 0; bx + wide <= side; bx += wide) {
            for (int i = 0; i < PACKET_RAYS; ++i) {
                uint k = (by + (uint)(i % LANES) / 4u) * side + bx + (uint)(i / LANES) * 4u +
                         (uint)i % 4u;
                GpuRay r = rays[k];
#ifdef PACKET_SCALAR
                hits[k] = traverse_wide(nodes, tris, &surf, r.origin.xyz, r.direction.xyz, 0.0f,
                                        INFINITY, false, &counters[4]);
#else
                packet_set_ray(&P, i, r.origin.xyz, r.direction.xyz, INFINITY);
#endif
            }
#ifndef PACKET_SCALAR
            packet_walk(&P, live, false, nodes, tris, &surf, &counters[4], 0);
            for (int i = 0; i < PACKET_RAYS; ++i) {
                uint k = (by + (uint)(i % LANES) / 4u) * side + bx + (uint)(i / LANES) * 4u +
                         (uint)i % 4u;
                hits[k] = packet_hit(&P, i);
            }
#endif
        }
    }
}
