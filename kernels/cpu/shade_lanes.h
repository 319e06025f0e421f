// Path vertices shaded LANES at a time, for the CPU megakernel's lanes (megakernel_lanes.cl): the
// vertices that the lanes' extension rays found wait in a batch, and a full batch is shaded in
// vectors, one vertex a lane, instead of one shade_vertex call after another. A scalar vertex
// costs about 700 instructions; the same work in eight- or sixteen-wide vectors is a fraction of
// that a vertex, but only with the vectors full: a return from the walk hands back two or three
// finished lanes, so the megakernel keeps twice as many paths in flight as lanes (MEGA_SLOTS) and
// the lanes walk other paths' rays while a batch fills.
//
// It is path.h's shade_vertex for the scenes whose shading is simplest: every material
// Lambertian, no textures, environment map, unlit materials, thin walls or two levels
// (LANES_SHADE, set by the host: cl::lanes_shade in src/cl/program.rs). Each lane computes what
// shade_vertex computes, operation for operation in the same order (the OpenCL library's dot,
// cross and length spelled out as it computes them; PoCL's compiler fuses scalar products into
// sums but not vector ones, so the few that it fuses in the scalar form are written fma()
// here), draws the same random numbers, and samples an emissive triangle as sample_light does
// (other lights by sample_light itself, lane by lane): the same paths, bit for bit
// (tests/megakernel.rs compares the images). A chunk's camera hits, LANES or fewer at once, are
// shaded here too.
// Batches took 11.7 % fewer instructions on the 1 M-triangle room and about 12 % less time
// (AMD Zen 3, AVX2, 2026-12-04); shading the lanes done at each return instead (commit 29fe987)
// was no faster: too few to fill the vectors.
#ifndef CPU_SHADE_LANES_H
#define CPU_SHADE_LANES_H

#include "shared/types.h"
#include "shared/rng.h"
#include "shared/textures.h"
#include "cpu/traverse_lanes.h"
#include "shared/lights.h"
#include "shared/path.h"

#ifdef LANES_SHADE
#if !defined(MEGA_LANES) || !defined(LAMBERT_ONLY) || defined(HAS_TEXTURES) ||              \
    defined(HAS_NORMAL_MAPS) || defined(TWO_LEVEL) || defined(HAS_ENV_MAP) ||                \
    defined(HAS_UNLIT) || defined(HAS_THIN_WALLS) || defined(HAS_TRANSMISSION) ||           \
    defined(HAS_CLEARCOAT) || defined(HAS_SHEEN) || defined(HAS_DIFFUSE_TRANSMISSION) ||     \
    defined(HAS_ANISOTROPY) || defined(HAS_DISPERSION) || defined(SMALL_SCENE) ||            \
    defined(HAS_IRIDESCENCE)
#error "LANES_SHADE is for the lanes of scenes whose shading is simplest (cl::lanes_shade)"
#endif

#if LANES == 16
typedef uint16 lanes_u;
#define as_lanes_u as_uint16
#define convert_lanes_f convert_float16
#define convert_lanes_u convert_uint16
#else
typedef uint8 lanes_u;
#define as_lanes_u as_uint8
#define convert_lanes_f convert_float8
#define convert_lanes_u convert_uint8
#endif

// A batch of vertices to shade, field by field: entry e is a path's state (a PathState's fields
// that these scenes use) and the hit its last ray found; shading leaves the path's next ray and
// its light sample (a ShadowQuery's fields but the thin walls' `unweight`) in their place.
typedef struct {
    float dx[LANES], dy[LANES], dz[LANES];  // the ray's direction; after shading the next one's
    float tx[LANES], ty[LANES], tz[LANES];  // throughput
    float rx[LANES], ry[LANES], rz[LANES];  // radiance gathered so far
    float pdf[LANES];                       // of the BSDF sample that made the ray
    uint flags[LANES], rng[LANES];
    uint bounce[LANES];                     // of the vertex
    int prim[LANES];                        // the hit (NO_HIT as -1)
    float t[LANES], u[LANES], v[LANES];
    float ox[LANES], oy[LANES], oz[LANES];  // after shading: the next ray's origin
    int alive[LANES];                       // after shading: whether the path goes on
    // The light sample: valid, and its segment and the radiance it adds when clear.
    int valid[LANES];
    float qox[LANES], qoy[LANES], qoz[LANES], qdx[LANES], qdy[LANES], qdz[LANES];
    float qtmax[LANES], qcx[LANES], qcy[LANES], qcz[LANES];
} ShadeBatch;

