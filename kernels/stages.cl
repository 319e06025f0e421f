// The wavefront stages of the path tracer, in the order the host launches them:
//   generate -> [extend -> shade -> connect -> advance] x (bounces + 2) -> accumulate
// Paths live in `paths` by slot (pixel + sample_in_wave * pixels); queues hold the slots of the
// live paths, compacted by atomic counters, so later bounces only touch live paths.

inline float power_heuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

kernel void generate(GpuFrame frame, GpuCamera camera, global GpuPath* paths, global uint* queue,
                     global uint* counters, global float2* cones) {
    uint slot = get_global_id(0);
    uint pixels = frame.width * frame.height;
    uint total = pixels * frame.samples_in_wave;
    if (slot == 0) {
        counters[COUNT_IN] = total;
        counters[COUNT_OUT] = 0;
        counters[COUNT_SHADOW] = 0;
    }
    if (slot >= total) return;
    uint pixel = slot % pixels;
    uint sample = frame.first_sample + slot / pixels;
    uint rng = hash_u32(hash_u32(pixel ^ hash_u32(frame.seed)) ^ hash_u32(sample * 0x9e3779b9u + 1u));

    // Jitter within the pixel (box filter) and form the pinhole or thin-lens ray.
    float fx = ((float)(pixel % frame.width) + rng_next(&rng)) / (float)frame.width;
    float fy = ((float)(pixel / frame.width) + rng_next(&rng)) / (float)frame.height;
    float3 dir = camera.forward.xyz + (2.0f * fx - 1.0f) * camera.right.xyz +
                 (1.0f - 2.0f * fy) * camera.up.xyz;
    float3 origin = camera.origin.xyz;
    float u1 = rng_next(&rng);
    float u2 = rng_next(&rng);
    if (camera.origin.w > 0.0f) {
        float3 focus = origin + dir * camera.forward.w;
        float r = camera.origin.w * sqrt(u1);
        float phi = 2.0f * PI_F * u2;
        origin += r * cos(phi) * normalize(camera.right.xyz) + r * sin(phi) * normalize(camera.up.xyz);
        dir = focus - origin;
    }
    GpuPath p;
    p.origin = (float4)(origin, 0.0f);
    p.direction = (float4)(normalize(dir), as_float(0u));
    p.throughput = (float4)(1.0f, 1.0f, 1.0f, as_float(slot));
    p.radiance = (float4)(0.0f, 0.0f, 0.0f, as_float(rng));
    paths[slot] = p;
    queue[slot] = slot;
    // The ray cone for texture filtering: no width at the eye, one pixel's angle of spread.
    cones[slot] = (float2)(0.0f, 2.0f * length(camera.up.xyz) / (float)frame.height);
}

kernel void extend(global const GpuBvhNode* nodes, global const GpuTriangle* tris,
                   global const GpuTriShading* shading, global const GpuTriTangents* tangents,
                   global const GpuMaterial* materials, global const GpuTexRef* tex_refs,
                   global const GpuTexture* textures, global const uint* texels,
                   global const GpuPath* paths, global const uint* queue,
                   volatile global uint* counters, global GpuHit* hits) {
    uint i = get_global_id(0);
    if (i >= counters[COUNT_IN]) return;
    SceneSurfaces surf = {shading, tangents, materials, tex_refs, textures, texels};
    global const GpuPath* p = &paths[queue[i]];
    hits[i] = traverse(nodes, tris, &surf, p->origin.xyz, p->direction.xyz, 0.0f, INFINITY,
                       false, &counters[COUNT_OVERFLOW]);
}

