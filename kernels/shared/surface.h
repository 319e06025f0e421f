// What a hit's textures do to its material: base color, metallic-roughness, transmission and
// emission, and the shading normal from a tangent-space normal map; with two levels, the hit's
// object-space triangle and shading data carried to world space by its instance.
#ifndef SHARED_SURFACE_H
#define SHARED_SURFACE_H

#include "shared/types.h"
#include "shared/rng.h"
#include "shared/textures.h"
#include "shared/bsdf.h"

#ifdef TWO_LEVEL
// M v: a vector to world space (src/bvh/instances.rs keeps M's rows in world0..2).
inline float3 instance_vector_to_world(const DeviceInstance* inst, float3 v) {
    return (float3)(inst->world0.x * v.x + inst->world0.y * v.y + inst->world0.z * v.z,
                    inst->world1.x * v.x + inst->world1.y * v.y + inst->world1.z * v.z,
                    inst->world2.x * v.x + inst->world2.y * v.y + inst->world2.z * v.z);
}

// p_world = M p + T (T in row0..2.w).
inline float3 instance_to_world(const DeviceInstance* inst, float3 p) {
    return instance_vector_to_world(inst, p) + (float3)(inst->row0.w, inst->row1.w, inst->row2.w);
}

// An object-space triangle in world space (payloads in .w kept), and in *err a bound on the
// rounding of its world vertices: gamma(4) (|M| |v| + |T|) for the largest |v| per coordinate.
// Vertices keep their order, so a mirrored instance's triangle winds the other way: callers
// flip its geometric normal (`instance_normal_sign`).
inline DeviceTriangle instance_triangle(const DeviceInstance* inst, DeviceTriangle t, float3* err) {
    const float gamma4 = 4.0f * 0x1p-24f / (1.0f - 4.0f * 0x1p-24f);
    float3 a = fmax(fmax(fabs(t.v0.xyz), fabs(t.v1.xyz)), fabs(t.v2.xyz));
    float3 m0 = fabs(inst->world0.xyz), m1 = fabs(inst->world1.xyz), m2 = fabs(inst->world2.xyz);
    float3 origin = fabs((float3)(inst->row0.w, inst->row1.w, inst->row2.w));
    *err = gamma4 * ((float3)(dot(m0, a), dot(m1, a), dot(m2, a)) + origin);
    DeviceTriangle w;
    w.v0 = (float4)(instance_to_world(inst, t.v0.xyz), t.v0.w);
    w.v1 = (float4)(instance_to_world(inst, t.v1.xyz), t.v1.w);
    w.v2 = (float4)(instance_to_world(inst, t.v2.xyz), t.v2.w);
    return w;
}

// -1 for a mirrored instance (its world triangles wind the other way), else 1.
inline float instance_normal_sign(const DeviceInstance* inst) {
    return (inst->flags & INSTANCE_MIRRORED) != 0u ? -1.0f : 1.0f;
}

// A normal to world space: L^T n (the inverse transpose of M), unit; 0 stays 0.
inline float3 instance_normal(const DeviceInstance* inst, float3 n) {
    float3 w = inst->row0.xyz * n.x + inst->row1.xyz * n.y + inst->row2.xyz * n.z;
    float len = length(w);
    return len > 0.0f ? w / len : w;
}
#endif

// The tangents at the corners of a hit's triangle in world space (w: bitangent sign). With two
// levels they are the mesh's, carried by M and with the sign flipped in a mirrored instance.
inline DeviceTriTangents hit_tangents(const SceneSurfaces* s, DeviceHit hit) {
    DeviceTriTangents tt = s->tangents[hit.prim];
#ifdef TWO_LEVEL
    DeviceInstance inst = s->instances[hit.instance];
    float sign = instance_normal_sign(&inst);
    tt.t0 = (float4)(instance_vector_to_world(&inst, tt.t0.xyz), tt.t0.w * sign);
    tt.t1 = (float4)(instance_vector_to_world(&inst, tt.t1.xyz), tt.t1.w * sign);
    tt.t2 = (float4)(instance_vector_to_world(&inst, tt.t2.xyz), tt.t2.w * sign);
#endif
    return tt;
}

