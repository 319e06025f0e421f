// BVH traversal: watertight ray-triangle test (Woop, Benthin, Wald 2013) over the flat node array.
// The host reference (src/bvh/traverse.rs) follows these steps exactly; contraction into fused
// multiply-adds is off so both sides round the same way.
#pragma OPENCL FP_CONTRACT OFF

#define STACK_SIZE 64
#define NO_HIT 0xffffffffu

typedef struct {
    float3 origin;
    float3 inv;  // safe reciprocal of the direction
    // The watertight test's permutation and shear as three rows: for a vertex offset A,
    // (dot3(A, row_x), dot3(A, row_y), dot3(A, row_z)) = (A[kx] - Sx A[kz], A[ky] - Sy A[kz],
    // Sz A[kz]), exactly (the other products are zeros), without per-vertex shuffles.
    float3 row_x;
    float3 row_y;
    float3 row_z;
} RayPrep;

inline float safe_rcp(float x) {
    return 1.0f / (fabs(x) > 1e-20f ? x : copysign(1e-20f, x));
}

inline float dot3(float3 a, float3 r) {
    return (a.x * r.x + a.y * r.y) + a.z * r.z;
}

inline float3 unit_axis(uint k, float s) {
    return (float3)(k == 0u ? s : 0.0f, k == 1u ? s : 0.0f, k == 2u ? s : 0.0f);
}

inline RayPrep prepare_ray(float3 o, float3 d) {
    RayPrep r;
    r.origin = o;
    r.inv = (float3)(safe_rcp(d.x), safe_rcp(d.y), safe_rcp(d.z));
    float3 a = fabs(d);
    uint kz = a.x > a.y ? (a.x > a.z ? 0u : 2u) : (a.y > a.z ? 1u : 2u);
    uint kx = (kz + 1u) % 3u;
    uint ky = (kx + 1u) % 3u;
    float dz = kz == 0u ? d.x : (kz == 1u ? d.y : d.z);
    if (dz < 0.0f) {
        uint tmp = kx;
        kx = ky;
        ky = tmp;
    }
    float dx = kx == 0u ? d.x : (kx == 1u ? d.y : d.z);
    float dy = ky == 0u ? d.x : (ky == 1u ? d.y : d.z);
    float sx = dx / dz;
    float sy = dy / dz;
    r.row_x = unit_axis(kx, 1.0f) + unit_axis(kz, -sx);
    r.row_y = unit_axis(ky, 1.0f) + unit_axis(kz, -sy);
    r.row_z = unit_axis(kz, 1.0f / dz);
    return r;
}

// Returns true on a hit in (tmin, *tmax), updating *tmax and the barycentrics.
inline bool intersect_triangle(const RayPrep* r, float4 v0, float4 v1, float4 v2, float tmin,
                               float* tmax, float* bu, float* bv) {
    float3 a = v0.xyz - r->origin;
    float3 b = v1.xyz - r->origin;
    float3 c = v2.xyz - r->origin;
    float ax = dot3(a, r->row_x);
    float ay = dot3(a, r->row_y);
    float bx = dot3(b, r->row_x);
    float by = dot3(b, r->row_y);
    float cx = dot3(c, r->row_x);
    float cy = dot3(c, r->row_y);
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
    float t = (u * dot3(a, r->row_z) + v * dot3(b, r->row_z) + w * dot3(c, r->row_z)) / det;
    if (!(t > tmin && t < *tmax)) return false;
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

// Closest hit (any_hit = false) or first hit (any_hit = true). On a stack overflow, which the
// builder's depth limit rules out, the overflow counter is raised instead of failing silently.
// With HAS_ALPHA, hits that the material's alpha cuts out (MASK) or lets through (BLEND, at
// random) are skipped; `surf` is read only then.
// Tests one child of a node: returns its node index when it is an interior node whose box the
// ray enters (entry distance in *dist), -1 otherwise; a leaf child's triangles are intersected
// on the spot. *done is set when an any-hit query found its hit.
inline int visit_child(float4 lo, float4 hi, const RayPrep* r, global const GpuTriangle* tris,
                       const SceneSurfaces* surf, float3 o, float3 d, float tmin, bool any_hit,
                       GpuHit* hit, float* dist, bool* done) {
    *dist = box_entry(lo, hi, r, tmin, hit->t);
    if (*dist == INFINITY) return -1;
    int ref = as_int(lo.w);
    if (ref >= 0) return ref;
    uint first = (uint)(~ref);
    uint count = as_uint(hi.w);
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
            if (any_hit) {
                *done = true;
                return -1;
            }
        }
#else
        if (intersect_triangle(r, t.v0, t.v1, t.v2, tmin, &hit->t, &hit->u, &hit->v)) {
            hit->prim = p;
            if (any_hit) {
                *done = true;
                return -1;
            }
        }
#endif
    }
    return -1;
}

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
    bool done = false;
    for (;;) {
        global const GpuBvhNode* n = &nodes[node];
        float dl, dr;
        int left = visit_child(n->left_min, n->left_max, &r, tris, surf, o, d, tmin, any_hit,
                               &hit, &dl, &done);
        if (done) return hit;
        int right = visit_child(n->right_min, n->right_max, &r, tris, surf, o, d, tmin, any_hit,
                                &hit, &dr, &done);
        if (done) return hit;
        if (left >= 0 && right >= 0) {
            uint first = dl <= dr ? (uint)left : (uint)right;
            uint second = dl <= dr ? (uint)right : (uint)left;
            if (sp == STACK_SIZE) {
                atomic_inc(overflow);
                return hit;
            }
            stack[sp++] = second;
            node = first;
        } else if (left >= 0) {
            node = (uint)left;
        } else if (right >= 0) {
            node = (uint)right;
        } else {
            if (sp == 0) return hit;
            node = stack[--sp];
        }
    }
}
