// The wavefront stages of the path tracer, in the order the host launches them:
//   generate -> [extend -> shade -> connect -> advance] x (bounces + 2) -> accumulate
// Paths live in `paths` by slot (pixel + sample_in_wave * pixels); queues hold the slots of the
// live paths, compacted by atomic counters, so later bounces only touch live paths. With
// adaptive sampling (adaptive.h) `generate` queues only the active pixels' slots and an
// `advance` follows it; `converge` and `converge_dilate` check the film between waves.

#include "shared/types.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/path.h"
#include "shared/adaptive.h"
#include "shared/aovs.h"

// Camera rays for the wave's slots. With adaptive sampling only the active pixels' slots are
// queued, in COUNT_OUT (0 here: every `advance` leaves it so), which the `advance` launched next
// makes the first bounce's input. With AOVS each slot's guide record starts in `aov_paths`.
kernel void generate(DeviceFrame frame, DeviceCamera camera, global DevicePath* paths, global uint* queue,
                     global uint* counters, global float2* cones, global const uint* state,
                     global float4* aov_paths) {
    uint slot = get_global_id(0);
    uint pixels = frame.width * frame.height;
    uint total = pixels * frame.samples_in_wave;
    if (frame.adaptive != 0u) {
        if (slot == 0) {
            counters[COUNT_IN] = 0;
            counters[COUNT_SHADOW] = 0;
        }
        if (slot >= total || pixel_converged(&frame, state, slot % pixels)) return;
    } else if (slot == 0) {
        counters[COUNT_IN] = total;
        counters[COUNT_OUT] = 0;
        counters[COUNT_SHADOW] = 0;
    }
    if (slot >= total) return;
    PathState s = camera_path(&frame, &camera, slot % pixels, frame.first_sample + slot / pixels);
    DevicePath p;
    p.origin = (float4)(s.origin, 0.0f);
    p.direction = (float4)(s.direction, as_float(0u));
    p.throughput = (float4)(s.throughput, as_float(slot));
    p.radiance = (float4)(s.radiance, as_float(s.rng));
    paths[slot] = p;
    cones[slot] = s.cone;
#ifdef AOVS
    aov_save(aov_paths, slot, &s.aov);
#endif
    if (frame.adaptive != 0u) {
        queue[atomic_inc(&counters[COUNT_OUT])] = slot;
    } else {
        queue[slot] = slot;
    }
}

kernel void extend(global const DeviceBvhNode* nodes, global const DeviceTriangle* tris,
                   global const DeviceInstance* instances, global const DeviceTriangle* object_tris,
                   global const DeviceTriShading* shading, global const DeviceTriUvs* uvs,
                   global const DeviceTriTangents* tangents, global const DeviceTriColors* colors,
                   global const DeviceMaterial* materials, global const DeviceTexRef* tex_refs,
                   global const DeviceTexture* textures, global const uint* texels,
                   global const DevicePath* paths, global const uint* queue,
                   volatile global uint* counters, global DeviceHit* hits) {
    uint i = get_global_id(0);
    if (i >= counters[COUNT_IN]) return;
    SceneSurfaces surf = {shading,  uvs,      tangents, colors,
                          materials, tex_refs, textures, texels, instances};
    global const DevicePath* p = &paths[queue[i]];
    float3 o = p->origin.xyz, d = p->direction.xyz;
#ifdef HAS_SINGLE_SIDED
    // A camera ray (no BSDF sample made it, and it passed no surface: no flags) culls the backs
    // of single-sided surfaces.
    bool culls = p->origin.w == 0.0f && as_uint(p->direction.w) == 0u;
    DeviceHit hit = camera_hit(nodes, tris, instances, object_tris, &surf, o, d, no_hit(INFINITY),
                               false, culls, &counters[COUNT_OVERFLOW]);
#else
    DeviceHit hit = trace_scene(nodes, tris, instances, object_tris, &surf, o, d, 0.0f, INFINITY,
                                false, &counters[COUNT_OVERFLOW]);
#endif
    hits[i] = hit;
}

