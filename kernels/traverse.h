// BVH traversal: watertight ray-triangle test (Woop, Benthin, Wald 2013) over the flat node array.
// The host reference (src/bvh/traverse.rs) follows these steps exactly; contraction into fused
// multiply-adds is off so both sides round the same way.
#pragma OPENCL FP_CONTRACT OFF

#define STACK_SIZE 64
#define NO_HIT 0xffffffffu

typedef struct {
    float3 origin;
    float3 inv;    // safe reciprocal of the direction
    uint4 perm;    // (kx, ky, kz, 3) for shuffle()
    float3 shear;  // (dx/dz, dy/dz, 1/dz) in the permuted frame
} RayPrep;

inline float safe_rcp(float x) {
    return 1.0f / (fabs(x) > 1e-20f ? x : copysign(1e-20f, x));
}

inline RayPrep prepare_ray(float3 o, float3 d) {
    RayPrep r;
    r.origin = o;
    r.inv = (float3)(safe_rcp(d.x), safe_rcp(d.y), safe_rcp(d.z));
    float3 a = fabs(d);
    uint kz = a.x > a.y ? (a.x > a.z ? 0u : 2u) : (a.y > a.z ? 1u : 2u);
    uint kx = (kz + 1u) % 3u;
    uint ky = (kx + 1u) % 3u;
    float4 d4 = (float4)(d, 0.0f);
    float dz = kz == 0u ? d.x : (kz == 1u ? d.y : d.z);
    if (dz < 0.0f) {
        uint tmp = kx;
        kx = ky;
        ky = tmp;
    }
    r.perm = (uint4)(kx, ky, kz, 3u);
    float4 p = shuffle(d4, r.perm);
    r.shear = (float3)(p.x / p.z, p.y / p.z, 1.0f / p.z);
    return r;
}

// gamma(n) of Higham's error analysis for single precision: n u / (1 - n u), u = 2^-24.
inline float gamma_f32(float n) {
    return (n * 5.96046448e-8f) / (1.0f - n * 5.96046448e-8f);
}

// The bound on the rounding error of a watertight hit's t (pbrt-v4, Triangle::Intersect),
// from the sheared vertices (x, y relative to the origin; z already scaled by shear.z), the
// edge functions and their sum; src/bvh/traverse.rs computes the same.
inline float triangle_t_error(float ax, float ay, float bx, float by, float cx, float cy,
                              float az, float bz, float cz, float u, float v, float w,
                              float det) {
    float max_z = fmax(fmax(fabs(az), fabs(bz)), fabs(cz));
    float delta_z = gamma_f32(3.0f) * max_z;
    float max_x = fmax(fmax(fabs(ax), fabs(bx)), fabs(cx));
    float max_y = fmax(fmax(fabs(ay), fabs(by)), fabs(cy));
    float delta_x = gamma_f32(5.0f) * (max_x + max_z);
    float delta_y = gamma_f32(5.0f) * (max_y + max_z);
    float delta_e = 2.0f * (gamma_f32(2.0f) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    float max_e = fmax(fmax(fabs(u), fabs(v)), fabs(w));
    return 3.0f * (gamma_f32(3.0f) * max_e * max_z + delta_e * max_z + delta_z * max_e) /
           fabs(det);
}

// Returns true on a hit in (tmin, *tmax), updating *tmax and the barycentrics.
inline bool intersect_triangle(const RayPrep* r, float4 v0, float4 v1, float4 v2, float tmin,
                               float* tmax, float* bu, float* bv) {
    float4 o = (float4)(r->origin, 0.0f);
    float4 a = shuffle(v0 - o, r->perm);
    float4 b = shuffle(v1 - o, r->perm);
    float4 c = shuffle(v2 - o, r->perm);
    float ax = a.x - r->shear.x * a.z;
    float ay = a.y - r->shear.y * a.z;
    float bx = b.x - r->shear.x * b.z;
    float by = b.y - r->shear.y * b.z;
    float cx = c.x - r->shear.x * c.z;
    float cy = c.y - r->shear.y * c.z;
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
#ifdef cl_khr_fp64
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        u = (float)((double)cx * (double)by - (double)cy * (double)bx);
        v = (float)((double)ax * (double)cy - (double)ay * (double)cx);
        w = (float)((double)bx * (double)ay - (double)by * (double)ax);
    }
#endif
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
    float det = u + v + w;
    if (det == 0.0f) return false;
    float az = r->shear.z * a.z, bz = r->shear.z * b.z, cz = r->shear.z * c.z;
    float t = (u * az + v * bz + w * cz) / det;
    if (!(t > tmin && t < *tmax)) return false;
    // pbrt-v4's conservative bound on t's rounding error: a hit closer than its own error
    // could lie behind the origin, as it does for a ray leaving this very triangle.
    if (t <= triangle_t_error(ax, ay, bx, by, cx, cy, az, bz, cz, u, v, w, det)) return false;
    *tmax = t;
    *bu = v / det;
    *bv = w / det;
    return true;
}

