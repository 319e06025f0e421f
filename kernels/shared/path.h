// One path vertex at a time: the camera ray, and the shading of the vertex a ray found
// (emission with MIS, one light sample, the BSDF sample and Russian roulette). Both execution
// shapes call these, so they compute the same estimator with the same random numbers:
//   - the wavefront (gpu/stages.cl) keeps the state in DevicePath slots between kernels and traces
//     the light sample later in `connect`;
//   - the megakernels (cpu/megakernel.cl, cpu/megakernel_lanes.cl) keep it in registers and
//     trace the light sample at once.
// The vertex's maths that does not depend on the material is written once for every lane width
// (DEFINE_VERTEX_MATHS): the CPU lanes' batched shading (cpu/shade_lanes.h) uses it on vectors.
#ifndef SHARED_PATH_H
#define SHARED_PATH_H

#include "shared/types.h"
#include "shared/vec3.h"
#include "shared/rng.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"
#include "shared/bsdf.h"
#include "shared/surface.h"
#include "shared/env.h"
#include "shared/lights.h"
#include "shared/aovs.h"

// Whether the uniform sky is black: an escaped ray then adds nothing.
inline bool frame_sky_black(const DeviceFrame* frame) {
    return frame->sky.x <= 0.0f && frame->sky.y <= 0.0f && frame->sky.z <= 0.0f;
}

// The maths of a path vertex that does not depend on the material, written once for every lane
// width: shade_vertex uses it on scalars, the CPU lanes' batched shading (cpu/shade_lanes.h) on
// vectors, so that the estimator's multiple importance sampling, Russian roulette and the
// vertex's normals and rays change in one place. DEFINE_VERTEX_MATHS(f, F, I, V, v) defines, for
// floats F with masks I (a comparison's type; scalar comparisons give 1, vector ones -1, and
// select() takes either) and 3-vectors V with the operations of shared/vec3.h (f3_* on float3,
// the lanes' lv_*):
//   f##_power_heuristic(a, b)   the power heuristic's weight of a sample of pdf a against b;
//   f##_emitter_pdf(sel, area, t, cos_l)  light sampling's solid-angle pdf of an emissive
//                               triangle's point at distance t (the light's selection
//                               probability sel, area `area`, cosine cos_l at the light; 0 where
//                               cos_l is not positive);
//   f##_light_sample_weight(light_pdf, bsdf_pdf, mis)  a light sample's MIS weight against the
//                               BSDF sample (1 where mis is clear or the light's pdf is 0: a
//                               delta light);
//   f##_survival(x, y, z)       Russian roulette's probability of going on for a throughput of
//                               (x, y, z);
//   f##_shading_normal(n, ng)   the interpolated normal n made unit and turned to ng's side, or
//                               ng where n has length 0 (a flat-shaded triangle);
//   f##_side_normal(ng, side)   ng, or -ng where side (a direction's cosine with ng) is not
//                               positive: the side a ray leaves on;
//   f##_light_sample_faces(side, wi, ns, radiance)  whether a light sample in direction wi
//                               (cosine side with ng) is on the side the shading normal ns says
//                               and brings light;
//   f##_light_contribution(throughput, bsdf, radiance, weight)  what the sample adds when clear;
//   f##_shadow_segment(from, wi, distance, target, on_surface, *dir)  the shadow ray's length and
//                               direction: to the light's point where it is on a surface (as
//                               traced from `from`), else along wi to `distance`;
//   f##_goes_on(pdf, side, wi, ns, throughput)  whether a BSDF sample continues the path.
// Each is one expression per operation in the order shade_vertex has always computed it, with
// no product next to a sum, so that no compiler fuses the scalar form and not the vector one.
#define DEFINE_VERTEX_MATHS(f, F, I, V, v)                                                         \
    SHADE_INLINE F f##_power_heuristic(F a, F b) {                                                 \
        F a2 = a * a;                                                                              \
        F b2 = b * b;                                                                              \
        return select((F)(0.0f), a2 / (a2 + b2), a2 + b2 > 0.0f);                                  \
    }                                                                                              \
    SHADE_INLINE F f##_emitter_pdf(F sel, F area, F t, F cos_l) {                                  \
        return select((F)(0.0f), sel * t * t / (area * cos_l), cos_l > 0.0f);                      \
    }                                                                                              \
    SHADE_INLINE F f##_light_sample_weight(F light_pdf, F bsdf_pdf, I mis) {                       \
        return select((F)(1.0f), f##_power_heuristic(light_pdf, bsdf_pdf),                         \
                      mis & (light_pdf > 0.0f));                                                   \
    }                                                                                              \
    SHADE_INLINE F f##_survival(F x, F y, F z) { return fmin(fmax(x, fmax(y, z)), 0.95f); }        \
    SHADE_INLINE V f##_shading_normal(V n, V ng) {                                                 \
        F len = v##_length(n);                                                                     \
        V nn = v##_div(n, len);                                                                    \
        nn = v##_select(nn, v##_neg(nn), v##_dot(nn, ng) < 0.0f);                                  \
        return v##_select(ng, nn, len > 0.0f);                                                     \
    }                                                                                              \
    SHADE_INLINE V f##_side_normal(V ng, F side) {                                                 \
        return v##_select(v##_neg(ng), ng, side > 0.0f);                                           \
    }                                                                                              \
    SHADE_INLINE I f##_light_sample_faces(F side, V wi, V ns, V radiance) {                        \
        return (side * v##_dot(wi, ns) > 0.0f) & v##_positive(radiance);                           \
    }                                                                                              \
    SHADE_INLINE V f##_light_contribution(V throughput, V bsdf, V radiance, F weight) {               \
        return v##_scale(v##_mul(v##_mul(throughput, bsdf), radiance), weight);                       \
    }                                                                                              \
    SHADE_INLINE F f##_shadow_segment(V from, V wi, F distance, V target, I on_surface,            \
                                      V* dir) {                                                    \
        V seg = v##_sub(target, from);                                                             \
        F len = v##_length(seg);                                                                   \
        *dir = v##_select(wi, v##_div(seg, len), on_surface);                                      \
        return select(distance, len, on_surface);                                                  \
    }                                                                                              \
    SHADE_INLINE I f##_goes_on(F pdf, F side, V wi, V ns, V throughput) {                          \
        return (pdf > 0.0f) & (side * v##_dot(wi, ns) > 0.0f) & v##_positive(throughput);          \
    }