#ifdef HAS_TEXTURES
// Multiplies the material's factors by its textures at the hit.
inline void apply_textures(SurfaceMaterial* m, global const DeviceMaterial* mat,
                           const SceneSurfaces* s, const TexCoords* tc) {
    if (mat->textures.x >= 0) m->base_color *= texture_sample(s, mat->textures.x, tc).xyz;
    if (mat->textures.y >= 0) {
        float4 mr = texture_sample(s, mat->textures.y, tc);
        m->roughness *= mr.y;
        m->metallic *= mr.z;
    }
#ifdef HAS_TRANSMISSION
    if (mat->textures2.x >= 0) m->transmission *= texture_sample(s, mat->textures2.x, tc).x;
#endif
#ifdef HAS_CLEARCOAT
    if (mat->textures3.x >= 0) m->clearcoat *= texture_sample(s, mat->textures3.x, tc).x;
    if (mat->textures3.y >= 0) m->coat_roughness *= texture_sample(s, mat->textures3.y, tc).y;
#endif
#ifdef HAS_SHEEN
    if (mat->textures2.z >= 0) m->sheen_color *= texture_sample(s, mat->textures2.z, tc).xyz;
    if (mat->textures2.w >= 0) m->sheen_roughness *= texture_sample(s, mat->textures2.w, tc).w;
#endif
#ifdef HAS_DIFFUSE_TRANSMISSION
    if (mat->textures4.w >= 0) m->diffuse_transmission *= texture_sample(s, mat->textures4.w, tc).w;
    if (mat->textures5.x >= 0) {
        m->diffuse_transmission_color *= texture_sample(s, mat->textures5.x, tc).xyz;
    }
#endif
#ifdef HAS_IRIDESCENCE
    // R: the factor; G: the thickness between the minimum and the maximum (else the maximum).
    if (mat->textures4.y >= 0) m->iridescence *= texture_sample(s, mat->textures4.y, tc).x;
    if (mat->textures4.z >= 0) {
        m->iridescence_thickness =
            mix(mat->iridescence.z, mat->iridescence.w, texture_sample(s, mat->textures4.z, tc).y);
    }
#endif
#ifdef HAS_ANISOTROPY
    // RG: the direction in tangent space (then turned by the rotation), B: the strength.
    if (mat->textures4.x >= 0) {
        float3 a = texture_sample(s, mat->textures4.x, tc).xyz;
        float2 d = a.xy * 2.0f - 1.0f;
        float2 r = m->aniso_rotation;
        if (dot(d, d) > 1e-12f) m->aniso_rotation = (float2)(r.x * d.x - r.y * d.y, r.y * d.x + r.x * d.y);
        m->anisotropy *= a.z;
    }
#endif
}

// Emitted radiance at the hit: the factor times the emissive texture.
inline float3 textured_emission(global const DeviceMaterial* mat, const SceneSurfaces* s,
                                const TexCoords* tc) {
    float3 e = mat->emission.xyz;
    if (mat->textures.w >= 0) e *= texture_sample(s, mat->textures.w, tc).xyz;
    return e;
}
#endif

#ifdef HAS_NORMAL_MAPS
// The shading normal from the normal map `tex` scaled by `scale` (the material's normal
// texture, or its clearcoat normal texture). ns and ng face the side the ray came from; `front`
// says whether that is the triangle's front, in which case the tangent frame is the file's,
// else every axis of it is reversed (glTF reverses back-face normals of double-sided
// materials); `tt` are the triangle's world-space tangents (`hit_tangents`). The result is
// bent to stay above the geometric surface.
inline float3 normal_map(const SceneSurfaces* s, int tex, float scale, const TexCoords* tc,
                         DeviceTriTangents tt, float u, float v, float3 ns, float3 ng, bool front) {
    float w0 = 1.0f - u - v;
    float3 t = w0 * tt.t0.xyz + u * tt.t1.xyz + v * tt.t2.xyz;
    float3 n = front ? ns : -ns;
    t -= n * dot(n, t);
    float len = length(t);
    if (!(len > 1e-8f)) return ns;
    t /= len;
    float3 b = cross(n, t) * (tt.t0.w < 0.0f ? -1.0f : 1.0f);
    float3 c = texture_sample(s, tex, tc).xyz * 2.0f - 1.0f;
    float3 mapped = normalize(c.x * scale * t + c.y * scale * b + c.z * n);
    if (!all(isfinite(mapped))) return ns;
    if (!front) mapped = -mapped;
    float cos_g = dot(mapped, ng);
    if (cos_g < 0.01f) mapped = normalize(mapped + (0.01f - cos_g) * ng);
    return mapped;
}
#endif

// The shading normal n turned towards the geometric normal ng (both facing w's side), in their
// plane, just enough that the mirror reflection of w about it rises min(0.9 cos_g(w), lift)
// above the geometric surface (Cycles' ensure_valid_reflection, whose lift is 0.01). A normal
// map leaning far from ng would otherwise send a glossy lobe's reflections below the surface,
// where the path ends: black rims on shiny normal-mapped surfaces. With n(θ) = sin θ X +
// cos θ ng (X the unit direction of n's tangential part), the reflection's cosine with ng is
// w_x sin 2θ + w_z cos 2θ = A cos(2θ - φ), A = |(w_x, w_z)|, φ = atan2(w_x, w_z): from w_z at
// θ = 0 it rises, if at all, then falls, so it stays above the threshold t on [0, θ*],
// θ* = (φ + acos(t / A)) / 2, and n(min(θ, θ*)) is returned. Bending for two directions in
// turn thus bends to the lesser of their θ*, in either order: the BSDF evaluated with the
// normals bent for both wo and wi is reciprocal (`bent_for`).
inline float3 bend_for_reflection(float3 ng, float3 w, float3 n, float lift) {
    float wz = dot(w, ng);
    float nz = dot(n, ng);
    float t = fmin(0.9f * wz, lift);
    if (2.0f * dot(n, w) * nz - wz >= t) return n;
    float3 x = n - nz * ng;
    float len = length(x);
    if (!(len > 1e-7f)) return n;
    x /= len;
    float wx = dot(w, x);
    float a = sqrt(wx * wx + wz * wz);
    if (!(a > 0.0f)) return n;
    float theta = 0.5f * (atan2(wx, wz) + acos(fmin(t / a, 1.0f)));
    return sin(theta) * x + cos(theta) * ng;
}

