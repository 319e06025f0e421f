// Traversal of the 4-wide BVH (src/bvh/wide.rs): one float4 per box plane, so a ray meets all
// four child boxes in a handful of vector instructions (SSE/AVX lanes on a CPU). The boxes,
// slab test and triangle test are traverse.h's, so the same hits are found; children are
// visited nearest first. src/bvh/wide.rs (WideBvh::intersect) is the host reference.

#define WIDE_STACK_SIZE 144  // (4 - 1) x the builder's depth limit of 48

// The children of wide node `n` that the prepared ray reaches before `tmax`, nearest first
// (insertion sort of at most four): their entry distances in dist, their slots in slot.
// Returns how many.
inline uint wide_children(global const GpuWideNode* n, const RayPrep* r, float tmin, float tmax,
                          float* dist, uint* slot) {
    float4 ox = (float4)(r->origin.x), oy = (float4)(r->origin.y), oz = (float4)(r->origin.z);
    float4 ix = (float4)(r->inv.x), iy = (float4)(r->inv.y), iz = (float4)(r->inv.z);
    float4 x0 = (n->min_x - ox) * ix, x1 = (n->max_x - ox) * ix;
    float4 y0 = (n->min_y - oy) * iy, y1 = (n->max_y - oy) * iy;
    float4 z0 = (n->min_z - oz) * iz, z1 = (n->max_z - oz) * iz;
    float4 near = fmax(fmax(fmax(fmin(x0, x1), fmin(y0, y1)), fmin(z0, z1)), (float4)(tmin));
    float4 far = fmin(fmin(fmax(x0, x1), fmax(y0, y1)), fmax(z0, z1)) * 1.00000024f;
    int4 valid = (n->child > 0) | (n->count > 0u);
    int4 mask = (near <= far) & (near < (float4)(tmax)) & valid;
    if (!any(mask)) return 0u;
    uint k = 0;
    float nd[4] = {near.x, near.y, near.z, near.w};
    int mk[4] = {mask.x, mask.y, mask.z, mask.w};
    for (uint c = 0; c < 4u; ++c) {
        if (!mk[c]) continue;
        uint j = k++;
        while (j > 0u && dist[j - 1u] > nd[c]) {
            dist[j] = dist[j - 1u];
            slot[j] = slot[j - 1u];
            --j;
        }
        dist[j] = nd[c];
        slot[j] = c;
    }
    return k;
}

// Pushes the interior children kept[1..count) (farthest first) and goes on to kept[0], or pops
// the next node when there is none. Returns WALK_ON, WALK_DONE or WALK_OVERFLOW (traverse.h).
inline uint wide_next(const uint* kept, uint kept_count, uint* stack, uint* sp, uint* node,
                      volatile global uint* overflow) {
    if (kept_count == 0u) {
        if (*sp == 0u) return WALK_DONE;
        *node = stack[--(*sp)];
        return WALK_ON;
    }
    if (*sp + kept_count - 1u > WIDE_STACK_SIZE) {
        atomic_inc(overflow);
        return WALK_OVERFLOW;
    }
    for (uint i = kept_count - 1u; i > 0u; --i) stack[(*sp)++] = kept[i];
    *node = kept[0];
    return WALK_ON;
}