// Entry e of the batch: a path's state and the hit of its last ray.
LANES_INLINE void shade_batch_put(ShadeBatch* B, int e, const PathState* s, uint bounce,
                                  GpuHit hit) {
    B->dx[e] = s->direction.x;
    B->dy[e] = s->direction.y;
    B->dz[e] = s->direction.z;
    B->tx[e] = s->throughput.x;
    B->ty[e] = s->throughput.y;
    B->tz[e] = s->throughput.z;
    B->rx[e] = s->radiance.x;
    B->ry[e] = s->radiance.y;
    B->rz[e] = s->radiance.z;
    B->pdf[e] = s->prev_pdf;
    B->flags[e] = s->flags;
    B->rng[e] = s->rng;
    B->bounce[e] = bounce;
    B->prim[e] = (int)hit.prim;
    B->t[e] = hit.t;
    B->u[e] = hit.u;
    B->v[e] = hit.v;
}

// The shaded entry e back into its path (as shade_vertex leaves it) and its light sample;
// returns whether the path goes on.
LANES_INLINE bool shade_batch_get(const ShadeBatch* B, int e, PathState* s, ShadowQuery* q) {
    s->radiance = (float3)(B->rx[e], B->ry[e], B->rz[e]);
    s->rng = B->rng[e];
    s->flags = B->flags[e];  // a camera ray's escape marked
    bool alive = B->alive[e] != 0;
    if (alive) {
        s->origin = (float3)(B->ox[e], B->oy[e], B->oz[e]);
        s->direction = (float3)(B->dx[e], B->dy[e], B->dz[e]);
        s->throughput = (float3)(B->tx[e], B->ty[e], B->tz[e]);
        s->prev_pdf = B->pdf[e];
    }
    q->valid = B->valid[e] != 0;
    if (q->valid) {
        q->origin = (float3)(B->qox[e], B->qoy[e], B->qoz[e]);
        q->direction = (float3)(B->qdx[e], B->qdy[e], B->qdz[e]);
        q->tmax = B->qtmax[e];
        q->contribution = (float3)(B->qcx[e], B->qcy[e], B->qcz[e]);
        q->unweight = 0.0f;  // only thin walls read it, and these scenes have none
    }
    return alive;
}

typedef struct {
    lanes_f x, y, z;
} LaneVec;

LANES_INLINE LaneVec lv_load(const float* x, const float* y, const float* z) {
    LaneVec v = {lanes_vload(0, x), lanes_vload(0, y), lanes_vload(0, z)};
    return v;
}

LANES_INLINE void lv_store(LaneVec v, float* x, float* y, float* z) {
    lanes_vstore(v.x, 0, x);
    lanes_vstore(v.y, 0, y);
    lanes_vstore(v.z, 0, z);
}

LANES_INLINE LaneVec lv_select(LaneVec a, LaneVec b, lanes_i m) {
    LaneVec r = {select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m)};
    return r;
}

LANES_INLINE LaneVec lv_neg(LaneVec a) {
    LaneVec r = {-a.x, -a.y, -a.z};
    return r;
}

// The OpenCL library's dot of float3 (kernel-x86_64 bitcode): the products, then x + y, then
// z added; one statement each, so that no compiler fuses a product into an addition.
LANES_INLINE lanes_f lv_dot(LaneVec a, LaneVec b) {
    lanes_f xx = a.x * b.x;
    lanes_f yy = a.y * b.y;
    lanes_f zz = a.z * b.z;
    lanes_f xy = xx + yy;
    return zz + xy;
}

// The library's length of float3: the root of dot(v, v), rescaled where that is below
// FLT_MIN or infinite (then the scalar length itself, lane by lane; all-zero lanes are 0
// either way).
LANES_INLINE lanes_f lv_length(LaneVec v) {
    lanes_f d = lv_dot(v, v);
    lanes_f len = sqrt(d);
    lanes_i zero = (v.x == 0.0f) & (v.y == 0.0f) & (v.z == 0.0f);
    lanes_i rare = ((d < 0x1p-126f) | (d == INFINITY)) & ~zero;
    if (lanes_any(rare)) {
        float x[LANES], y[LANES], z[LANES], out[LANES];
        int r[LANES];
        lv_store(v, x, y, z);
        lanes_vstore(len, 0, out);
        lanes_vstore(rare, 0, r);
        for (int l = 0; l < LANES; ++l) {
            if (r[l]) out[l] = length((float3)(x[l], y[l], z[l]));
        }
        len = lanes_vload(0, out);
    }
    return select(len, (lanes_f)(0.0f), zero);
}

