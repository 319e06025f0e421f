// Traversal of the 4-wide BVH (src/bvh/wide.rs): one float4 per box plane, so a ray meets all
// four child boxes in a handful of vector instructions (SSE/AVX lanes on a CPU). The boxes,
// slab test and triangle test are traverse.h's, so the same hits are found; children are
// visited nearest first. src/bvh/wide.rs (WideBvh::intersect) is the host reference.
#ifndef SHARED_TRAVERSE_WIDE_H
#define SHARED_TRAVERSE_WIDE_H

#include "shared/types.h"
#include "shared/textures.h"
#include "shared/traverse.h"

#define WIDE_STACK_SIZE 144  // (4 - 1) x the builder's depth limit of 48

// The ray in four lanes: origin and safe reciprocal direction, one coordinate per vector, and
// for each axis the byte offsets in a DeviceWideNode of the box planes the ray meets first (min_*
// where the direction is positive, max_* where negative) and last, so that a node's entry and
// exit distances need no minimum and maximum per axis.
typedef struct {
    float4 ox, oy, oz, ix, iy, iz;
    uint nx, ny, nz, fx, fy, fz;
} WideRay;

inline WideRay wide_ray(const RayPrep* r) {
    WideRay w;
    w.ox = (float4)(r->origin.x);
    w.oy = (float4)(r->origin.y);
    w.oz = (float4)(r->origin.z);
    w.ix = (float4)(r->inv.x);
    w.iy = (float4)(r->inv.y);
    w.iz = (float4)(r->inv.z);
    // min_x, min_y, min_z, max_x, max_y, max_z: 16 bytes each.
    w.nx = r->inv.x >= 0.0f ? 0u : 48u;
    w.ny = r->inv.y >= 0.0f ? 16u : 64u;
    w.nz = r->inv.z >= 0.0f ? 32u : 80u;
    w.fx = w.nx ^ 48u;
    w.fy = w.ny ^ 80u;
    w.fz = w.nz ^ 112u;
    return w;
}

// The box plane of node n at a byte offset of wide_ray's.
#define WIDE_PLANE(n, offset) (*(global const float4*)((global const char*)(n) + (offset)))

// traverse.h's slab test on the four children of n at once: their entry distances in *near,
// and the mask of those the ray reaches before tmax (empty slots never).
// The minimum and maximum are written as comparisons: OpenCL's fmin and fmax must return the
// other operand of a NaN, which costs x86 two more instructions each (vminps alone does not),
// and no slab distance here is NaN: the reciprocal direction is finite and nonzero, and empty
// slots are masked out by `valid`. The bunnies' rays ran 3 % faster on PoCL, with the same
// images bit for bit. (traverse_packet.h's slab test uses them too.)
#define WIDE_MIN(a, b) select(b, a, a < b)
#define WIDE_MAX(a, b) select(b, a, a > b)
inline int4 wide_reach(global const DeviceWideNode* n, const WideRay* w, float tmin, float tmax,
                       float4* near) {
    // With lo <= hi, (lo - o) * inv <= (hi - o) * inv where inv > 0 (rounding is monotonic) and
    // >= where inv < 0: the near plane's distance is the minimum of the two, bit for bit.
    float4 x0 = (WIDE_PLANE(n, w->nx) - w->ox) * w->ix;
    float4 x1 = (WIDE_PLANE(n, w->fx) - w->ox) * w->ix;
    float4 y0 = (WIDE_PLANE(n, w->ny) - w->oy) * w->iy;
    float4 y1 = (WIDE_PLANE(n, w->fy) - w->oy) * w->iy;
    float4 z0 = (WIDE_PLANE(n, w->nz) - w->oz) * w->iz;
    float4 z1 = (WIDE_PLANE(n, w->fz) - w->oz) * w->iz;
    *near = WIDE_MAX(WIDE_MAX(WIDE_MAX(x0, y0), z0), (float4)(tmin));
    float4 far = WIDE_MIN(WIDE_MIN(x1, y1), z1) * 1.00000024f;
    int4 valid = (n->child > 0) | (n->count > 0u);
    return (*near <= far) & (*near < (float4)(tmax)) & valid;
}
#undef WIDE_PLANE