DEFINE_VERTEX_MATHS(vertex, float, int, float3, f3)

// A path between two vertices.
typedef struct {
    float3 origin;      // of the next ray
    float3 direction;   // of the next ray (unit)
    float3 throughput;
    float3 radiance;    // gathered so far
    float prev_pdf;     // pdf of the BSDF sample that made the ray (0: camera ray)
    uint flags;         // PATH_SPECULAR, PATH_ESCAPED, PATH_THROUGH_WALL; the wavelength
                        // from PATH_WAVELENGTH_SHIFT up (HAS_DISPERSION)
    uint rng;
    float2 cone;        // ray cone (width, spread angle) for texture filtering
#ifdef AOVS
    PathAov aov;        // the guide buffers' record (aovs.h)
#endif
} PathState;

// A light sample to test for visibility: `contribution` is added to the path's radiance when
// the segment (origin, direction, 0..tmax) is unoccluded, or only blocked by smooth thin walls
// (then tinted by them and multiplied by `unweight`, the inverse of its MIS weight).
typedef struct {
    float3 origin;
    float3 direction;
    float tmax;
    float3 contribution;
    float unweight;
    bool valid;
} ShadowQuery;

// What shading reads of the scene.
typedef struct {
    global const DeviceTriangle* tris;
    SceneSurfaces surf;
    EnvMap env;
    global const DeviceLight* lights;
    global const float* light_cdf;
} ShadeScene;