// Walks the wide BVH below node `root` as traverse_bvh (traverse.h) walks the binary one, with
// the same arguments and result.
inline bool traverse_wide_bvh(global const GpuWideNode* nodes, uint root,
                              global const GpuTriangle* tris, const SceneSurfaces* surf,
                              const RayPrep* r, float3 o, float3 d, float tmin, bool any_hit,
                              uint prim_offset, bool swap_uv, GpuHit* hit,
                              volatile global uint* overflow) {
    uint stack[WIDE_STACK_SIZE];
    uint sp = 0;
    uint node = root;
    for (;;) {
        global const GpuWideNode* n = &nodes[node];
        float dist[4];
        uint slot[4];
        uint k = wide_children(n, r, tmin, hit->t, dist, slot);
        int ch[4] = {n->child.x, n->child.y, n->child.z, n->child.w};
        uint cnt[4] = {n->count.x, n->count.y, n->count.z, n->count.w};
        // Leaves on the spot (they shorten the ray); interior children kept in order.
        uint inner[4];
        float inner_dist[4];
        uint inner_count = 0;
        for (uint i = 0; i < k; ++i) {
            uint c = slot[i];
            if (cnt[c] == 0u) {
                inner[inner_count] = (uint)ch[c];
                inner_dist[inner_count++] = dist[i];
                continue;
            }
            if (!(dist[i] < hit->t)) continue;
            uint first = (uint)(~ch[c]);
            if (intersect_leaf(r, tris, surf, first, cnt[c], tmin, o, d, any_hit, prim_offset,
                               swap_uv, hit)) {
                return true;
            }
        }
        // Interior children whose boxes start beyond a hit found meanwhile are skipped.
        uint kept[4];
        uint kept_count = 0;
        for (uint i = 0; i < inner_count; ++i) {
            if (inner_dist[i] < hit->t) kept[kept_count++] = inner[i];
        }
        uint next = wide_next(kept, kept_count, stack, &sp, &node, overflow);
        if (next != WALK_ON) return next == WALK_OVERFLOW;
    }
}

// Closest hit (any_hit = false) or first hit (any_hit = true), as traverse() in traverse.h.
inline GpuHit traverse_wide(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                            const SceneSurfaces* surf, float3 o, float3 d, float tmin,
                            float tmax, bool any_hit, volatile global uint* overflow) {
    RayPrep r = prepare_ray(o, d);
    GpuHit hit = no_hit(tmax);
    traverse_wide_bvh(nodes, 0u, tris, surf, &r, o, d, tmin, any_hit, 0u, false, &hit,
                      overflow);
    return hit;
}

// Two levels through wide nodes, as traverse_two_level (traverse.h): the top level from node
// 0, each instance's bottom level from its wide_root.
inline GpuHit traverse_wide_two_level(global const GpuWideNode* nodes,
                                      global const GpuInstance* instances,
                                      global const GpuTriangle* object_tris,
                                      const SceneSurfaces* surf, float3 o, float3 d,
                                      float tmin, float tmax, bool any_hit,
                                      volatile global uint* overflow) {
    RayPrep r = prepare_ray(o, d);
    GpuHit hit = no_hit(tmax);
    TopStack s;
    s.sp = 0;
    top_push(&s, 0u, 0u, tmin, overflow);
    uint first, count;
    while (top_pop(&s, hit.t, &first, &count)) {
        if (count > 0u) {
            ENTER_INSTANCES(traverse_wide_bvh, wide_root)
            continue;
        }
        global const GpuWideNode* n = &nodes[first];
        float dist[4];
        uint slot[4];
        uint k = wide_children(n, &r, tmin, hit.t, dist, slot);
        int ch[4] = {n->child.x, n->child.y, n->child.z, n->child.w};
        uint cnt[4] = {n->count.x, n->count.y, n->count.z, n->count.w};
        // Farthest first, so that the nearest is popped first.
        for (uint i = k; i > 0u; --i) {
            uint c = slot[i - 1u];
            uint ref = cnt[c] > 0u ? (uint)(~ch[c]) : (uint)ch[c];
            if (!top_push(&s, ref, cnt[c], dist[i - 1u], overflow)) return hit;
        }
    }
    return hit;
}

// The scene's traversal through wide nodes: flat, or with TWO_LEVEL two levels.
inline GpuHit trace_scene_wide(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                               global const GpuInstance* instances,
                               global const GpuTriangle* object_tris, const SceneSurfaces* surf,
                               float3 o, float3 d, float tmin, float tmax, bool any_hit,
                               volatile global uint* overflow) {
#ifdef TWO_LEVEL
    // With two levels `tris` holds the meshes' object-space triangles (object_tris is unused).
    return traverse_wide_two_level(nodes, instances, tris, surf, o, d, tmin, tmax,
                                   any_hit, overflow);
#else
    return traverse_wide(nodes, tris, surf, o, d, tmin, tmax, any_hit, overflow);
#endif
}
