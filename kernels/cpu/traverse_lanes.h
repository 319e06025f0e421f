// Rays in vector lanes, for the CPU megakernel (MEGA_LANES: set by the host on CPU devices with
// AVX-512 or AVX2, for flat scenes without alpha; strategy::kernel_strategy in
// src/render/strategy.rs): sixteen independent rays walk the 4-wide BVH together, one ray a lane,
// each at its own node, the lanes' nodes and triangles loaded as rows and transposed into
// vectors (lanes_rows8; LANES_GATHERS: by gathers). One ray at a time, a walk
// waits on memory at nearly every node it visits in a large scene (about 45 % of a diffuse
// ray's time waited for nodes and triangles, 2026-12-01); sixteen walks keep sixteen loads in
// flight, and a lane whose ray is done takes its path's next ray while the others go on.
//
// The rays are extension rays, from tmin 0 to infinity, for the nearest hit, or shadow rays, from
// tmin 0 to their light, for any hit (`any`: such a lane is done at its first). Each lane computes
// traverse_wide.h's slab test and intersect_leaf4's watertight arithmetic, so that the hit is
// traverse_wide's (of equally near hits the two walks may keep different triangles), and the
// scalar test's rare cases (an edge function of zero, a hit within the rounding-error bound)
// go to intersect_leaf itself. Leaves are stack items, as in Embree's walk, tested once enough
// lanes have reached one; a node's reached children are sorted by entry distance in every
// lane, the nearest entered and the others pushed farthest first.
#ifndef CPU_TRAVERSE_LANES_H
#define CPU_TRAVERSE_LANES_H

#include "shared/types.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"
#include "cpu/simd.h"

#ifdef MEGA_LANES
#define LANES_STACK (WIDE_STACK_SIZE + 1)
// A lane's stack is LANES_STACK entries and three more, which the eight-lane push of a node's
// children in one 32-byte store (lanes_walk) may write past its top.
#define LANES_STACK_STRIDE (LANES_STACK + 3)

// The word offset of each lane's stack entry sp (a lane's entries side by side).
LANES_INLINE vint lanes_entry(vint sp) {
    return (LANE_IDS * (vint)(LANES_STACK_STRIDE) + sp) * (vint)(2);
}

// intersect_triangle's arithmetic in every lane (traverse_wide.h): LanesTriangle, LanesEdges,
// LanesVerdict, lanes_edges and lanes_verdict.
DEFINE_LANE_TRIANGLE_TEST(Lanes, lanes, vfloat, vint)

// The lanes' rays and walks, one field a lane (offsets are in 4-byte words: a DeviceWideNode is 32,
// min_x, min_y, min_z, max_x, max_y, max_z, child, count, 4 each; a DeviceTriangle 12):
//   ox oy oz     origin                      ix iy iz   safe reciprocal direction (prepare_ray's)
//   px py pz     origin in the permuted axes sx sy sz   shear (prepare_ray's)
//   kx ky kz     the permutation, as word offsets in a vertex
//   tfar         the nearest hit's t so far  hv hw hdet its edge functions v, w and their sum
//   prim         its triangle (NO_HIT, -1, while none)
//   cur          the item visited, in lanes_pack form: a node, or a leaf (negative)
//   sp           stack entries               live has fin: lanes with a ray, with an item to
//                                            visit, done and not yet returned by lanes_walk
//   any          lanes whose ray is a shadow ray: done at its first hit before tfar
#define LANES_FLOAT_FIELDS(X) X(ox) X(oy) X(oz) X(ix) X(iy) X(iz) X(px) X(py) X(pz) \
    X(sx) X(sy) X(sz) X(tfar) X(hv) X(hw) X(hdet)
#define LANES_INT_FIELDS(X) X(kx) X(ky) X(kz) X(prim) X(cur) X(sp) X(live) X(has) X(fin) X(any)

// The fields as vectors, as lanes_walk works on them.
typedef struct {
#define LANES_VECTOR_F(f) vfloat f;
#define LANES_VECTOR_I(f) vint f;
    LANES_FLOAT_FIELDS(LANES_VECTOR_F)
    LANES_INT_FIELDS(LANES_VECTOR_I)
#undef LANES_VECTOR_F
#undef LANES_VECTOR_I
} Lanes;

// What the lanes keep: their fields, their stacks and rays. The fields are one block seen two
// ways: lane by lane (`M->ox[l]`), as scalar code writes a lane's ray, and as Lanes' vectors
// (`M->V.ox`), which lanes_walk reads and writes where they are. The compiler keeps a walk's
// fields in memory either way (26 vectors with the walk's temporaries are more than the 32
// registers); a private copy for the walk, loaded as it began and stored as it returned, cost
// 3-6 % of the 1 M-triangle scenes' time in the copies (AMD Zen 4, 2026-12-03).
typedef struct {
    union {
        Lanes V;
        struct {
#define LANES_ARRAY_F(f) float f[LANES];
#define LANES_ARRAY_I(f) int f[LANES];
            LANES_FLOAT_FIELDS(LANES_ARRAY_F)
            LANES_INT_FIELDS(LANES_ARRAY_I)
#undef LANES_ARRAY_F
#undef LANES_ARRAY_I
        };
    };
    // The stacks: entry k of lane l at word 2 (l LANES_STACK_STRIDE + k) (lanes_entry), its entry
    // distance, then its item in lanes_pack form (as float bits).
    float stack[2 * LANES_STACK_STRIDE * LANES];
    float3 o[LANES], d[LANES];  // the rays, for the scalar test's rare cases
} LaneMemory;

LANES_INLINE void lanes_init(LaneMemory* M) {
    const Lanes zero = {0};
    M->V = zero;
    M->V.hdet = (vfloat)(1.0f);
    M->V.prim = (vint)(-1);
}