kernel void shade(DeviceFrame frame, DeviceEnvironment environment, global const DeviceTriangle* tris,
                  global const DeviceInstance* instances, global const DeviceTriShading* shading,
                  global const DeviceTriUvs* uvs, global const DeviceTriTangents* tangents,
                  global const DeviceTriColors* colors,
                  global const DeviceMaterial* materials, global const DeviceTexRef* tex_refs,
                  global const DeviceTexture* textures, global const uint* texels,
                  global const float* env_texels, global const float* env_marginal,
                  global const float* env_conditional,
                  global const DeviceLight* lights, global const float* light_cdf,
                  global DevicePath* paths, global const uint* queue_in, global const DeviceHit* hits,
                  global uint* queue_out, global DeviceShadowRay* shadow_rays,
                  volatile global uint* counters, global float2* cones,
                  global float4* aov_paths, global uint* rays) {
    uint i = get_global_id(0);
    if (i >= counters[COUNT_IN]) return;
    uint slot = queue_in[i];
    DevicePath path = paths[slot];
    ShadeScene sc = {tris,
                     {shading, uvs, tangents, colors, materials, tex_refs, textures, texels, instances},
                     {environment, env_texels, env_marginal, env_conditional},
                     lights,
                     light_cdf};
    PathState s;
    s.origin = path.origin.xyz;
    s.direction = path.direction.xyz;
    s.throughput = path.throughput.xyz;
    s.radiance = path.radiance.xyz;
    s.prev_pdf = path.origin.w;
    s.flags = as_uint(path.direction.w);
    s.rng = as_uint(path.radiance.w);
#ifdef HAS_TEXTURES
    s.cone = cones[slot];
#endif
#ifdef AOVS
    s.aov = aov_load(aov_paths, slot);
#endif
    ShadowQuery q;
    bool alive = shade_vertex(&frame, frame.bounce, &sc, hits[i], &s, &q);
    if (q.valid) {
        DeviceShadowRay ray;
        ray.origin = (float4)(q.origin, q.tmax);
        ray.direction = (float4)(q.direction, as_float(slot));
        ray.contribution = (float4)(q.contribution, q.unweight);
        shadow_rays[atomic_inc(&counters[COUNT_SHADOW])] = ray;
    }
    // The cost rule's ray count (adaptive.h): the extension ray that found this vertex and its
    // light sample's. Only that rule reads it: the other modes pay no atomic here.
    if (frame.adaptive == ADAPTIVE_COST) atomic_add(&rays[slot % (frame.width * frame.height)], q.valid ? 2u : 1u);
#ifdef HAS_TEXTURES
    cones[slot] = s.cone;
#endif
#ifdef AOVS
    aov_save(aov_paths, slot, &s.aov);
#endif
    path.radiance = (float4)(s.radiance, as_float(s.rng));
    if (alive) {
        path.origin = (float4)(s.origin, s.prev_pdf);
        path.direction = (float4)(s.direction, as_float(s.flags));
        path.throughput.xyz = s.throughput;
        queue_out[atomic_inc(&counters[COUNT_OUT])] = slot;
    } else if (frame.background != BACKGROUND_ENV) {
        path.direction.w = as_float(s.flags);  // PATH_ESCAPED for `accumulate`
    }
    paths[slot] = path;
}