LANES_INLINE lanes_f lanes_power_heuristic(lanes_f a, lanes_f b) {
    lanes_f a2 = a * a;
    lanes_f b2 = b * b;
    return select((lanes_f)(0.0f), a2 / (a2 + b2), a2 + b2 > 0.0f);
}

// rng_next in the lanes of m (the others' states kept; their numbers are meaningless).
LANES_INLINE lanes_f lanes_rng_next(lanes_u* state, lanes_i m) {
    lanes_u s = *state * 747796405u + 2891336453u;
    lanes_u word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    word = (word >> 22u) ^ word;
    *state = select(*state, s, m);
    return convert_lanes_f(word >> 8u) * (1.0f / 16777216.0f);
}

// offset_ray (traverse.h) in every lane.
LANES_INLINE LaneVec lanes_offset_ray(LaneVec p, LaneVec err, LaneVec n) {
    LaneVec an = {fabs(n.x), fabs(n.y), fabs(n.z)};
    lanes_f k = lv_dot(an, err);
    LaneVec r;
#define LANES_OFFSET(c)                                                                      \
    {                                                                                        \
        lanes_f offset = k * n.c;                                                            \
        lanes_f po = p.c + offset;                                                           \
        lanes_i bits = as_lanes_i(po);                                                       \
        lanes_i away = (po > 0.0f) == (offset > 0.0f);                                       \
        lanes_i stepped = select(bits - 1, bits + 1, away);                                  \
        stepped = select(stepped, select((lanes_i)(0x80000001), (lanes_i)(1), offset > 0.0f), \
                         po == 0.0f);                                                        \
        r.c = select(po, as_lanes_f(stepped), offset != 0.0f);                               \
    }
    LANES_OFFSET(x)
    LANES_OFFSET(y)
    LANES_OFFSET(z)
#undef LANES_OFFSET
    return r;
}

// unit_circle (rng.h) in every lane: (cos, sin) of 2 pi u, fused where the scalar form is.
LANES_INLINE void lanes_unit_circle(lanes_f u, lanes_f* cx, lanes_f* cy) {
    lanes_f q = rint(4.0f * u);
    lanes_f x = fma(q, (lanes_f)(-0.25f), u) * (2.0f * PI_F);
    lanes_f x2 = x * x;
    lanes_f s = fma(x * x2,
                    fma(x2, fma(x2, fma(x2, (lanes_f)(1.0f / 362880.0f), (lanes_f)(-1.0f / 5040.0f)),
                                (lanes_f)(1.0f / 120.0f)),
                        (lanes_f)(-1.0f / 6.0f)),
                    x);
    lanes_f c = fma(x2,
                    fma(x2, fma(x2, fma(x2, (lanes_f)(1.0f / 40320.0f), (lanes_f)(-1.0f / 720.0f)),
                                (lanes_f)(1.0f / 24.0f)),
                        (lanes_f)(-0.5f)),
                    (lanes_f)(1.0f));
    lanes_u k = convert_lanes_u(q) & 3u;
    lanes_i odd = as_lanes_i(k & 1u) != 0, back = as_lanes_i(k & 2u) != 0;
    lanes_f px = select(c, -s, odd), py = select(s, c, odd);
    *cx = select(px, -px, back);
    *cy = select(py, -py, back);
}

// surface_point (traverse.h) in every lane: the point at barycentrics (u, v) and its error bound.
LANES_INLINE LaneVec lanes_surface_point(LaneVec v0, LaneVec v1, LaneVec v2, lanes_f u, lanes_f v,
                                         LaneVec* err) {
    const float gamma7 = 7.0f * 0x1p-24f / (1.0f - 7.0f * 0x1p-24f);
    const float gamma64 = 64.0f * 0x1p-24f / (1.0f - 64.0f * 0x1p-24f);
    lanes_f w = 1.0f - u - v;
    LaneVec p = {w * v0.x + u * v1.x + v * v2.x, w * v0.y + u * v1.y + v * v2.y,
                 w * v0.z + u * v1.z + v * v2.z};
    lanes_f ex = fmax(fmax(fabs(v0.x - p.x), fabs(v1.x - p.x)), fabs(v2.x - p.x));
    lanes_f ey = fmax(fmax(fabs(v0.y - p.y), fabs(v1.y - p.y)), fabs(v2.y - p.y));
    lanes_f ez = fmax(fmax(fabs(v0.z - p.z), fabs(v1.z - p.z)), fabs(v2.z - p.z));
    lanes_f reach = fmax(fmax(ex, ey), ez);
    err->x = gamma7 * (fabs(w * v0.x) + fabs(u * v1.x) + fabs(v * v2.x)) + gamma64 * reach;
    err->y = gamma7 * (fabs(w * v0.y) + fabs(u * v1.y) + fabs(v * v2.y)) + gamma64 * reach;
    err->z = gamma7 * (fabs(w * v0.z) + fabs(u * v1.z) + fabs(v * v2.z)) + gamma64 * reach;
    return p;
}