// The camera ray of sample `sample` of `pixel` (box filter, pinhole or thin lens), with the
// random state seeded from (pixel, sample, seed).
inline PathState camera_path(const DeviceFrame* frame, const DeviceCamera* camera, uint pixel,
                             uint sample) {
    uint rng = hash_u32(hash_u32(pixel ^ hash_u32(frame->seed)) ^
                        hash_u32(sample * 0x9e3779b9u + 1u));
    // Jitter within the pixel (box filter) and form the pinhole or thin-lens ray.
    float fx = ((float)(pixel % frame->width) + rng_next(&rng)) / (float)frame->width;
    float fy = ((float)(pixel / frame->width) + rng_next(&rng)) / (float)frame->height;
    float3 dir = camera->forward.xyz + (2.0f * fx - 1.0f) * camera->right.xyz +
                 (1.0f - 2.0f * fy) * camera->up.xyz;
    float3 origin = camera->origin.xyz;
    float u1 = rng_next(&rng);
    float u2 = rng_next(&rng);
    if (camera->origin.w > 0.0f) {
        float3 focus = origin + dir * camera->forward.w;
        float r = camera->origin.w * sqrt(u1);
        float phi = 2.0f * PI_F * u2;
        origin += r * cos(phi) * normalize(camera->right.xyz) +
                  r * sin(phi) * normalize(camera->up.xyz);
        dir = focus - origin;
    }
    PathState s;
    s.origin = origin;
    s.direction = normalize(dir);
    s.throughput = (float3)(1.0f, 1.0f, 1.0f);
    s.radiance = (float3)(0.0f, 0.0f, 0.0f);
    s.prev_pdf = 0.0f;
    s.flags = 0u;
    s.rng = rng;
    // The ray cone for texture filtering: no width at the eye, one pixel's angle of spread.
    s.cone = (float2)(0.0f, 2.0f * length(camera->up.xyz) / (float)frame->height);
#ifdef AOVS
    s.aov = aov_start();
#endif
    return s;
}

