// The path tracer as one kernel, for CPU devices: a work item follows the paths of one pixel
// from the camera to their end, `frame.samples_in_wave` samples one after the other, with the
// path state in registers: no queues, no path buffers, one launch per pass. Each vertex is
// shaded by path.h's shade_vertex, as the wavefront's `shade` does, and its light sample is
// traced at once (the wavefront's `connect`), so both compute the same estimator from the
// same random numbers. The samples of a pixel are added to its film sum in order, one by one.
//
// Rays are traced through the 4-wide BVH (traverse_wide.h), whose box tests use the CPU's
// vector lanes.

// The kernel's parameters, in both forms below.
#define MEGAKERNEL_PARAMS                                                                   \
    GpuFrame frame, GpuCamera camera, GpuEnvironment environment,                           \
        global const GpuWideNode *nodes, global const GpuTriangle *tris,                    \
        global const GpuInstance *instances, global const GpuTriangle *object_tris,         \
        global const GpuTriShading *shading, global const GpuTriUvs *uvs,                   \
        global const GpuTriTangents *tangents, global const GpuMaterial *materials,         \
        global const GpuTexRef *tex_refs, global const GpuTexture *textures,                \
        global const uint *texels, global const float *env_texels,                          \
        global const float *env_marginal, global const float *env_conditional,              \
        global const GpuLight *lights, global const float *light_cdf, global float4 *film, \
        volatile global uint *counters

// What shading reads of the scene, from the kernel's parameters.
#define MEGA_SHADE_SCENE(sc)                                                                \
    ShadeScene sc = {tris,                                                                  \
                     {shading, uvs, tangents, materials, tex_refs, textures, texels, instances}, \
                     {environment, env_texels, env_marginal, env_conditional},              \
                     lights,                                                                \
                     light_cdf}

// A finished sample: its radiance added to the pixel's sum (a non-finite one dropped and
// counted), and counted in the film's .w when its camera ray hit.
inline void mega_add_sample(const PathState* s, float3* sum, uint* counted, uint* nonfinite) {
    *counted += (s->flags & PATH_ESCAPED) == 0u;
    if (all(isfinite(s->radiance))) {
        *sum += s->radiance;
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

#ifdef MEGA_LANES
// With MEGA_LANES a work item renders a square of LANES_TILE² pixels through LANES lanes
// (traverse_lanes.h): a lane takes a pixel, traces its samples one after the other, as the
// one-pixel kernel below does (so a pixel's samples are added in the same order, and the
// image is the same bit for bit), then takes the next pixel. The lanes' extension rays are
// walked together; when some are done, their vertices are shaded at once by the same
// shade_vertex, their light samples traced there and then (one ray at a time: the any-hit walk
// without sorting is as fast alone as in lanes), and each lane takes its path's next ray.
kernel void megakernel(MEGAKERNEL_PARAMS) {
    // The work item's square of pixels, LANES_TILE on a side, taken row by row.
    uint tiles_x = (frame.width + LANES_TILE - 1u) / LANES_TILE;
    uint tile_x = (uint)get_global_id(0) % tiles_x * LANES_TILE;
    uint tile_y = (uint)get_global_id(0) / tiles_x * LANES_TILE;
    if (tile_y >= frame.height || frame.samples_in_wave == 0u) return;
    uint tile_w = min((uint)LANES_TILE, frame.width - tile_x);
    uint next_pixel = 0u;  // of the tile
    uint end_pixel = tile_w * min((uint)LANES_TILE, frame.height - tile_y);
    MEGA_SHADE_SCENE(sc);
    volatile global uint* overflow = &counters[COUNT_OVERFLOW];
    LaneMemory M;
    lanes_init(&M);
    PathState s[LANES];
    float3 sum[LANES];
    float film_w[LANES];
    uint pixel[LANES], bounce[LANES], sample[LANES], counted[LANES];
    uint extension_rays = 0;
    uint shadow_rays = 0;
    uint nonfinite = 0;
    // A lane takes the next pixel (its film sum and its first camera ray); with none left it
    // stays idle.
#define LANE_NEXT_PIXEL(l)                                                             \
    if (next_pixel < end_pixel) {                                                      \
        uint p = (tile_y + next_pixel / tile_w) * frame.width + tile_x + next_pixel % tile_w; \
        ++next_pixel;                                                                  \
        float4 f = film[p];                                                            \
        pixel[l] = p;                                                                  \
        sum[l] = f.xyz;                                                                \
        film_w[l] = f.w;                                                               \
        counted[l] = 0u;                                                               \
        sample[l] = 0u;                                                                \
        bounce[l] = 0u;                                                                \
        s[l] = camera_path(&frame, &camera, p, frame.first_sample);                    \
        lanes_set_ray(&M, l, s[l].origin, s[l].direction);                             \
    }
    for (int l = 0; l < LANES; ++l) {
        LANE_NEXT_PIXEL(l)
    }
    for (;;) {
        int16 done = lanes_walk(&M, nodes, tris, &sc.surf, overflow);
        if (!lanes_any(done)) break;
        int done_[LANES];
        vstore16(done, 0, done_);
        for (int l = 0; l < LANES; ++l) {
            if (!done_[l]) continue;
            ++extension_rays;
            ShadowQuery q;
            bool alive = shade_vertex(&frame, bounce[l], &sc, lanes_hit(&M, l), &s[l], &q);
            if (q.valid) {
                ++shadow_rays;
                s[l].radiance +=
                    shadow_pass_wide(nodes, tris, instances, object_tris, &sc.surf, &q, overflow);
            }
            // The path goes on, or the pixel's next sample starts, or the lane's next pixel.
            if (alive && ++bounce[l] <= frame.max_bounces + 1u) {
                lanes_set_ray(&M, l, s[l].origin, s[l].direction);
                continue;
            }
            mega_add_sample(&s[l], &sum[l], &counted[l], &nonfinite);
            if (++sample[l] < frame.samples_in_wave) {
                bounce[l] = 0u;
                s[l] = camera_path(&frame, &camera, pixel[l], frame.first_sample + sample[l]);
                lanes_set_ray(&M, l, s[l].origin, s[l].direction);
                continue;
            }
            uint c = frame.background == BACKGROUND_ENV ? frame.samples_in_wave : counted[l];
            film[pixel[l]] = (float4)(sum[l], film_w[l] + (float)c);
            LANE_NEXT_PIXEL(l)
        }
    }
#undef LANE_NEXT_PIXEL
    mega_count(counters, extension_rays, shadow_rays, nonfinite);
}
#else
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
#define MEGA_TRACE(o, d, any_hit) \
    trace_small(&small, tris, &sc.surf, o, d, 0.0f, INFINITY, any_hit)
#define MEGA_SHADOW(q) shadow_pass_small(&small, tris, instances, object_tris, &sc.surf, q, overflow)
#else
#define MEGA_TRACE(o, d, any_hit)                                                              \
    trace_scene_wide(nodes, tris, instances, object_tris, &sc.surf, o, d, 0.0f, INFINITY, any_hit, \
                     overflow)
#define MEGA_SHADOW(q) shadow_pass_wide(nodes, tris, instances, object_tris, &sc.surf, q, overflow)
#endif
    for (uint j = 0; j < frame.samples_in_wave; ++j) {
        PathState s = camera_path(&frame, &camera, pixel, frame.first_sample + j);
        for (uint bounce = 0; bounce <= frame.max_bounces + 1u; ++bounce) {
            GpuHit hit = MEGA_TRACE(s.origin, s.direction, false);
            ++extension_rays;
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
#endif
