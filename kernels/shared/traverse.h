// BVH traversal: watertight ray-triangle test (Woop, Benthin, Wald 2013) over the flat node array.
// The host reference (src/bvh/traverse.rs) follows these steps exactly; contraction into fused
// multiply-adds is off so both sides round the same way.
#ifndef SHARED_TRAVERSE_H
#define SHARED_TRAVERSE_H

#include "shared/types.h"
#include "shared/vec3.h"
#include "shared/textures.h"

#pragma OPENCL FP_CONTRACT OFF

#define STACK_SIZE 64
#define NO_HIT 0xffffffffu

typedef struct {
    float3 origin;
    float3 inv;    // safe reciprocal of the direction
    uint4 perm;    // (kx, ky, kz, 3) for shuffle()
    float3 shear;  // (dx/dz, dy/dz, 1/dz) in the permuted frame
} RayPrep;

// A ray's set-up for every lane width (shared/vec3.h): f##safe_rcp(x) the reciprocal of a
// direction's coordinate x, or of +-1e-20 where x is nearer 0; f##pick(x, y, z, k) coordinate k
// (0, 1 or 2) of (x, y, z); f##ray_axes(ax, ay, az, *kx, *ky, *kz) the axes of a direction of
// magnitudes (ax, ay, az) that the watertight test permutes it to: kz the dominant one (the
// first of equals but z), kx and ky the next ones round; f##to_ray_axes(x, y, z, z0, z1, *px,
// *py, *pz) (x, y, z) in those axes, by selects, for kz 0 (z0), 1 (z1) or 2 (neither).
#define DEFINE_RAY_MATHS(Q, f, F, I)                                                               \
    Q F f##safe_rcp(F x) {                                                                         \
        return 1.0f / select(copysign((F)(1e-20f), x), x, fabs(x) > 1e-20f);                      \
    }                                                                                              \
    Q F f##pick(F x, F y, F z, I k) { return select(select(x, y, k == 1), z, k == 2); }            \
    Q void f##ray_axes(F ax, F ay, F az, I* kx, I* ky, I* kz) {                                    \
        *kz = select(select((I)(2), (I)(1), ay > az), select((I)(2), (I)(0), ax > az), ax > ay);   \
        *kx = select(select((I)(1), (I)(2), *kz == 1), (I)(0), *kz == 2);                          \
        *ky = select(select((I)(2), (I)(0), *kz == 1), (I)(1), *kz == 2);                          \
    }                                                                                              \
    Q void f##to_ray_axes(F x, F y, F z, I z0, I z1, F* px, F* py, F* pz) {                        \
        *px = select(select(x, z, z1), y, z0);                                                     \
        *py = select(select(y, x, z1), z, z0);                                                     \
        *pz = select(select(z, y, z1), x, z0);                                                     \
    }

DEFINE_RAY_MATHS(inline, , float, int)

// v's coordinates in the ray's permuted order (kx, ky, kz), a rotation named by kz. A CPU
// does this in one shuffle instruction; NVIDIA's compiler turns shuffle() with a mask that
// changes inside the loop (the two-level traversal's ray changes at every instance) into more
// work than these selects, which made two levels 3-10 % faster on an H200 and flat about 1-2 %
// (measured 2026-12-01). The program defines PERMUTE_BY_SELECT for devices other than CPUs.
inline float4 ray_permute(float4 v, uint4 p) {
#ifdef PERMUTE_BY_SELECT
    float x, y, z;
    to_ray_axes(v.x, v.y, v.z, p.z == 0u, p.z == 1u, &x, &y, &z);
    return (float4)(x, y, z, 0.0f);
#else
    return shuffle(v, p);
#endif
}