// Shades the vertex that the path's ray found at `bounce` (hit.prim == NO_HIT: it escaped).
// Adds emission to s->radiance, fills *shadow with the light sample to test (valid = false
// when there is none) and, when the path goes on, sets the next ray. Returns whether it does.
SHADE_INLINE bool shade_vertex(const DeviceFrame* frame, uint bounce, const ShadeScene* sc, DeviceHit hit,
                               PathState* s, ShadowQuery* shadow) {
    shadow->valid = false;
    float3 throughput = s->throughput;
    float3 radiance = s->radiance;
    uint rng = s->rng;
    float3 wo = -s->direction;
    float prev_pdf = s->prev_pdf;
    bool prev_specular = (s->flags & PATH_SPECULAR) != 0u;
    bool counts_emission = bounce == 0u || prev_specular || frame->strategy != STRATEGY_LIGHTS;
    // Seen through a thin wall from a scattering vertex, a light is left to that vertex's light
    // sample, whose shadow ray passes the wall unweighted (see `shadow_pass`).
    bool mis = bounce > 0u && !prev_specular && frame->strategy == STRATEGY_MIS;
#ifdef HAS_THIN_WALLS
    bool light_sampled_only = mis && (s->flags & PATH_THROUGH_WALL) != 0u;
#else
    bool light_sampled_only = false;
#endif
    const SceneSurfaces* surf = &sc->surf;
    global const DeviceMaterial* materials = surf->materials;

    if (hit.prim == NO_HIT) {
        // An escaped camera ray is marked for the film's coverage count (the film's .w then
        // counts the samples whose camera ray hit); with the background cut out it adds nothing.
        if (bounce == 0u && frame->background != BACKGROUND_ENV) {
            s->flags |= PATH_ESCAPED;
            if (frame->background == BACKGROUND_CUTOUT) {
#ifdef AOVS
                aov_escape(&s->aov, (float3)(0.0f));
#endif
                return false;
            }
        }
#ifdef HAS_ENV_MAP
        // Escaped into the environment map, weighted against its sampling at the last vertex.
        float env_pdf;
        float3 le = env_radiance(&sc->env, -wo, &env_pdf);
        // Seen directly, by a camera ray or its continuation straight through thin walls (no BSDF
        // sample made it: prev_pdf 0), the map is filtered: as smooth through a pane as beside it.
        if (prev_pdf == 0.0f) le = env_background(&sc->env, -wo);
#ifdef AOVS
        aov_escape(&s->aov, le);
#endif
        float weight = 1.0f;
        if (mis) weight = vertex_power_heuristic(prev_pdf, sc->env.info.scale.z * env_pdf);
        if (light_sampled_only) weight = 0.0f;
        if (counts_emission) radiance += throughput * le * weight;
#else
        // Escaped: the uniform sky, reached by BSDF sampling only.
        if (counts_emission) radiance += throughput * frame->sky.xyz;
#ifdef AOVS
        aov_escape(&s->aov, frame->sky.xyz);
#endif
#endif
        s->radiance = radiance;
        return false;
    }

#ifdef AOVS
    if (bounce == 0u) s->aov.depth = hit.t;  // the camera ray is unit: t is the distance
#endif
    DeviceTriangle tri = sc->tris[hit.prim];
#ifdef TWO_LEVEL
    // The mesh's object-space triangle, carried to world space by the hit's instance.
    DeviceInstance inst = surf->instances[hit.instance];
    float3 world_err;
    tri = instance_triangle(&inst, tri, &world_err);
#endif
    float w0 = 1.0f - hit.u - hit.v;
    float3 p_err;
    float3 p = surface_point(tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, hit.u, hit.v, &p_err);
    float3 ng = flat_normal(surf, hit.prim, tri);
#ifdef TWO_LEVEL
    p_err += world_err;
    ng *= instance_normal_sign(&inst);
#endif
    global const DeviceMaterial* mat = &materials[as_uint(tri.v0.w)];
    bool front = dot(ng, wo) > 0.0f;
#ifdef HAS_TEXTURES
    DeviceTriUvs uvs = surf->uvs[hit.prim];
    TexCoords tc = texcoords_at(uvs, hit.u, hit.v);
    // The ray cone's footprint picks the mip levels; it widens by the roughness at each bounce.
    float2 cone = s->cone;
    float cone_width = cone.x + cone.y * hit.t;
    texcoords_footprint(&tc, uvs, tri.v1.xyz - tri.v0.xyz, tri.v2.xyz - tri.v0.xyz, cone_width,
                        fabs(dot(ng, wo)));
    tc.xi = rng_next(&rng);
#endif

#ifdef HAS_TRIANGLE_LIGHTS
    // Emission of a light hit by this ray, weighted against light sampling of the last vertex.
    int light_index = as_int(tri.v1.w);
#ifdef TWO_LEVEL
    if (light_index >= 0) light_index += as_int(inst.world0.w);
#endif
    bool two_sided = (as_uint(mat->emission.w) & MATERIAL_DOUBLE_SIDED) != 0u;
    if (light_index >= 0 && (front || two_sided) && counts_emission) {
        float weight = 1.0f;
        if (mis) {
            global const DeviceLight* l = &sc->lights[light_index];
            float cos_l = fabs(dot(ng, wo));
            float light_pdf = vertex_emitter_pdf(l->extra.y, l->spot.y, hit.t, cos_l);
            weight = vertex_power_heuristic(prev_pdf, light_pdf);
        }
        if (light_sampled_only) weight = 0.0f;
#ifdef HAS_TEXTURES
        // Past the camera ray, emission is read at the finest level, as light sampling reads it.
        TexCoords etc = bounce == 0u ? tc : texcoords_at(uvs, hit.u, hit.v);
        radiance += throughput * textured_emission(mat, surf, &etc) * weight;
#else
        radiance += throughput * mat->emission.xyz * weight;
#endif
    }
#endif

#ifdef HAS_UNLIT
    // An unlit material shows its base color (textured) and scatters nothing; nothing else
    // samples it, so it counts in full.
    if ((as_uint(mat->emission.w) & MATERIAL_UNLIT) != 0u) {
        float3 color = mat->base_color.xyz;
#ifdef HAS_TEXTURES
        if (mat->textures.x >= 0) color *= texture_sample(surf, mat->textures.x, &tc).xyz;
#endif
#ifdef HAS_VERTEX_COLORS
        color *= vertex_color(surf, hit.prim, hit.u, hit.v).xyz;
#endif
        s->radiance = radiance + throughput * color;
#ifdef AOVS
        aov_plain(&s->aov, color, front ? ng : -ng);
#endif
        return false;
    }
#endif

    // The last extension only looks for emitters (the MIS partner of the last light sample).
    if (bounce > frame->max_bounces) {
        s->radiance = radiance;
        return false;
    }

    // Face the normals towards the side the ray came from.
    if (!front) ng = -ng;
    float3 ns = ng;
    {
        // A flat-shaded triangle's corner normals are 0: n has length 0 and ns stays ng.
        global const float* sh = surf->shading[hit.prim].n;
        float3 n = barycentric(vload3(0, sh), vload3(1, sh), vload3(2, sh), w0, hit.u, hit.v);
#ifdef TWO_LEVEL
        n = instance_normal(&inst, n);
#endif
        ns = vertex_shading_normal(n, ng);
    }
#ifdef HAS_CLEARCOAT
    // The coat has its own normal texture; without one it takes the interpolated normal.
    float3 coat_normal = ns;
#ifdef HAS_NORMAL_MAPS
    if (mat->textures3.z >= 0) {
        coat_normal = normal_map(surf, mat->textures3.z, mat->coat.z, &tc,
                                 hit_tangents(surf, hit), hit.u, hit.v, ns, ng, front);
    }
#endif
#endif
#ifdef HAS_NORMAL_MAPS
    // A normal-mapped vertex's normals are bent to keep wo's reflection above the surface
    // (`bend_normals`, once the material's roughness is known), and bent for wi too where the
    // BSDF is evaluated (`bent_for`).
    bool mapped = mat->textures.z >= 0;
    if (mapped) {
        ns = normal_map(surf, mat->textures.z, mat->alpha.w, &tc, hit_tangents(surf, hit), hit.u,
                        hit.v, ns, ng, front);
    }
#ifdef HAS_CLEARCOAT
    mapped = mapped || mat->textures3.z >= 0;
#endif
#endif
    SurfaceMaterial m = surface_material(mat);
#ifdef HAS_CLEARCOAT
    m.coat_normal = coat_normal;
#endif
#ifdef HAS_VERTEX_COLORS
    m.base_color *= vertex_color(surf, hit.prim, hit.u, hit.v).xyz;
#endif
#ifdef HAS_TEXTURES
    apply_textures(&m, mat, surf, &tc);
    float alpha_r = m.roughness * m.roughness;
    s->cone = (float2)(cone_width, cone.y + alpha_r);
#endif
#ifdef HAS_NORMAL_MAPS
    if (mapped) bend_normals(&m, ng, wo, &ns);
#endif
#ifdef HAS_ANISOTROPY
    if (m.anisotropy > 0.0f) {
        m.aniso_dir = anisotropy_direction(surf, hit.prim, hit.u, hit.v, ns, front, m.aniso_rotation);
    }
#endif
#ifdef AOVS
    aov_surface(&s->aov, &m, ns);
#endif

#ifdef HAS_DISPERSION
    // A dispersive volume: its index is that of the path's wavelength, picked at the first
    // such surface (weighted by its RGB response over its pdf) and kept in the flags' high
    // bits to the end of the path (material.h, "KHR_materials_dispersion").
    if (mat->aniso.w > 0.0f && m.transmission > 0.0f && m.thickness > 0.0f) {
        uint wavelength = s->flags >> PATH_WAVELENGTH_SHIFT;
        if (wavelength == 0u) {
            float lambda = sample_wavelength(rng_next(&rng));
            throughput *= wavelength_rgb(lambda) / wavelength_pdf(lambda);
            wavelength = max((uint)(lambda * 64.0f + 0.5f), 1u);
            s->flags |= wavelength << PATH_WAVELENGTH_SHIFT;
        }
        m.ior = dispersive_ior(m.ior, mat->aniso.w, (float)wavelength * (1.0f / 64.0f));
    }
#endif

    // Hit from behind, a transmissive volume was travelled through: attenuate the segment
    // (Beer–Lambert) and see the interface from inside. Other back faces shade as front faces.
    if (!front && m.transmission > 0.0f && m.thickness > 0.0f) {
        throughput *= volume_transmittance(&m, hit.t);
        material_from_inside(&m);
    }

    // Next-event estimation: one light sample, its visibility tested by the caller.
    if (frame->strategy != STRATEGY_BSDF && frame->light_count > 0u) {
        uint index = cdf_search(sc->light_cdf, frame->light_count, rng_next(&rng));
        float u1 = rng_next(&rng);
        float u2 = rng_next(&rng);
        LightSample ls =
            sample_light(sc->lights, sc->tris, materials, surf, &sc->env, index, p, u1, u2);
        // A light behind the surface is reached through transmission when bsdf_eval says so;
        // the geometric and shading normals must agree on the side. Transmissive surfaces
        // block shadow rays (no caustics through next-event estimation), except smooth thin
        // walls, which `shadow_pass` passes with their tint and without the MIS weight.
        float side = dot(ls.wi, ng);
        if (vertex_light_sample_faces(side, ls.wi, ns, ls.radiance)) {
            float bsdf_pdf;
#ifdef HAS_NORMAL_MAPS
            float3 f = mapped ? bsdf_eval_bent(&m, ng, ns, wo, ls.wi, &bsdf_pdf)
                              : bsdf_eval(&m, ns, wo, ls.wi, &bsdf_pdf);
#else
            float3 f = bsdf_eval(&m, ns, wo, ls.wi, &bsdf_pdf);
#endif
            float weight =
                vertex_light_sample_weight(ls.pdf, bsdf_pdf, frame->strategy == STRATEGY_MIS);
            float3 contribution = vertex_light_contribution(throughput, f, ls.radiance, weight);
            if (f3_positive(contribution)) {
                float3 from = offset_ray(p, p_err, vertex_side_normal(ng, side));
                // Virtual lights (spheres, discs, the sky) are not geometry: trace to them.
                float3 dir;
                float tmax = vertex_shadow_segment(from, ls.wi, ls.distance, ls.target,
                                                   ls.on_surface, &dir);
                shadow->origin = from;
                shadow->direction = dir;
                shadow->tmax = tmax;
                shadow->contribution = contribution;
                shadow->unweight = weight > 0.0f ? 1.0f / weight : 0.0f;
                shadow->valid = true;
            }
        }
    }

#if !defined(HAS_TRIANGLE_LIGHTS) && !defined(HAS_ENV_MAP) && !defined(HAS_UNLIT)
    // The last extension only looks for emitters, and a scene without emissive triangles, an
    // environment map or unlit materials has none for a ray to find but the sky: under a black
    // sky the path ends here, its last ray untraced (it would add exactly nothing).
    if (bounce == frame->max_bounces && frame_sky_black(frame)) {
        s->radiance = radiance;
        s->rng = rng;
        return false;
    }
#endif

    // Sample the BSDF for the next ray; Russian roulette after rr_depth bounces.
    float3 wi;
    float pdf;
    bool specular;
    float u1 = rng_next(&rng);
    float u2 = rng_next(&rng);
    float u3 = m.transmission > 0.0f ? rng_next(&rng) : 0.0f;
    float3 weight = bsdf_sample(&m, ns, wo, (float3)(u1, u2, u3), &wi, &pdf, &specular);
#ifdef HAS_NORMAL_MAPS
    // As the light sample: the value with the normals bent for wi too, over the sampling's pdf
    // (a delta lobe's reflection about the bent normal is wo's mirror image, which bends
    // nothing).
    if (mapped && !specular && pdf > 0.0f) {
        SurfaceMaterial mi;
        float3 ni;
        if (bent_for(&m, ng, ns, wi, &mi, &ni)) {
            float unused;
            weight = bsdf_eval(&mi, ni, wo, wi, &unused) / pdf;
        }
    }
#endif
    throughput *= weight;
    float side = dot(wi, ng);
    bool alive = vertex_goes_on(pdf, side, wi, ns, throughput);
    if (alive && bounce >= frame->rr_depth) {
        // Inside a volume of index n the throughput carries the 1/n^2 that radiance lost coming
        // in and gets back going out; the roulette judges the path without it (pbrt's eta
        // scale), or it would cull light inside glass for a loss that is not one. `ng` faces
        // `wo`, so the path goes on inside when it crosses in from the front (side < 0) or
        // reflects off the boundary from inside (side > 0, a back face); seen from inside,
        // `m.ior` is already the inverse (material_from_inside).
        float3 judged = throughput;
        bool goes_on_inside = (side < 0.0f) == front;
        if (m.transmission > 0.0f && m.thickness > 0.0f && goes_on_inside) {
            float n = front ? m.ior : 1.0f / m.ior;
            judged *= n * n;
        }
        float q = vertex_survival(judged.x, judged.y, judged.z);
        if (rng_next(&rng) >= q) {
            alive = false;
        } else {
            throughput /= q;
        }
    }
    s->radiance = radiance;
    s->rng = rng;
    if (alive) {
        uint flags = specular ? PATH_SPECULAR : 0u;
#ifdef HAS_THIN_WALLS
        // Straight through a thin wall the path keeps its last scattering vertex's pdf and
        // flags, as the shadow rays of that vertex pass the wall (a camera ray stays direct).
        if (specular && side < 0.0f && bsdf_passes_straight(&m)) {
            pdf = prev_pdf;
            flags = bounce == 0u ? PATH_SPECULAR : s->flags;
            if (!prev_specular && bounce > 0u) flags |= PATH_THROUGH_WALL;
        }
#endif
#ifdef HAS_DISPERSION
        flags |= s->flags & (0xffffffffu << PATH_WAVELENGTH_SHIFT);  // the path's wavelength
#endif
        s->origin = offset_ray(p, p_err, vertex_side_normal(ng, side));
        s->prev_pdf = pdf;
        s->direction = wi;
        s->flags = flags;
        s->throughput = throughput;
    }
    return alive;
}