// Slab test with the far distance scaled up by two ulps (Ize 2013); returns the entry distance
// or INFINITY on a miss.
inline float box_entry(float4 lo, float4 hi, const RayPrep* r, float tmin, float tmax) {
    float3 t0 = (lo.xyz - r->origin) * r->inv;
    float3 t1 = (hi.xyz - r->origin) * r->inv;
    float3 mn = fmin(t0, t1);
    float3 mx = fmax(t0, t1);
    float near = fmax(fmax(fmax(mn.x, mn.y), mn.z), tmin);
    float far = fmin(fmin(mx.x, mx.y), mx.z) * 1.00000024f;
    return (near <= far && near < tmax) ? near : INFINITY;
}

// Tests the triangles first .. first + count - 1 of a leaf, keeping the closest hit in *hit
// (with HAS_ALPHA, hits the material's alpha cuts out or lets through are skipped). Returns
// true when any_hit and a hit was found: the traversal can stop.
inline bool intersect_leaf(const RayPrep* r, global const GpuTriangle* tris,
                           const SceneSurfaces* surf, uint first, uint count, float tmin,
                           float3 o, float3 d, bool any_hit, GpuHit* hit) {
    for (uint p = first; p < first + count; ++p) {
        GpuTriangle t = tris[p];
#ifdef HAS_ALPHA
        float t_hit = hit->t;
        float bu, bv;
        if (intersect_triangle(r, t.v0, t.v1, t.v2, tmin, &t_hit, &bu, &bv) &&
            !alpha_passes(surf, p, as_uint(t.v0.w), bu, bv, o, d)) {
            hit->t = t_hit;
            hit->u = bu;
            hit->v = bv;
            hit->prim = p;
            if (any_hit) return true;
        }
#else
        if (intersect_triangle(r, t.v0, t.v1, t.v2, tmin, &hit->t, &hit->u, &hit->v)) {
            hit->prim = p;
            if (any_hit) return true;
        }
#endif
    }
    return false;
}