// Rays given to lanes, lane by lane (scalar stores, which lanes_set_rays and packet_set_rays
// then load by vector: one wait for the stores a batch of rays, where a vector a field put
// together by selects lived on the stack, three instructions a field a ray): origins,
// directions, each ray's end (tmax), whether it is a shadow ray (any: done at its first hit),
// and the lanes that took one (bit l of `taken`). Lanes that took none keep stale values, which
// are computed on and discarded.
typedef struct {
    float ox[LANES], oy[LANES], oz[LANES], dx[LANES], dy[LANES], dz[LANES], tmax[LANES];
    int any[LANES];
    uint taken;
} LanesRays;

LANES_INLINE void lanes_rays_init(LanesRays* R) {
    for (int l = 0; l < LANES; ++l) {
        R->ox[l] = R->oy[l] = R->oz[l] = R->dx[l] = R->dy[l] = R->dz[l] = R->tmax[l] = 0.0f;
        R->any[l] = 0;
    }
    R->taken = 0u;
}

// Lane `lane` of R takes the ray from o along d, to tmax (any_hit: a shadow ray).
LANES_INLINE void lanes_rays_put(LanesRays* R, int lane, float3 o, float3 d, float tmax,
                                 bool any_hit) {
    R->ox[lane] = o.x;
    R->oy[lane] = o.y;
    R->oz[lane] = o.z;
    R->dx[lane] = d.x;
    R->dy[lane] = d.y;
    R->dz[lane] = d.z;
    R->tmax[lane] = tmax;
    R->any[lane] = any_hit ? -1 : 0;
    R->taken |= 1u << lane;
}

// traverse.h's ray set-up in every lane (shared/vec3.h): lanes_safe_rcp, lanes_pick (a component
// of each lane's vector (x, y, z) picked by the lane's axis k), lanes_ray_axes.
DEFINE_RAY_MATHS(LANES_INLINE, lanes_, vfloat, vint)

// A ray's origin and safe reciprocal direction in every lane, as the slab test reads them.
typedef struct {
    vfloat ox, oy, oz, ix, iy, iz;
} LanesSlabRay;

// traverse_wide.h's slab test of one box (its planes lx .. hz) in every lane of r: the entry
// distance (at least 0), and the exit distance in *far. With lo <= hi the near plane's distance
// is the lesser of the two, bit for bit (rounding is monotonic), so no plane is picked by the
// direction's sign.
LANES_INLINE vfloat lanes_box(const LanesSlabRay* r, float lx, float ly, float lz, float hx,
                              float hy, float hz, vfloat* far) {
    vfloat x0 = ((vfloat)(lx) - r->ox) * r->ix, x1 = ((vfloat)(hx) - r->ox) * r->ix;
    vfloat y0 = ((vfloat)(ly) - r->oy) * r->iy, y1 = ((vfloat)(hy) - r->oy) * r->iy;
    vfloat z0 = ((vfloat)(lz) - r->oz) * r->iz, z1 = ((vfloat)(hz) - r->oz) * r->iz;
    *far = WIDE_MIN(WIDE_MIN(WIDE_MAX(x0, x1), WIDE_MAX(y0, y1)), WIDE_MAX(z0, z1)) * 1.00000024f;
    return WIDE_MAX(WIDE_MAX(WIDE_MIN(x0, x1), WIDE_MIN(y0, y1)),
                    WIDE_MAX(WIDE_MIN(z0, z1), (vfloat)(0.0f)));
}

// prepare_ray's values in every lane: the safe reciprocal direction (ix, iy, iz), the
// permutation (kx, ky, kz: z the dominant axis), the origin in the permuted axes (px, py, pz)
// and the shear (sx, sy, sz).
typedef struct {
    vfloat ix, iy, iz, px, py, pz, sx, sy, sz;
    vint kx, ky, kz;
} LanesPrepared;

// prepare_ray lane by lane on the rays from (ox, oy, oz) along (dx, dy, dz), by selects (no
// branch on the dominant axis; one division an axis for all the lanes) and with prepare_ray's
// arithmetic (DEFINE_RAY_MATHS): its values bit for bit.
LANES_INLINE LanesPrepared lanes_prepare_rays(vfloat ox, vfloat oy, vfloat oz, vfloat dx,
                                              vfloat dy, vfloat dz) {
    LanesPrepared r;
    r.ix = lanes_safe_rcp(dx);
    r.iy = lanes_safe_rcp(dy);
    r.iz = lanes_safe_rcp(dz);
    lanes_ray_axes(fabs(dx), fabs(dy), fabs(dz), &r.kx, &r.ky, &r.kz);
    vfloat rz = lanes_pick(r.ix, r.iy, r.iz, r.kz);
    r.sx = lanes_pick(dx, dy, dz, r.kx) * rz;
    r.sy = lanes_pick(dx, dy, dz, r.ky) * rz;
    r.sz = rz;
    r.px = lanes_pick(ox, oy, oz, r.kx);
    r.py = lanes_pick(ox, oy, oz, r.ky);
    r.pz = lanes_pick(ox, oy, oz, r.kz);
    return r;
}

// R's rays as vectors: their origins in *ox, *oy, *oz, and lanes_prepare_rays's values.
LANES_INLINE LanesPrepared lanes_load_rays(const LanesRays* R, vfloat* ox, vfloat* oy,
                                           vfloat* oz) {
    *ox = vload_lanes(0, R->ox);
    *oy = vload_lanes(0, R->oy);
    *oz = vload_lanes(0, R->oz);
    return lanes_prepare_rays(*ox, *oy, *oz, vload_lanes(0, R->dx), vload_lanes(0, R->dy),
                              vload_lanes(0, R->dz));
}

// Lane `lane` will take the ray from o along d, to tmax (any_hit: a shadow ray, done at its
// first hit: any one, a hit says the segment is blocked); lanes_set_rays gives it the ray.
LANES_INLINE void lanes_take_ray(LaneMemory* M, LanesRays* R, int lane, float3 o, float3 d,
                                 float tmax, bool any_hit) {
    lanes_rays_put(R, lane, o, d, tmax, any_hit);
    M->o[lane] = o;
    M->d[lane] = d;
}

