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
// (LANES_SHADE, set by the host: strategy::kernel_strategy in src/render/strategy.rs). Each lane
// computes what shade_vertex computes, draws the same random numbers, and samples an emissive
// triangle as sample_light does (other lights by sample_light itself, lane by lane): the same
// paths, bit for bit (tests/megakernel.rs compares the images). A chunk's camera hits, LANES or
// fewer at once, are shaded here too. The maths is the scalar path's, each function defined once
// for both widths by its generator (shared/vec3.h): the vertex's MIS weights, Russian
// roulette, normals, light sample test and shadow segment (path.h), the random numbers, onb and
// cosine and triangle sampling (rng.h), the hit's point, error bound and normal and the offset
// rays (traverse.h), the Lambertian BSDF's evaluation and sample (lambert.h) and an emissive
// triangle's sample (lights.h). What is written here is only the lanes' own: the batch, the
// loads of triangles, materials and normals as rows, and the order of shade_vertex's steps
// over masks instead of branches.
// Batches took 11.7 % fewer instructions on the 1 M-triangle room and about 12 % less time
// (AMD Zen 3, AVX2, 2026-12-04); shading the lanes done at each return instead (commit 29fe987)
// was no faster: too few to fill the vectors.
#ifndef CPU_SHADE_LANES_H
#define CPU_SHADE_LANES_H

#include "shared/types.h"
#include "shared/vec3.h"
#include "shared/rng.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "cpu/simd.h"
#include "cpu/traverse_lanes.h"
#include "shared/bsdf.h"
#include "shared/lambert.h"
#include "shared/lights.h"
#include "shared/path.h"

#ifdef LANES_SHADE
#if !defined(MEGA_LANES) || !defined(LAMBERT_ONLY) || defined(HAS_TEXTURES) ||              \
    defined(HAS_NORMAL_MAPS) || defined(TWO_LEVEL) || defined(HAS_ENV_MAP) ||                \
    defined(HAS_UNLIT) || defined(HAS_THIN_WALLS) || defined(HAS_TRANSMISSION) ||           \
    defined(HAS_CLEARCOAT) || defined(HAS_SHEEN) || defined(HAS_DIFFUSE_TRANSMISSION) ||     \
    defined(HAS_ANISOTROPY) || defined(HAS_DISPERSION) || defined(SMALL_SCENE) ||            \
    defined(HAS_IRIDESCENCE) || defined(HAS_VERTEX_COLORS)