// intersect_triangle's arithmetic in lanes (a triangle a lane), one definition for every width:
// DEFINE_LANE_TRIANGLE_TEST(T, f, TF, TI) defines, for lanes of floats TF with masks of TI,
//   T##Triangle  the vertices a, b, c relative to the ray's origin in its permuted axes;
//   T##Edges     the edge functions u, v, w;
//   T##Verdict   the verdict: the edge functions' sum det, the distance t, the mask ok of the
//                lanes with a hit and the mask special of those that need the scalar test (an
//                edge function of zero, or a hit close enough for its rounding-error bound);
//   f##_edges(tri, sx, sy)  the edge functions of the sheared vertices (shear sx, sy);
//   f##_verdict(tri, e, sz, mask, tmin, tmax)  the verdict for the lanes of mask, a hit in
//                (tmin, tmax), from the edge functions e and the shear's z.
// (intersect_leaf4 uses it on four triangles, trace_small on sixteen, the CPU lanes at their
// width.)
// Each lane computes what intersect_triangle computes, operation for operation. With the CPU's
// lanes (MEGA_LANES) they are always inlined, as the walks' own code.
#ifdef MEGA_LANES
#define LANE_TEST_INLINE inline __attribute__((always_inline))
#else
#define LANE_TEST_INLINE inline
#endif
#define DEFINE_LANE_TRIANGLE_TEST(T, f, TF, TI)                                                    \
    typedef struct {                                                                               \
        TF aX, aY, aZ, bX, bY, bZ, cX, cY, cZ;                                                     \
    } T##Triangle;                                                                                 \
    typedef struct {                                                                               \
        TF u, v, w;                                                                                \
    } T##Edges;                                                                                    \
    typedef struct {                                                                               \
        TF det, t;                                                                                 \
        TI ok, special;                                                                            \
    } T##Verdict;                                                                                  \
    LANE_TEST_INLINE T##Edges f##_edges(const T##Triangle* r, TF sx,                               \
                                                             TF sy) {                              \
        TF ax = r->aX - sx * r->aZ;                                                                \
        TF ay = r->aY - sy * r->aZ;                                                                \
        TF bx = r->bX - sx * r->bZ;                                                                \
        TF by = r->bY - sy * r->bZ;                                                                \
        TF cx = r->cX - sx * r->cZ;                                                                \
        TF cy = r->cY - sy * r->cZ;                                                                \
        T##Edges e;                                                                                \
        e.u = cx * by - cy * bx;                                                                   \
        e.v = ax * cy - ay * cx;                                                                   \
        e.w = bx * ay - by * ax;                                                                   \
        return e;                                                                                  \
    }                                                                                              \
    LANE_TEST_INLINE T##Verdict f##_verdict(const T##Triangle* r, T##Edges e,                      \
                                                           TF sz, TI mask, TF tmin, TF tmax) {     \
        const TF zero = (TF)(0.0f);                                                                \
        T##Verdict h;                                                                              \
        h.ok = mask & ~(((e.u < zero) | (e.v < zero) | (e.w < zero)) &                             \
                        ((e.u > zero) | (e.v > zero) | (e.w > zero)));                             \
        h.det = e.u + e.v + e.w;                                                                   \
        h.ok &= h.det != zero;                                                                     \
        TF az = sz * r->aZ, bz = sz * r->bZ, cz = sz * r->cZ;                                      \
        h.t = (e.u * az + e.v * bz + e.w * cz) / h.det;                                            \
        h.ok &= (h.t > tmin) & (h.t < tmax);                                                       \
        TF far_z = select(fabs(az), fabs(bz), fabs(bz) > fabs(az));                                \
        far_z = select(far_z, fabs(cz), fabs(cz) > far_z);                                         \
        h.special = mask & ((e.u == zero) | (e.v == zero) | (e.w == zero) |                        \
                            (h.ok & (h.t < 0.00390625f * far_z)));                                 \
        return h;                                                                                  \
    }
DEFINE_LANE_TRIANGLE_TEST(Lane4, lane4, float4, int4)

// intersect_leaf for a leaf of at most four triangles, the four tested at once in float4 lanes
// with intersect_triangle's arithmetic lane by lane, so that the same hit is kept: the first
// triangle of the nearest hit (the scalar loop keeps a later one only when strictly nearer), or
// with any_hit the first triangle hit. Leaves whose test needs the double-precision edge
// functions or the rounding-error bound fall back to the scalar loop. Used for leaves of three
// or four triangles (src/bvh/wide.rs merges small subtrees into such leaves in large scenes):
// for one or two, the scalar tests measured as fast or faster (a 32-triangle Cornell box with
// merged leaves ran 7-10 % slower: 2-core dev machine, 2026-12-01).
#ifndef HAS_ALPHA
// A vertex of four triangles (p0 .. p3) relative to the ray's origin o4 in its permuted axes
// (perm), one triangle a lane: its axes in *X, *Y, *Z.
inline void leaf4_vertex(float4 p0, float4 p1, float4 p2, float4 p3, float4 o4, uint4 perm,
                         float4* X, float4* Y, float4* Z) {
    p0 = shuffle(p0 - o4, perm);
    p1 = shuffle(p1 - o4, perm);
    p2 = shuffle(p2 - o4, perm);
    p3 = shuffle(p3 - o4, perm);
    *X = (float4)(p0.x, p1.x, p2.x, p3.x);
    *Y = (float4)(p0.y, p1.y, p2.y, p3.y);
    *Z = (float4)(p0.z, p1.z, p2.z, p3.z);
}

