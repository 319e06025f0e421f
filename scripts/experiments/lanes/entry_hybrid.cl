// trace_range (native_trace's entry point): the dump's rays (a square image's, in row order)
// in packets of 4×4 neighbouring pixels walked together through the top of the tree until
// few of them reach an item (traverse_packet.h's hand-off), then each in lanes
// (traverse_lanes.h), a lane whose ray is done taking the next packet's next ray.
void trace_range(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                 global const GpuRay* rays, uint first, uint end, global GpuHit* hits,
                 volatile global uint* counters, uint passes) {
    SceneSurfaces surf = {0};
    uint side = (uint)sqrt((float)end);
    uint blocks = side / 4u;
    Packet P;
    PacketHandoff H;
    LaneMemory M;
    lanes_init(&M);
    int16 all = (int16)(-1);
    uint block = 0, queued = LANES, id[LANES];
    bool busy[LANES];
#define TAKE(l)                                                                      \
    {                                                                                \
        busy[l] = false;                                                             \
        if (queued == LANES && block < blocks * blocks) {                            \
            uint bx = block % blocks * 4u, by = block / blocks * 4u;                 \
            ++block;                                                                 \
            for (int i = 0; i < LANES; ++i) {                                        \
                GpuRay r = rays[(by + (uint)i / 4u) * side + bx + (uint)i % 4u];     \
                packet_set_ray(&P, i, r.origin.xyz, r.direction.xyz, INFINITY);      \
            }                                                                        \
            packet_walk(&P, &all, false, nodes, tris, &surf, &counters[4], &H);      \
            queued = 0;                                                              \
            for (int i = 0; i < LANES; ++i) id[i] = 0;                               \
        }                                                                            \
        if (queued < LANES) {                                                        \
            int i = (int)queued++;                                                   \
            uint bb = block - 1u, bx = bb % blocks * 4u, by = bb / blocks * 4u;      \
            ray_of[l] = (by + (uint)i / 4u) * side + bx + (uint)i % 4u;              \
            lanes_set_ray(&M, l, P.o[i], P.d[i]);                                    \
            lanes_take_handoff(&M, l, &P, &H, i);                                    \
            busy[l] = true;                                                          \
        }                                                                            \
    }
    uint ray_of[LANES];
    for (int l = 0; l < LANES; ++l) TAKE(l)
    for (;;) {
        int16 done = lanes_walk(&M, nodes, tris, &surf, &counters[4]);
        if (!lanes_any(done)) break;
        int done_[LANES];
        vstore16(done, 0, done_);
        for (int l = 0; l < LANES; ++l) {
            if (!done_[l]) continue;
            hits[ray_of[l]] = lanes_hit(&M, l);
            TAKE(l)
        }
    }
#undef TAKE
}