kernel void connect(global const DeviceBvhNode* nodes, global const DeviceTriangle* tris,
                    global const DeviceInstance* instances, global const DeviceTriangle* object_tris,
                    global const DeviceTriShading* shading, global const DeviceTriUvs* uvs,
                    global const DeviceTriTangents* tangents, global const DeviceTriColors* colors,
                    global const DeviceMaterial* materials, global const DeviceTexRef* tex_refs,
                    global const DeviceTexture* textures, global const uint* texels,
                    global const DeviceShadowRay* shadow_rays, volatile global uint* counters,
                    global DevicePath* paths) {
    uint i = get_global_id(0);
    if (i >= counters[COUNT_SHADOW]) return;
    SceneSurfaces surf = {shading,  uvs,      tangents, colors,
                          materials, tex_refs, textures, texels, instances};
    DeviceShadowRay r = shadow_rays[i];
    ShadowQuery q;
    q.origin = r.origin.xyz;
    q.direction = r.direction.xyz;
    q.tmax = r.origin.w;
    q.contribution = r.contribution.xyz;
    q.unweight = r.contribution.w;
    float3 c = shadow_pass(nodes, tris, instances, object_tris, &surf, &q,
                           &counters[COUNT_OVERFLOW]);
    if (any(c != 0.0f)) paths[as_uint(r.direction.w)].radiance.xyz += c;
}

// One work item: counts the rays of this bounce and makes the output queue the next input.
kernel void advance(global uint* counters, global ulong* stats) {
    if (get_global_id(0) != 0) return;
    stats[STAT_EXTENSION_RAYS] += counters[COUNT_IN];
    stats[STAT_SHADOW_RAYS] += counters[COUNT_SHADOW];
    counters[COUNT_IN] = counters[COUNT_OUT];
    counters[COUNT_OUT] = 0;
    counters[COUNT_SHADOW] = 0;
}

// Adds every finished sample of the wave to the film (.xyz radiance sum, .w sample count; with
// coverage counted, .w counts the samples whose camera ray hit), in a fixed order per pixel
// so the result does not depend on the queues' order. Non-finite samples are counted and dropped.
// With adaptive sampling converged pixels are skipped and the others' half buffers and sample
// counts updated (adaptive.h). With AOVS the slots' guide records go into the AOV sums (aovs.h).
kernel void accumulate(DeviceFrame frame, global const DevicePath* paths, global ulong4* film,
                       volatile global uint* counters, global float4* halves, global uint* state,
                       global const float4* aov_paths, global float4* aov_albedo,
                       global float4* aov_normal, global float2* aov_depth) {
    uint pixel = get_global_id(0);
    uint pixels = frame.width * frame.height;
    if (pixel >= pixels || pixel_converged(&frame, state, pixel)) return;
    ulong4 pixel_film = film[pixel];
    ulong3 sum = pixel_film.xyz;
    for (uint j = 0; j < frame.samples_in_wave; ++j) {
        float3 r = paths[pixel + j * pixels].radiance.xyz;
        if (all(isfinite(r))) {
            film_add(&sum, r);
        } else {
            atomic_inc(&counters[COUNT_NONFINITE]);
        }
    }
    uint counted = frame.samples_in_wave;
    if (frame.background != BACKGROUND_ENV) {
        counted = 0u;
        for (uint j = 0; j < frame.samples_in_wave; ++j) {
            counted += (as_uint(paths[pixel + j * pixels].direction.w) & PATH_ESCAPED) == 0u;
        }
    }
    film[pixel] = (ulong4)(sum, pixel_film.w + counted);
    if (frame.adaptive != 0u) {
        float3 even = (float3)(0.0f);
        uint evens = 0u;
        for (uint j = 0; j < frame.samples_in_wave; ++j) {
            half_add(paths[pixel + j * pixels].radiance.xyz, frame.first_sample + j, &even, &evens);
        }
        half_store(halves, state, pixel, even, evens, frame.samples_in_wave);
    }
#ifdef AOVS
    float3 albedo = (float3)(0.0f), normal = (float3)(0.0f);
    float2 depth = (float2)(0.0f);
    for (uint j = 0; j < frame.samples_in_wave; ++j) {
        PathAov a = aov_load(aov_paths, pixel + j * pixels);
        aov_add(&a, &albedo, &normal, &depth);
    }
    aov_store(aov_albedo, aov_normal, aov_depth, pixel, albedo, normal, depth,
              frame.samples_in_wave);
#endif
}