// The lanes that took rays in R take them, with no hit yet, written by vector (the walk reads them by
// vector: a vector load of words just stored one by one would wait for the stores, and the ray's
// set-up lane by lane cost 100 scalar instructions, with a branch on its dominant axis).
LANES_INLINE void lanes_set_rays(LaneMemory* M, const LanesRays* R) {
    Lanes* L = &M->V;
    const vint m =
        ((vint)((int)R->taken) >> LANE_IDS & (vint)(1)) != (vint)(0);
    vfloat ox, oy, oz;
    LanesPrepared r = lanes_load_rays(R, &ox, &oy, &oz);
    L->ox = select(L->ox, ox, m);
    L->oy = select(L->oy, oy, m);
    L->oz = select(L->oz, oz, m);
    L->ix = select(L->ix, r.ix, m);
    L->iy = select(L->iy, r.iy, m);
    L->iz = select(L->iz, r.iz, m);
    L->px = select(L->px, r.px, m);
    L->py = select(L->py, r.py, m);
    L->pz = select(L->pz, r.pz, m);
    L->sx = select(L->sx, r.sx, m);
    L->sy = select(L->sy, r.sy, m);
    L->sz = select(L->sz, r.sz, m);
    L->kx = select(L->kx, r.kx, m);
    L->ky = select(L->ky, r.ky, m);
    L->kz = select(L->kz, r.kz, m);
    L->tfar = select(L->tfar, vload_lanes(0, R->tmax), m);
    // No hit: hv, hw and hdet are read only with a hit, which sets them.
    L->prim = select(L->prim, (vint)(-1), m);
    L->sp = select(L->sp, (vint)(0), m);
    L->any = select(L->any, vload_lanes(0, R->any), m);
    L->cur = select(L->cur, (vint)(0), m);
    L->live |= m;
    L->has |= m;
}

// A lane's hit from its fields: distance, triangle (NO_HIT: none), edge functions v, w and
// their sum.
LANES_INLINE DeviceHit lanes_hit_from(float t, int prim, float v, float w, float det) {
    DeviceHit h;
    h.t = t;
    h.prim = (uint)prim;
    h.u = h.prim == NO_HIT ? 0.0f : v / det;
    h.v = h.prim == NO_HIT ? 0.0f : w / det;
    h.instance = 0u;
    return h;
}

// The hit of a lane whose walk is done.
LANES_INLINE DeviceHit lanes_hit(const LaneMemory* M, int lane) {
    return lanes_hit_from(M->tfar[lane], M->prim[lane], M->hv[lane], M->hw[lane],
                          M->hdet[lane]);
}

// The lanes' watertight test's rare cases (an edge function of zero, a hit within the
// rounding-error bound): for each lane of `special`, the scalar test (intersect_leaf: double-
// precision edge functions, the error bound) decides triangle tri of that lane's ray o, d,
// with the lane's hit so far in *t, *v, *w, *det, *prim, which it updates.
LANES_INLINE void lanes_rare_cases(vint special, vint tri, const float3* o, const float3* d,
                                   global const DeviceTriangle* tris, const SceneSurfaces* surf,
                                   bool any_hit, vfloat* t, vfloat* v, vfloat* w,
                                   vfloat* det, vint* prim) {
    int sp_[LANES], tri_[LANES], prim_[LANES];
    float t_[LANES], v_[LANES], w_[LANES], det_[LANES];
    vstore_lanes(special, 0, sp_);
    vstore_lanes(tri, 0, tri_);
    vstore_lanes(*t, 0, t_);
    vstore_lanes(*v, 0, v_);
    vstore_lanes(*w, 0, w_);
    vstore_lanes(*det, 0, det_);
    vstore_lanes(*prim, 0, prim_);
    for (int l = 0; l < LANES; ++l) {
        if (!sp_[l]) continue;
        RayPrep r = prepare_ray(o[l], d[l]);
        DeviceHit h = no_hit(t_[l]);
        intersect_leaf(&r, tris, surf, (uint)tri_[l], 1u, 0.0f, o[l], d[l], any_hit, &h);
        if (h.prim != NO_HIT) {
            t_[l] = h.t;
            v_[l] = h.u;
            w_[l] = h.v;
            det_[l] = 1.0f;
            prim_[l] = (int)h.prim;
        }
    }
    *t = vload_lanes(0, t_);
    *v = vload_lanes(0, v_);
    *w = vload_lanes(0, w_);
    *det = vload_lanes(0, det_);
    *prim = vload_lanes(0, prim_);
}

// Triangle tri's verdict h (with its edge functions e) kept in the lanes of h.ok that it does
// not send to the scalar test, nearer than their hits so far (*t, *v, *w, *det, *prim); the
// scalar test decides the lanes of h.special (whose rays are o[l], d[l]).
LANES_INLINE void lanes_keep_hits(LanesVerdict h, LanesEdges e, vint tri, const float3* o,
                                  const float3* d, global const DeviceTriangle* tris,
                                  const SceneSurfaces* surf, bool any_hit, vfloat* t, vfloat* v,
                                  vfloat* w, vfloat* det, vint* prim) {
    vint ok = h.ok & ~h.special;
    *t = select(*t, h.t, ok);
    *v = select(*v, e.v, ok);
    *w = select(*w, e.w, ok);
    *det = select(*det, h.det, ok);
    *prim = select(*prim, tri, ok);
    if (lanes_any(h.special)) {
        lanes_rare_cases(h.special, tri, o, d, tris, surf, any_hit, t, v, w, det, prim);
    }
}

// Lanes at a leaf are tested together once at least this many are (the others wait at it).
// Six of sixteen and three of eight measured fastest; two or four of eight were no faster on
// AMD's Zen 3 (2026-12-04).
#ifndef LANES_LEAF_MIN
#define LANES_LEAF_MIN (LANES == 16 ? 6 : 3)
#endif

// lanes_walk returns once this many lanes are done (or none is left walking): each return
// costs the shading loop's round over the lanes and the lanes' vectors to and from memory.
#ifndef LANES_DONE_MIN
#define LANES_DONE_MIN (LANES / 4)
#endif