#error "LANES_SHADE is for the lanes of scenes whose shading is simplest (strategy::kernel_strategy)"
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
                                  DeviceHit hit) {
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

// A 3-vector a lane, with shared/vec3.h's operations (lv_*), each as the OpenCL library
// computes it on float3.
typedef struct {
    vfloat x, y, z;
} LaneVec;

LANES_INLINE LaneVec lv_load(const float* x, const float* y, const float* z) {
    LaneVec v = {vload_lanes(0, x), vload_lanes(0, y), vload_lanes(0, z)};
    return v;
}

LANES_INLINE void lv_store(LaneVec v, float* x, float* y, float* z) {
    vstore_lanes(v.x, 0, x);
    vstore_lanes(v.y, 0, y);
    vstore_lanes(v.z, 0, z);
}

LANES_INLINE LaneVec lv_make(vfloat x, vfloat y, vfloat z) {
    LaneVec r = {x, y, z};
    return r;
}

LANES_INLINE LaneVec lv_splat(vfloat s) {
    LaneVec r = {s, s, s};
    return r;
}

LANES_INLINE LaneVec lv_select(LaneVec a, LaneVec b, vint m) {
    LaneVec r = {select(a.x, b.x, m), select(a.y, b.y, m), select(a.z, b.z, m)};
    return r;
}

LANES_INLINE LaneVec lv_neg(LaneVec a) {
    LaneVec r = {-a.x, -a.y, -a.z};
    return r;
}

LANES_INLINE LaneVec lv_add(LaneVec a, LaneVec b) {
    LaneVec r = {a.x + b.x, a.y + b.y, a.z + b.z};
    return r;
}

LANES_INLINE LaneVec lv_sub(LaneVec a, LaneVec b) {
    LaneVec r = {a.x - b.x, a.y - b.y, a.z - b.z};
    return r;
}

LANES_INLINE LaneVec lv_mul(LaneVec a, LaneVec b) {
    LaneVec r = {a.x * b.x, a.y * b.y, a.z * b.z};
    return r;
}

LANES_INLINE LaneVec lv_scale(LaneVec a, vfloat s) {
    LaneVec r = {a.x * s, a.y * s, a.z * s};
    return r;
}

LANES_INLINE LaneVec lv_div(LaneVec a, vfloat s) {
    LaneVec r = {a.x / s, a.y / s, a.z / s};
    return r;
}

LANES_INLINE LaneVec lv_abs(LaneVec a) {
    LaneVec r = {fabs(a.x), fabs(a.y), fabs(a.z)};
    return r;
}

LANES_INLINE LaneVec lv_max(LaneVec a, LaneVec b) {
    LaneVec r = {fmax(a.x, b.x), fmax(a.y, b.y), fmax(a.z, b.z)};
    return r;
}

// The OpenCL library's cross of float3: each coordinate's two products, then their difference.
LANES_INLINE LaneVec lv_cross(LaneVec a, LaneVec b) {
    vfloat c1 = a.y * b.z, c2 = a.z * b.y;
    vfloat c3 = a.z * b.x, c4 = a.x * b.z;
    vfloat c5 = a.x * b.y, c6 = a.y * b.x;
    LaneVec r = {c1 - c2, c3 - c4, c5 - c6};
    return r;
}

LANES_INLINE bool lv_any(vint m) { return lanes_any(m); }

// The lanes where some component is positive.
LANES_INLINE vint lv_positive(LaneVec a) {
    return (a.x > 0.0f) | (a.y > 0.0f) | (a.z > 0.0f);
}

// The OpenCL library's dot of float3 (kernel-x86_64 bitcode): the products, then x + y, then
// z added; one statement each, so that no compiler fuses a product into an addition.
LANES_INLINE vfloat lv_dot(LaneVec a, LaneVec b) {
    vfloat xx = a.x * b.x;
    vfloat yy = a.y * b.y;
    vfloat zz = a.z * b.z;
    vfloat xy = xx + yy;
    return zz + xy;
}

// The library's length of float3: the root of dot(v, v), rescaled where that is below
// FLT_MIN or infinite (then the scalar length itself, lane by lane; all-zero lanes are 0
// either way).
LANES_INLINE vfloat lv_length(LaneVec v) {
    vfloat d = lv_dot(v, v);
    vfloat len = sqrt(d);
    vint zero = (v.x == 0.0f) & (v.y == 0.0f) & (v.z == 0.0f);
    vint rare = ((d < 0x1p-126f) | (d == INFINITY)) & ~zero;
    if (lanes_any(rare)) {
        float x[LANES], y[LANES], z[LANES], out[LANES];
        int r[LANES];
        lv_store(v, x, y, z);
        vstore_lanes(len, 0, out);
        vstore_lanes(rare, 0, r);
        for (int l = 0; l < LANES; ++l) {
            if (r[l]) out[l] = length((float3)(x[l], y[l], z[l]));
        }
        len = vload_lanes(0, out);
    }
    return select(len, (vfloat)(0.0f), zero);
}

// The maths shared with one ray at a time, in every lane (shared/vec3.h): path.h's vertex maths
// (lanes_power_heuristic, lanes_emitter_pdf, lanes_light_sample_weight, lanes_survival,
// lanes_shading_normal, lanes_side_normal, lanes_light_sample_faces, lanes_light_contribution,
// lanes_shadow_segment, lanes_goes_on), rng.h's sampling (lanes_rng_advance, lanes_rng_value,
// lanes_onb, lanes_unit_circle, lanes_sample_cosine, lanes_sample_triangle), traverse.h's
// surface point (lanes_barycentric, lanes_surface_point, lanes_triangle_normal,
// lanes_offset_step, lanes_offset_ray), lambert.h's Lambertian BSDF (lanes_lambert_eval,
// lanes_lambert_sample) and lights.h's emissive triangle sample (lanes_triangle_light_sample).
DEFINE_VERTEX_MATHS(lanes, vfloat, vint, LaneVec, lv)
DEFINE_SAMPLING_MATHS(LANES_INLINE, lanes_, vfloat, vint, vuint, LaneVec, lv)
DEFINE_OFFSET_STEP(LANES_INLINE, lanes_, vfloat, vint)

LANES_INLINE LaneVec lv_offset_step(LaneVec p, LaneVec offset) {
    LaneVec r = {lanes_offset_step(p.x, offset.x), lanes_offset_step(p.y, offset.y),
                 lanes_offset_step(p.z, offset.z)};
    return r;
}

DEFINE_SURFACE_MATHS(LANES_INLINE, lanes_, vfloat, vint, vuint, LaneVec, lv)
DEFINE_LAMBERT_MATHS(LANES_INLINE, lanes_, vfloat, vint, vuint, LaneVec, lv)
DEFINE_TRIANGLE_LIGHT_MATHS(LANES_INLINE, lanes_, vfloat, vint, vuint, LaneVec, lv)

// rng_next in the lanes of m (the others' states kept; their numbers are meaningless).
LANES_INLINE vfloat lanes_rng_next(vuint* state, vint m) {
    vuint s = lanes_rng_advance(*state);
    *state = select(*state, s, m);
    return lanes_rng_value(s);
}

// A triangle's vertices (words 0-11 of each lane's DeviceTriangle at word offset off[l]) and its
// words 3 and 7 (material, light index).
LANES_INLINE void lanes_triangle_rows(global const DeviceTriangle* tris, const int* off, LaneVec* v0,
                                      LaneVec* v1, LaneVec* v2, vint* w3, vint* w7) {
    vfloat T[12];
    global const float* tw = (global const float*)tris;
    lanes_rows8(tw, off, 0, T);
    lanes_rows4(tw, off, 8, T + 8);
    v0->x = T[0], v0->y = T[1], v0->z = T[2];
    v1->x = T[4], v1->y = T[5], v1->z = T[6];
    v2->x = T[8], v2->y = T[9], v2->z = T[10];
    *w3 = as_vint(T[3]);
    *w7 = as_vint(T[7]);
}

// Shades entries [0, n) of the batch, as shade_vertex does (see above): emission with MIS, the
// light sample, the BSDF sample of the next ray.
LANES_INLINE void lanes_shade(const DeviceFrame* frame, const ShadeScene* sc, ShadeBatch* B,
                              int n) {
    const vfloat zero = (vfloat)(0.0f);
    const SceneSurfaces* surf = &sc->surf;
    vint m = LANE_IDS < (vint)(n);
    vint valid = (vint)(0), alive = (vint)(0);
    vuint bounce = as_vuint(vload_lanes(0, (const int*)B->bounce));
    vuint rng = as_vuint(vload_lanes(0, (const int*)B->rng));
    vuint flags = as_vuint(vload_lanes(0, (const int*)B->flags));
    LaneVec thr = lv_load(B->tx, B->ty, B->tz);
    LaneVec rad = lv_load(B->rx, B->ry, B->rz);
    LaneVec wo = lv_neg(lv_load(B->dx, B->dy, B->dz));
    vfloat prev_pdf = vload_lanes(0, B->pdf);
    vint prev_specular = as_vint(flags & PATH_SPECULAR) != 0;
    vint camera = bounce == (vuint)(0u);
    vint counts_emission =
        camera | prev_specular | (vint)(frame->strategy != STRATEGY_LIGHTS ? -1 : 0);
    vint mis = ~camera & ~prev_specular & (vint)(frame->strategy == STRATEGY_MIS ? -1 : 0);
    vint prim = vload_lanes(0, B->prim);
    vfloat t = vload_lanes(0, B->t);

    // Escaped: the uniform sky, reached by BSDF sampling only. An escaped camera ray is marked
    // for the film's coverage count; with the background cut out it adds nothing.
    vint escaped = m & (prim < 0);
    vint ce = escaped & counts_emission;
    if (frame->background != BACKGROUND_ENV) {
        vint marked = escaped & camera;
        flags = select(flags, flags | PATH_ESCAPED, marked);
        if (frame->background == BACKGROUND_CUTOUT) ce &= ~marked;
    }
    rad.x = select(rad.x, rad.x + thr.x * frame->sky.x, ce);
    rad.y = select(rad.y, rad.y + thr.y * frame->sky.y, ce);
    rad.z = select(rad.z, rad.z + thr.z * frame->sky.z, ce);
    m &= ~escaped;
    if (lanes_any(m)) {
        // The hit: its triangle's rows (lanes outside m read triangle 0).
        vfloat hu = vload_lanes(0, B->u), hv = vload_lanes(0, B->v);
        int off[LANES];
        vstore_lanes(select((vint)(0), prim * (vint)(12), m), 0, off);
        LaneVec v0, v1, v2;
        vint mat, light_index;
        lanes_triangle_rows(sc->tris, off, &v0, &v1, &v2, &mat, &light_index);
        vfloat w0 = 1.0f - hu - hv;
        LaneVec perr;
        LaneVec p = lanes_surface_point(v0, v1, v2, hu, hv, &perr);
        LaneVec ng = lanes_triangle_normal(v0, v1, v2);
        vint front = lv_dot(ng, wo) > 0.0f;
        // The material's base color and emission (lanes outside m read material 0).
        int moff[LANES];
        vstore_lanes(select((vint)(0), mat * (vint)(sizeof(DeviceMaterial) / 4), m), 0, moff);
        vfloat MB[8];
        lanes_rows8((global const float*)surf->materials, moff, 0, MB);
#ifdef HAS_TRIANGLE_LIGHTS
        // Emission of a light hit by this ray, weighted against light sampling of the last
        // vertex.
        {
            vint two_sided = (as_vint(MB[7]) & (vint)(MATERIAL_DOUBLE_SIDED)) != 0;
            vint em = m & (light_index >= 0) & (front | two_sided) & counts_emission;
            if (lanes_any(em)) {
                vfloat weight = (vfloat)(1.0f);
                vint w_mis = em & mis;
                if (lanes_any(w_mis)) {
                    // The light's selection probability and area, lane by lane (rare).
                    float sel_[LANES], area_[LANES];
                    int li_[LANES];
                    vstore_lanes(select((vint)(0), light_index, w_mis), 0, li_);
                    for (int l = 0; l < LANES; ++l) {
                        global const DeviceLight* lt = &sc->lights[li_[l]];
                        sel_[l] = lt->extra.y;
                        area_[l] = lt->spot.y;
                    }
                    vfloat sel = vload_lanes(0, sel_), area = vload_lanes(0, area_);
                    vfloat cos_l = fabs(lv_dot(ng, wo));
                    vfloat light_pdf = lanes_emitter_pdf(sel, area, t, cos_l);
                    weight = select(weight, lanes_power_heuristic(prev_pdf, light_pdf), w_mis);
                }
                rad.x = select(rad.x, rad.x + thr.x * MB[4] * weight, em);
                rad.y = select(rad.y, rad.y + thr.y * MB[5] * weight, em);
                rad.z = select(rad.z, rad.z + thr.z * MB[6] * weight, em);
            }
        }
#endif
        // The last extension only looks for emitters.
        m &= bounce <= (vuint)(frame->max_bounces);
        // Face the normals towards the side the ray came from; the shading normal.
        ng = lv_select(lv_neg(ng), ng, front);
        LaneVec ns = ng;
        {
            int soff[LANES];
            vstore_lanes(select((vint)(0), prim * (vint)(9), m), 0, soff);
            vfloat N[8];
            global const float* shw = (global const float*)surf->shading;
            lanes_rows8(shw, soff, 0, N);
            float n8_[LANES];
            for (int l = 0; l < LANES; ++l) n8_[l] = shw[soff[l] + 8];
            vfloat n8 = vload_lanes(0, n8_);
            LaneVec sn = lanes_barycentric(lv_make(N[0], N[1], N[2]), lv_make(N[3], N[4], N[5]),
                                           lv_make(N[6], N[7], n8), w0, hu, hv);
            ns = lanes_shading_normal(sn, ng);
        }
        LaneVec base = {MB[0], MB[1], MB[2]};

        // Next-event estimation: one light sample, its visibility tested by the caller.
        if (frame->strategy != STRATEGY_BSDF && frame->light_count > 0u && lanes_any(m)) {
            vfloat ui = lanes_rng_next(&rng, m);
            vfloat u1 = lanes_rng_next(&rng, m);
            vfloat u2 = lanes_rng_next(&rng, m);
            float ui_[LANES], u1_[LANES], u2_[LANES], px[LANES], py[LANES], pz[LANES];
            float wx[LANES], wy[LANES], wz[LANES], dist[LANES], lx[LANES], ly[LANES], lz[LANES];
            float lpdf[LANES], gx[LANES], gy[LANES], gz[LANES];
            int on[LANES], tri_light[LANES], lprim[LANES];
            float lsel[LANES], larea[LANES];
            vstore_lanes(ui, 0, ui_);
            vstore_lanes(u1, 0, u1_);
            vstore_lanes(u2, 0, u2_);
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
                global const DeviceLight* lt = &sc->lights[index];
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
            vfloat ls_pdf = vload_lanes(0, lpdf);
            vfloat ls_dist = vload_lanes(0, dist);
            LaneVec target = lv_load(gx, gy, gz);
            vint on_surface = vload_lanes(0, on);
#ifdef HAS_TRIANGLE_LIGHTS
            vint tl = vload_lanes(0, tri_light);
            if (lanes_any(tl)) {
                // sample_light's emissive triangle, in vectors.
                LaneVec t0, t1, t2;
                vint lmat, unused;
                lanes_triangle_rows(sc->tris, lprim, &t0, &t1, &t2, &lmat, &unused);
                vfloat b1, b2;
                lanes_sample_triangle(u1, u2, &b1, &b2);
                LaneVec q_err;
                LaneVec q = lanes_surface_point(t0, t1, t2, b1, b2, &q_err);
                LaneVec lng = lanes_triangle_normal(t0, t1, t2);
                int loff[LANES];
                vstore_lanes(select((vint)(0), lmat * (vint)(sizeof(DeviceMaterial) / 4), tl),
                             0, loff);
                vfloat E[4];
                lanes_rows4((global const float*)surf->materials, loff, 4, E);
                vint two_sided = (as_vint(E[3]) & (vint)(MATERIAL_DOUBLE_SIDED)) != 0;
                LaneVec lwi, ltarget;
                vfloat ldist, lp;
                vint lon;
                vint emits = lanes_triangle_light_sample(
                    p, q, q_err, lng, vload_lanes(0, lsel), vload_lanes(0, larea), two_sided, &lwi,
                    &ldist, &ltarget, &lon, &lp);
                wi = lv_select(wi, lwi, tl);
                ls_dist = select(ls_dist, ldist, tl);
                target = lv_select(target, ltarget, tl);
                on_surface = select(on_surface, lon, tl);
                ls_pdf = select(ls_pdf, lp, tl);
                LaneVec lrad = lv_div(lv_make(E[0], E[1], E[2]), lp);
                lr = lv_select(lr, lv_select(lv_splat(zero), lrad, emits), tl);
            }
#endif
            vfloat side = lv_dot(wi, ng);
            vint ok = m & lanes_light_sample_faces(side, wi, ns, lr);
            if (lanes_any(ok)) {
                vfloat bsdf_pdf;
                LaneVec f = lanes_lambert_eval(base, ns, wo, wi, &bsdf_pdf);
                vfloat weight = lanes_light_sample_weight(
                    ls_pdf, bsdf_pdf, (vint)(frame->strategy == STRATEGY_MIS ? -1 : 0));
                LaneVec c = lanes_light_contribution(thr, f, lr, weight);
                ok &= lv_positive(c);
                if (lanes_any(ok)) {
                    LaneVec from = lanes_offset_ray(p, perr, lanes_side_normal(ng, side));
                    LaneVec sd;
                    vfloat tmax = lanes_shadow_segment(from, wi, ls_dist, target, on_surface, &sd);
                    lv_store(from, B->qox, B->qoy, B->qoz);
                    lv_store(sd, B->qdx, B->qdy, B->qdz);
                    vstore_lanes(tmax, 0, B->qtmax);
                    lv_store(c, B->qcx, B->qcy, B->qcz);
                    valid = ok;
                }
            }
        }

#if !defined(HAS_TRIANGLE_LIGHTS) && !defined(HAS_ENV_MAP) && !defined(HAS_UNLIT)
        // The last extension only looks for emitters, and there are none but the sky: under a
        // black sky the path ends here, its last ray untraced.
        if (frame_sky_black(frame)) m &= bounce != (vuint)(frame->max_bounces);
#endif

        // Sample the BSDF for the next ray (Lambertian: by its cosine); Russian roulette after
        // rr_depth bounces.
        if (lanes_any(m)) {
            vfloat u1 = lanes_rng_next(&rng, m);
            vfloat u2 = lanes_rng_next(&rng, m);
            LaneVec wi, weight;
            vfloat pdf = lanes_lambert_sample(base, ns, wo, u1, u2, &wi, &weight);
            thr = lv_mul(thr, weight);
            vfloat side = lv_dot(wi, ng);
            vint go = m & lanes_goes_on(pdf, side, wi, ns, thr);
            vint rr = go & (bounce >= (vuint)(frame->rr_depth));
            if (lanes_any(rr)) {
                vfloat q = lanes_survival(thr.x, thr.y, thr.z);
                vfloat x = lanes_rng_next(&rng, rr);
                go &= ~(rr & (x >= q));
                vint keep = rr & go;
                thr.x = select(thr.x, thr.x / q, keep);
                thr.y = select(thr.y, thr.y / q, keep);
                thr.z = select(thr.z, thr.z / q, keep);
            }
            LaneVec o = lanes_offset_ray(p, perr, lanes_side_normal(ng, side));
            lv_store(o, B->ox, B->oy, B->oz);
            lv_store(wi, B->dx, B->dy, B->dz);
            lv_store(thr, B->tx, B->ty, B->tz);
            vstore_lanes(pdf, 0, B->pdf);
            flags = select(flags, (vuint)(0u), go);
            alive = go;
        }
    }
    lv_store(rad, B->rx, B->ry, B->rz);
    vstore_lanes(as_vint(rng), 0, (int*)B->rng);
    vstore_lanes(as_vint(flags), 0, (int*)B->flags);
    vstore_lanes(alive, 0, B->alive);
    vstore_lanes(valid, 0, B->valid);
}
#endif

#endif  // CPU_SHADE_LANES_H