kernel void shade(GpuFrame frame, GpuEnvironment environment, global const GpuTriangle* tris,
                  global const GpuTriShading* shading, global const GpuTriTangents* tangents,
                  global const GpuMaterial* materials, global const GpuTexRef* tex_refs,
                  global const GpuTexture* textures, global const uint* texels,
                  global const float* env_texels, global const float* env_marginal,
                  global const float* env_conditional,
                  global const GpuLight* lights, global const float* light_cdf,
                  global GpuPath* paths, global const uint* queue_in, global const GpuHit* hits,
                  global uint* queue_out, global GpuShadowRay* shadow_rays,
                  volatile global uint* counters, global float2* cones) {
    uint i = get_global_id(0);
    if (i >= counters[COUNT_IN]) return;
    uint slot = queue_in[i];
    GpuPath path = paths[slot];
    GpuHit hit = hits[i];
    float3 throughput = path.throughput.xyz;
    float3 radiance = path.radiance.xyz;
    uint rng = as_uint(path.radiance.w);
    float3 wo = -path.direction.xyz;
    float prev_pdf = path.origin.w;
    bool prev_specular = (as_uint(path.direction.w) & PATH_SPECULAR) != 0u;
    bool counts_emission = frame.bounce == 0u || prev_specular || frame.strategy != STRATEGY_LIGHTS;
    // Seen through a thin wall from a scattering vertex, a light is left to that vertex's light
    // sample, whose shadow ray passes the wall unweighted (see `connect`).
    bool mis = frame.bounce > 0u && !prev_specular && frame.strategy == STRATEGY_MIS;
#ifdef HAS_THIN_WALLS
    bool light_sampled_only = mis && (as_uint(path.direction.w) & PATH_THROUGH_WALL) != 0u;
#else
    bool light_sampled_only = false;
#endif
    SceneSurfaces surf = {shading, tangents, materials, tex_refs, textures, texels};
    EnvMap env = {environment, env_texels, env_marginal, env_conditional};

    if (hit.prim == NO_HIT) {
#ifdef HAS_ENV_MAP
        // Escaped into the environment map, weighted against its sampling at the last vertex.
        float env_pdf;
        float3 le = env_radiance(&env, -wo, &env_pdf);
        float weight = 1.0f;
        if (mis) weight = power_heuristic(prev_pdf, environment.scale.z * env_pdf);
        if (light_sampled_only) weight = 0.0f;
        if (counts_emission) radiance += throughput * le * weight;
#else
        // Escaped: the uniform sky, reached by BSDF sampling only.
        if (counts_emission) radiance += throughput * frame.sky.xyz;
#endif
        paths[slot].radiance.xyz = radiance;
        return;
    }

    GpuTriangle tri = tris[hit.prim];
    float w0 = 1.0f - hit.u - hit.v;
    float3 p = w0 * tri.v0.xyz + hit.u * tri.v1.xyz + hit.v * tri.v2.xyz;
    float3 ng = normalize(cross(tri.v1.xyz - tri.v0.xyz, tri.v2.xyz - tri.v0.xyz));
    global const GpuMaterial* mat = &materials[as_uint(tri.v0.w)];
    bool front = dot(ng, wo) > 0.0f;
    GpuTriShading sh = shading[hit.prim];
    TexCoords tc = texcoords_at(sh, hit.u, hit.v);
#ifdef HAS_TEXTURES
    // The ray cone's footprint picks the mip levels; it widens by the roughness at each bounce.
    float2 cone = cones[slot];
    float cone_width = cone.x + cone.y * hit.t;
    texcoords_footprint(&tc, sh, tri.v1.xyz - tri.v0.xyz, tri.v2.xyz - tri.v0.xyz, cone_width,
                        fabs(dot(ng, wo)));
    tc.xi = rng_next(&rng);
#endif

#ifdef HAS_TRIANGLE_LIGHTS
    // Emission of a light hit by this ray, weighted against light sampling of the last vertex.
    int light_index = as_int(tri.v1.w);
    bool two_sided = (as_uint(mat->emission.w) & MATERIAL_DOUBLE_SIDED) != 0u;
    if (light_index >= 0 && (front || two_sided) && counts_emission) {
        float weight = 1.0f;
        if (mis) {
            global const GpuLight* l = &lights[light_index];
            float cos_l = fabs(dot(ng, wo));
            float light_pdf = cos_l > 0.0f ? l->extra.y * hit.t * hit.t / (l->spot.y * cos_l) : 0.0f;
            weight = power_heuristic(prev_pdf, light_pdf);
        }
        if (light_sampled_only) weight = 0.0f;
#ifdef HAS_TEXTURES
        // Past the camera ray, emission is read at the finest level, as light sampling reads it.
        TexCoords etc = frame.bounce == 0u ? tc : texcoords_at(sh, hit.u, hit.v);
        radiance += throughput * textured_emission(mat, &surf, &etc) * weight;
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
        if (mat->textures.x >= 0) color *= texture_sample(&surf, mat->textures.x, &tc).xyz;
#endif
        paths[slot].radiance.xyz = radiance + throughput * color;
        return;
    }
#endif

    // The last extension only looks for emitters (the MIS partner of the last light sample).
    if (frame.bounce > frame.max_bounces) {
        paths[slot].radiance.xyz = radiance;
        return;
    }

    // Face the normals towards the side the ray came from.
    if (!front) ng = -ng;
    float3 ns = ng;
    if (sh.n0.w > 0.0f) {
        float3 n = w0 * sh.n0.xyz + hit.u * sh.n1.xyz + hit.v * sh.n2.xyz;
        float len = length(n);
        if (len > 0.0f) {
            ns = n / len;
            if (dot(ns, ng) < 0.0f) ns = -ns;
        }
    }
#ifdef HAS_CLEARCOAT
    // The coat has its own normal texture; without one it takes the interpolated normal.
    float3 coat_normal = ns;
#ifdef HAS_NORMAL_MAPS
    if (mat->textures3.z >= 0) {
        coat_normal = normal_map(&surf, mat->textures3.z, mat->coat.z, &tc, hit.prim, hit.u,
                                 hit.v, ns, ng, front);
    }
#endif
#endif
#ifdef HAS_NORMAL_MAPS
    if (mat->textures.z >= 0) {
        ns = normal_map(&surf, mat->textures.z, mat->alpha.w, &tc, hit.prim, hit.u, hit.v, ns, ng,
                        front);
    }
#endif
    SurfaceMaterial m = surface_material(mat);
#ifdef HAS_CLEARCOAT
    m.coat_normal = coat_normal;
#endif
#ifdef HAS_TEXTURES
    apply_textures(&m, mat, &surf, &tc);
    float alpha_r = m.roughness * m.roughness;
    cones[slot] = (float2)(cone_width, cone.y + alpha_r);
#endif

    // Hit from behind, a transmissive volume was travelled through: attenuate the segment
    // (Beer–Lambert) and see the interface from inside. Other back faces shade as front faces.
    if (!front && m.transmission > 0.0f && m.thickness > 0.0f) {
        throughput *= volume_transmittance(&m, hit.t);
        material_from_inside(&m);
    }

    // Next-event estimation: one light sample, traced later by `connect`.
    if (frame.strategy != STRATEGY_BSDF && frame.light_count > 0u) {
        uint index = cdf_search(light_cdf, frame.light_count, rng_next(&rng));
        float u1 = rng_next(&rng);
        float u2 = rng_next(&rng);
        LightSample ls = sample_light(lights, tris, materials, &surf, &env, index, p, u1, u2);
        // A light behind the surface is reached through transmission when bsdf_eval says so;
        // the geometric and shading normals must agree on the side. Transmissive surfaces
        // block shadow rays (no caustics through next-event estimation), except smooth thin
        // walls, which `connect` passes with their tint and without the MIS weight.
        float side = dot(ls.wi, ng);
        if (side * dot(ls.wi, ns) > 0.0f &&
            (ls.radiance.x > 0.0f || ls.radiance.y > 0.0f || ls.radiance.z > 0.0f)) {
            float bsdf_pdf;
            float3 f = bsdf_eval(&m, ns, wo, ls.wi, &bsdf_pdf);
            float weight = (frame.strategy == STRATEGY_MIS && ls.pdf > 0.0f)
                               ? power_heuristic(ls.pdf, bsdf_pdf)
                               : 1.0f;
            float3 contribution = throughput * f * ls.radiance * weight;
            if (contribution.x > 0.0f || contribution.y > 0.0f || contribution.z > 0.0f) {
                uint s = atomic_inc(&counters[COUNT_SHADOW]);
                GpuShadowRay ray;
                float3 from = offset_ray(p, side > 0.0f ? ng : -ng);
                float3 dir = ls.wi;
                // Virtual lights (spheres, discs, the sky) are not geometry: trace to them.
                float tmax = ls.distance;
                if (ls.on_surface) {
                    float3 seg = ls.target - from;
                    tmax = length(seg);
                    dir = seg / tmax;
                }
                ray.origin = (float4)(from, tmax);
                ray.direction = (float4)(dir, as_float(slot));
                ray.contribution = (float4)(contribution, weight > 0.0f ? 1.0f / weight : 0.0f);
                shadow_rays[s] = ray;
            }
        }
    }

    // Sample the BSDF for the next ray; Russian roulette after rr_depth bounces.
    float3 wi;
    float pdf;
    bool specular;
    float u1 = rng_next(&rng);
    float u2 = rng_next(&rng);
    float u3 = m.transmission > 0.0f ? rng_next(&rng) : 0.0f;
    float3 weight = bsdf_sample(&m, ns, wo, (float3)(u1, u2, u3), &wi, &pdf, &specular);
    throughput *= weight;
    float side = dot(wi, ng);
    bool alive = pdf > 0.0f && side * dot(wi, ns) > 0.0f &&
                 (throughput.x > 0.0f || throughput.y > 0.0f || throughput.z > 0.0f);
    if (alive && frame.bounce >= frame.rr_depth) {
        float q = fmin(fmax(throughput.x, fmax(throughput.y, throughput.z)), 0.95f);
        if (rng_next(&rng) >= q) {
            alive = false;
        } else {
            throughput /= q;
        }
    }
    path.radiance = (float4)(radiance, as_float(rng));
    if (alive) {
        uint flags = specular ? PATH_SPECULAR : 0u;
#ifdef HAS_THIN_WALLS
        // Straight through a thin wall the path keeps its last scattering vertex's pdf and
        // flags, as the shadow rays of that vertex pass the wall (a camera ray stays direct).
        if (specular && side < 0.0f && bsdf_passes_straight(&m)) {
            pdf = prev_pdf;
            flags = frame.bounce == 0u ? PATH_SPECULAR : as_uint(path.direction.w);
            if (!prev_specular && frame.bounce > 0u) flags |= PATH_THROUGH_WALL;
        }
#endif
        path.origin = (float4)(offset_ray(p, side > 0.0f ? ng : -ng), pdf);
        path.direction = (float4)(wi, as_float(flags));
        path.throughput.xyz = throughput;
        queue_out[atomic_inc(&counters[COUNT_OUT])] = slot;
    }
    paths[slot] = path;
}

