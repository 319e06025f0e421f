// Packets of coherent rays, for the CPU megakernel (MEGA_LANES): sixteen rays that start close
// together and go nearly the same way (a pixel's camera rays, or a 4×4 block's, and their light
// samples toward one point) walk the 4-wide BVH together, one node at a time for all of them:
// the node's boxes are read once, as scalars broadcast to the sixteen lanes, and tested against
// every ray of the packet, and a triangle is read once and tested against all of them. Where
// traverse_lanes.h's independent lanes pay sixteen gathers for every plane of every node, a
// packet pays one load, at the price of visiting the union of its rays' nodes, so it is for
// coherent rays only (Wald, Slusallek, Benthin, Wagner 2001; Embree's packet kernels).
//
// Each lane computes traverse_wide.h's slab test and intersect_leaf4's watertight arithmetic,
// so a closest hit is the scalar walk's (but for equally near triangles) and an any-hit
// verdict is the same; the scalar test's rare cases go to intersect_leaf itself, as in
// traverse_lanes.h. A stack entry holds an item (lanes_pack form: a node, or a leaf) and the
// entry distance of each lane that reached it (infinity for the others), so a popped entry
// is visited by exactly the lanes that reached it and whose hit is not nearer.
#ifndef CPU_TRAVERSE_PACKET_H
#define CPU_TRAVERSE_PACKET_H

#include "shared/types.h"
#include "shared/textures.h"
#include "shared/traverse_wide.h"
#include "cpu/simd.h"
#include "cpu/traverse_lanes.h"

#ifdef MEGA_LANES
#define PACKET_STACK (WIDE_STACK_SIZE + 1)

// A packet's rays, lane by lane (written by scalar code, loaded into vectors by packet_walk):
// origin, safe reciprocal direction, origin in the permuted axes, shear, the dominant axis
// (prepare_ray's kz, which names the permutation), and the hit: its distance (the ray's tmax
// until one is found), edge functions and triangle (-1 while none).
typedef struct {
    float ox[LANES], oy[LANES], oz[LANES], ix[LANES], iy[LANES], iz[LANES];
    float px[LANES], py[LANES], pz[LANES], sx[LANES], sy[LANES], sz[LANES];
    int kz[LANES];
    float tfar[LANES], hv[LANES], hw[LANES], hdet[LANES];
    int prim[LANES];
    float3 o[LANES], d[LANES];  // the rays, for the scalar test's rare cases
} Packet;

// Lane `lane` of the packet will take the ray from o along d, to tmax (packet_set_rays gives it).
LANES_INLINE void packet_take_ray(Packet* P, LanesRays* R, int lane, float3 o, float3 d,
                                  float tmax) {
    lanes_rays_put(R, lane, o, d, tmax, false);
    P->o[lane] = o;
    P->d[lane] = d;
}

// The packet's lanes take R's rays (all of them: the walk's mask says which it walks), with no
// hit yet.
LANES_INLINE void packet_set_rays(Packet* P, const LanesRays* R) {
    vfloat ox, oy, oz;
    LanesPrepared r = lanes_load_rays(R, &ox, &oy, &oz);
    vstore_lanes(ox, 0, P->ox);
    vstore_lanes(oy, 0, P->oy);
    vstore_lanes(oz, 0, P->oz);
    vstore_lanes(r.ix, 0, P->ix);
    vstore_lanes(r.iy, 0, P->iy);
    vstore_lanes(r.iz, 0, P->iz);
    vstore_lanes(r.px, 0, P->px);
    vstore_lanes(r.py, 0, P->py);
    vstore_lanes(r.pz, 0, P->pz);
    vstore_lanes(r.sx, 0, P->sx);
    vstore_lanes(r.sy, 0, P->sy);
    vstore_lanes(r.sz, 0, P->sz);
    vstore_lanes(r.kz, 0, P->kz);
    vstore_lanes(vload_lanes(0, R->tmax), 0, P->tfar);
    vstore_lanes((vfloat)(0.0f), 0, P->hv);
    vstore_lanes((vfloat)(0.0f), 0, P->hw);
    vstore_lanes((vfloat)(1.0f), 0, P->hdet);
    vstore_lanes((vint)(-1), 0, P->prim);
}

