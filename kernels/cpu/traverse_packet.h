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
    LANES_LOAD_RAYS(R)
    vstore_lanes(ox, 0, P->ox);
    vstore_lanes(oy, 0, P->oy);
    vstore_lanes(oz, 0, P->oz);
    vstore_lanes(ix, 0, P->ix);
    vstore_lanes(iy, 0, P->iy);
    vstore_lanes(iz, 0, P->iz);
    vstore_lanes(px, 0, P->px);
    vstore_lanes(py, 0, P->py);
    vstore_lanes(pz, 0, P->pz);
    vstore_lanes(sx, 0, P->sx);
    vstore_lanes(sy, 0, P->sy);
    vstore_lanes(sz, 0, P->sz);
    vstore_lanes(kz, 0, P->kz);
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

// Walks the rays of the lanes `live` (from tmin 0 to each lane's tfar) for their nearest hits,
// or with any_hit for some hit each (a lane's prim >= 0 after it: occluded), writing the hits
// to P. A packet whose stack would overflow ends with the hits so far (counted).
LANES_INLINE void packet_walk(Packet* P, vint live, bool any_hit,
                              global const DeviceWideNode* nodes, global const DeviceTriangle* tris,
                              const SceneSurfaces* surf, volatile global uint* overflow) {
    const vfloat inf = (vfloat)(INFINITY), zero = (vfloat)(0.0f);
    const vint izero = (vint)(0);
    vfloat ox = vload_lanes(0, P->ox), oy = vload_lanes(0, P->oy), oz = vload_lanes(0, P->oz);
    vfloat ix = vload_lanes(0, P->ix), iy = vload_lanes(0, P->iy), iz = vload_lanes(0, P->iz);
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
            float4 lx = n->min_x, ly = n->min_y, lz = n->min_z;
            float4 hx = n->max_x, hy = n->max_y, hz = n->max_z;
            int4 ch = n->child;
            int4 ct = as_int4(n->count);
            vfloat dv[4];
            float key[4];
            int cv[4];
            // Child J (component C): the slab test in every lane of m (LANES_BOX).
#define PACKET_CHILD(J, C)                                                                   \
    {                                                                                        \
        LANES_BOX(lx.C, ly.C, lz.C, hx.C, hy.C, hz.C, near, far)                             \
        vint reach = m & (near <= far) & (near < tfar);                                     \
        if (ch.C <= 0 && ct.C == 0) reach = izero;                                           \
        dv[J] = select(inf, near, reach);                                                    \
        key[J] = packet_min(dv[J]);                                                          \
        cv[J] = ct.C != 0 ? (int)(0x80000000u | ((uint)ct.C << 27) | (uint)~ch.C) : ch.C;   \
    }
            PACKET_CHILD(0, x)
            PACKET_CHILD(1, y)
            PACKET_CHILD(2, z)
            PACKET_CHILD(3, w)
#undef PACKET_CHILD
            // Nearest first (by the nearest lane's entry; with any_hit in slot order): the
            // others pushed farthest first, the nearest entered.
            uint s0 = 0u, s1 = 1u, s2 = 2u, s3 = 3u;
            if (!any_hit) {
#define PACKET_ORDER(A, B)                        \
    if (key[s##B] < key[s##A]) {                  \
        uint t_ = s##A;                           \
        s##A = s##B;                              \
        s##B = t_;                                \
    }
                PACKET_ORDER(0, 1)
                PACKET_ORDER(2, 3)
                PACKET_ORDER(0, 2)
                PACKET_ORDER(1, 3)
                PACKET_ORDER(1, 2)
#undef PACKET_ORDER
            }
            if (sp + 3 > PACKET_STACK) {
                atomic_inc(overflow);
                break;
            }
#define PACKET_PUSH(S)                          \
    if (key[S] < INFINITY) {                    \
        stack_d[sp] = dv[S];                    \
        stack_item[sp++] = cv[S];               \
    }
            PACKET_PUSH(s3)
            PACKET_PUSH(s2)
            PACKET_PUSH(s1)
#undef PACKET_PUSH
            if (key[s0] < INFINITY) {
                item = cv[s0];
                m = dv[s0] < inf;
                continue;
            }
        } else {
            // A leaf: each of its triangles against every lane of m.
            int first = item & LANES_FIRST_MASK;
            int count = (item >> 27) & 15;
            for (int k = 0; k < count; ++k) {
                DeviceTriangle tri = tris[first + k];
#define PACKET_VERTEX(V, X, Y, Z)                                                     \
    vfloat X, Y, Z;                                                                  \
    {                                                                                 \
        vfloat vx = (vfloat)(tri.V.x), vy = (vfloat)(tri.V.y), vz = (vfloat)(tri.V.z); \
        X = select(select(vx, vz, z1), vy, z0) - px;                                  \
        Y = select(select(vy, vx, z1), vz, z0) - py;                                  \
        Z = select(select(vz, vy, z1), vx, z0) - pz;                                  \
    }
                PACKET_VERTEX(v0, aX, aY, aZ)
                PACKET_VERTEX(v1, bX, bY, bZ)
                PACKET_VERTEX(v2, cX, cY, cZ)
#undef PACKET_VERTEX
                LANE_EDGES(vfloat)
                LANE_HITS_T(vfloat, vint, m, zero, tfar)
                LANES_KEEP_HITS(first + k, P->o, P->d, any_hit)
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