// The height bend_for_reflection keeps a lobe's mirror direction above the surface: 0.01 for
// a mirror, raised by the lobe's width (alpha = roughness²) so that most of a glossy lobe stays
// above too, at most 0.1 (so that a rough surface's normal map keeps its shape; seen head-on a
// normal then leans at most 42°). A white metal of roughness 0.1 seen head-on through a normal
// 70° off kept 0.73 of a furnace's light at 0.01 and keeps 0.92 with this (tests/textures.rs).
inline float reflection_lift(float roughness) {
    return fmin(0.01f + 2.0f * roughness * roughness, 0.1f);
}

// The roughness below which a lobe's normal is bent: a rougher lobe spreads below the surface
// whatever its normal, and its normal map's shape matters more than a mirror direction.
#define BEND_ROUGHNESS_MAX 0.5f

// m's normals at a normal-mapped vertex, *ns and the coat's, bent for direction w where their
// lobe is glossy: a base with a specular layer or metal of roughness below BEND_ROUGHNESS_MAX,
// a coat below it. A Lambertian base is never bent: it has no reflection to keep above the
// surface, and bending it for wi would light it from below its mapped normal's horizon.
inline void bend_normals(SurfaceMaterial* m, float3 ng, float3 w, float3* ns) {
    bool glossy = m->metallic > 0.0f || m->specular_factor > 0.0f;
    if (glossy && m->roughness < BEND_ROUGHNESS_MAX) {
        *ns = bend_for_reflection(ng, w, *ns, reflection_lift(m->roughness));
    }
#ifdef HAS_CLEARCOAT
    if (dot(m->coat_normal, m->coat_normal) > 0.0f && m->clearcoat > 0.0f &&
        m->coat_roughness < BEND_ROUGHNESS_MAX) {
        m->coat_normal =
            bend_for_reflection(ng, w, m->coat_normal, reflection_lift(m->coat_roughness));
    }
#endif
}

// The material and shading normal of a normal-mapped vertex (m, ns: bent for wo) bent for wi
// too, into *mi and *ni (coat normal included); false when wi bends nothing (wi below the
// surface: transmission has no reflection to keep above it).
inline bool bent_for(const SurfaceMaterial* m, float3 ng, float3 ns, float3 wi,
                     SurfaceMaterial* mi, float3* ni) {
    if (!(dot(wi, ng) > 0.0f)) return false;
    *mi = *m;
    *ni = ns;
    bend_normals(mi, ng, wi, ni);
    bool bent = any(*ni != ns);
#ifdef HAS_CLEARCOAT
    bent = bent || any(mi->coat_normal != m->coat_normal);
#endif
    return bent;
}

// bsdf_eval (f·|cos|) at a normal-mapped vertex: with m's normals and ns bent for wo, and for
// wi too (`bent_for`), so reciprocal; *pdf is that of sampling with wo's normals.
inline float3 bsdf_eval_bent(const SurfaceMaterial* m, float3 ng, float3 ns, float3 wo, float3 wi,
                             float* pdf) {
    float3 f = bsdf_eval(m, ns, wo, wi, pdf);
    SurfaceMaterial mi;
    float3 ni;
    if (bent_for(m, ng, ns, wi, &mi, &ni)) {
        float unused;
        f = bsdf_eval(&mi, ni, wo, wi, &unused);
    }
    return f;
}

#ifdef HAS_ANISOTROPY
// The anisotropy direction (world) at a hit: `dir` (cos, sin of its angle, or the texture's
// direction turned by the rotation) in the frame (T, B) of the interpolated tangent, made
// orthogonal to the shading normal ns, and B = w N × T as normal maps use it (the file's frame,
// reversed on back faces). Without a tangent (no texture coordinates) the frame is onb's.
inline float3 anisotropy_direction(const SceneSurfaces* s, uint prim, float u, float v, float3 ns,
                                   bool front, float2 dir) {
    float3 n = front ? ns : -ns;
    float3 t, b;
    onb(n, &t, &b);
#ifdef HAS_TANGENTS
    DeviceTriTangents tt = s->tangents[prim];
    float3 tg = (1.0f - u - v) * tt.t0.xyz + u * tt.t1.xyz + v * tt.t2.xyz;
    tg -= n * dot(n, tg);
    float len = length(tg);
    if (len > 1e-8f) {
        t = tg / len;
        b = cross(n, t) * (tt.t0.w < 0.0f ? -1.0f : 1.0f);
    }
#endif
    return dir.x * t + dir.y * b;
}
#endif

#endif  // SHARED_SURFACE_H