// Closest hit (any_hit = false) or first hit (any_hit = true). On a stack overflow, which the
// builder's depth limit rules out, the overflow counter is raised instead of failing silently.
// With HAS_ALPHA, hits that the material's alpha cuts out (MASK) or lets through (BLEND, at
// random) are skipped; `surf` is read only then.
inline GpuHit traverse(global const GpuBvhNode* nodes, global const GpuTriangle* tris,
                       const SceneSurfaces* surf, float3 o, float3 d, float tmin, float tmax,
                       bool any_hit, volatile global uint* overflow) {
    RayPrep r = prepare_ray(o, d);
    GpuHit hit;
    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.prim = NO_HIT;
    uint stack[STACK_SIZE];
    uint sp = 0;
    uint node = 0;
    for (;;) {
        GpuBvhNode n = nodes[node];
        float dist[2];
        int child[2];
        for (int side = 0; side < 2; ++side) {
            float4 lo = side == 0 ? n.left_min : n.right_min;
            float4 hi = side == 0 ? n.left_max : n.right_max;
            child[side] = -1;
            dist[side] = box_entry(lo, hi, &r, tmin, hit.t);
            if (dist[side] == INFINITY) continue;
            int ref = as_int(lo.w);
            if (ref >= 0) {
                child[side] = ref;
                continue;
            }
            uint first = (uint)(~ref);
            uint count = as_uint(hi.w);
            if (intersect_leaf(&r, tris, surf, first, count, tmin, o, d, any_hit, &hit)) {
                return hit;
            }
        }
        if (child[0] >= 0 && child[1] >= 0) {
            uint first = dist[0] <= dist[1] ? (uint)child[0] : (uint)child[1];
            uint second = dist[0] <= dist[1] ? (uint)child[1] : (uint)child[0];
            if (sp == STACK_SIZE) {
                atomic_inc(overflow);
                return hit;
            }
            stack[sp++] = second;
            node = first;
        } else if (child[0] >= 0) {
            node = (uint)child[0];
        } else if (child[1] >= 0) {
            node = (uint)child[1];
        } else {
            if (sp == 0) return hit;
            node = stack[--sp];
        }
    }
}

// The point at barycentrics (u, v) of a triangle and a bound on how far a spawned ray's origin
// must move off it, per coordinate: pbrt-v4's gamma(7) times the barycentric sum of the
// vertices' magnitudes (the rounding of p), plus gamma(64) times the triangle's extent around p
// in every coordinate, which stands in for pbrt's conservative t check in the ray-triangle test
// (a point exactly on a triangle in the plane x = 0 has no rounding error, yet the sheared
// ray-triangle test can still find it at a tiny positive t). Both follow the vertices, not a
// scene-wide epsilon, so they hold at any scale and offset.
inline float3 surface_point(float3 v0, float3 v1, float3 v2, float u, float v, float3* err) {
    float w = 1.0f - u - v;
    const float gamma7 = 7.0f * 0x1p-24f / (1.0f - 7.0f * 0x1p-24f);
    const float gamma64 = 64.0f * 0x1p-24f / (1.0f - 64.0f * 0x1p-24f);
    float3 p = w * v0 + u * v1 + v * v2;
    float3 extent = fmax(fmax(fabs(v0 - p), fabs(v1 - p)), fabs(v2 - p));
    float reach = fmax(fmax(extent.x, extent.y), extent.z);
    *err = gamma7 * (fabs(w * v0) + fabs(u * v1) + fabs(v * v2)) + gamma64 * reach;
    return p;
}

// The unit geometric normal of a triangle (counter-clockwise front). The cross product is
// scaled by a power of two before normalizing, so triangles of 1e-10 or 1e10 units do not
// underflow or overflow its squared length.
inline float3 triangle_normal(float3 v0, float3 v1, float3 v2) {
    float3 c = cross(v1 - v0, v2 - v0);
    float m = fmax(fmax(fabs(c.x), fabs(c.y)), fabs(c.z));
    return m > 0.0f ? normalize(c * ldexp(1.0f, -ilogb(m))) : c;
}

// Moves p, whose coordinates are off by at most err, off the surface along the geometric
// normal n (pointing to the side the ray leaves on) by the error bound projected on n, then
// rounds each moved coordinate one more ulp away from p (pbrt-v4's OffsetRayOrigin). A ray
// from the result can neither re-hit the surface it leaves nor start behind it; tests/stress.rs
// checks this from 1e-8 to 1e8 through `spawn_test`.
inline float3 offset_ray(float3 p, float3 err, float3 n) {
    float3 offset = dot(fabs(n), err) * n;
    float3 po = p + offset;
    po = select(po, nextafter(po, (float3)(INFINITY)), offset > 0.0f);
    return select(po, nextafter(po, (float3)(-INFINITY)), offset < 0.0f);
}