// The hit of a lane after a closest-hit walk.
LANES_INLINE DeviceHit packet_hit(const Packet* P, int lane) {
    return lanes_hit_from(P->tfar[lane], P->prim[lane], P->hv[lane], P->hw[lane],
                          P->hdet[lane]);
}

// The least lane of x.
inline float packet_min(vfloat x) {
#if LANES == 16
    float8 a = select(x.hi, x.lo, x.lo < x.hi);
#else
    float8 a = x;
#endif
    float4 b = select(a.hi, a.lo, a.lo < a.hi);
    float2 c = select(b.hi, b.lo, b.lo < b.hi);
    return c.x < c.y ? c.x : c.y;
}

// Child j of node n in the lanes of m: its entry distance in each lane that reaches it before
// its hit tfar, else infinity (lanes_box's slab test).
LANES_INLINE vfloat packet_child(const LanesSlabRay* ray, global const DeviceWideNode* n, int j,
                                 vint m, vfloat tfar) {
    global const float* w = (global const float*)n;  // min_x .. max_z, 4 words each
    vfloat far;
    vfloat near = lanes_box(ray, w[j], w[4 + j], w[8 + j], w[12 + j], w[16 + j], w[20 + j], &far);
    vint reach = m & (near <= far) & (near < tfar);
    return select((vfloat)(INFINITY), near, reach);
}

// Swaps the children in slots *a and *b where b's key is less (nearest first).
LANES_INLINE void packet_order(const float* key, uint* a, uint* b) {
    if (key[*b] < key[*a]) {
        uint t = *a;
        *a = *b;
        *b = t;
    }
}

// A triangle's vertex v relative to each lane's origin (px, py, pz) in its permuted axes, the
// permutation named by the dominant axis (z0: x is, z1: y is; else z).
LANES_INLINE void packet_vertex(float4 v, vint z0, vint z1, vfloat px, vfloat py, vfloat pz,
                                vfloat* X, vfloat* Y, vfloat* Z) {
    lanes_to_ray_axes((vfloat)(v.x), (vfloat)(v.y), (vfloat)(v.z), z0, z1, X, Y, Z);
    *X = *X - px;
    *Y = *Y - py;
    *Z = *Z - pz;
}

// A triangle's vertices relative to each lane's origin in its permuted axes (packet_vertex).
LANES_INLINE LanesTriangle packet_triangle(DeviceTriangle tri, vint z0, vint z1, vfloat px,
                                           vfloat py, vfloat pz) {
    LanesTriangle T;
    packet_vertex(tri.v0, z0, z1, px, py, pz, &T.aX, &T.aY, &T.aZ);
    packet_vertex(tri.v1, z0, z1, px, py, pz, &T.bX, &T.bY, &T.bZ);
    packet_vertex(tri.v2, z0, z1, px, py, pz, &T.cX, &T.cY, &T.cZ);
    return T;
}