// Shadow rays pass at most this many thin walls.
#define MAX_THIN_WALLS 8u

// Whether the surface hit by a shadow ray along dir is a smooth thin wall; if so, multiplies
// *tint by what it lets through. Without thin walls in the scene, nothing is.
inline bool thin_wall_tint(global const DeviceTriangle* tris, const SceneSurfaces* surf, DeviceHit hit,
                           float3 dir, float3* tint) {
#ifdef HAS_THIN_WALLS
    DeviceTriangle tri = tris[hit.prim];
    global const DeviceMaterial* mat = &surf->materials[as_uint(tri.v0.w)];
    SurfaceMaterial m = surface_material(mat);
#ifdef HAS_TEXTURES
    TexCoords tc = texcoords_at(surf->uvs[hit.prim], hit.u, hit.v);
    apply_textures(&m, mat, surf, &tc);
#endif
#ifdef HAS_VERTEX_COLORS
    m.base_color *= vertex_color(surf, hit.prim, hit.u, hit.v).xyz;
#endif
    if (!bsdf_passes_straight(&m)) return false;
    float3 ng = triangle_normal(tri.v0.xyz, tri.v1.xyz, tri.v2.xyz);
#ifdef TWO_LEVEL
    DeviceInstance inst = surf->instances[hit.instance];
    ng = instance_normal(&inst, ng);  // object-space triangle: its normal to world space
#endif
    *tint *= thin_wall_transmittance(&m, fabs(dot(ng, dir)));
    return true;
#else
    return false;
#endif
}