// An item (the one a lane visits, or a stack entry) in one word: an interior child's index,
// or a leaf (child ~first, count k) as the sign bit, k in the next four bits and first below
// (the host enables lanes only for scenes of fewer than 2^27 triangles and leaves of at most
// 15: lanes_megakernel).
#define LANES_FIRST_MASK 0x07ffffff
LANES_INLINE vint lanes_pack(vint c, vint k) {
    return select(c, (vint)(0x80000000) | (k << (vint)(27)) | ~c, k != (vint)(0));
}

// Starts loading, for each lane of m, `bytes` bytes from element `first` (of `size` bytes) of
// the array at `base` into the caches, one prefetch a 64 bytes and no branch but the loop over
// the lanes (a lane reaching a leaf waits for others to reach theirs, a lane done for others
// to finish: the loads meanwhile cost nothing). The last byte's line is fetched too where an
// element may straddle one more line than the loop reaches; elements of whole lines (the
// nodes, 128 bytes, in buffers aligned to pages) need no such fetch, and after inlining the
// test folds away.
// With eight lanes every lane prefetches, those outside m element 0 (the root node, the first
// triangle: cached), with no branch but the mask's test: the loop over m's lanes took 6 % more
// time on the 1 M-triangle scenes on Zen 3; sixteen lanes keep the loop (not measured where
// they run).

// lanes_prefetch's loads of one element, at a.
LANES_INLINE void lanes_prefetch_element(ulong a, uint size, uint bytes) {
    // No unroll pragma: `bytes` is a constant only after inlining, and the compiler unrolls
    // these few iterations itself then (the pragma made PoCL warn where it could not).
    for (uint o = 0u; o < bytes; o += 64u) __builtin_prefetch((const void*)(a + o));
    if (size % 64u != 0u || bytes % 64u != 0u) __builtin_prefetch((const void*)(a + bytes - 1u));
}

LANES_INLINE void lanes_prefetch(ulong base, vint first, uint size, uint bytes, vint m) {
    uint bits = lanes_kmask(m);
    if (bits == 0u) return;
#if LANES == 8
    // The lanes' byte offsets as one vector of 64-bit words (one shift or multiply for all
    // lanes, 10-25 % fewer instructions in the prefetches than offsets lane by lane).
    long at_[LANES];
    vstore8(convert_long8(select((vint)(0), first, m)) * (long8)((long)size), 0, at_);
#pragma unroll
    for (int l = 0; l < LANES; ++l) lanes_prefetch_element(base + (ulong)at_[l], size, bytes);
#else
    int first_[LANES];
    vstore_lanes(first, 0, first_);
    while (bits != 0u) {
        uint l = (uint)__builtin_ctz(bits);
        bits &= bits - 1u;
        lanes_prefetch_element(base + (ulong)first_[l] * size, size, bytes);
    }
#endif
}

// The triangles prefetched of a leaf (a fixed number: a loop over each leaf's own count cost
// more in mispredicted branches than it saved; 2, 3 and 4 measured alike).
#ifndef LANES_PREFETCH_TRIS
#define LANES_PREFETCH_TRIS 4
#endif

// The node of `nodes` each lane of m goes to next (item, if a node): its two cache lines are
// fetched as the lane takes it, a node step's leaves and pops before the step loads it, so the
// sixteen lanes' misses overlap that work (4-8 % of the 1 M-triangle scenes' time on Zen 4).
LANES_INLINE void lanes_prefetch_node(global const DeviceWideNode* nodes, vint item, vint m) {
    lanes_prefetch((ulong)nodes, item, sizeof(DeviceWideNode), sizeof(DeviceWideNode),
                   m & (item >= (vint)(0)));
}

// Triangle tri of each lane of mask m (tw: the triangles as words), its vertices relative to the
// lane's origin in its permuted axes (kx, ky, kz: 0, 1 or 2; px, py, pz). Lanes outside m read
// triangle 0.
#ifdef LANES_GATHERS
LANES_INLINE LanesTriangle lanes_triangle(global const float* tw, vint tri, vint m, vint kx,
                                          vint ky, vint kz, vfloat px, vfloat py, vfloat pz) {
    LanesTriangle T;
    vint b = tri * (vint)(12);
    T.aX = lanes_gather((ulong)tw, b + kx, m) - px;
    T.aY = lanes_gather((ulong)tw, b + ky, m) - py;
    T.aZ = lanes_gather((ulong)tw, b + kz, m) - pz;
    T.bX = lanes_gather((ulong)tw, b + (vint)(4) + kx, m) - px;
    T.bY = lanes_gather((ulong)tw, b + (vint)(4) + ky, m) - py;
    T.bZ = lanes_gather((ulong)tw, b + (vint)(4) + kz, m) - pz;
    T.cX = lanes_gather((ulong)tw, b + (vint)(8) + kx, m) - px;
    T.cY = lanes_gather((ulong)tw, b + (vint)(8) + ky, m) - py;
    T.cZ = lanes_gather((ulong)tw, b + (vint)(8) + kz, m) - pz;
    return T;
}
#else
// Word v, v + 1 or v + 2 of the rows R, as k1 or k2 (the axis is 1, or 2) says.
LANES_INLINE vfloat lanes_axis(const vfloat* R, int v, vint k1, vint k2) {
    return select(select(R[v], R[v + 1], k1), R[v + 2], k2);
}