// triangle_normal (traverse.h) in the lanes of m: the library's cross, scaled by a power of
// two, normalized.
LANES_INLINE LaneVec lanes_triangle_normal(LaneVec v0, LaneVec v1, LaneVec v2, lanes_i m) {
    LaneVec a = {v1.x - v0.x, v1.y - v0.y, v1.z - v0.z};
    LaneVec b = {v2.x - v0.x, v2.y - v0.y, v2.z - v0.z};
    lanes_f c1 = a.y * b.z, c2 = a.z * b.y;
    lanes_f c3 = a.z * b.x, c4 = a.x * b.z;
    lanes_f c5 = a.x * b.y, c6 = a.y * b.x;
    LaneVec c = {c1 - c2, c3 - c4, c5 - c6};
    lanes_f mc = fmax(fmax(fabs(c.x), fabs(c.y)), fabs(c.z));
    lanes_u e = (as_lanes_u(mc) >> 23u) & 0xffu;
    lanes_i normal_e = (e - 1u) < (lanes_u)(253u);
    lanes_f scale = as_lanes_f((254u - e) << 23u);
    if (lanes_any(m & ~normal_e)) {
        scale = select(ldexp((lanes_f)(1.0f), -ilogb(mc)), scale, normal_e);
    }
    LaneVec cs = {c.x * scale, c.y * scale, c.z * scale};
    lanes_f inv = 1.0f / sqrt(cs.x * cs.x + cs.y * cs.y + cs.z * cs.z);
    LaneVec n = {cs.x * inv, cs.y * inv, cs.z * inv};
    return lv_select(c, n, mc > 0.0f);
}

// A triangle's vertices (words 0-11 of each lane's GpuTriangle at word offset off[l]) and its
// words 3 and 7 (material, light index).
LANES_INLINE void lanes_triangle_rows(global const GpuTriangle* tris, const int* off, LaneVec* v0,
                                      LaneVec* v1, LaneVec* v2, lanes_i* w3, lanes_i* w7) {
    lanes_f T[12];
    global const float* tw = (global const float*)tris;
    lanes_rows8(tw, off, 0, T);
    lanes_rows4(tw, off, 8, T + 8);
    v0->x = T[0], v0->y = T[1], v0->z = T[2];
    v1->x = T[4], v1->y = T[5], v1->z = T[6];
    v2->x = T[8], v2->y = T[9], v2->z = T[10];
    *w3 = as_lanes_i(T[3]);
    *w7 = as_lanes_i(T[7]);
}