// The shadow test of a light sample, for a scene in NODES traced by TRACE (flat or two-level): what of
// q->contribution reaches the path, or 0 when something other than smooth thin walls is in the
// way. Through walls the light comes tinted by each wall and no longer shared with the BSDF
// sample (the MIS weight undone: BSDF samples through walls leave such lights to light
// sampling). The wavefront's `connect` and the megakernel use the same test this way.
#define DEFINE_SHADOW_TEST(NAME, NODES, TRACE)                                               \
    inline float3 NAME(NODES nodes, global const DeviceTriangle* tris,                            \
                       global const DeviceInstance* instances,                                    \
                       global const DeviceTriangle* object_tris, const SceneSurfaces* surf,        \
                       const ShadowQuery* q, volatile global uint* overflow) {                 \
        DeviceHit hit = TRACE(nodes, tris, instances, object_tris, surf, q->origin, q->direction, \
                           0.0f, q->tmax, true, overflow);                                     \
        if (hit.prim == NO_HIT) return q->contribution;                                        \
        float3 tint = (float3)(1.0f);                                                          \
        if (!thin_wall_tint(tris, surf, hit, q->direction, &tint)) return (float3)(0.0f);      \
        /* The walls in order, nearest first, each beyond the last. */                         \
        tint = (float3)(q->unweight);                                                          \
        hit = TRACE(nodes, tris, instances, object_tris, surf, q->origin, q->direction, 0.0f,  \
                    q->tmax, false, overflow);                                                 \
        for (uint walls = 0u; hit.prim != NO_HIT; ++walls) {                                   \
            if (walls == MAX_THIN_WALLS ||                                                     \
                !thin_wall_tint(tris, surf, hit, q->direction, &tint)) {                       \
                return (float3)(0.0f);                                                         \
            }                                                                                  \
            hit = TRACE(nodes, tris, instances, object_tris, surf, q->origin, q->direction,    \
                        hit.t, q->tmax, false, overflow);                                      \
        }                                                                                      \
        return q->contribution * tint;                                                         \
    }