// As rows: each vertex's words in the lane's permuted axes by selects.
LANES_INLINE LanesTriangle lanes_triangle(global const float* tw, vint tri, vint m, vint kx,
                                          vint ky, vint kz, vfloat px, vfloat py, vfloat pz) {
    int off[LANES];
    vstore_lanes(select((vint)(0), tri * (vint)(12), m), 0, off);
    vfloat R[12];
    lanes_rows8(tw, off, 0, R);
    lanes_rows4(tw, off, 8, R + 8);
    vint kx1 = kx == (vint)(1), kx2 = kx == (vint)(2);
    vint ky1 = ky == (vint)(1), ky2 = ky == (vint)(2);
    vint kz1 = kz == (vint)(1), kz2 = kz == (vint)(2);
    LanesTriangle T;
    T.aX = lanes_axis(R, 0, kx1, kx2) - px;
    T.aY = lanes_axis(R, 0, ky1, ky2) - py;
    T.aZ = lanes_axis(R, 0, kz1, kz2) - pz;
    T.bX = lanes_axis(R, 4, kx1, kx2) - px;
    T.bY = lanes_axis(R, 4, ky1, ky2) - py;
    T.bZ = lanes_axis(R, 4, kz1, kz2) - pz;
    T.cX = lanes_axis(R, 8, kx1, kx2) - px;
    T.cY = lanes_axis(R, 8, ky1, ky2) - py;
    T.cZ = lanes_axis(R, 8, kz1, kz2) - pz;
    return T;
}
#endif

// The most (lane, triangle) pairs a leaf step tests sixteen at a time (more: one triangle of
// every lane at a time).
#ifndef LANES_PAIRS_MAX
#define LANES_PAIRS_MAX 64
#endif

// A child's slab test, one axis: the distances along the lanes' rays (origin o, reciprocal
// direction inv) of its near and far planes pn, pf, which become its entry and exit distances
// (first: the first axis), or are folded into them (*d, *f) as traverse_wide.h's slab test does.
LANES_INLINE void lanes_slab(vfloat pn, vfloat pf, vfloat o, vfloat inv, bool first, vfloat* d,
                             vfloat* f) {
    vfloat n = (pn - o) * inv, x = (pf - o) * inv;
    *d = first ? n : select(*d, n, n > *d);
    *f = first ? x : select(*f, x, x < *f);
}

// A child after its slab test (entry and exit distances d, f; child and count words cw, kw) in
// the lanes of mi: its entry distance (at least 0) where it is reached before the lane's hit
// tfar, else infinity; its item in lanes_pack form in *c.
LANES_INLINE vfloat lanes_child(vfloat d, vfloat f, vint cw, vint kw, vint mi, vfloat tfar,
                                vint* c) {
    const vfloat zero = (vfloat)(0.0f);
    const vint izero = (vint)(0);
    vfloat nr = select(d, zero, zero > d), fr = f * 1.00000024f;
    vint reach = mi & ((cw > izero) | (kw != izero)) & (nr <= fr) & (nr < tfar);
    *c = lanes_pack(cw, kw);
    return select((vfloat)(INFINITY), nr, reach);
}

#ifdef LANES_GATHERS
// Children j and j + 1 of each lane's node (at word offset base, lanes of mi, km its bits) by
// gathers: a row's words of two children are side by side, so one 8-byte gather element brings
// both (half the gathered elements). The near planes' word offsets are n*, the far ones' f*.
LANES_INLINE void lanes_children_gathered(const Lanes* L, global const float* nw, vint base,
                                          vint mi, vmask km, vint nx, vint ny, vint nz,
                                          vint fx, vint fy, vint fz, int j, vfloat* d,
                                          vint* c) {
    vint at = base + (vint)(j);
    vfloat n0, n1, f0, f1, d0, d1, e0, e1;
    lanes_gather_pair((ulong)nw, at + nx, km, &n0, &n1);
    lanes_gather_pair((ulong)nw, at + fx, km, &f0, &f1);
    lanes_slab(n0, f0, L->ox, L->ix, true, &d0, &e0);
    lanes_slab(n1, f1, L->ox, L->ix, true, &d1, &e1);
    lanes_gather_pair((ulong)nw, at + ny, km, &n0, &n1);
    lanes_gather_pair((ulong)nw, at + fy, km, &f0, &f1);
    lanes_slab(n0, f0, L->oy, L->iy, false, &d0, &e0);
    lanes_slab(n1, f1, L->oy, L->iy, false, &d1, &e1);
    lanes_gather_pair((ulong)nw, at + nz, km, &n0, &n1);
    lanes_gather_pair((ulong)nw, at + fz, km, &f0, &f1);
    lanes_slab(n0, f0, L->oz, L->iz, false, &d0, &e0);
    lanes_slab(n1, f1, L->oz, L->iz, false, &d1, &e1);
    vfloat cw0, cw1, kw0, kw1;
    lanes_gather_pair((ulong)nw, at + (vint)(24), km, &cw0, &cw1);
    lanes_gather_pair((ulong)nw, at + (vint)(28), km, &kw0, &kw1);
    d[j] = lanes_child(d0, e0, as_vint(cw0), as_vint(kw0), mi, L->tfar, &c[j]);
    d[j + 1] = lanes_child(d1, e1, as_vint(cw1), as_vint(kw1), mi, L->tfar, &c[j + 1]);
}
#else
// One axis of the four children's slab tests, the lanes' nodes as rows (each lane's at word
// offset off[l]): the planes at words wlo (minima) and whi (maxima), for the lanes' origin o
// and reciprocal direction inv (first: the first axis).
LANES_INLINE void lanes_node_axis(global const float* nw, const int* off, int wlo, int whi,
                                  vfloat o, vfloat inv, bool first, vfloat* d, vfloat* f) {
    vfloat lo[4], hi[4];
    vint pos = inv >= (vfloat)(0.0f);
    lanes_rows4(nw, off, wlo, lo);
    lanes_rows4(nw, off, whi, hi);
#pragma unroll
    for (int j = 0; j < 4; ++j) {
        lanes_slab(select(hi[j], lo[j], pos), select(lo[j], hi[j], pos), o, inv, first, &d[j],
                   &f[j]);
    }
}
#endif

// Compare-exchange of children a and b's (distance, item) pairs in every lane, nearest first.
LANES_INLINE void lanes_order(vfloat* d, vint* c, int a, int b) {
    vint s = d[b] < d[a];
    vfloat td = d[a];
    d[a] = select(d[a], d[b], s);
    d[b] = select(d[b], td, s);
    vint tc = c[a];
    c[a] = select(c[a], c[b], s);
    c[b] = select(c[b], tc, s);
}