// Walks the rays of the lanes `live` (from tmin 0 to each lane's tfar) for their nearest hits,
// or with any_hit for some hit each (a lane's prim >= 0 after it: occluded), writing the hits
// to P. A packet whose stack would overflow ends with the hits so far (counted).
LANES_INLINE void packet_walk(Packet* P, vint live, bool any_hit,
                              global const DeviceWideNode* nodes, global const DeviceTriangle* tris,
                              const SceneSurfaces* surf, volatile global uint* overflow) {
    const vfloat inf = (vfloat)(INFINITY), zero = (vfloat)(0.0f);
    const vint izero = (vint)(0);
    const LanesSlabRay ray = {vload_lanes(0, P->ox), vload_lanes(0, P->oy), vload_lanes(0, P->oz),
                              vload_lanes(0, P->ix), vload_lanes(0, P->iy), vload_lanes(0, P->iz)};
    vfloat px = vload_lanes(0, P->px), py = vload_lanes(0, P->py), pz = vload_lanes(0, P->pz);
    vfloat sx = vload_lanes(0, P->sx), sy = vload_lanes(0, P->sy), sz = vload_lanes(0, P->sz);
    vint kz = vload_lanes(0, P->kz);
    vint z0 = kz == izero, z1 = kz == (vint)(1);
    vfloat tfar = vload_lanes(0, P->tfar), hv = vload_lanes(0, P->hv), hw = vload_lanes(0, P->hw);
    vfloat hdet = vload_lanes(0, P->hdet);
    vint prim = vload_lanes(0, P->prim);
    vfloat stack_d[PACKET_STACK];
    int stack_item[PACKET_STACK];
    int sp = 0;
    int item = 0;       // the root
    vint m = live;     // the lanes visiting `item`
    vint open = live;  // the lanes still looking (with any_hit: not yet blocked)
    for (;;) {
        if (item >= 0) {
            global const DeviceWideNode* n = &nodes[item];
            global const int* ch = (global const int*)&n->child;
            global const int* ct = (global const int*)&n->count;
            vfloat dv[4];
            float key[4];
            int cv[4];
            // Each child's slab test in every lane of m (an empty slot in none), its item in
            // lanes_pack form.
#pragma unroll
            for (int j = 0; j < 4; ++j) {
                vint mj = ch[j] <= 0 && ct[j] == 0 ? izero : m;
                dv[j] = packet_child(&ray, n, j, mj, tfar);
                key[j] = packet_min(dv[j]);
                cv[j] = ct[j] != 0 ? (int)(0x80000000u | ((uint)ct[j] << 27) | (uint)~ch[j])
                                   : ch[j];
            }
            // Nearest first (by the nearest lane's entry; with any_hit in slot order): the
            // others pushed farthest first, the nearest entered.
            uint s[4] = {0u, 1u, 2u, 3u};
            if (!any_hit) {
                packet_order(key, &s[0], &s[1]);
                packet_order(key, &s[2], &s[3]);
                packet_order(key, &s[0], &s[2]);
                packet_order(key, &s[1], &s[3]);
                packet_order(key, &s[1], &s[2]);
            }
            if (sp + 3 > PACKET_STACK) {
                atomic_inc(overflow);
                break;
            }
            for (int i = 3; i >= 1; --i) {
                if (key[s[i]] < INFINITY) {
                    stack_d[sp] = dv[s[i]];
                    stack_item[sp++] = cv[s[i]];
                }
            }
            if (key[s[0]] < INFINITY) {
                item = cv[s[0]];
                m = dv[s[0]] < inf;
                continue;
            }
        } else {
            // A leaf: each of its triangles against every lane of m.
            int first = item & LANES_FIRST_MASK;
            int count = (item >> 27) & 15;
            for (int k = 0; k < count; ++k) {
                LanesTriangle tv = packet_triangle(tris[first + k], z0, z1, px, py, pz);
                LanesEdges e = lanes_edges(&tv, sx, sy);
                LanesVerdict h = lanes_verdict(&tv, e, sz, m, zero, tfar);
                lanes_keep_hits(h, e, (vint)(first + k), P->o, P->d, tris, surf, any_hit, &tfar,
                                &hv, &hw, &hdet, &prim);
                if (any_hit) {
                    // A blocked lane is done.
                    open &= prim < izero;
                    m &= open;
                    if (!lanes_any(m)) break;
                }
            }
            if (any_hit && !lanes_any(open)) break;
        }
        // The nearest pushed entry that some open lane still reaches before its hit.
        bool found = false;
        while (sp > 0) {
            --sp;
            m = open & (stack_d[sp] < tfar);
            if (lanes_any(m)) {
                item = stack_item[sp];
                found = true;
                break;
            }
        }
        if (!found) break;
    }
    vstore_lanes(tfar, 0, P->tfar);
    vstore_lanes(hv, 0, P->hv);
    vstore_lanes(hw, 0, P->hw);
    vstore_lanes(hdet, 0, P->hdet);
    vstore_lanes(prim, 0, P->prim);
}

#endif  // MEGA_LANES

#endif  // CPU_TRAVERSE_PACKET_H
