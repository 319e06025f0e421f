// Next-event estimation: pick a light by the host's power table, then a point or direction on it.
#ifndef SHARED_LIGHTS_H
#define SHARED_LIGHTS_H

#include "shared/types.h"
#include "shared/vec3.h"
#include "shared/rng.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"
#include "shared/bsdf.h"
#include "shared/surface.h"
#include "shared/env.h"

typedef struct {
    float3 wi;          // unit direction towards the light
    float distance;     // distance to the sampled point (INFINITY for directional lights)
    float3 radiance;    // incident radiance divided by the solid-angle pdf (selection included)
    float pdf;          // solid-angle pdf including selection; 0 for delta lights
    float3 target;      // emissive triangles: the sampled point moved off the light towards
                        // the shading point, where the shadow ray ends
    bool on_surface;    // whether `target` is set (the light is geometry the shadow ray could hit)
} LightSample;

// An emissive triangle's light sample for every lane width (shared/vec3.h), from the point q
// sampled on the light (error bound q_err, geometric normal ng) for the shading point p, with
// the light's selection probability sel, its area and whether it emits from both sides:
// f##triangle_light_sample(p, q, q_err, ng, sel, area, two_sided, *wi, *distance, *target,
// *on_surface, *pdf) sets the unit direction to q, its distance, the shadow ray's end (q moved
// a few ulps off the light, on p's side, so that the ray can neither hit the light itself nor
// stop short of an occluder, at any scale) and *on_surface where p and q are apart (elsewhere
// +z, 0, p and false), and the solid-angle pdf where the light faces p (else 0); returns
// whether it does (the sample then brings the light's emission over that pdf).
#define DEFINE_TRIANGLE_LIGHT_MATHS(Q, f, F, I, U, V, v)                                          \
    Q I f##triangle_light_sample(V p, V q, V q_err, V ng, F sel, F area, I two_sided, V* wi,       \
                                 F* distance, V* target, I* on_surface, F* pdf) {                  \
        V d = v##_sub(q, p);                                                                       \
        F dist2 = v##_dot(d, d);                                                                   \
        I apart = !(dist2 <= 0.0f);                                                                \
        F dist = sqrt(dist2);                                                                      \
        V dir = v##_div(d, dist);                                                                  \
        V out = v##_select(v##_neg(ng), ng, v##_dot(ng, v##_sub(p, q)) > 0.0f);                    \
        *wi = v##_select(v##_make((F)(0.0f), (F)(0.0f), (F)(1.0f)), dir, apart);                   \
        *distance = select((F)(0.0f), dist, apart);                                                \
        *target = v##_select(p, f##offset_ray(q, q_err, out), apart);                              \
        *on_surface = apart;                                                                       \
        F cos_l = -v##_dot(ng, dir);                                                               \
        I emits = apart & (two_sided | !(cos_l <= 0.0f));                                          \
        cos_l = fabs(cos_l);                                                                       \
        emits = emits & !(cos_l <= 0.0f);                                                          \
        *pdf = select((F)(0.0f), sel * dist2 / (area * cos_l), emits);                             \
        return emits;                                                                              \
    }

DEFINE_TRIANGLE_LIGHT_MATHS(SHADE_INLINE, , float, int, uint, float3, f3)

// Spot cone attenuation as the glTF KHR_lights_punctual specification writes it.
inline float spot_falloff(global const DeviceLight* l, float3 to_point) {
    float cos_outer = l->spot.w;
    float cos_inner = l->extra.x;
    float scale = 1.0f / fmax(0.001f, cos_inner - cos_outer);
    float offset = -cos_outer * scale;
    float cd = dot(l->spot.xyz, to_point);
    float a = clamp(cd * scale + offset, 0.0f, 1.0f);
    return a * a;
}