// A node's sorted children 1, 2, 3 (entry distances d, items c) pushed, farthest first, onto the
// stacks of the lanes of mi that reached them (d < infinity), each lane's stack pointer *sp
// moved down past them.
LANES_INLINE void lanes_push_children(float* stack, vint* sp, vint mi, const vfloat* d,
                                      const vint* c) {
    const vfloat inf = (vfloat)(INFINITY);
#if LANES == 8
    // Eight lanes: a lane's pushed entries are one 32-byte store at its stack pointer. The
    // reached children are a prefix of 1, 2, 3 (sorted; the others at infinity), so the
    // entries, farthest first, are selects: the top is child 1, below it 2, 3.
    vint p1 = mi & (d[1] < inf), p2 = mi & (d[2] < inf), p3 = mi & (d[3] < inf);
    vfloat e[8];
    e[0] = select(select(d[1], d[2], p2), d[3], p3);
    e[1] = as_vfloat(select(select(c[1], c[2], p2), c[3], p3));
    e[2] = select(d[1], d[2], p3);
    e[3] = as_vfloat(select(c[1], c[2], p3));
    e[4] = d[1];
    e[5] = as_vfloat(c[1]);
    e[6] = e[7] = (vfloat)(0.0f);
    vfloat rows[8];
    lanes_transpose8(e, rows);
    int at[LANES];
    vstore_lanes(lanes_entry(*sp), 0, at);
#pragma unroll
    for (int l = 0; l < LANES; ++l) vstore8(rows[l], 0, stack + at[l]);
    *sp -= p1 + p2 + p3;
#else
    for (int j = 3; j >= 1; --j) {
        vint p = mi & (d[j] < inf);
        lanes_push_pair(stack, lanes_entry(*sp), lanes_kmask(p), d[j], as_vfloat(c[j]));
        *sp -= p;
    }
#endif
}

