// What the CPU megakernels share (megakernel.cl one path at a time, megakernel_lanes.cl with
// MEGA_LANES): the kernel's parameters, the scene shading reads from them, a finished sample's
// sum and the work item's ray counts (and adaptive sampling's film, shared/adaptive.h), and the last ray traced only toward the emitters.
#ifndef CPU_MEGAKERNEL_H
#define CPU_MEGAKERNEL_H

#include "shared/types.h"
#include "shared/traverse.h"
#include "shared/path.h"
#include "shared/adaptive.h"
#include "shared/aovs.h"

// The kernel's parameters, in both megakernels.
#define MEGAKERNEL_PARAMS                                                                   \
    DeviceFrame frame, DeviceCamera camera, DeviceEnvironment environment,                           \
        global const DeviceWideNode *nodes, global const DeviceTriangle *tris,                    \
        global const DeviceInstance *instances, global const DeviceTriangle *object_tris,         \
        global const DeviceTriShading *shading, global const DeviceTriUvs *uvs,                   \
        global const DeviceTriTangents *tangents, global const DeviceTriColors *colors,           \
        global const DeviceMaterial *materials,                                                   \
        global const DeviceTexRef *tex_refs, global const DeviceTexture *textures,                \
        global const uint *texels, global const float *env_texels,                          \
        global const float *env_marginal, global const float *env_conditional,              \
        global const DeviceLight *lights, global const float *light_cdf, global ulong4 *film, \
        volatile global uint *counters, global float4 *halves, global uint *state,           \
        global uint *rays,                                                                  \
        global float4 *aov_albedo, global float4 *aov_normal, global float2 *aov_depth

// What shading reads of the scene, from the kernel's parameters.
inline ShadeScene mega_shade_scene(DeviceEnvironment environment,
                                   global const DeviceTriangle* tris,
                                   global const DeviceInstance* instances,
                                   global const DeviceTriShading* shading,
                                   global const DeviceTriUvs* uvs,
                                   global const DeviceTriTangents* tangents,
                                   global const DeviceTriColors* colors,
                                   global const DeviceMaterial* materials,
                                   global const DeviceTexRef* tex_refs,
                                   global const DeviceTexture* textures, global const uint* texels,
                                   global const float* env_texels,
                                   global const float* env_marginal,
                                   global const float* env_conditional,
                                   global const DeviceLight* lights,
                                   global const float* light_cdf) {
    ShadeScene sc = {tris,
                     {shading, uvs, tangents, colors, materials, tex_refs, textures, texels, instances},
                     {environment, env_texels, env_marginal, env_conditional},
                     lights,
                     light_cdf};
    return sc;
}

// A finished sample of radiance `radiance`: added to the pixel's sum (a non-finite one dropped
// and counted), and counted in the film's .w unless its camera ray escaped.
inline void mega_add_sample(float3 radiance, bool escaped, ulong3* sum, uint* counted,
                            uint* nonfinite) {
    *counted += !escaped;
    if (all(isfinite(radiance))) {
        film_add(sum, radiance);
    } else {
        ++*nonfinite;
    }
}

// A work item's statistics, one atomic each; `advance` moves them into the totals.
inline void mega_count(volatile global uint* counters, uint extension_rays, uint shadow_rays,
                       uint nonfinite) {
    atomic_add(&counters[COUNT_IN], extension_rays);
    atomic_add(&counters[COUNT_SHADOW], shadow_rays);
    if (nonfinite > 0u) atomic_add(&counters[COUNT_NONFINITE], nonfinite);
}

// The last extension ray (bounce max_bounces + 1) only looks for emitters: with the lights'
// triangles the only surfaces that add anything there (no environment map, no unlit
// materials, a black sky, no alpha), and few of them, the ray is tested against those
// triangles first, by the traversal's own watertight test. When it meets none, it would add
// nothing and is not traced; when it meets one at t, only an any-hit ray over (0, t) is
// traced, and an unblocked ray shades that hit as the closest-hit ray would have found it.
// The same estimator, the same image;
// -DLAST_RAY_TRACED traces it as before.
#if defined(HAS_TRIANGLE_LIGHTS) && !defined(HAS_ENV_MAP) && !defined(HAS_UNLIT) && \
    !defined(HAS_ALPHA) && !defined(TWO_LEVEL) && !defined(LAST_RAY_TRACED)
#define LAST_RAY_EMITTERS
// The most lights for which the last ray tests their triangles one by one.
#define LAST_RAY_LIGHTS_MAX 16u

inline bool mega_last_ray_by_emitters(const DeviceFrame* frame) {
    return frame->light_count <= LAST_RAY_LIGHTS_MAX && frame_sky_black(frame);
}

// The nearest of the lights' triangles along the ray from o along d, or NO_HIT.
inline DeviceHit mega_nearest_emitter(const DeviceFrame* frame, const ShadeScene* sc, float3 o,
                                   float3 d) {
    RayPrep r = prepare_ray(o, d);
    DeviceHit hit = no_hit(INFINITY);
    for (uint i = 0u; i < frame->light_count; ++i) {
        global const DeviceLight* l = &sc->lights[i];
        if (as_uint(l->position.w) != LIGHT_TRIANGLE) continue;
        uint prim = as_uint(l->spot.x);
        DeviceTriangle t = sc->tris[prim];
        float t_hit = hit.t, bu, bv;
        if (intersect_triangle(&r, t.v0, t.v1, t.v2, 0.0f, &t_hit, &bu, &bv)) {
            hit.t = t_hit;
            hit.u = bu;
            hit.v = bv;
            hit.prim = prim;
        }
    }
    return hit;
}
#endif

#endif  // CPU_MEGAKERNEL_H
