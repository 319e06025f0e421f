// Traversal of the 4-wide BVH (src/bvh/wide.rs): one float4 per box plane, so a ray meets all
// four child boxes in a handful of vector instructions (SSE/AVX lanes on a CPU). The boxes,
// slab test and triangle test are traverse.h's, so the same hits are found; children are
// visited nearest first. src/bvh/wide.rs (WideBvh::intersect) is the host reference.

#define WIDE_STACK_SIZE 144  // (4 - 1) x the builder's depth limit of 48

// Closest hit (any_hit = false) or first hit (any_hit = true), as traverse() in traverse.h.
inline GpuHit traverse_wide(global const GpuWideNode* nodes, global const GpuTriangle* tris,
                            const SceneSurfaces* surf, float3 o, float3 d, float tmin,
                            float tmax, bool any_hit, volatile global uint* overflow) {
    RayPrep r = prepare_ray(o, d);
    float4 ox = (float4)(o.x), oy = (float4)(o.y), oz = (float4)(o.z);
    float4 ix = (float4)(r.inv.x), iy = (float4)(r.inv.y), iz = (float4)(r.inv.z);
    float4 tmin4 = (float4)(tmin);
    GpuHit hit;
    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.prim = NO_HIT;
    uint stack[WIDE_STACK_SIZE];
    uint sp = 0;
    uint node = 0;
    for (;;) {
        global const GpuWideNode* n = &nodes[node];
        float4 x0 = (n->min_x - ox) * ix, x1 = (n->max_x - ox) * ix;
        float4 y0 = (n->min_y - oy) * iy, y1 = (n->max_y - oy) * iy;
        float4 z0 = (n->min_z - oz) * iz, z1 = (n->max_z - oz) * iz;
        float4 near = fmax(fmax(fmax(fmin(x0, x1), fmin(y0, y1)), fmin(z0, z1)), tmin4);
        float4 far = fmin(fmin(fmax(x0, x1), fmax(y0, y1)), fmax(z0, z1)) * 1.00000024f;
        int4 child = n->child;
        uint4 count = n->count;
        int4 valid = (child > 0) | (count > 0u);
        int4 mask = (near <= far) & (near < (float4)(hit.t)) & valid;
        if (!any(mask)) {
            if (sp == 0) return hit;
            node = stack[--sp];
            continue;
        }
        // The hit children, nearest first (insertion sort of at most four).
        float dist[4];
        uint slot[4];
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
        int ch[4] = {child.x, child.y, child.z, child.w};
        uint cnt[4] = {count.x, count.y, count.z, count.w};
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
            if (!(dist[i] < hit.t)) continue;
            uint first = (uint)(~ch[c]);
            if (intersect_leaf(&r, tris, surf, first, cnt[c], tmin, o, d, any_hit, &hit)) {
                return hit;
            }
        }
        // Interior children whose boxes start beyond a hit found meanwhile are skipped.
        uint kept[4];
        uint kept_count = 0;
        for (uint i = 0; i < inner_count; ++i) {
            if (inner_dist[i] < hit.t) kept[kept_count++] = inner[i];
        }
        if (kept_count == 0u) {
            if (sp == 0) return hit;
            node = stack[--sp];
            continue;
        }
        if (sp + kept_count - 1u > WIDE_STACK_SIZE) {
            atomic_inc(overflow);
            return hit;
        }
        for (uint i = kept_count - 1u; i > 0u; --i) stack[sp++] = kept[i];
        node = kept[0];
    }
}
