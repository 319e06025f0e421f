// The path tracer as one kernel, one path at a time (without MEGA_LANES; the default on CPU
// devices, and on any device with --kernel megakernel): a work item follows the paths of one
// pixel from the camera to their end, `frame.samples_in_wave` samples one after the other, with
// the path state in registers: no queues, no path buffers, one launch per pass. Each vertex is
// shaded by path.h's shade_vertex, as the wavefront's `shade` does, and its light sample is
// traced at once (the wavefront's `connect`), so both compute the same estimator from the
// same random numbers. The samples of a pixel are added to its film sum in order, one by one.
//
// Rays are traced through the 4-wide BVH (traverse_wide.h), whose box tests use the CPU's
// vector lanes, or with SMALL_SCENE tested against every triangle of a small scene.

#include "shared/types.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"
#include "shared/path.h"
#include "cpu/megakernel.h"

#ifndef MEGA_LANES
kernel void megakernel(MEGAKERNEL_PARAMS) {
#ifdef SMALL_SCENE
    local SmallScene small;
    // Before any work item returns: it waits for the group.
    small_scene_load(tris, frame.triangles, &small);
#endif
    uint pixel = get_global_id(0);
    uint pixels = frame.width * frame.height;
    if (pixel >= pixels) return;
    MEGA_SHADE_SCENE(sc);
    volatile global uint* overflow = &counters[COUNT_OVERFLOW];
    // The samples are added to the film's sum one by one, so that the image does not depend
    // on how many samples each launch took (a float sum depends on its order).
    float4 pixel_film = film[pixel];
    float3 sum = pixel_film.xyz;
    uint extension_rays = 0;
    uint shadow_rays = 0;
    uint nonfinite = 0;
    uint counted = 0;  // samples whose camera ray hit (the film's .w with the background cut out)
#ifdef SMALL_SCENE
    sc.surf.small = &small;
#define MEGA_TRACE_TO(o, d, tmax, any_hit) \
    trace_small(&small, tris, &sc.surf, o, d, 0.0f, tmax, any_hit)
#define MEGA_SHADOW(q) shadow_pass_small(&small, tris, instances, object_tris, &sc.surf, q, overflow)
#define MEGA_CAMERA_HIT(o, d, hit) \
    camera_hit_small(&small, tris, instances, object_tris, &sc.surf, o, d, hit, overflow)
#else
#define MEGA_TRACE_TO(o, d, tmax, any_hit)                                                 \
    trace_scene_wide(nodes, tris, instances, object_tris, &sc.surf, o, d, 0.0f, tmax, any_hit, \
                     overflow)
#define MEGA_SHADOW(q) shadow_pass_wide(nodes, tris, instances, object_tris, &sc.surf, q, overflow)
#define MEGA_CAMERA_HIT(o, d, hit) \
    camera_hit_wide(nodes, tris, instances, object_tris, &sc.surf, o, d, hit, overflow)
#endif
#define MEGA_TRACE(o, d, any_hit) MEGA_TRACE_TO(o, d, INFINITY, any_hit)
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
                if (MEGA_TRACE_TO(s.origin, s.direction, hit.t, true).prim != NO_HIT) break;
            } else
#endif
            {
                hit = MEGA_TRACE(s.origin, s.direction, false);
#ifdef HAS_SINGLE_SIDED
                if (bounce == 0u) hit = MEGA_CAMERA_HIT(s.origin, s.direction, hit);
#endif
                ++extension_rays;
            }
            ShadowQuery q;
            bool alive = shade_vertex(&frame, bounce, &sc, hit, &s, &q);
            if (q.valid) {
                ++shadow_rays;
                s.radiance += MEGA_SHADOW(&q);
            }
            if (!alive) break;
        }
        mega_add_sample(&s, &sum, &counted, &nonfinite);
    }
    if (frame.background == BACKGROUND_ENV) counted = frame.samples_in_wave;
    film[pixel] = (float4)(sum, pixel_film.w + (float)counted);
    mega_count(counters, extension_rays, shadow_rays, nonfinite);
}
#endif  // !MEGA_LANES
