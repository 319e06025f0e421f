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

#ifdef MEGA_LANES
#define PACKET_STACK (WIDE_STACK_SIZE + 1)
// A packet is PACKET_GROUPS groups of LANES rays (one float16 a field a group).
#ifndef PACKET_GROUPS
#define PACKET_GROUPS 1
#endif
#define PACKET_RAYS (PACKET_GROUPS * LANES)
#define PACKET_FOR_GROUPS _Pragma("unroll") for (int g = 0; g < PACKET_GROUPS; ++g)

// A packet's rays, ray by ray (written by scalar code, loaded into vectors by packet_walk):
// origin, safe reciprocal direction, origin in the permuted axes, shear, the dominant axis
// (prepare_ray's kz, which names the permutation), and the hit: its distance (the ray's tmax
// until one is found), edge functions and triangle (-1 while none).
typedef struct {
    float ox[PACKET_RAYS], oy[PACKET_RAYS], oz[PACKET_RAYS];
    float ix[PACKET_RAYS], iy[PACKET_RAYS], iz[PACKET_RAYS];
    float px[PACKET_RAYS], py[PACKET_RAYS], pz[PACKET_RAYS];
    float sx[PACKET_RAYS], sy[PACKET_RAYS], sz[PACKET_RAYS];
    int kz[PACKET_RAYS];
    float tfar[PACKET_RAYS], hv[PACKET_RAYS], hw[PACKET_RAYS], hdet[PACKET_RAYS];
    int prim[PACKET_RAYS];
    float3 o[PACKET_RAYS], d[PACKET_RAYS];  // the rays, for the scalar test's rare cases
} Packet;

// Ray `i` of the packet: from o along d, to tmax.
LANES_INLINE void packet_set_ray(Packet* P, int i, float3 o, float3 d, float tmax) {
    RayPrep r = prepare_ray(o, d);
    float4 p = ray_permute((float4)(o, 0.0f), r.perm);
    P->ox[i] = o.x;
    P->oy[i] = o.y;
    P->oz[i] = o.z;
    P->ix[i] = r.inv.x;
    P->iy[i] = r.inv.y;
    P->iz[i] = r.inv.z;
    P->px[i] = p.x;
    P->py[i] = p.y;
    P->pz[i] = p.z;
    P->sx[i] = r.shear.x;
    P->sy[i] = r.shear.y;
    P->sz[i] = r.shear.z;
    P->kz[i] = (int)r.perm.z;
    P->tfar[i] = tmax;
    P->hv[i] = 0.0f;
    P->hw[i] = 0.0f;
    P->hdet[i] = 1.0f;
    P->prim[i] = -1;
    P->o[i] = o;
    P->d[i] = d;
}

// The hit of ray `i` after a closest-hit walk.
LANES_INLINE GpuHit packet_hit(const Packet* P, int i) {
    GpuHit h;
    h.t = P->tfar[i];
    h.prim = (uint)P->prim[i];
    h.u = h.prim == NO_HIT ? 0.0f : P->hv[i] / P->hdet[i];
    h.v = h.prim == NO_HIT ? 0.0f : P->hw[i] / P->hdet[i];
    h.instance = 0u;
    return h;
}

// The least lane of x.
inline float packet_min(float16 x) {
    float8 a = select(x.hi, x.lo, x.lo < x.hi);
    float4 b = select(a.hi, a.lo, a.lo < a.hi);
    float2 c = select(b.hi, b.lo, b.lo < b.hi);
    return c.x < c.y ? c.x : c.y;
}

#define PACKET_MIN(a, b) select(b, a, a < b)
#define PACKET_MAX(a, b) select(b, a, a > b)

// A packet walk can stop where its rays part ways: a node or leaf that few of them reach is
// not visited but handed to each of those rays, as an entry (its entry distance, the item) to
// push on the ray's stack in lanes (traverse_lanes.h), which walk the rest one ray a lane.
// Rays from one point in many directions (a pixel's samples' next rays) share the top of
// the tree, where lanes would gather the same nodes sixteen times over.
#ifndef PACKET_HANDOFF_ENTRIES
#define PACKET_HANDOFF_ENTRIES 24
#endif
#ifndef PACKET_HANDOFF_LANES
#define PACKET_HANDOFF_LANES 8  // an item reached by at most this many rays is handed off
#endif
typedef struct {
    float d[PACKET_HANDOFF_ENTRIES][PACKET_RAYS];
    int item[PACKET_HANDOFF_ENTRIES][PACKET_RAYS];
    int count[PACKET_RAYS];  // entries; -1 when more were due (the ray walks from the root)
} PacketHandoff;