inline bool intersect_leaf4(const RayPrep* r, global const DeviceTriangle* tris,
                            const SceneSurfaces* surf, uint first, uint count, float tmin,
                            float3 o, float3 d, bool any_hit, DeviceHit* hit) {
    uint last = first + count - 1u;
    DeviceTriangle t0 = tris[first], t1 = tris[min(first + 1u, last)];
    DeviceTriangle t2 = tris[min(first + 2u, last)], t3 = tris[min(first + 3u, last)];
    float4 o4 = (float4)(r->origin, 0.0f);
    Lane4Triangle tri4;
    leaf4_vertex(t0.v0, t1.v0, t2.v0, t3.v0, o4, r->perm, &tri4.aX, &tri4.aY, &tri4.aZ);
    leaf4_vertex(t0.v1, t1.v1, t2.v1, t3.v1, o4, r->perm, &tri4.bX, &tri4.bY, &tri4.bZ);
    leaf4_vertex(t0.v2, t1.v2, t2.v2, t3.v2, o4, r->perm, &tri4.cX, &tri4.cY, &tri4.cZ);
    float4 sx = (float4)(r->shear.x), sy = (float4)(r->shear.y), sz = (float4)(r->shear.z);
    Lane4Edges e = lane4_edges(&tri4, sx, sy);
    int4 lane = (int4)(0, 1, 2, 3) < (int4)((int)count);
    Lane4Verdict h = lane4_verdict(&tri4, e, sz, lane, (float4)(tmin), (float4)(hit->t));
    // Rare cases for the scalar test: an edge function of zero (double precision there) or a
    // hit close enough for the error bound.
    if (any(h.special)) {
        return intersect_leaf(r, tris, surf, first, count, tmin, o, d, any_hit, hit);
    }
    int4 ok = h.ok;
    float4 t = h.t, v = e.v, w = e.w, det = h.det;
    if (!any(ok)) return false;
    float4 tt = select((float4)(INFINITY), t, ok);
    uint k;
    if (any_hit) {
        k = ok.x ? 0u : ok.y ? 1u : ok.z ? 2u : 3u;
    } else {
        float m = fmin(fmin(tt.x, tt.y), fmin(tt.z, tt.w));
        k = tt.x == m ? 0u : tt.y == m ? 1u : tt.z == m ? 2u : 3u;
    }
    float tk = k == 0u ? t.x : k == 1u ? t.y : k == 2u ? t.z : t.w;
    float vk = k == 0u ? v.x : k == 1u ? v.y : k == 2u ? v.z : v.w;
    float wk = k == 0u ? w.x : k == 1u ? w.y : k == 2u ? w.z : w.w;
    float dk = k == 0u ? det.x : k == 1u ? det.y : k == 2u ? det.z : det.w;
    hit->t = tk;
    hit->u = vk / dk;
    hit->v = wk / dk;
    hit->prim = first + k;
    return any_hit;
}
#endif

// The test of a leaf of `count` triangles from `first`: four at once where it holds three or
// four (and the scene no alpha), else one by one. Returns whether the walk ends (any_hit and a
// hit), as intersect_leaf does.
inline bool intersect_wide_leaf(const RayPrep* r, global const DeviceTriangle* tris,
                                const SceneSurfaces* surf, uint first, uint count, float tmin,
                                float3 o, float3 d, bool any_hit, DeviceHit* hit) {
#ifndef HAS_ALPHA
    if (count - 3u <= 1u) {
        return intersect_leaf4(r, tris, surf, first, count, tmin, o, d, any_hit, hit);
    }
#endif
    return intersect_leaf(r, tris, surf, first, count, tmin, o, d, any_hit, hit);
}

// Child slot s of wide node n: a node index, or for a leaf the complement of its first
// triangle; and the leaf's triangle count (0: an interior node).
inline int wide_child(global const DeviceWideNode* n, uint s) {
    return ((global const int*)&n->child)[s];
}

inline uint wide_count(global const DeviceWideNode* n, uint s) {
    return ((global const uint*)&n->count)[s];
}