#ifdef HAS_THIN_WALLS
// Shadow rays pass at most this many thin walls.
#define MAX_THIN_WALLS 8u

// Whether the surface hit by a shadow ray along dir is a smooth thin wall; if so, multiplies
// *tint by what it lets through.
inline bool thin_wall_tint(global const GpuTriangle* tris, const SceneSurfaces* surf, GpuHit hit,
                           float3 dir, float3* tint) {
    GpuTriangle tri = tris[hit.prim];
    global const GpuMaterial* mat = &surf->materials[as_uint(tri.v0.w)];
    SurfaceMaterial m = surface_material(mat);
#ifdef HAS_TEXTURES
    TexCoords tc = texcoords_at(surf->shading[hit.prim], hit.u, hit.v);
    apply_textures(&m, mat, surf, &tc);
#endif
    if (!bsdf_passes_straight(&m)) return false;
    float3 ng = normalize(cross(tri.v1.xyz - tri.v0.xyz, tri.v2.xyz - tri.v0.xyz));
    *tint *= thin_wall_transmittance(&m, fabs(dot(ng, dir)));
    return true;
}
#endif

kernel void connect(global const GpuBvhNode* nodes, global const GpuTriangle* tris,
                    global const GpuTriShading* shading, global const GpuTriTangents* tangents,
                    global const GpuMaterial* materials, global const GpuTexRef* tex_refs,
                    global const GpuTexture* textures, global const uint* texels,
                    global const GpuShadowRay* shadow_rays, volatile global uint* counters,
                    global GpuPath* paths) {
    uint i = get_global_id(0);
    if (i >= counters[COUNT_SHADOW]) return;
    SceneSurfaces surf = {shading, tangents, materials, tex_refs, textures, texels};
    GpuShadowRay r = shadow_rays[i];
    GpuHit hit = traverse(nodes, tris, &surf, r.origin.xyz, r.direction.xyz, 0.0f, r.origin.w,
                          true, &counters[COUNT_OVERFLOW]);
#ifdef HAS_THIN_WALLS
    // Something is in the way: if it and everything else in the way are smooth thin walls, the
    // light comes through, tinted by each wall and no longer shared with the BSDF sample (the
    // MIS weight undone: BSDF samples through walls leave such lights to light sampling).
    float3 tint = (float3)(1.0f);
    if (hit.prim != NO_HIT) {
        if (!thin_wall_tint(tris, &surf, hit, r.direction.xyz, &tint)) return;
        // The walls in order, nearest first, each beyond the last.
        tint = (float3)(r.contribution.w);
        hit = traverse(nodes, tris, &surf, r.origin.xyz, r.direction.xyz, 0.0f, r.origin.w,
                       false, &counters[COUNT_OVERFLOW]);
        for (uint walls = 0u; hit.prim != NO_HIT; ++walls) {
            if (walls == MAX_THIN_WALLS || !thin_wall_tint(tris, &surf, hit, r.direction.xyz, &tint)) {
                return;
            }
            hit = traverse(nodes, tris, &surf, r.origin.xyz, r.direction.xyz, hit.t, r.origin.w,
                           false, &counters[COUNT_OVERFLOW]);
        }
    }
    paths[as_uint(r.direction.w)].radiance.xyz += r.contribution.xyz * tint;
#else
    if (hit.prim == NO_HIT) paths[as_uint(r.direction.w)].radiance.xyz += r.contribution.xyz;
#endif
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

// Adds every finished sample of the wave to the film (.xyz radiance sum, .w sample count), in a
// fixed order per pixel so the result does not depend on the queues' order. Non-finite samples
// are counted and dropped.
kernel void accumulate(GpuFrame frame, global const GpuPath* paths, global float4* film,
                       volatile global uint* counters) {
    uint pixel = get_global_id(0);
    uint pixels = frame.width * frame.height;
    if (pixel >= pixels) return;
    float3 sum = (float3)(0.0f);
    for (uint j = 0; j < frame.samples_in_wave; ++j) {
        float3 r = paths[pixel + j * pixels].radiance.xyz;
        if (all(isfinite(r))) {
            sum += r;
        } else {
            atomic_inc(&counters[COUNT_NONFINITE]);
        }
    }
    film[pixel] += (float4)(sum, (float)frame.samples_in_wave);
}