// Samples light `index` from point p. Punctual lights with radius r > 0 become spheres of the
// same power (radiance I / (pi r^2)); directional lights with angular radius a > 0 become discs
// of directions (radiance E / (pi sin^2 a)).
SHADE_INLINE LightSample sample_light(global const DeviceLight* lights,
                                      global const DeviceTriangle* tris,
                                      global const DeviceMaterial* materials,
                                      const SceneSurfaces* surf, const EnvMap* env, uint index,
                                      float3 p, float u1, float u2) {
    global const DeviceLight* l = &lights[index];
    float select = l->extra.y;
    uint kind = as_uint(l->position.w);
    float radius = l->intensity.w;
    LightSample s;
    s.pdf = 0.0f;
    s.radiance = (float3)(0.0f);
    s.wi = (float3)(0.0f, 0.0f, 1.0f);
    s.distance = 0.0f;
    s.target = p;
    s.on_surface = false;
    if (kind == LIGHT_DIRECTIONAL) {
        float3 axis = -l->position.xyz;
        s.distance = INFINITY;
        if (radius > 0.0f) {
            float half_sin = sin(0.5f * radius);
            float one_minus_cos = 2.0f * half_sin * half_sin;
            float sin_max = sin(radius);
            float sin2 = fmax(1e-12f, sin_max * sin_max);
            s.wi = normalize(to_world(sample_cone(u1, u2, one_minus_cos), axis));
            float pdf = 1.0f / (2.0f * PI_F * one_minus_cos);
            s.radiance = l->intensity.xyz / (PI_F * sin2) / (pdf * select);
            s.pdf = pdf * select;
        } else {
            s.wi = axis;
            s.radiance = l->intensity.xyz / select;
        }
        return s;
    }
#ifdef HAS_ENV_MAP
    if (kind == LIGHT_ENVIRONMENT) {
        float3 radiance;
        float pdf;
        s.wi = env_sample(env, u1, u2, &radiance, &pdf);
        s.distance = INFINITY;
        if (pdf > 0.0f) {
            s.pdf = pdf * select;
            s.radiance = radiance / s.pdf;
        }
        return s;
    }
#endif
#ifdef HAS_TRIANGLE_LIGHTS
    if (kind == LIGHT_TRIANGLE) {
        uint prim = as_uint(l->spot.x);
        float area = l->spot.y;
        DeviceTriangle t = tris[prim];
#ifdef TWO_LEVEL
        // Two levels: the mesh's object-space triangle, placed by the light's instance.
        DeviceInstance inst = surf->instances[as_uint(l->spot.z)];
        float3 world_err;
        t = instance_triangle(&inst, t, &world_err);
#endif
        float b1, b2;
        sample_triangle(u1, u2, &b1, &b2);
        float3 q_err;
        float3 q = surface_point(t.v0.xyz, t.v1.xyz, t.v2.xyz, b1, b2, &q_err);
        float3 ng = flat_normal(surf, prim, t);
#ifdef TWO_LEVEL
        q_err += world_err;
        ng *= instance_normal_sign(&inst);
#endif
        global const DeviceMaterial* m = &materials[as_uint(t.v0.w)];
        bool two_sided = (as_uint(m->emission.w) & MATERIAL_DOUBLE_SIDED) != 0u;
        int on_surface;
        bool emits = triangle_light_sample(p, q, q_err, ng, select, area, two_sided, &s.wi,
                                           &s.distance, &s.target, &on_surface, &s.pdf);
        s.on_surface = on_surface;
        if (!emits) return s;
#ifdef HAS_TEXTURES
        TexCoords tc = texcoords_at(surf->uvs[prim], b1, b2);
        s.radiance = textured_emission(m, surf, &tc) / s.pdf;
#else
        s.radiance = m->emission.xyz / s.pdf;
#endif
        return s;
    }
#endif
    float3 center = l->position.xyz;
    float3 d = center - p;
    float dist2 = dot(d, d);
    float dist = sqrt(dist2);
    if (dist <= 0.0f) return s;
    float3 intensity = l->intensity.xyz;
    if (kind == LIGHT_SPOT) intensity *= spot_falloff(l, -d / dist);
    if (radius > 0.0f && dist > radius) {
        // Uniform sampling of the cone the sphere subtends.
        float sin2_max = radius * radius / dist2;
        float cos_max = sqrt(fmax(0.0f, 1.0f - sin2_max));
        float one_minus_cos = sin2_max / (1.0f + cos_max);
        float3 axis = d / dist;
        s.wi = normalize(to_world(sample_cone(u1, u2, one_minus_cos), axis));
        // Distance to the near side of the sphere along wi.
        float b = dot(s.wi, d);
        float disc = b * b - dist2 + radius * radius;
        s.distance = b - sqrt(fmax(0.0f, disc));
        float pdf = 1.0f / (2.0f * PI_F * one_minus_cos);
        s.radiance = intensity / (PI_F * radius * radius) / (pdf * select);
        s.pdf = pdf * select;
    } else {
        s.wi = d / dist;
        s.distance = dist;
        s.radiance = intensity / (dist2 * select);
    }
    return s;
}

#endif  // SHARED_LIGHTS_H