// The children of a wide node that a ray reaches, nearest first: their entry distances
// d0 <= d1 <= d2 <= d3 (INFINITY for those not reached) and slots s0 .. s3. Scalars, not arrays,
// so that they stay in registers.
typedef struct {
    float d0, d1, d2, d3;
    uint s0, s1, s2, s3;
} WideOrder;

// Compare-and-swap of two (entry distance, slot) pairs, ordered by distance and then slot, so
// that the network of wide_sort_children sorts as a stable sort would (the host reference's
// order).
inline void wide_order(float* da, uint* sa, float* db, uint* sb) {
    if (*db < *da || (*db == *da && *sb < *sa)) {
        float td = *da;
        *da = *db;
        *db = td;
        uint ts = *sa;
        *sa = *sb;
        *sb = ts;
    }
}

// The children of a node that `mask` reaches (their entry distances in `near`), sorted by a
// five-exchange network.
inline WideOrder wide_sort_children(float4 near, int4 mask) {
    float4 dist = select((float4)(INFINITY), near, mask);
    WideOrder c = {dist.x, dist.y, dist.z, dist.w, 0u, 1u, 2u, 3u};
    wide_order(&c.d0, &c.s0, &c.d1, &c.s1);
    wide_order(&c.d2, &c.s2, &c.d3, &c.s3);
    wide_order(&c.d0, &c.s0, &c.d2, &c.s2);
    wide_order(&c.d1, &c.s1, &c.d3, &c.s3);
    wide_order(&c.d1, &c.s1, &c.d2, &c.s2);
    return c;
}

// A leaf among the sorted children (entry distance dist, slot s of node n), tested on the spot
// when it starts before the hit so far. Returns whether the walk ends.
inline bool wide_leaf(float dist, uint s, global const DeviceWideNode* n, const RayPrep* r,
                      global const DeviceTriangle* tris, const SceneSurfaces* surf, float tmin,
                      float3 o, float3 d, bool any_hit, DeviceHit* hit) {
    return dist < hit->t && wide_count(n, s) > 0u &&
           intersect_wide_leaf(r, tris, surf, (uint)(~wide_child(n, s)), wide_count(n, s), tmin,
                               o, d, any_hit, hit);
}

// An interior child among the sorted ones (entry distance dist, slot s of node n), pushed with
// its distance when it starts before the hit at t; *next is then its node.
inline void wide_push(float dist, uint s, global const DeviceWideNode* n, float t, uint* stack,
                      float* stack_d, uint* sp, uint* next) {
    if (dist < t && wide_count(n, s) == 0u) {
        *next = (uint)wide_child(n, s);
        stack[*sp] = *next;
        stack_d[(*sp)++] = dist;
    }
}

// For any hit: child slot s of node n, when `bits` has it, tested if a leaf, else pushed (to be
// entered whatever its distance: the walk ends at the first hit). Returns whether a hit ends
// the walk.
inline bool wide_any(uint bits, uint s, global const DeviceWideNode* n, const RayPrep* r,
                     global const DeviceTriangle* tris, const SceneSurfaces* surf, float tmin,
                     float3 o, float3 d, DeviceHit* hit, uint* stack, float* stack_d, uint* sp) {
    if (((bits >> s) & 1u) == 0u) return false;
    if (wide_count(n, s) == 0u) {
        stack[*sp] = (uint)wide_child(n, s);
        stack_d[(*sp)++] = -INFINITY;
        return false;
    }
    return intersect_wide_leaf(r, tris, surf, (uint)(~wide_child(n, s)), wide_count(n, s), tmin,
                               o, d, true, hit);
}

// The lanes of a mask as bits (lane i: bit i). On x86 one movmskps (a kmov from the compare's
// AVX-512 mask): OpenCL's any() became a dozen instructions and two branches there.
inline uint wide_bits(int4 mask) {
#if defined(__SSE__) && defined(__x86_64__)
    return (uint)__builtin_ia32_movmskps(as_float4(mask));
#else
    int4 b = mask & (int4)(1, 2, 4, 8);
    return (uint)((b.x | b.y) | (b.z | b.w));
#endif
}

