// The path tracer as one kernel, one path at a time (without MEGA_LANES; the default on CPU
// devices, and on any device with --kernel megakernel): a work item follows the paths of one
// pixel from the camera to their end, `frame.samples_in_wave` samples one after the other, with
// the path state in registers: no queues, no path buffers, one launch per pass. Each vertex is
// shaded by path.h's shade_vertex, as the wavefront's `shade` does, and its light sample is
// traced at once (the wavefront's `connect`), so both compute the same estimator from the
// same random numbers. The samples of a pixel are added to its film sum in order, one by one;
// with adaptive sampling a converged pixel takes none. With AOVS each path's guide record
// (shared/aovs.h) is added to the pixel's AOV sums in the same order.
//
// Rays are traced through the 4-wide BVH (traverse_wide.h), whose box tests use the CPU's
// vector lanes, or with SMALL_SCENE tested against every triangle of a small scene.

#include "shared/types.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"
#include "shared/path.h"
#include "cpu/megakernel.h"

#ifndef MEGA_LANES
// What the kernel traces rays through: the 4-wide BVH, or with SMALL_SCENE the work group's
// copy of a small scene.
typedef struct {
#ifdef SMALL_SCENE
    local const SmallScene* small;
#else
    global const DeviceWideNode* nodes;
#endif
    global const DeviceTriangle* tris;
    global const DeviceInstance* instances;
    global const DeviceTriangle* object_tris;
    const SceneSurfaces* surf;
    volatile global uint* overflow;
} MegaTracer;

// The nearest hit of the ray from o along d in (0, tmax), or with any_hit some hit.
inline DeviceHit mega_trace(const MegaTracer* T, float3 o, float3 d, float tmax, bool any_hit) {
#ifdef SMALL_SCENE
    return trace_small(T->small, T->tris, T->surf, o, d, 0.0f, tmax, any_hit);
#else
    return trace_scene_wide(T->nodes, T->tris, T->instances, T->object_tris, T->surf, o, d, 0.0f,
                            tmax, any_hit, T->overflow);
#endif
}

#ifdef HAS_SINGLE_SIDED
// What a camera ray sees, given its closest hit: the backs of single-sided surfaces passed.
inline DeviceHit mega_camera_hit(const MegaTracer* T, float3 o, float3 d, DeviceHit hit) {
#ifdef SMALL_SCENE
    return camera_hit_small(T->small, T->tris, T->instances, T->object_tris, T->surf, o, d, hit,
                            true, true, T->overflow);
#else
    return camera_hit_wide(T->nodes, T->tris, T->instances, T->object_tris, T->surf, o, d, hit,
                           true, true, T->overflow);
#endif
}
#endif

// What of a light sample's contribution reaches the path (path.h's shadow test).
inline float3 mega_shadow(const MegaTracer* T, const ShadowQuery* q) {
#ifdef SMALL_SCENE
    return shadow_pass_small(T->small, T->tris, T->instances, T->object_tris, T->surf, q,
                             T->overflow);
#else
    return shadow_pass_wide(T->nodes, T->tris, T->instances, T->object_tris, T->surf, q,
                            T->overflow);
#endif
}

kernel void megakernel(MEGAKERNEL_PARAMS) {
#ifdef SMALL_SCENE
    local SmallScene small;
    // Before any work item returns: it waits for the group.
    small_scene_load(tris, frame.triangles, &small);
#endif
    uint pixel = get_global_id(0);
    uint pixels = frame.width * frame.height;
    if (pixel >= pixels || pixel_converged(&frame, state, pixel)) return;
    ShadeScene sc = mega_shade_scene(environment, tris, instances, shading, uvs, tangents, colors,
                                     materials, tex_refs, textures, texels, env_texels,
                                     env_marginal, env_conditional, lights, light_cdf);
    volatile global uint* overflow = &counters[COUNT_OVERFLOW];
    ulong4 pixel_film = film[pixel];
    ulong3 sum = pixel_film.xyz;
    uint extension_rays = 0;
    uint shadow_rays = 0;
    uint nonfinite = 0;
    uint counted = 0;  // samples whose camera ray hit (the film's .w with the background cut out)
    float3 even = (float3)(0.0f);  // adaptive sampling's half buffer (shared/adaptive.h)
    uint evens = 0;
#ifdef AOVS
    float3 aov_albedo_sum = (float3)(0.0f), aov_normal_sum = (float3)(0.0f);
    float2 aov_depth_sum = (float2)(0.0f);
#endif
#ifdef SMALL_SCENE
    sc.surf.small = &small;
    const MegaTracer T = {&small, tris, instances, object_tris, &sc.surf, overflow};
#else
    const MegaTracer T = {nodes, tris, instances, object_tris, &sc.surf, overflow};
#endif
#ifdef LAST_RAY_EMITTERS
    bool last_by_emitters = mega_last_ray_by_emitters(&frame);
#endif
    for (uint j = 0; j < frame.samples_in_wave; ++j) {
        PathState s = camera_path(&frame, &camera, pixel, frame.first_sample + j);
        for (uint bounce = 0; bounce <= frame.max_bounces + 1u; ++bounce) {
            DeviceHit hit;
#ifdef LAST_RAY_EMITTERS
            if (last_by_emitters && bounce == frame.max_bounces + 1u) {
                // The last ray: the emitter it meets, if nothing is in the way (megakernel.h).
                hit = mega_nearest_emitter(&frame, &sc, s.origin, s.direction);
                if (hit.prim == NO_HIT) break;
                ++extension_rays;
                if (mega_trace(&T, s.origin, s.direction, hit.t, true).prim != NO_HIT) break;
            } else
#endif
            {
                hit = mega_trace(&T, s.origin, s.direction, INFINITY, false);
#ifdef HAS_SINGLE_SIDED
                if (bounce == 0u) hit = mega_camera_hit(&T, s.origin, s.direction, hit);
#endif
                ++extension_rays;
            }
            ShadowQuery q;
            bool alive = shade_vertex(&frame, bounce, &sc, hit, &s, &q);
            if (q.valid) {
                ++shadow_rays;
                s.radiance += mega_shadow(&T, &q);
            }
            if (!alive) break;
        }
        mega_add_sample(s.radiance, (s.flags & PATH_ESCAPED) != 0u, &sum, &counted, &nonfinite);
        if (frame.adaptive != 0u) half_add(s.radiance, frame.first_sample + j, &even, &evens);
#ifdef AOVS
        aov_add(&s.aov, &aov_albedo_sum, &aov_normal_sum, &aov_depth_sum);
#endif
    }
    if (frame.background == BACKGROUND_ENV) counted = frame.samples_in_wave;
    film[pixel] = (ulong4)(sum, pixel_film.w + counted);
    if (frame.adaptive != 0u) {
        half_store(halves, state, pixel, even, evens, frame.samples_in_wave);
        if (frame.adaptive == ADAPTIVE_COST) rays[pixel] += extension_rays + shadow_rays;
    }
#ifdef AOVS
    aov_store(aov_albedo, aov_normal, aov_depth, pixel, aov_albedo_sum, aov_normal_sum,
              aov_depth_sum, frame.samples_in_wave);
#endif
    mega_count(counters, extension_rays, shadow_rays, nonfinite);
}
#endif  // !MEGA_LANES