// Whether any lane of any group of masks is set.
#define PACKET_ANY(M, out)                       \
    {                                            \
        int16 any_ = (int16)(0);                 \
        PACKET_FOR_GROUPS any_ |= (M)[g];        \
        out = lanes_any(any_);                   \
    }

// Walks the rays whose lanes are set in `live` (from tmin 0 to each ray's tfar) for their
// nearest hits, or with any_hit for some hit each (a ray's prim >= 0 after it: blocked),
// writing the hits to P. A packet whose stack would overflow ends with the hits so far
// (counted).
LANES_INLINE void packet_walk(Packet* P, const int16* live, bool any_hit,
                              global const GpuWideNode* nodes, global const GpuTriangle* tris,
                              const SceneSurfaces* surf, volatile global uint* overflow,
                              PacketHandoff* H) {
    const float16 inf = (float16)(INFINITY), zero = (float16)(0.0f);
    const int16 izero = (int16)(0);
    float16 ox[PACKET_GROUPS], oy[PACKET_GROUPS], oz[PACKET_GROUPS];
    float16 ix[PACKET_GROUPS], iy[PACKET_GROUPS], iz[PACKET_GROUPS], tfar[PACKET_GROUPS];
    int16 m[PACKET_GROUPS], open[PACKET_GROUPS];
    PACKET_FOR_GROUPS {
        ox[g] = vload16(g, P->ox);
        oy[g] = vload16(g, P->oy);
        oz[g] = vload16(g, P->oz);
        ix[g] = vload16(g, P->ix);
        iy[g] = vload16(g, P->iy);
        iz[g] = vload16(g, P->iz);
        tfar[g] = vload16(g, P->tfar);
        m[g] = live[g];     // the lanes visiting `item`
        open[g] = live[g];  // the lanes still looking (with any_hit: not yet blocked)
    }
    float16 entry[PACKET_GROUPS];  // the entry distances of `item` in the lanes of m
    PACKET_FOR_GROUPS entry[g] = select(inf, zero, live[g]);
    if (H) {
        for (int i = 0; i < PACKET_RAYS; ++i) H->count[i] = 0;
    }
    float16 stack_d[PACKET_STACK][PACKET_GROUPS];
    int stack_item[PACKET_STACK];
    int sp = 0;
    int item = 0;  // the root
    for (;;) {
        bool handed = false;
        if (H) {
            int reached = 0;
            PACKET_FOR_GROUPS reached += lanes_count(m[g]);
            if (reached <= PACKET_HANDOFF_LANES) {
                handed = true;
                PACKET_FOR_GROUPS {
                    uint bits = lanes_kmask(m[g]);
                    float d_[LANES];
                    vstore16(entry[g], 0, d_);
                    while (bits != 0u) {
                        int l = (int)__builtin_ctz(bits);
                        bits &= bits - 1u;
                        int i = g * LANES + l;
                        int c = H->count[i];
                        if (c < 0) continue;
                        if (c == PACKET_HANDOFF_ENTRIES) {
                            H->count[i] = -1;
                            continue;
                        }
                        H->d[c][i] = d_[l];
                        H->item[c][i] = item;
                        H->count[i] = c + 1;
                    }
                }
            }
        }
        if (handed) {
        } else if (item >= 0) {
            global const GpuWideNode* n = &nodes[item];
            float4 lx = n->min_x, ly = n->min_y, lz = n->min_z;
            float4 hx = n->max_x, hy = n->max_y, hz = n->max_z;
            int4 ch = n->child;
            int4 ct = as_int4(n->count);
            float16 dv[4][PACKET_GROUPS];
            float key[4];
            int cv[4];
            // Child J (component C): traverse_wide.h's slab test in every lane of m. With lo <=
            // hi the near plane's distance is the lesser of the two, bit for bit (rounding is
            // monotonic), so no plane is picked by the direction's sign.
#define PACKET_CHILD(J, C)                                                                   \
    {                                                                                        \
        bool used = ch.C > 0 || ct.C != 0;                                                   \
        key[J] = INFINITY;                                                                   \
        PACKET_FOR_GROUPS {                                                                  \
            float16 x0 = ((float16)(lx.C) - ox[g]) * ix[g];                                  \
            float16 x1 = ((float16)(hx.C) - ox[g]) * ix[g];                                  \
            float16 y0 = ((float16)(ly.C) - oy[g]) * iy[g];                                  \
            float16 y1 = ((float16)(hy.C) - oy[g]) * iy[g];                                  \
            float16 z0_ = ((float16)(lz.C) - oz[g]) * iz[g];                                 \
            float16 z1_ = ((float16)(hz.C) - oz[g]) * iz[g];                                 \
            float16 near = PACKET_MAX(PACKET_MAX(PACKET_MIN(x0, x1), PACKET_MIN(y0, y1)),    \
                                      PACKET_MAX(PACKET_MIN(z0_, z1_), zero));               \
            float16 far = PACKET_MIN(PACKET_MIN(PACKET_MAX(x0, x1), PACKET_MAX(y0, y1)),     \
                                     PACKET_MAX(z0_, z1_)) *                                 \
                          1.00000024f;                                                       \
            int16 reach = m[g] & (near <= far) & (near < tfar[g]);                           \
            if (!used) reach = izero;                                                        \
            dv[J][g] = select(inf, near, reach);                                             \
            key[J] = fmin(key[J], packet_min(dv[J][g]));                                     \
        }                                                                                    \
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
#ifndef PACKET_NO_PREFETCH
            // The reached children's nodes or triangles start loading: the packet visits
            // nearly all of them.
            for (int j = 0; j < 4; ++j) {
                if (!(key[j] < INFINITY)) continue;
                global const char* a = cv[j] >= 0
                    ? (global const char*)&nodes[cv[j]]
                    : (global const char*)&tris[cv[j] & LANES_FIRST_MASK];
                __builtin_prefetch(a);
                __builtin_prefetch(a + 64);
                if (cv[j] < 0) __builtin_prefetch(a + 128);
            }
#endif
            if (sp + 3 > PACKET_STACK) {
                atomic_inc(overflow);
                break;
            }
#define PACKET_PUSH(S)                                        \
    if (key[S] < INFINITY) {                                  \
        PACKET_FOR_GROUPS stack_d[sp][g] = dv[S][g];          \
        stack_item[sp++] = cv[S];                             \
    }
            PACKET_PUSH(s3)
            PACKET_PUSH(s2)
            PACKET_PUSH(s1)
#undef PACKET_PUSH
            if (key[s0] < INFINITY) {
                item = cv[s0];
                PACKET_FOR_GROUPS {
                    entry[g] = dv[s0][g];
                    m[g] = entry[g] < inf;
                }
                continue;
            }
        } else {
            // A leaf: each of its triangles against every lane of m.
            int first = item & LANES_FIRST_MASK;
            int count = (item >> 27) & 15;
            bool any_open = true;
            PACKET_FOR_GROUPS {
                if (!lanes_any(m[g])) continue;
                float16 px = vload16(g, P->px), py = vload16(g, P->py), pz = vload16(g, P->pz);
                float16 sx = vload16(g, P->sx), sy = vload16(g, P->sy), sz = vload16(g, P->sz);
                int16 kz = vload16(g, P->kz);
                int16 z0 = kz == izero, z1 = kz == (int16)(1);
                float16 hv = vload16(g, P->hv), hw = vload16(g, P->hw);
                float16 hdet = vload16(g, P->hdet);
                int16 prim = vload16(g, P->prim);
                float16 tf = tfar[g];
                int16 mg = m[g];
                for (int k = 0; k < count; ++k) {
                    GpuTriangle tri = tris[first + k];
#define PACKET_VERTEX(V, X, Y, Z)                                                          \
    float16 X, Y, Z;                                                                       \
    {                                                                                      \
        float16 vx = (float16)(tri.V.x), vy = (float16)(tri.V.y), vz = (float16)(tri.V.z); \
        X = select(select(vx, vz, z1), vy, z0) - px;                                       \
        Y = select(select(vy, vx, z1), vz, z0) - py;                                       \
        Z = select(select(vz, vy, z1), vx, z0) - pz;                                       \
    }
                    PACKET_VERTEX(v0, aX, aY, aZ)
                    PACKET_VERTEX(v1, bX, bY, bZ)
                    PACKET_VERTEX(v2, cX, cY, cZ)
#undef PACKET_VERTEX
                    LANE_EDGES(float16)
                    LANE_HITS16(mg, zero, tf)
                    ok &= ~special;
                    tf = select(tf, t, ok);
                    hv = select(hv, v, ok);
                    hw = select(hw, w, ok);
                    hdet = select(hdet, det, ok);
                    prim = select(prim, (int16)(first + k), ok);
                    if (lanes_any(special)) {
                        // The scalar test decides these lanes' triangle, with their hits so far.
                        int sp_[LANES], prim_[LANES];
                        float t_[LANES], v_[LANES], w_[LANES], det_[LANES];
                        vstore16(special, 0, sp_);
                        vstore16(tf, 0, t_);
                        vstore16(hv, 0, v_);
                        vstore16(hw, 0, w_);
                        vstore16(hdet, 0, det_);
                        vstore16(prim, 0, prim_);
                        for (int l = 0; l < LANES; ++l) {
                            if (!sp_[l]) continue;
                            int i = g * LANES + l;
                            RayPrep r = prepare_ray(P->o[i], P->d[i]);
                            GpuHit h = no_hit(t_[l]);
                            intersect_leaf(&r, tris, surf, (uint)(first + k), 1u, 0.0f, P->o[i],
                                           P->d[i], any_hit, &h);
                            if (h.prim != NO_HIT) {
                                t_[l] = h.t;
                                v_[l] = h.u;
                                w_[l] = h.v;
                                det_[l] = 1.0f;
                                prim_[l] = (int)h.prim;
                            }
                        }
                        tf = vload16(0, t_);
                        hv = vload16(0, v_);
                        hw = vload16(0, w_);
                        hdet = vload16(0, det_);
                        prim = vload16(0, prim_);
                    }
                    if (any_hit) {
                        // A blocked lane is done.
                        open[g] &= prim < izero;
                        mg &= open[g];
                        if (!lanes_any(mg)) break;
                    }
                }
                tfar[g] = tf;
                vstore16(hv, g, P->hv);
                vstore16(hw, g, P->hw);
                vstore16(hdet, g, P->hdet);
                vstore16(prim, g, P->prim);
            }
            if (any_hit) {
                PACKET_ANY(open, any_open)
                if (!any_open) break;
            }
        }
        // The nearest pushed entry that some open lane still reaches before its hit.
        bool found = false;
        while (sp > 0) {
            --sp;
            PACKET_FOR_GROUPS m[g] = open[g] & (stack_d[sp][g] < tfar[g]);
            PACKET_ANY(m, found)
            if (found) {
                item = stack_item[sp];
                PACKET_FOR_GROUPS entry[g] = stack_d[sp][g];
                break;
            }
        }
        if (!found) break;
    }
    PACKET_FOR_GROUPS vstore16(tfar[g], g, P->tfar);
}
#undef PACKET_MIN
#undef PACKET_MAX
#undef PACKET_ANY

// Lane `lane`, after lanes_set_ray, takes over ray i of a packet walk that handed it off: the
// hit the packet found for it, and the entries handed to it on its stack, the first handed
// (the packet went nearest first) on top; a ray with too many walks from the root.
LANES_INLINE void lanes_take_handoff(LaneMemory* M, int lane, const Packet* P,
                                     const PacketHandoff* H, int i) {
    M->tfar[lane] = P->tfar[i];
    M->hv[lane] = P->hv[i];
    M->hw[lane] = P->hw[i];
    M->hdet[lane] = P->hdet[i];
    M->prim[lane] = P->prim[i];
    int c = H->count[i];
    if (c < 0) return;
    for (int k = 0; k < c; ++k) {
        int at = ((c - 1 - k) * LANES + lane) * 2;
        M->stack[at] = H->d[k][i];
        M->stack[at + 1] = as_float(H->item[k][i]);
    }
    M->sp[lane] = c;
    M->has[lane] = 0;
}

#endif  // MEGA_LANES