// Walks the wide BVH below node `root` as traverse_bvh (traverse.h) walks the binary one, with
// the same arguments and result. The children a ray reaches are sorted by entry distance with
// a five-exchange network on scalars (registers, not arrays): leaves are tested in that order,
// interior children pushed farthest first with their distance, and a popped node that starts
// beyond the hit found meanwhile is skipped; the nearest of them is entered at once, its index
// from a register rather than read back from the stack. The visiting order is
// src/bvh/wide.rs's. With
// any_hit the children are not sorted (wide_any): bunnies' shadow rays ran 20-25 % faster
// (2-core dev machine, 2026-12-01), and a shadow test's result does not depend on which
// hit is found first (path.h's shadow tests walk thin walls again nearest first).
inline bool traverse_wide_bvh(global const DeviceWideNode* nodes, uint root,
                              global const DeviceTriangle* tris, const SceneSurfaces* surf,
                              const RayPrep* r, float3 o, float3 d, float tmin, bool any_hit,
                              DeviceHit* hit,
                              volatile global uint* overflow) {
    uint stack[WIDE_STACK_SIZE + 1];
    float stack_d[WIDE_STACK_SIZE + 1];
    uint sp = 0;
    uint node = root;
    WideRay w = wide_ray(r);
    for (;;) {
        global const DeviceWideNode* n = &nodes[node];
        float4 near;
        int4 mask = wide_reach(n, &w, tmin, hit->t, &near);
        uint bits = wide_bits(mask);
        if (bits != 0u && any_hit) {
            // Any hit ends the walk, so the order of the children does not matter: they are
            // taken in slot order, without sorting (as Embree's occlusion walk takes them).
            if (sp + 4u > WIDE_STACK_SIZE + 1u) {
                atomic_inc(overflow);
                return true;
            }
            if (wide_any(bits, 0u, n, r, tris, surf, tmin, o, d, hit, stack, stack_d, &sp) ||
                wide_any(bits, 1u, n, r, tris, surf, tmin, o, d, hit, stack, stack_d, &sp) ||
                wide_any(bits, 2u, n, r, tris, surf, tmin, o, d, hit, stack, stack_d, &sp) ||
                wide_any(bits, 3u, n, r, tris, surf, tmin, o, d, hit, stack, stack_d, &sp)) {
                return true;
            }
        } else if (bits != 0u) {
            WideOrder c = wide_sort_children(near, mask);
            if (wide_leaf(c.d0, c.s0, n, r, tris, surf, tmin, o, d, any_hit, hit) ||
                wide_leaf(c.d1, c.s1, n, r, tris, surf, tmin, o, d, any_hit, hit) ||
                wide_leaf(c.d2, c.s2, n, r, tris, surf, tmin, o, d, any_hit, hit) ||
                wide_leaf(c.d3, c.s3, n, r, tris, surf, tmin, o, d, any_hit, hit)) {
                return true;
            }
            if (sp + 4u > WIDE_STACK_SIZE + 1u) {
                atomic_inc(overflow);
                return true;
            }
            uint before = sp, next = 0u;
            wide_push(c.d3, c.s3, n, hit->t, stack, stack_d, &sp, &next);
            wide_push(c.d2, c.s2, n, hit->t, stack, stack_d, &sp, &next);
            wide_push(c.d1, c.s1, n, hit->t, stack, stack_d, &sp, &next);
            wide_push(c.d0, c.s0, n, hit->t, stack, stack_d, &sp, &next);
            // The nearest pushed child is entered at once (it starts before the hit: no leaf
            // was tested since it was pushed), its address from a register, not the stack.
            if (sp != before) {
                --sp;
                node = next;
                continue;
            }
        }
        // The nearest pushed node that still starts before the hit.
        for (;;) {
            if (sp == 0u) return false;
            --sp;
            if (stack_d[sp] < hit->t) break;
        }
        node = stack[sp];
    }
}

// Closest hit (any_hit = false) or first hit (any_hit = true), as traverse() in traverse.h.
inline DeviceHit traverse_wide(global const DeviceWideNode* nodes, global const DeviceTriangle* tris,
                            const SceneSurfaces* surf, float3 o, float3 d, float tmin,
                            float tmax, bool any_hit, volatile global uint* overflow) {
    RayPrep r = prepare_ray(o, d);
    DeviceHit hit = no_hit(tmax);
    traverse_wide_bvh(nodes, 0u, tris, surf, &r, o, d, tmin, any_hit, &hit, overflow);
    return hit;
}

#define TOP_WIDE_STACK (WIDE_STACK_SIZE + 4)

// A top-level child among the sorted ones (entry distance dist, slot s of node n), pushed with
// its distance when it starts before the hit at t: an interior node, or a leaf's pieces
// (INSTANCE_BIT, traverse.h). Returns false when the stack overflowed (counted in *overflow).
inline bool top_wide_push(float dist, uint s, global const DeviceWideNode* n, float t,
                          uint* stack, float* stack_d, uint* sp, volatile global uint* overflow) {
    if (!(dist < t)) return true;
    uint count = wide_count(n, s);
    if (count == 0u) {
        stack[*sp] = (uint)wide_child(n, s);
        stack_d[(*sp)++] = dist;
        return true;
    }
    uint first = (uint)(~wide_child(n, s));
    for (uint i = first + count; i > first; --i) {
        if (*sp == TOP_WIDE_STACK) {
            atomic_inc(overflow);
            return false;
        }
        stack[*sp] = (i - 1u) | INSTANCE_BIT;
        stack_d[(*sp)++] = dist;
    }
    return true;
}