// Walks the lanes' rays until LANES_DONE_MIN are done or none is left walking; returns the
// mask of those done (their `live` lanes cleared). No lane live: returns an empty mask.
LANES_INLINE vint lanes_walk(LaneMemory* M, global const DeviceWideNode* nodes,
                              global const DeviceTriangle* tris, const SceneSurfaces* surf,
                              volatile global uint* overflow) {
    const vfloat inf = (vfloat)(INFINITY), zero = (vfloat)(0.0f);
    const vint izero = (vint)(0), lane = LANE_IDS;
    global const float* nw = (global const float*)nodes;
    global const float* tw = (global const float*)tris;
    Lanes* L = &M->V;
    while (lanes_any(L->live)) {
        vint arrived = izero;  // lanes that reached a leaf in this round
        // Interior nodes.
        vint mi = L->has & (L->cur >= izero);
        if (lanes_any(mi)) {
            vint base = L->cur * (vint)(32);
            vfloat d[4];
            vint c[4];
#ifdef LANES_GATHERS
            vmask km = lanes_kmask(mi);
            vint nx = select((vint)(12), izero, L->ix >= zero);
            vint ny = select((vint)(16), (vint)(4), L->iy >= zero);
            vint nz = select((vint)(20), (vint)(8), L->iz >= zero);
            vint fx = (vint)(12) - nx, fy = (vint)(20) - ny, fz = (vint)(28) - nz;
            lanes_children_gathered(L, nw, base, mi, km, nx, ny, nz, fx, fy, fz, 0, d, c);
            lanes_children_gathered(L, nw, base, mi, km, nx, ny, nz, fx, fy, fz, 2, d, c);
#else
            // The nodes as rows, one axis at a time, so that only one axis's planes and the
            // running distances are live: the 32 words of a node at once were more vectors than
            // registers.
            int off[LANES];
            vstore_lanes(select(izero, base, mi), 0, off);
            vfloat f[4];
            lanes_node_axis(nw, off, 0, 12, L->ox, L->ix, true, d, f);
            lanes_node_axis(nw, off, 4, 16, L->oy, L->iy, false, d, f);
            lanes_node_axis(nw, off, 8, 20, L->oz, L->iz, false, d, f);
            vfloat W[8];
            lanes_rows8(nw, off, 24, W);
#pragma unroll
            for (int j = 0; j < 4; ++j) {
                d[j] = lanes_child(d[j], f[j], as_vint(W[j]), as_vint(W[4 + j]), mi, L->tfar,
                                   &c[j]);
            }
#endif
            lanes_order(d, c, 0, 1);
            lanes_order(d, c, 2, 3);
            lanes_order(d, c, 0, 2);
            lanes_order(d, c, 1, 3);
            lanes_order(d, c, 1, 2);
            // A lane about to overflow its stack ends its walk with the hit so far (as
            // traverse_wide_bvh does; the overflow is counted).
            vint full = mi & (L->sp > (vint)(LANES_STACK - 4));
            if (lanes_any(full)) {
                atomic_add(overflow, (uint)lanes_count(full));
                L->sp = select(L->sp, izero, full);
                mi &= ~full;
                L->has &= ~full;
            }
            // The reached children but the nearest pushed, farthest first; the nearest entered.
            lanes_push_children(M->stack, &L->sp, mi, d, c);
            vint enter = mi & (d[0] < inf);
            arrived |= enter & (c[0] < izero);
            L->cur = select(L->cur, c[0], enter);
            lanes_prefetch_node(nodes, c[0], enter);
            L->has &= ~(mi & ~enter);
        }
        // Leaves, once enough lanes are at one (or no lane is at a node).
        vint ml = L->has & (L->cur < izero);
        if (lanes_any(ml) && (lanes_count(ml) >= LANES_LEAF_MIN || !lanes_any(L->has & ~ml))) {
            vint first = L->cur & (vint)(LANES_FIRST_MASK);
            vint cnt = (L->cur >> (vint)(27)) & (vint)(15);
            int kmax = lanes_max(select(izero, cnt, ml));
            // The leaves' (lane, triangle) pairs in order, each lane's first triangle before its
            // second (pl, pt): sixteen pairs a test, not one triangle of every lane a test, of
            // which the lanes whose leaves are done (or that wait at a node) would take no part.
            int pl[LANES_PAIRS_MAX + LANES], pt[LANES_PAIRS_MAX + LANES];
            int pairs = 0;
            bool by_k = kmax > LANES_PAIRS_MAX / LANES;
            for (int k = 0; k < kmax && !by_k; ++k) {
                ushort km = lanes_kmask(ml & ((vint)(k) < cnt));
                vstore_lanes(lanes_compress(lane, km), 0, pl + pairs);
                vstore_lanes(lanes_compress(first + (vint)(k), km), 0, pt + pairs);
                pairs += popcount((uint)km);
            }
            // Each pair's verdict against its lane's hit before the leaves (the nearest of a
            // lane's hits is then kept, the first of equally near ones: the walk by triangle
            // order's). A pair that needs the scalar test sends the leaves to that walk.
            float rt[LANES_PAIRS_MAX], rv[LANES_PAIRS_MAX], rw[LANES_PAIRS_MAX];
            float rdet[LANES_PAIRS_MAX];
            uint hits[LANES_PAIRS_MAX / LANES], found = 0u;
            for (int p0 = 0; p0 < pairs && !by_k; p0 += LANES) {
                vint idx = vload_lanes(0, pl + p0);
                vint tri = vload_lanes(0, pt + p0);
                vint m = (lane + (vint)(p0)) < (vint)(pairs);
                idx = select(izero, idx, m);
                vint kx = lanes_permute_i(L->kx, idx), ky = lanes_permute_i(L->ky, idx);
                vint kz = lanes_permute_i(L->kz, idx);
                vfloat px = lanes_permute(L->px, idx), py = lanes_permute(L->py, idx);
                vfloat pz = lanes_permute(L->pz, idx);
                vfloat sx = lanes_permute(L->sx, idx), sy = lanes_permute(L->sy, idx);
                vfloat sz = lanes_permute(L->sz, idx);
                LanesTriangle tv = lanes_triangle(tw, tri, m, kx, ky, kz, px, py, pz);
                LanesEdges e = lanes_edges(&tv, sx, sy);
                LanesVerdict h = lanes_verdict(&tv, e, sz, m, zero, lanes_permute(L->tfar, idx));
                by_k = lanes_any(h.special);
                vstore_lanes(h.t, 0, rt + p0);
                vstore_lanes(e.v, 0, rv + p0);
                vstore_lanes(e.w, 0, rw + p0);
                vstore_lanes(h.det, 0, rdet + p0);
                hits[p0 / LANES] = lanes_kmask(h.ok);
                found |= hits[p0 / LANES];
            }
            // No pair hit: the lanes' hits stand as they are. Else each hit, in pair order,
            // replaces its lane's if nearer, by selects (no branch on the distances, and no
            // vector load of words just stored one by one, which waits for the stores).
            if (!by_k && found != 0u) {
                vfloat tf = L->tfar, hv = L->hv, hw = L->hw, hdet = L->hdet;
                vint prim = L->prim;
                for (int p0 = 0; p0 < pairs; p0 += LANES) {
                    for (uint h = hits[p0 / LANES]; h != 0u; h &= h - 1u) {
                        int i = p0 + (int)__builtin_ctz(h);
                        vfloat t_ = (vfloat)(rt[i]);
                        vint nearer = (lane == (vint)(pl[i])) & (t_ < tf);
                        tf = select(tf, t_, nearer);
                        hv = select(hv, (vfloat)(rv[i]), nearer);
                        hw = select(hw, (vfloat)(rw[i]), nearer);
                        hdet = select(hdet, (vfloat)(rdet[i]), nearer);
                        prim = select(prim, (vint)(pt[i]), nearer);
                    }
                }
                L->tfar = tf;
                L->hv = hv;
                L->hw = hw;
                L->hdet = hdet;
                L->prim = prim;
            }
            if (!by_k) kmax = 0;  // done: no walk by triangle order
            // The leaves one triangle of every lane at a time, in order, each lane's hit updated
            // as it goes; the scalar test's rare cases in turn.
            for (int k = 0; k < kmax; ++k) {
                vint m = ml & ((vint)(k) < cnt);
                vint tri = first + (vint)(k);
                LanesTriangle tv =
                    lanes_triangle(tw, tri, m, L->kx, L->ky, L->kz, L->px, L->py, L->pz);
                LanesEdges e = lanes_edges(&tv, L->sx, L->sy);
                LanesVerdict h = lanes_verdict(&tv, e, L->sz, m, zero, L->tfar);
                lanes_keep_hits(h, e, tri, M->o, M->d, tris, surf, false, &L->tfar, &L->hv,
                                &L->hw, &L->hdet, &L->prim);
            }
            // A shadow ray that hit something is done: its stack emptied.
            L->sp = select(L->sp, izero, ml & L->any & (L->prim >= izero));
            L->has &= ~ml;
        }
        // The lanes without an item pop one, passing over entries beyond their hit; a lane
        // with an empty stack is done.
        vint done = izero;
        for (int round = 0; round < 3; ++round) {
            vint pm = L->live & ~L->has & ~done;
            if (!lanes_any(pm)) break;
            vint m = pm & (L->sp > izero);
            done |= pm & ~m;
            if (!lanes_any(m)) break;
            L->sp += m;
            vint at = lanes_entry(L->sp);
            vfloat d, itemf;
            lanes_pop_pair(M->stack, at, lanes_kmask(m), &d, &itemf);
            vint keep = m & (d < L->tfar);
            vint item = as_vint(itemf);
            L->cur = select(L->cur, item, keep);
            L->has |= keep;
            arrived |= keep & (item < izero);
            lanes_prefetch_node(nodes, item, keep);
        }
        // A leaf waits for other lanes to reach theirs: its triangles are fetched meanwhile.
        lanes_prefetch((ulong)tris, L->cur & (vint)(LANES_FIRST_MASK), sizeof(DeviceTriangle),
                       LANES_PREFETCH_TRIS * sizeof(DeviceTriangle), arrived & L->has);
        done &= L->live;
        // What shading reads of the hit (the triangle was just read).
        lanes_prefetch((ulong)surf->shading, L->prim, sizeof(DeviceTriShading), sizeof(DeviceTriShading),
                       done & (L->prim >= izero));
        L->live &= ~done;
        L->fin |= done;
        if (lanes_count(L->fin) >= LANES_DONE_MIN || !lanes_any(L->live)) {
            vint fin = L->fin;
            L->fin = izero;
            return fin;
        }
    }
    return (vint)(0);
}