inline RayPrep prepare_ray(float3 o, float3 d) {
    RayPrep r;
    r.origin = o;
    r.inv = (float3)(safe_rcp(d.x), safe_rcp(d.y), safe_rcp(d.z));
    float3 a = fabs(d);
    // The axes rotated so that z is the dominant one. (Woop et al. also swap x and y where the
    // direction's z is negative, to keep the winding; that only negates the edge functions and
    // their sum exactly, and this test takes either sign.)
    int kx, ky, kz;
    ray_axes(a.x, a.y, a.z, &kx, &ky, &kz);
    float4 d4 = (float4)(d, 0.0f);
    r.perm = (uint4)((uint)kx, (uint)ky, (uint)kz, 3u);
    float4 p = ray_permute(d4, r.perm);
    // No division of its own: the shear's x and y scale by the reciprocal of its z, which is
    // the box test's reciprocal of the dominant axis (src/bvh/traverse.rs computes the same).
    float iz = pick(r.inv.x, r.inv.y, r.inv.z, kz);
    r.shear = (float3)(p.x * iz, p.y * iz, iz);
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
    float4 a = ray_permute(v0 - o, r->perm);
    float4 b = ray_permute(v1 - o, r->perm);
    float4 c = ray_permute(v2 - o, r->perm);
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
    // Only a hit much closer than the triangle's farthest vertex can be that close to its own
    // error; the bound is evaluated for those alone (it is cheap, but not free on a GPU).
    if (t < 0.00390625f * fmax(fmax(fabs(az), fabs(bz)), fabs(cz)) &&
        t <= triangle_t_error(ax, ay, bx, by, cx, cy, az, bz, cz, u, v, w, det))
        return false;
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
// true when any_hit and a hit was found: the traversal can stop. `o` and `d` are the ray in
// world space (the alpha hash reads them).
inline bool intersect_leaf(const RayPrep* r, global const DeviceTriangle* tris,
                           const SceneSurfaces* surf, uint first, uint count, float tmin,
                           float3 o, float3 d, bool any_hit, DeviceHit* hit) {
    for (uint p = first; p < first + count; ++p) {
        DeviceTriangle t = tris[p];
        float t_hit = hit->t;
        float bu, bv;
        if (!intersect_triangle(r, t.v0, t.v1, t.v2, tmin, &t_hit, &bu, &bv)) continue;
#ifdef HAS_ALPHA
        if (alpha_passes(surf, p, as_uint(t.v0.w), bu, bv, o, d)) continue;
#endif
        hit->t = t_hit;
        hit->u = bu;
        hit->v = bv;
        hit->prim = p;
        if (any_hit) return true;
    }
    return false;
}

// Walks the binary BVH below node `root` along the prepared ray, keeping the closest hit (or
// with any_hit the first) in *hit; leaves index `tris`. Returns true when the walk must end
// the whole traversal: an any-hit was found, or the stack overflowed (which the builder's depth
// limit rules out; the overflow counter is raised instead of failing silently).
inline bool traverse_bvh(global const DeviceBvhNode* nodes, uint root,
                         global const DeviceTriangle* tris, const SceneSurfaces* surf,
                         const RayPrep* r, float3 o, float3 d, float tmin, bool any_hit,
                         DeviceHit* hit,
                         volatile global uint* overflow) {
    // Written out in one loop, without helper functions taking pointers: compilers keep this
    // form's state in registers (the flat BVH's rays on an H200 lost 8 % to a version through
    // helpers).
    uint stack[STACK_SIZE];
    uint sp = 0;
    uint node = root;
    for (;;) {
        DeviceBvhNode n = nodes[node];
        float dist[2];
        int child[2];
        for (int side = 0; side < 2; ++side) {
            float4 lo = side == 0 ? n.left_min : n.right_min;
            float4 hi = side == 0 ? n.left_max : n.right_max;
            child[side] = -1;
            dist[side] = box_entry(lo, hi, r, tmin, hit->t);
            if (dist[side] == INFINITY) continue;
            int ref = as_int(lo.w);
            if (ref >= 0) {
                child[side] = ref;
                continue;
            }
            if (intersect_leaf(r, tris, surf, (uint)(~ref), as_uint(hi.w), tmin, o, d, any_hit,
                               hit)) {
                return true;
            }
        }
        // On to the nearer child reached, pushing the other; or to the next node on the stack.
        if (child[0] >= 0 && child[1] >= 0) {
            uint first = dist[0] <= dist[1] ? (uint)child[0] : (uint)child[1];
            uint second = dist[0] <= dist[1] ? (uint)child[1] : (uint)child[0];
            if (sp == STACK_SIZE) {
                atomic_inc(overflow);
                return true;
            }
            stack[sp++] = second;
            node = first;
        } else if (child[0] >= 0) {
            node = (uint)child[0];
        } else if (child[1] >= 0) {
            node = (uint)child[1];
        } else {
            if (sp == 0u) return false;
            node = stack[--sp];
        }
    }
}

inline DeviceHit no_hit(float tmax) {
    DeviceHit hit;
    hit.t = tmax;
    hit.u = 0.0f;
    hit.v = 0.0f;
    hit.prim = NO_HIT;
    hit.instance = 0u;
    return hit;
}

// Closest hit (any_hit = false) or first hit (any_hit = true) in the flat BVH. With HAS_ALPHA,
// hits that the material's alpha cuts out (MASK) or lets through (BLEND, at random) are
// skipped; `surf` is read only then.
inline DeviceHit traverse(global const DeviceBvhNode* nodes, global const DeviceTriangle* tris,
                       const SceneSurfaces* surf, float3 o, float3 d, float tmin, float tmax,
                       bool any_hit, volatile global uint* overflow) {
    RayPrep r = prepare_ray(o, d);
    DeviceHit hit = no_hit(tmax);
    traverse_bvh(nodes, 0u, tris, surf, &r, o, d, tmin, any_hit, &hit, overflow);
    return hit;
}

// Two levels (src/bvh/instances.rs is the host reference). A ray reaching an instance in the
// top level is carried into object space, o' = L (o - T) and d' = L d, its direction not
// renormalised, so t stays the world ray's parameter and the watertight test runs unchanged on
// the object-space triangles. Subtracting T (the world position of the object's origin) first
// keeps the error relative to the distance from the object, not from the render origin: o' is
// off by at most err = gamma(8) |L| |o - T| per coordinate, and as pbrt-v4 does, hits closer
// than that error along the ray are ignored (tmin grows by dot(|d'|, err) / |d'|^2). Shading
// carries the hit's object-space triangle back to world space (M v + T in f32) and adds that
// rounding's bound to the hit point's error (`instance_triangle` in surface.h), so the
// offset_ray a spawned ray leaves its surface by covers it: a ray cannot find its own surface
// again in object space.
inline float3 instance_point(const DeviceInstance* inst, float3 p) {
    float3 q = p - (float3)(inst->row0.w, inst->row1.w, inst->row2.w);
    return (float3)(inst->row0.x * q.x + inst->row0.y * q.y + inst->row0.z * q.z,
                    inst->row1.x * q.x + inst->row1.y * q.y + inst->row1.z * q.z,
                    inst->row2.x * q.x + inst->row2.y * q.y + inst->row2.z * q.z);
}

inline float3 instance_vector(const DeviceInstance* inst, float3 v) {
    return (float3)(inst->row0.x * v.x + inst->row0.y * v.y + inst->row0.z * v.z,
                    inst->row1.x * v.x + inst->row1.y * v.y + inst->row1.z * v.z,
                    inst->row2.x * v.x + inst->row2.y * v.y + inst->row2.z * v.z);
}

// The tmin of the object-space ray (o', d') of world ray origin o (see above).
inline float instance_tmin(const DeviceInstance* inst, float3 o, float3 od, float tmin) {
    const float gamma8 = 8.0f * 0x1p-24f / (1.0f - 8.0f * 0x1p-24f);
    float3 a = fabs(o - (float3)(inst->row0.w, inst->row1.w, inst->row2.w));
    float3 m0 = fabs(inst->row0.xyz), m1 = fabs(inst->row1.xyz), m2 = fabs(inst->row2.xyz);
    float3 err = gamma8 * (float3)(m0.x * a.x + m0.y * a.y + m0.z * a.z,
                                   m1.x * a.x + m1.y * a.y + m1.z * a.z,
                                   m2.x * a.x + m2.y * a.y + m2.z * a.z);
    float3 ad = fabs(od);
    float len2 = od.x * od.x + od.y * od.y + od.z * od.z;
    float dt = len2 > 0.0f ? (ad.x * err.x + ad.y * err.y + ad.z * err.z) / len2 : 0.0f;
    return fmax(tmin, dt);
}

// A top-level piece of one triangle (INSTANCE_PIECE_TRIANGLE: a small mesh's, src/bvh/
// instances.rs) against the world ray: the triangle's world-space copy (`copy` in `tris`,
// carried to world space by the host as shading carries it), tested without entering the
// instance. A hit names the mesh's triangle (`prim`) and the slot as a bottom-level hit does.
// Returns true when an any-hit ends the traversal.
inline bool intersect_piece_triangle(uint copy, uint prim, uint slot,
                                     global const DeviceTriangle* tris, const SceneSurfaces* surf,
                                     const RayPrep* r, float3 o, float3 d, float tmin,
                                     bool any_hit, DeviceHit* hit) {
    DeviceTriangle t = tris[copy];
    float t_hit = hit->t;
    float bu, bv;
    if (!intersect_triangle(r, t.v0, t.v1, t.v2, tmin, &t_hit, &bu, &bv)) return false;
#ifdef HAS_ALPHA
    if (alpha_passes(surf, prim, as_uint(t.v0.w), bu, bv, o, d)) return false;
#endif
    hit->t = t_hit;
    hit->u = bu;
    hit->v = bv;
    hit->prim = prim;
    hit->instance = slot;
    return any_hit;
}

// On the two-level traversal's stack: an instance to enter (its slot in `instances`, with
// this bit set), else a node.
#define INSTANCE_BIT 0x80000000u
// No child reached (the two-level traversal's children are uints: nodes or instances).
#define NO_CHILD 0xffffffffu
// A hit's instance while the walk is still in it (the slot waits on the stack).
#define INSTANCE_PENDING 0xffffffffu
// A top-level path and a bottom-level one below it on one stack.
#define TWO_LEVEL_STACK (2 * STACK_SIZE)
// The world ray at the bottom of the two-level stack: origin, direction, reciprocal
// direction and tmin, read back where an instance is entered or left.
#define WORLD_SLOTS 10u

inline float3 stack_float3(const uint* s, uint i) {
    return (float3)(as_float(s[i]), as_float(s[i + 1u]), as_float(s[i + 2u]));
}

// Closest or first hit through the top level (`nodes` from 0, leaves index `instances`) and
// the instances' bottom levels (in the same node array, from each instance's root; leaves
// index `object_tris`, the meshes' object-space triangles). Hits name the object-space
// triangle and the instance (its slot, where shading finds its transforms).
// One loop over both levels, as traverse_bvh's, with one stack. Reaching a top-level leaf
// (one piece, marked TLAS_LEAF by the host) pushes the piece's slot, carries the ray into the
// instance's object space and goes on at the piece's node, with `base` the stack height
// above the slot; popping down to it ends the bottom level and brings the world ray back.
// What the bottom level does not need stays in memory, not in registers: the world ray in
// the stack's first slots, the instance's slot under its walk (a hit found there names it as
// INSTANCE_PENDING until the walk ends). With the fewer registers, more rays run at once to
// hide the node loads (measured on an H200, 2026-12-01).
inline DeviceHit traverse_two_level(global const DeviceBvhNode* nodes,
                                 global const DeviceInstance* instances,
                                 global const DeviceTriangle* object_tris,
                                 const SceneSurfaces* surf, float3 o, float3 d, float tmin,
                                 float tmax, bool any_hit, volatile global uint* overflow) {
    RayPrep r = prepare_ray(o, d);
#ifdef HAS_TRIANGLE_PIECES
    // Top-level triangle pieces are tested against the whole world ray (CPUs only, where the
    // registers matter less).
    const RayPrep world = r;
#endif
    float rtmin = tmin;
    DeviceHit hit = no_hit(tmax);
    uint stack[TWO_LEVEL_STACK + WORLD_SLOTS];
    stack[0] = as_uint(o.x);
    stack[1] = as_uint(o.y);
    stack[2] = as_uint(o.z);
    stack[3] = as_uint(d.x);
    stack[4] = as_uint(d.y);
    stack[5] = as_uint(d.z);
    stack[6] = as_uint(r.inv.x);
    stack[7] = as_uint(r.inv.y);
    stack[8] = as_uint(r.inv.z);
    stack[9] = as_uint(tmin);
    uint sp = WORLD_SLOTS;
    // The stack height of the bottom level walked (0: the walk is in the top level).
    uint base = 0u;
    uint node = 0;
    for (;;) {
        if (node & INSTANCE_BIT) {
            // A piece: tested on the spot when it is one triangle (HAS_TRIANGLE_PIECES: small
            // meshes on CPUs), else entered.
            uint slot = node & ~INSTANCE_BIT;
            global const DeviceInstance* piece = &instances[slot];
#ifdef HAS_TRIANGLE_PIECES
            if (piece->flags & INSTANCE_PIECE_TRIANGLE) {
                if (intersect_piece_triangle(piece->root, piece->wide_root, slot, object_tris,
                                             surf, &world, o, d, tmin, any_hit, &hit)) {
                    return hit;
                }
                if (sp == WORLD_SLOTS) return hit;
                node = stack[--sp];
                continue;
            }
#endif
            if (sp == TWO_LEVEL_STACK + WORLD_SLOTS) {
                atomic_inc(overflow);
                return hit;
            }
            stack[sp++] = slot;
            base = sp;
            DeviceInstance inst = *piece;
            float3 wo = stack_float3(stack, 0u);
            float3 od = instance_vector(&inst, stack_float3(stack, 3u));
            r = prepare_ray(instance_point(&inst, wo), od);
            rtmin = instance_tmin(&inst, wo, od, as_float(stack[9]));
            node = inst.root;
        }
        DeviceBvhNode n = nodes[node];
        float dist[2];
        uint child[2];
        for (int side = 0; side < 2; ++side) {
            float4 lo = side == 0 ? n.left_min : n.right_min;
            float4 hi = side == 0 ? n.left_max : n.right_max;
            child[side] = NO_CHILD;
            dist[side] = box_entry(lo, hi, &r, rtmin, hit.t);
            if (dist[side] == INFINITY) continue;
            int ref = as_int(lo.w);
            uint count = as_uint(hi.w);
            if (ref >= 0) {
                child[side] = (uint)ref;
            } else if (count & TLAS_LEAF) {
                child[side] = (uint)(~ref) | INSTANCE_BIT;
            } else {
                float before = hit.t;
                bool stop = intersect_leaf(&r, object_tris, surf, (uint)(~ref), count, rtmin, o,
                                           d, any_hit, &hit);
                if (hit.t < before) hit.instance = INSTANCE_PENDING;
                if (stop) {
                    hit.instance = stack[base - 1u];
                    return hit;
                }
            }
        }
        // On to the nearer child reached, pushing the other; or to the next entry on the stack.
        if (child[0] != NO_CHILD && child[1] != NO_CHILD) {
            uint first = dist[0] <= dist[1] ? child[0] : child[1];
            uint second = dist[0] <= dist[1] ? child[1] : child[0];
            if (sp == TWO_LEVEL_STACK + WORLD_SLOTS) {
                atomic_inc(overflow);
                if (hit.instance == INSTANCE_PENDING) hit.instance = stack[base - 1u];
                return hit;
            }
            stack[sp++] = second;
            node = first;
        } else if (child[0] != NO_CHILD) {
            node = child[0];
        } else if (child[1] != NO_CHILD) {
            node = child[1];
        } else {
            if (sp == base) {
                // The instance is done: its slot names a hit found in it, and the world ray
                // and the top level are back.
                if (hit.instance == INSTANCE_PENDING) hit.instance = stack[base - 1u];
                r.origin = stack_float3(stack, 0u);
                r.inv = stack_float3(stack, 6u);
                rtmin = as_float(stack[9]);
                base = 0u;
                --sp;
            }
            if (sp == WORLD_SLOTS) return hit;
            node = stack[--sp];
        }
    }
}

// The scene's traversal: the flat BVH, or with TWO_LEVEL the instances' two levels.
inline DeviceHit trace_scene(global const DeviceBvhNode* nodes, global const DeviceTriangle* tris,
                          global const DeviceInstance* instances,
                          global const DeviceTriangle* object_tris, const SceneSurfaces* surf,
                          float3 o, float3 d, float tmin, float tmax, bool any_hit,
                          volatile global uint* overflow) {
#ifdef TWO_LEVEL
    // With two levels `tris` holds the meshes' object-space triangles (object_tris is unused).
    return traverse_two_level(nodes, instances, tris, surf, o, d, tmin, tmax, any_hit,
                              overflow);
#else
    return traverse(nodes, tris, surf, o, d, tmin, tmax, any_hit, overflow);
#endif
}

// A surface point's arithmetic for every lane width (shared/vec3.h):
//   f##barycentric(a, b, c, w, bu, bv)  w a + bu b + bv c;
//   f##surface_point(v0, v1, v2, bu, bv, *err)  the point at barycentrics (bu, bv) of a triangle
//       and a bound on how far a spawned ray's origin must move off it, per coordinate:
//       pbrt-v4's gamma(7) times the barycentric sum of the vertices' magnitudes (the rounding of
//       p), plus gamma(64) times the triangle's extent around p in every coordinate, which
//       stands in for pbrt's conservative t check in the ray-triangle test (a point exactly on a
//       triangle in the plane x = 0 has no rounding error, yet the sheared ray-triangle test can
//       still find it at a tiny positive t). Both follow the vertices, not a scene-wide epsilon,
//       so they hold at any scale and offset;
//   f##triangle_normal(v0, v1, v2)  the unit geometric normal of a triangle (counter-clockwise
//       front), or its cross product where that is 0. The cross product is scaled by a power of
//       two before normalizing, so triangles of 1e-10 or 1e10 units do not underflow or
//       overflow its squared length: 2^-ilogb(m) from m's exponent bits where m is normal and
//       the power too (ldexp's general form, three multiplications, elsewhere): the same value.
//       Then normalize() as the OpenCL library computes it (the product by the reciprocal of
//       the root of the squared length), less its rescaling for tiny or huge lengths: the
//       largest coordinate is now in [1, 2);
//   f##offset_ray(p, err, n)  p, whose coordinates are off by at most err, moved off the surface
//       along the geometric normal n (pointing to the side the ray leaves on) by the error bound
//       projected on n, each coordinate then rounded one more ulp away (pbrt-v4's
//       OffsetRayOrigin). A ray from the result can neither re-hit the surface it leaves nor
//       start behind it; tests/stress.rs checks this from 1e-8 to 1e8 through `spawn_test`.
#define DEFINE_SURFACE_MATHS(Q, f, F, I, U, V, v)                                                 \
    Q V f##barycentric(V a, V b, V c, F w, F bu, F bv) {                                           \
        return v##_add(v##_add(v##_scale(a, w), v##_scale(b, bu)), v##_scale(c, bv));              \
    }                                                                                              \
    Q V f##surface_point(V v0, V v1, V v2, F bu, F bv, V* err) {                                   \
        F w = 1.0f - bu - bv;                                                                      \
        const float gamma7 = 7.0f * 0x1p-24f / (1.0f - 7.0f * 0x1p-24f);                           \
        const float gamma64 = 64.0f * 0x1p-24f / (1.0f - 64.0f * 0x1p-24f);                        \
        V p = f##barycentric(v0, v1, v2, w, bu, bv);                                               \
        V extent = v##_max(v##_max(v##_abs(v##_sub(v0, p)), v##_abs(v##_sub(v1, p))),             \
                           v##_abs(v##_sub(v2, p)));                                               \
        F reach = fmax(fmax(extent.x, extent.y), extent.z);                                        \
        V magnitude = v##_add(v##_add(v##_abs(v##_scale(v0, w)), v##_abs(v##_scale(v1, bu))),      \
                              v##_abs(v##_scale(v2, bv)));                                         \
        *err = v##_add(v##_scale(magnitude, gamma7), v##_splat(gamma64 * reach));                  \
        return p;                                                                                  \
    }                                                                                              \
    Q V f##triangle_normal(V v0, V v1, V v2) {                                                     \
        V c = v##_cross(v##_sub(v1, v0), v##_sub(v2, v0));                                         \
        F m = fmax(fmax(fabs(c.x), fabs(c.y)), fabs(c.z));                                         \
        U e = (as_##U(m) >> 23u) & 0xffu;                                                          \
        I normal_e = e - 1u < 253u;                                                                \
        F scale = as_##F((254u - e) << 23u);                                                       \
        if (v##_any(!normal_e)) scale = select(ldexp((F)(1.0f), -ilogb(m)), scale, normal_e);      \
        V cs = v##_scale(c, scale);                                                                \
        V n = v##_scale(cs, 1.0f / sqrt(cs.x * cs.x + cs.y * cs.y + cs.z * cs.z));                  \
        return v##_select(c, n, m > 0.0f);                                                         \
    }                                                                                              \
    Q V f##offset_ray(V p, V err, V n) {                                                           \
        return v##_offset_step(p, v##_scale(n, v##_dot(v##_abs(n), err)));                         \
    }