#ifdef HAS_TRIANGLE_PIECES
// A top-level leaf of one triangle piece among the sorted children (entry distance *dist, slot s
// of node n), tested on the spot (as wide_leaf tests a leaf) when it starts before the hit so
// far; *dist is then made infinite so that top_wide_push passes it over. Returns whether the
// walk ends.
inline bool top_wide_triangle(float* dist, uint s, global const DeviceWideNode* n,
                              global const DeviceInstance* instances,
                              global const DeviceTriangle* object_tris, const SceneSurfaces* surf,
                              const RayPrep* world, float3 o, float3 d, float tmin, bool any_hit,
                              DeviceHit* hit) {
    if (!(*dist < hit->t && wide_count(n, s) == 1u)) return false;
    uint slot = (uint)(~wide_child(n, s));
    global const DeviceInstance* piece = &instances[slot];
    if (!(piece->flags & INSTANCE_PIECE_TRIANGLE)) return false;
    if (intersect_piece_triangle(piece->root, piece->wide_root, slot, object_tris, surf, world, o,
                                 d, tmin, any_hit, hit)) {
        return true;
    }
    *dist = INFINITY;
    return false;
}
#endif

// Two levels through wide nodes: the top level (from node 0; its leaves name pieces in
// `instances`) walked nearest first as traverse_wide_bvh walks a tree: a leaf of a small
// mesh's triangle is tested on the spot as the flat loop tests its leaves (top_wide_triangle:
// through the stack, primary rays in the bunny room ran about 10 % slower), and any other
// piece the ray reaches before the hit so far is entered: the ray is carried into the
// instance's object space, and the instance's bottom level walked from its wide_root by
// traverse_wide_bvh itself, the flat BVH's loop, with a stack of its own. On a CPU this is faster than one loop over both levels (traverse.h's form, which
// GPUs keep for their binary nodes): the bottom levels, where rays spend nearly all their
// visits, run the flat loop's code with its registers.
inline DeviceHit traverse_wide_two_level(global const DeviceWideNode* nodes,
                                      global const DeviceInstance* instances,
                                      global const DeviceTriangle* object_tris,
                                      const SceneSurfaces* surf, float3 o, float3 d,
                                      float tmin, float tmax, bool any_hit,
                                      volatile global uint* overflow) {
    const RayPrep world = prepare_ray(o, d);
    const WideRay w = wide_ray(&world);
    DeviceHit hit = no_hit(tmax);
    uint stack[TOP_WIDE_STACK];
    float stack_d[TOP_WIDE_STACK];
    uint sp = 0;
    uint node = 0;
    for (;;) {
        if (node & INSTANCE_BIT) {
            uint slot = node & ~INSTANCE_BIT;
            global const DeviceInstance* piece = &instances[slot];
#ifdef HAS_TRIANGLE_PIECES
            if (piece->flags & INSTANCE_PIECE_TRIANGLE) {
                if (intersect_piece_triangle(piece->root, piece->wide_root, slot, object_tris,
                                             surf, &world, o, d, tmin, any_hit, &hit)) {
                    return hit;
                }
            } else
#endif
            {
                DeviceInstance inst = *piece;
                float3 od = instance_vector(&inst, d);
                RayPrep r = prepare_ray(instance_point(&inst, o), od);
                float before = hit.t;
                bool stop = traverse_wide_bvh(nodes, inst.wide_root, object_tris, surf, &r, o,
                                              d, instance_tmin(&inst, o, od, tmin), any_hit,
                                              &hit, overflow);
                if (hit.t < before) hit.instance = slot;
                if (stop) return hit;
            }
        } else {
            global const DeviceWideNode* n = &nodes[node];
            float4 near;
            int4 mask = wide_reach(n, &w, tmin, hit.t, &near);
            if (wide_bits(mask) != 0u) {
                WideOrder c = wide_sort_children(near, mask);
#ifdef HAS_TRIANGLE_PIECES
                if (top_wide_triangle(&c.d0, c.s0, n, instances, object_tris, surf, &world, o, d,
                                      tmin, any_hit, &hit) ||
                    top_wide_triangle(&c.d1, c.s1, n, instances, object_tris, surf, &world, o, d,
                                      tmin, any_hit, &hit) ||
                    top_wide_triangle(&c.d2, c.s2, n, instances, object_tris, surf, &world, o, d,
                                      tmin, any_hit, &hit) ||
                    top_wide_triangle(&c.d3, c.s3, n, instances, object_tris, surf, &world, o, d,
                                      tmin, any_hit, &hit)) {
                    return hit;
                }
#endif
                if (sp + 4u > TOP_WIDE_STACK) {
                    atomic_inc(overflow);
                    return hit;
                }
                if (!top_wide_push(c.d3, c.s3, n, hit.t, stack, stack_d, &sp, overflow) ||
                    !top_wide_push(c.d2, c.s2, n, hit.t, stack, stack_d, &sp, overflow) ||
                    !top_wide_push(c.d1, c.s1, n, hit.t, stack, stack_d, &sp, overflow) ||
                    !top_wide_push(c.d0, c.s0, n, hit.t, stack, stack_d, &sp, overflow)) {
                    return hit;
                }
            }
        }
        // The nearest pushed entry that still starts before the hit.
        for (;;) {
            if (sp == 0u) return hit;
            --sp;
            if (stack_d[sp] < hit.t) break;
        }
        node = stack[sp];
    }
}

