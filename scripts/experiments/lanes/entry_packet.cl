// trace_range (native_trace's entry point) over kernels/traverse_packet.h: the dump's rays
// (a square image's, in row order) in packets of 4×4 neighbouring pixels, for their nearest
// hits; with PACKET_SCALAR each ray alone through traverse_wide instead, in the same order.
void trace_range(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                 global const GpuRay* rays, uint first, uint end, global GpuHit* hits,
                 volatile global uint* counters, uint passes) {
    SceneSurfaces surf = {0};
    uint side = (uint)sqrt((float)end);
    uint blocks = side / 4u;
    Packet P;
    for (uint b = 0; b < blocks * blocks; ++b) {
        uint bx = b % blocks * 4u, by = b / blocks * 4u;
        for (int l = 0; l < LANES; ++l) {
            uint i = (by + (uint)l / 4u) * side + bx + (uint)l % 4u;
            GpuRay r = rays[i];
#ifdef PACKET_SCALAR
            hits[i] = traverse_wide(nodes, tris, &surf, r.origin.xyz, r.direction.xyz, 0.0f,
                                    INFINITY, false, &counters[4]);
#else
            packet_set_ray(&P, l, r.origin.xyz, r.direction.xyz, INFINITY);
#endif
        }
#ifndef PACKET_SCALAR
        packet_walk(&P, (int16)(-1), false, nodes, tris, &surf, &counters[4]);
        for (int l = 0; l < LANES; ++l) {
            uint i = (by + (uint)l / 4u) * side + bx + (uint)l % 4u;
            hits[i] = packet_hit(&P, l);
        }
#endif
    }
}