DEFINE_SHADOW_TEST(shadow_pass, global const DeviceBvhNode*, trace_scene)
DEFINE_SHADOW_TEST(shadow_pass_wide, global const DeviceWideNode*, trace_scene_wide)
#ifdef SMALL_SCENE
DEFINE_SHADOW_TEST(shadow_pass_small, local const SmallScene*, trace_small_scene)
#endif

#ifdef HAS_SINGLE_SIDED
// The most culled back faces a camera ray passes; beyond them it shades the next one found.
#define MAX_CULLED 16u

// Whether a camera ray along d meets `hit` on the back of a single-sided surface, which the
// glTF spec culls (doubleSided false): the camera does not see it. Its geometric normal is
// shade_vertex's (with two levels, the object-space normal carried to world space).
inline bool camera_culls(global const DeviceTriangle* tris, const SceneSurfaces* surf, DeviceHit hit,
                         float3 d) {
    DeviceTriangle tri = tris[hit.prim];
    global const DeviceMaterial* mat = &surf->materials[as_uint(tri.v0.w)];
    if ((as_uint(mat->emission.w) & MATERIAL_DOUBLE_SIDED) != 0u) return false;
    float3 ng = flat_normal(surf, hit.prim, tri);
#ifdef TWO_LEVEL
    DeviceInstance inst = surf->instances[hit.instance];
    ng = instance_normal(&inst, ng);
#endif
    return dot(ng, d) > 0.0f;
}