// The scene's traversal through wide nodes: flat, or with TWO_LEVEL two levels.
inline DeviceHit trace_scene_wide(global const DeviceWideNode* nodes, global const DeviceTriangle* tris,
                               global const DeviceInstance* instances,
                               global const DeviceTriangle* object_tris, const SceneSurfaces* surf,
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

#ifdef SMALL_SCENE
// A scene of at most a few dozen triangles (SMALL_SCENE: their number rounded up to a whole
// batch of SMALL_LANES, set by the host on CPU devices for flat scenes without alpha; the number
// itself comes with the frame, so that hiding an object builds no kernels unless the batches
// change): every ray tests every triangle, sixteen at a time in float16 lanes, with no tree.
// Each lane computes intersect_triangle's arithmetic, so the hits are the same; of equally near
// hits the lowest triangle index is kept (the tree kept the first it visited). The coordinates
// are held by vertex and axis, so that a ray's axis permutation picks rows instead of shuffling
// each vertex.
#define SMALL_BATCHES ((SMALL_SCENE + SMALL_LANES - 1) / SMALL_LANES)
DEFINE_LANE_TRIANGLE_TEST(Lane16, lane16, float16, int16)
typedef struct SmallScene {
    float c[9][SMALL_BATCHES * SMALL_LANES];  // [vertex * 3 + axis][triangle]
    float4 normal[SMALL_SCENE];               // triangle_normal's
    uint count;                               // triangles, 1..=SMALL_SCENE
} SmallScene;

// The work group's copy of the scene, in local memory (written once a launch for all of the
// group's paths: a work item, one or a few samples, would not repay it alone).
inline void small_scene_load(global const DeviceTriangle* tris, uint count, local SmallScene* s) {
    count = clamp(count, 1u, (uint)SMALL_SCENE);
    if (get_local_id(0) == 0u) s->count = count;
    for (uint i = get_local_id(0); i < SMALL_BATCHES * SMALL_LANES; i += get_local_size(0)) {
        // Lanes past the last triangle repeat it (and are masked out).
        DeviceTriangle t = tris[min(i, count - 1u)];
        s->c[0][i] = t.v0.x;
        s->c[1][i] = t.v0.y;
        s->c[2][i] = t.v0.z;
        s->c[3][i] = t.v1.x;
        s->c[4][i] = t.v1.y;
        s->c[5][i] = t.v1.z;
        s->c[6][i] = t.v2.x;
        s->c[7][i] = t.v2.y;
        s->c[8][i] = t.v2.z;
        if (i < count) {
            s->normal[i] = (float4)(triangle_normal(t.v0.xyz, t.v1.xyz, t.v2.xyz), 0.0f);
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
}

// The least lane of x.
inline int small_min(int16 x) {
    int8 y = min(x.lo, x.hi);
    int4 b = min(y.lo, y.hi);
    int2 c = min(b.lo, b.hi);
    return min(c.x, c.y);
}

// The nearest hit of the ray in (tmin, tmax) among all triangles, or with any_hit some hit.
// The batches are tested without a branch between them: each lane keeps its nearest hit so far
// (a later batch's only when strictly nearer), and the lanes' nearest with the lowest index
// wins, the hit the triangles tested one by one in order would keep. The rare rays that need
// the scalar test's double precision or error bound somewhere are tested by it throughout.
inline DeviceHit trace_small(local const SmallScene* s, global const DeviceTriangle* tris,
                          const SceneSurfaces* surf, float3 o, float3 d, float tmin, float tmax,
                          bool any_hit) {
    RayPrep r = prepare_ray(o, d);
    DeviceHit hit = no_hit(tmax);
    float4 op = ray_permute((float4)(o, 0.0f), r.perm);
    uint kx = r.perm.x, ky = r.perm.y, kz = r.perm.z;
    float16 sx = (float16)(r.shear.x), sy = (float16)(r.shear.y), sz = (float16)(r.shear.z);
    float16 zero = (float16)(0.0f);
    float16 best_t = (float16)(tmax);
    float16 best_v = zero, best_w = zero, best_det = zero;
    int16 best_index = (int16)(SMALL_BATCHES * SMALL_LANES);
    int16 any_special = (int16)(0);
    int16 lanes = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    uint count = s->count;
#pragma unroll
    for (uint at = 0u; at < SMALL_BATCHES * SMALL_LANES; at += SMALL_LANES) {
        Lane16Triangle tri;
        tri.aX = vload16(0, &s->c[kx][at]) - (float16)(op.x);
        tri.aY = vload16(0, &s->c[ky][at]) - (float16)(op.y);
        tri.aZ = vload16(0, &s->c[kz][at]) - (float16)(op.z);
        tri.bX = vload16(0, &s->c[3u + kx][at]) - (float16)(op.x);
        tri.bY = vload16(0, &s->c[3u + ky][at]) - (float16)(op.y);
        tri.bZ = vload16(0, &s->c[3u + kz][at]) - (float16)(op.z);
        tri.cX = vload16(0, &s->c[6u + kx][at]) - (float16)(op.x);
        tri.cY = vload16(0, &s->c[6u + ky][at]) - (float16)(op.y);
        tri.cZ = vload16(0, &s->c[6u + kz][at]) - (float16)(op.z);
        Lane16Edges e = lane16_edges(&tri, sx, sy);
        int16 index = lanes + (int16)((int)at);
        int16 lane = index < (int16)((int)count);
        Lane16Verdict h = lane16_verdict(&tri, e, sz, lane, (float16)(tmin), best_t);
        int16 ok = h.ok;
        any_special |= h.special;
        best_t = select(best_t, h.t, ok);
        best_v = select(best_v, e.v, ok);
        best_w = select(best_w, e.w, ok);
        best_det = select(best_det, h.det, ok);
        best_index = select(best_index, index, ok);
    }
    if (small_min(any_special) < 0) {
        // Rare cases for the scalar test, as in intersect_leaf4.
        intersect_leaf(&r, tris, surf, 0u, count, tmin, o, d, any_hit, &hit);
        return hit;
    }
    int16 found = best_index < (int16)((int)count);
    if (small_min(found) == 0) return hit;
    // Distances above tmin >= 0 order as their bits do.
    float m = as_float(small_min(as_int16(best_t)));
    int k = small_min(select((int16)(SMALL_BATCHES * SMALL_LANES), best_index,
                             found & (best_t == (float16)(m))));
    float vk[SMALL_LANES], wk[SMALL_LANES], dk[SMALL_LANES];
    vstore16(best_v, 0, vk);
    vstore16(best_w, 0, wk);
    vstore16(best_det, 0, dk);
    int lane = k % SMALL_LANES;
    hit.t = m;
    hit.u = vk[lane] / dk[lane];
    hit.v = wk[lane] / dk[lane];
    hit.prim = (uint)k;
    return hit;
}

// trace_small in trace_scene_wide's form (the tree's arguments unused).
inline DeviceHit trace_small_scene(local const SmallScene* s, global const DeviceTriangle* tris,
                                global const DeviceInstance* instances,
                                global const DeviceTriangle* object_tris, const SceneSurfaces* surf,
                                float3 o, float3 d, float tmin, float tmax, bool any_hit,
                                volatile global uint* overflow) {
    return trace_small(s, tris, surf, o, d, tmin, tmax, any_hit);
}
#endif

// triangle_normal of triangle `prim`, t, read from the megakernel's copy of a small scene
// where there is one.
inline float3 flat_normal(const SceneSurfaces* surf, uint prim, DeviceTriangle t) {
#ifdef SMALL_SCENE
    if (surf->small) return surf->small->normal[prim].xyz;
#endif
    return triangle_normal(t.v0.xyz, t.v1.xyz, t.v2.xyz);
}

#endif  // SHARED_TRAVERSE_WIDE_H