// Shades entries [0, n) of the batch, as shade_vertex does (see above): emission with MIS, the
// light sample, the BSDF sample of the next ray.
LANES_INLINE void lanes_shade(const GpuFrame* frame, const ShadeScene* sc, ShadeBatch* B,
                              int n) {
    const lanes_f zero = (lanes_f)(0.0f);
    const SceneSurfaces* surf = &sc->surf;
    lanes_i m = LANE_IDS < (lanes_i)(n);
    lanes_i valid = (lanes_i)(0), alive = (lanes_i)(0);
    lanes_u bounce = as_lanes_u(lanes_vload(0, (const int*)B->bounce));
    lanes_u rng = as_lanes_u(lanes_vload(0, (const int*)B->rng));
    lanes_u flags = as_lanes_u(lanes_vload(0, (const int*)B->flags));
    LaneVec thr = lv_load(B->tx, B->ty, B->tz);
    LaneVec rad = lv_load(B->rx, B->ry, B->rz);
    LaneVec wo = lv_neg(lv_load(B->dx, B->dy, B->dz));
    lanes_f prev_pdf = lanes_vload(0, B->pdf);
    lanes_i prev_specular = as_lanes_i(flags & PATH_SPECULAR) != 0;
    lanes_i camera = bounce == (lanes_u)(0u);
    lanes_i counts_emission =
        camera | prev_specular | (lanes_i)(frame->strategy != STRATEGY_LIGHTS ? -1 : 0);
    lanes_i mis = ~camera & ~prev_specular & (lanes_i)(frame->strategy == STRATEGY_MIS ? -1 : 0);
    lanes_i prim = lanes_vload(0, B->prim);
    lanes_f t = lanes_vload(0, B->t);

    // Escaped: the uniform sky, reached by BSDF sampling only. An escaped camera ray is marked
    // for the film's coverage count; with the background cut out it adds nothing.
    lanes_i escaped = m & (prim < 0);
    lanes_i ce = escaped & counts_emission;
    if (frame->background != BACKGROUND_ENV) {
        lanes_i marked = escaped & camera;
        flags = select(flags, flags | PATH_ESCAPED, marked);
        if (frame->background == BACKGROUND_CUTOUT) ce &= ~marked;
    }
    rad.x = select(rad.x, rad.x + thr.x * frame->sky.x, ce);
    rad.y = select(rad.y, rad.y + thr.y * frame->sky.y, ce);
    rad.z = select(rad.z, rad.z + thr.z * frame->sky.z, ce);
    m &= ~escaped;
    if (lanes_any(m)) {
        // The hit: its triangle's rows (lanes outside m read triangle 0).
        lanes_f hu = lanes_vload(0, B->u), hv = lanes_vload(0, B->v);
        int off[LANES];
        lanes_vstore(select((lanes_i)(0), prim * (lanes_i)(12), m), 0, off);
        LaneVec v0, v1, v2;
        lanes_i mat, light_index;
        lanes_triangle_rows(sc->tris, off, &v0, &v1, &v2, &mat, &light_index);
        lanes_f w0 = 1.0f - hu - hv;
        LaneVec perr;
        LaneVec p = lanes_surface_point(v0, v1, v2, hu, hv, &perr);
        LaneVec ng = lanes_triangle_normal(v0, v1, v2, m);
        lanes_i front = lv_dot(ng, wo) > 0.0f;
        // The material's base color and emission (lanes outside m read material 0).
        int moff[LANES];
        lanes_vstore(select((lanes_i)(0), mat * (lanes_i)(sizeof(GpuMaterial) / 4), m), 0, moff);
        lanes_f MB[8];
        lanes_rows8((global const float*)surf->materials, moff, 0, MB);
#ifdef HAS_TRIANGLE_LIGHTS
        // Emission of a light hit by this ray, weighted against light sampling of the last
        // vertex.
        {
            lanes_i two_sided = (as_lanes_i(MB[7]) & (lanes_i)(MATERIAL_DOUBLE_SIDED)) != 0;
            lanes_i em = m & (light_index >= 0) & (front | two_sided) & counts_emission;
            if (lanes_any(em)) {
                lanes_f weight = (lanes_f)(1.0f);
                lanes_i w_mis = em & mis;
                if (lanes_any(w_mis)) {
                    // The light's selection probability and area, lane by lane (rare).
                    float sel_[LANES], area_[LANES];
                    int li_[LANES];
                    lanes_vstore(select((lanes_i)(0), light_index, w_mis), 0, li_);
                    for (int l = 0; l < LANES; ++l) {
                        global const GpuLight* lt = &sc->lights[li_[l]];
                        sel_[l] = lt->extra.y;
                        area_[l] = lt->spot.y;
                    }
                    lanes_f sel = lanes_vload(0, sel_), area = lanes_vload(0, area_);
                    lanes_f cos_l = fabs(lv_dot(ng, wo));
                    lanes_f light_pdf = select(zero, sel * t * t / (area * cos_l), cos_l > 0.0f);
                    weight = select(weight, lanes_power_heuristic(prev_pdf, light_pdf), w_mis);
                }
                rad.x = select(rad.x, rad.x + thr.x * MB[4] * weight, em);
                rad.y = select(rad.y, rad.y + thr.y * MB[5] * weight, em);
                rad.z = select(rad.z, rad.z + thr.z * MB[6] * weight, em);
            }
        }
#endif
        // The last extension only looks for emitters.
        m &= bounce <= (lanes_u)(frame->max_bounces);
        // Face the normals towards the side the ray came from; the shading normal.
        ng = lv_select(lv_neg(ng), ng, front);
        LaneVec ns = ng;
        {
            int soff[LANES];
            lanes_vstore(select((lanes_i)(0), prim * (lanes_i)(9), m), 0, soff);
            lanes_f N[8];
            global const float* shw = (global const float*)surf->shading;
            lanes_rows8(shw, soff, 0, N);
            float n8_[LANES];
            for (int l = 0; l < LANES; ++l) n8_[l] = shw[soff[l] + 8];
            lanes_f n8 = lanes_vload(0, n8_);
            LaneVec sn = {w0 * N[0] + hu * N[3] + hv * N[6], w0 * N[1] + hu * N[4] + hv * N[7],
                          w0 * N[2] + hu * N[5] + hv * n8};
            lanes_f len = lv_length(sn);
            lanes_i has = len > 0.0f;
            LaneVec nn = {sn.x / len, sn.y / len, sn.z / len};
            nn = lv_select(nn, lv_neg(nn), lv_dot(nn, ng) < 0.0f);
            ns = lv_select(ns, nn, has);
        }
        LaneVec base = {MB[0], MB[1], MB[2]};

        // Next-event estimation: one light sample, its visibility tested by the caller.
        if (frame->strategy != STRATEGY_BSDF && frame->light_count > 0u && lanes_any(m)) {
            lanes_f ui = lanes_rng_next(&rng, m);
            lanes_f u1 = lanes_rng_next(&rng, m);
            lanes_f u2 = lanes_rng_next(&rng, m);
            float ui_[LANES], u1_[LANES], u2_[LANES], px[LANES], py[LANES], pz[LANES];
            float wx[LANES], wy[LANES], wz[LANES], dist[LANES], lx[LANES], ly[LANES], lz[LANES];
            float lpdf[LANES], gx[LANES], gy[LANES], gz[LANES];
            int on[LANES], tri_light[LANES], lprim[LANES];
            float lsel[LANES], larea[LANES];
            lanes_vstore(ui, 0, ui_);
            lanes_vstore(u1, 0, u1_);
            lanes_vstore(u2, 0, u2_);
            lv_store(p, px, py, pz);
            // The lights picked; emissive triangles are sampled in vectors below, other lights
            // by the scalar sample_light.
            for (int l = 0; l < LANES; ++l) {
                tri_light[l] = 0;
                lprim[l] = 0;
                lsel[l] = larea[l] = 1.0f;
            }
            for (uint bits = lanes_kmask(m); bits != 0u; bits &= bits - 1u) {
                int l = (int)__builtin_ctz(bits);
                uint index = cdf_search(sc->light_cdf, frame->light_count, ui_[l]);
#ifdef HAS_TRIANGLE_LIGHTS
                global const GpuLight* lt = &sc->lights[index];
                if (as_uint(lt->position.w) == LIGHT_TRIANGLE) {
                    tri_light[l] = -1;
                    lprim[l] = (int)as_uint(lt->spot.x) * 12;
                    lsel[l] = lt->extra.y;
                    larea[l] = lt->spot.y;
                    continue;
                }
#endif
                LightSample ls = sample_light(sc->lights, sc->tris, surf->materials, surf, &sc->env,
                                              index, (float3)(px[l], py[l], pz[l]), u1_[l], u2_[l]);
                wx[l] = ls.wi.x;
                wy[l] = ls.wi.y;
                wz[l] = ls.wi.z;
                dist[l] = ls.distance;
                lx[l] = ls.radiance.x;
                ly[l] = ls.radiance.y;
                lz[l] = ls.radiance.z;
                lpdf[l] = ls.pdf;
                gx[l] = ls.target.x;
                gy[l] = ls.target.y;
                gz[l] = ls.target.z;
                on[l] = ls.on_surface ? -1 : 0;
            }
            // Lanes outside m: their (uninitialised) values are selected away below.
            LaneVec wi = lv_load(wx, wy, wz), lr = lv_load(lx, ly, lz);
            lanes_f ls_pdf = lanes_vload(0, lpdf);
            lanes_f ls_dist = lanes_vload(0, dist);
            LaneVec target = lv_load(gx, gy, gz);
            lanes_i on_surface = lanes_vload(0, on);
#ifdef HAS_TRIANGLE_LIGHTS
            lanes_i tl = lanes_vload(0, tri_light);
            if (lanes_any(tl)) {
                // sample_light's emissive triangle, lane by lane as it computes it.
                LaneVec t0, t1, t2;
                lanes_i lmat, unused;
                lanes_triangle_rows(sc->tris, lprim, &t0, &t1, &t2, &lmat, &unused);
                lanes_f su = sqrt(u1);
                lanes_f bx = su * (1.0f - u2), by = su * u2;
                LaneVec q_err;
                LaneVec q = lanes_surface_point(t0, t1, t2, bx, by, &q_err);
                LaneVec lng = lanes_triangle_normal(t0, t1, t2, tl);
                LaneVec d = {q.x - p.x, q.y - p.y, q.z - p.z};
                lanes_f dist2 = lv_dot(d, d);
                lanes_i far = tl & ~(dist2 <= 0.0f);  // else nothing (pdf 0), wi +z, target p
                lanes_f distance = sqrt(dist2);
                LaneVec lwi = {d.x / distance, d.y / distance, d.z / distance};
                LaneVec pq = {p.x - q.x, p.y - q.y, p.z - q.z};
                LaneVec ltarget =
                    lanes_offset_ray(q, q_err, lv_select(lv_neg(lng), lng, lv_dot(lng, pq) > 0.0f));
                int loff[LANES];
                lanes_vstore(select((lanes_i)(0), lmat * (lanes_i)(sizeof(GpuMaterial) / 4), far),
                             0, loff);
                lanes_f E[4];
                lanes_rows4((global const float*)surf->materials, loff, 4, E);
                lanes_f cos_l = -lv_dot(lng, lwi);
                lanes_i two_sided = (as_lanes_i(E[3]) & (lanes_i)(MATERIAL_DOUBLE_SIDED)) != 0;
                lanes_i emits = far & (two_sided | ~(cos_l <= 0.0f));
                cos_l = fabs(cos_l);
                emits &= ~(cos_l <= 0.0f);
                lanes_f lp = lanes_vload(0, lsel) * dist2 / (lanes_vload(0, larea) * cos_l);
                LaneVec one = {(lanes_f)(0.0f), (lanes_f)(0.0f), (lanes_f)(1.0f)};
                wi = lv_select(wi, lv_select(one, lwi, far), tl);
                ls_dist = select(ls_dist, select(zero, distance, far), tl);
                target = lv_select(target, lv_select(p, ltarget, far), tl);
                on_surface = select(on_surface, far, tl);
                ls_pdf = select(ls_pdf, select(zero, lp, emits), tl);
                LaneVec lrad = {E[0] / lp, E[1] / lp, E[2] / lp};
                lr = lv_select(lr, lv_select((LaneVec){zero, zero, zero}, lrad, emits), tl);
            }
#endif
            lanes_f side = lv_dot(wi, ng);
            lanes_i ok = m & (side * lv_dot(wi, ns) > 0.0f) &
                         ((lr.x > 0.0f) | (lr.y > 0.0f) | (lr.z > 0.0f));
            if (lanes_any(ok)) {
                // bsdf_eval, Lambertian.
                lanes_f cos_i = lv_dot(wi, ns);
                lanes_i lit = (lv_dot(wo, ns) > 0.0f) & (cos_i > 0.0f);
                lanes_f bsdf_pdf = select(zero, cos_i * INV_PI_F, lit);
                lanes_f fc = cos_i * INV_PI_F;
                LaneVec f = {select(zero, base.x * fc, lit), select(zero, base.y * fc, lit),
                             select(zero, base.z * fc, lit)};
                lanes_f weight = select((lanes_f)(1.0f), lanes_power_heuristic(ls_pdf, bsdf_pdf),
                                        (lanes_i)(frame->strategy == STRATEGY_MIS ? -1 : 0) &
                                            (ls_pdf > 0.0f));
                LaneVec c = {thr.x * f.x * lr.x * weight, thr.y * f.y * lr.y * weight,
                             thr.z * f.z * lr.z * weight};
                ok &= (c.x > 0.0f) | (c.y > 0.0f) | (c.z > 0.0f);
                if (lanes_any(ok)) {
                    LaneVec from = lanes_offset_ray(p, perr, lv_select(lv_neg(ng), ng, side > 0.0f));
                    LaneVec sd = wi;
                    lanes_f tmax = ls_dist;
                    LaneVec seg = {target.x - from.x, target.y - from.y, target.z - from.z};
                    lanes_f seg_len = lv_length(seg);
                    LaneVec seg_dir = {seg.x / seg_len, seg.y / seg_len, seg.z / seg_len};
                    tmax = select(tmax, seg_len, on_surface);
                    sd = lv_select(sd, seg_dir, on_surface);
                    lv_store(from, B->qox, B->qoy, B->qoz);
                    lv_store(sd, B->qdx, B->qdy, B->qdz);
                    lanes_vstore(tmax, 0, B->qtmax);
                    lv_store(c, B->qcx, B->qcy, B->qcz);
                    valid = ok;
                }
            }
        }

#if !defined(HAS_TRIANGLE_LIGHTS) && !defined(HAS_ENV_MAP) && !defined(HAS_UNLIT)
        // The last extension only looks for emitters, and there are none but the sky: under a
        // black sky the path ends here, its last ray untraced.
        if (frame_sky_black(frame)) m &= bounce != (lanes_u)(frame->max_bounces);
#endif

        // Sample the BSDF for the next ray (Lambertian: by its cosine); Russian roulette after
        // rr_depth bounces.
        if (lanes_any(m)) {
            lanes_f u1 = lanes_rng_next(&rng, m);
            lanes_f u2 = lanes_rng_next(&rng, m);
            lanes_i ok0 = lv_dot(wo, ns) > 0.0f;
            lanes_f r = sqrt(u1);
            lanes_f ccx, ccy;
            lanes_unit_circle(u2, &ccx, &ccy);
            LaneVec wl = {r * ccx, r * ccy, sqrt(fmax(0.0f, 1.0f - u1))};
            lanes_i ok1 = ok0 & (wl.z > 0.0f);
            // onb (rng.h) around ns, fused where the compiler fuses the scalar form.
            lanes_f s = select((lanes_f)(-1.0f), (lanes_f)(1.0f), ns.z >= 0.0f);
            lanes_f a = -1.0f / (s + ns.z);
            lanes_f c = ns.x * ns.y * a;
            LaneVec tt = {fma(s * ns.x * ns.x, a, (lanes_f)(1.0f)), s * c, -s * ns.x};
            LaneVec bb = {c, fma(ns.y * ns.y, a, s), -ns.y};
            LaneVec wi = {wl.x * tt.x + wl.y * bb.x + wl.z * ns.x,
                          wl.x * tt.y + wl.y * bb.y + wl.z * ns.y,
                          wl.x * tt.z + wl.y * bb.z + wl.z * ns.z};
            wi = lv_select(ns, wi, ok1);
            lanes_f cos_i = lv_dot(wi, ns);
            lanes_i ok2 = ok1 & (cos_i > 0.0f);
            lanes_f pdf = select(zero, cos_i * INV_PI_F, ok2);
            thr.x = thr.x * select(zero, base.x, ok2);
            thr.y = thr.y * select(zero, base.y, ok2);
            thr.z = thr.z * select(zero, base.z, ok2);
            lanes_f side = lv_dot(wi, ng);
            lanes_i go = m & (pdf > 0.0f) & (side * lv_dot(wi, ns) > 0.0f) &
                         ((thr.x > 0.0f) | (thr.y > 0.0f) | (thr.z > 0.0f));
            lanes_i rr = go & (bounce >= (lanes_u)(frame->rr_depth));
            if (lanes_any(rr)) {
                lanes_f q = fmin(fmax(thr.x, fmax(thr.y, thr.z)), 0.95f);
                lanes_f x = lanes_rng_next(&rng, rr);
                go &= ~(rr & (x >= q));
                lanes_i keep = rr & go;
                thr.x = select(thr.x, thr.x / q, keep);
                thr.y = select(thr.y, thr.y / q, keep);
                thr.z = select(thr.z, thr.z / q, keep);
            }
            LaneVec o = lanes_offset_ray(p, perr, lv_select(lv_neg(ng), ng, side > 0.0f));
            lv_store(o, B->ox, B->oy, B->oz);
            lv_store(wi, B->dx, B->dy, B->dz);
            lv_store(thr, B->tx, B->ty, B->tz);
            lanes_vstore(pdf, 0, B->pdf);
            flags = select(flags, (lanes_u)(0u), go);
            alive = go;
        }
    }
    lv_store(rad, B->rx, B->ry, B->rz);
    lanes_vstore(as_lanes_i(rng), 0, (int*)B->rng);
    lanes_vstore(as_lanes_i(flags), 0, (int*)B->flags);
    lanes_vstore(alive, 0, B->alive);
    lanes_vstore(valid, 0, B->valid);
}
#endif

#endif  // CPU_SHADE_LANES_H