// p + offset rounded one more float away from p, coordinate by coordinate, for floats (or float
// vectors) F with integer masks I of their width: nextafter(po, +-INFINITY) on the bits, for
// finite po, one step of the magnitude away from zero where po's sign is the step's, towards
// zero where it is not, and from a zero the smallest number of the step's sign. For float3 it
// is f3_offset_step, v##_offset_step of DEFINE_SURFACE_MATHS (the lanes' lv_offset_step applies
// lanes_offset_step to each coordinate).
#define DEFINE_OFFSET_STEP(Q, f, F, I)                                                             \
    Q F f##offset_step(F p, F offset) {                                                            \
        F po = p + offset;                                                                         \
        I bits = as_##I(po);                                                                       \
        I away = (po > 0.0f) == (offset > 0.0f); /* the step goes away from zero */               \
        I stepped = select(bits - 1, bits + 1, away);                                              \
        stepped = select(stepped, select((I)(0x80000001), (I)(1), offset > 0.0f), po == 0.0f);     \
        return select(po, as_##F(stepped), offset != 0.0f);                                        \
    }

DEFINE_OFFSET_STEP(inline, f3_, float3, int3)
DEFINE_SURFACE_MATHS(inline, , float, int, uint, float3, f3)

#endif  // SHARED_TRAVERSE_H