// The hit a ray (o, d) sees. Unless `traced`, its closest hit is traced first; else `hit` is it.
// A camera ray (`culls`) passes the backs of single-sided surfaces as if absent, each further
// hit found beyond the last (as shadow rays pass thin walls). Only camera rays cull: see
// docs/gltf-conformance.md for why the paths' other rays meet both sides. The traversal has one
// call site, so a kernel that traces through this alone (the wavefront's `extend`) inlines one
// copy of it: two (a trace, then the culling's) cost the bunny room 5.5 % of its samples/s on an
// H100.
#define DEFINE_CAMERA_HIT(NAME, NODES, TRACE)                                                  \
    inline DeviceHit NAME(NODES nodes, global const DeviceTriangle* tris,                         \
                          global const DeviceInstance* instances,                                 \
                          global const DeviceTriangle* object_tris, const SceneSurfaces* surf,    \
                          float3 o, float3 d, DeviceHit hit, bool traced, bool culls,             \
                          volatile global uint* overflow) {                                       \
        float tmin = 0.0f;                                                                    \
        for (uint k = 0u;; ++k) {                                                             \
            if (!traced)                                                                      \
                hit = TRACE(nodes, tris, instances, object_tris, surf, o, d, tmin, INFINITY,  \
                            false, overflow);                                                 \
            traced = false;                                                                   \
            if (!culls || k == MAX_CULLED || hit.prim == NO_HIT ||                            \
                !camera_culls(tris, surf, hit, d))                                            \
                return hit;                                                                   \
            tmin = hit.t;                                                                     \
        }                                                                                     \
    }
DEFINE_CAMERA_HIT(camera_hit, global const DeviceBvhNode*, trace_scene)
DEFINE_CAMERA_HIT(camera_hit_wide, global const DeviceWideNode*, trace_scene_wide)
#ifdef SMALL_SCENE
DEFINE_CAMERA_HIT(camera_hit_small, local const SmallScene*, trace_small_scene)
#endif
#endif

#endif  // SHARED_PATH_H