#ifdef LANES_SMALL
// A small scene (LANES_SMALL: at most SMALL_SCENE_MAX triangles) is tested whole rather than
// walked: the root's four child boxes against every live lane, then each reached child's
// triangles against the lanes that reach it, all of them, with no stack and no turns at nodes,
// leaves and pops. A triangle's words are the same in every lane (loaded once, no gather), and
// every lane is done in one call. A subtree's triangles are a range in the tree's order; a
// ray that leaves the scene from a surface (an open scene's sky) still skips the children it
// does not reach.

// The triangles under each of the root's children: [first[j], end[j]) (empty for an empty
// slot), found once a work item by a walk of the small tree. A range covers its subtree's
// leaves (were they not contiguous, it would cover triangles of other children too, which are
// then tested twice, with the same verdicts).
LANES_INLINE void lanes_small_child(global const DeviceWideNode* nodes, int n, int i,
                                    uint* first, uint* end, int* stack, int* sp) {
    // Child i of node n: a leaf widens the range, an interior node is walked later.
    int c = ((global const int*)&nodes[n].child)[i];
    uint k = ((global const uint*)&nodes[n].count)[i];
    if (k != 0u) {
        *first = min(*first, (uint)~c);
        *end = max(*end, (uint)~c + k);
    } else if (c > 0) {
        stack[(*sp)++] = c;
    }
}

LANES_INLINE void lanes_small_ranges(global const DeviceWideNode* nodes, uint count, uint* first,
                                     uint* end) {
    for (int j = 0; j < 4; ++j) {
        first[j] = count;
        end[j] = 0u;
        int stack[LANES_STACK];
        int sp = 0;
        lanes_small_child(nodes, 0, j, &first[j], &end[j], stack, &sp);
        while (sp > 0) {
            if (sp + 4 > LANES_STACK) {
                // Deeper than a tree of so few triangles can be: all of them.
                first[j] = 0u;
                end[j] = count;
                break;
            }
            int n = stack[--sp];
            for (int i = 0; i < 4; ++i) {
                lanes_small_child(nodes, n, i, &first[j], &end[j], stack, &sp);
            }
        }
        end[j] = min(end[j], count);
    }
}

// Vertex v's axis k (each lane's permutation), relative to the lane's origin p on that axis.
LANES_INLINE vfloat lanes_small_axis(float4 v, vint k, vfloat p) {
    return lanes_pick((vfloat)(v.x), (vfloat)(v.y), (vfloat)(v.z), k) - p;
}

// Every live lane's ray against the triangles of the root's children it reaches (ranges:
// lanes_small_ranges's), each child's in order; the nearest hit is kept, the first of equally
// near ones (the verdicts are the leaf steps': lanes_edges, lanes_verdict, the scalar test's rare
// cases). Returns the lanes done: all that were live.
LANES_INLINE vint lanes_walk_small(LaneMemory* M, global const DeviceWideNode* nodes,
                                      global const DeviceTriangle* tris, const uint* first,
                                      const uint* end, const SceneSurfaces* surf) {
    Lanes* L = &M->V;
    const vint live = L->live;
    if (!lanes_any(live)) return (vint)(0);
    const vfloat zero = (vfloat)(0.0f);
    global const float4* tv = (global const float4*)tris;
    const vint kx = L->kx, ky = L->ky, kz = L->kz;
    const LanesSlabRay ray = {L->ox, L->oy, L->oz, L->ix, L->iy, L->iz};
    const vfloat px = L->px, py = L->py, pz = L->pz, sx = L->sx, sy = L->sy, sz = L->sz;
    vfloat tfar = L->tfar, hv = L->hv, hw = L->hw, hdet = L->hdet;
    vint prim = L->prim;
    global const float* r = (global const float*)nodes;  // the root: min_x .. max_z, 4 words each
    for (int j = 0; j < 4; ++j) {
        if (first[j] >= end[j]) continue;
        vfloat far;
        vfloat near = lanes_box(&ray, r[j], r[4 + j], r[8 + j], r[12 + j], r[16 + j], r[20 + j],
                                &far);
        const vint m = live & (near <= far) & (near < tfar);
        if (!lanes_any(m)) continue;
        for (uint i = first[j]; i < end[j]; ++i) {
            float4 a = tv[3u * i], b = tv[3u * i + 1u], c = tv[3u * i + 2u];
            LanesTriangle tri = {
                lanes_small_axis(a, kx, px), lanes_small_axis(a, ky, py),
                lanes_small_axis(a, kz, pz), lanes_small_axis(b, kx, px),
                lanes_small_axis(b, ky, py), lanes_small_axis(b, kz, pz),
                lanes_small_axis(c, kx, px), lanes_small_axis(c, ky, py),
                lanes_small_axis(c, kz, pz)};
            LanesEdges e = lanes_edges(&tri, sx, sy);
            LanesVerdict h = lanes_verdict(&tri, e, sz, m, zero, tfar);
            lanes_keep_hits(h, e, (vint)((int)i), M->o, M->d, tris, surf, false, &tfar, &hv, &hw,
                            &hdet, &prim);
        }
    }
    L->tfar = tfar;
    L->hv = hv;
    L->hw = hw;
    L->hdet = hdet;
    L->prim = prim;
    L->has &= ~live;
    L->live = (vint)(0);
    L->fin = (vint)(0);
    return live;
}
#endif

#endif  // MEGA_LANES

#endif  // CPU_TRAVERSE_LANES_H
