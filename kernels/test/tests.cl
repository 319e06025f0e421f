// Kernels only the tests use (built into the test program, src/cl/program.rs): the layout
// probe, texture lookups and environment samples. kernels/test/bsdf_test.cl holds the BSDF ones.

#include "shared/types.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/env.h"

// Writes, per shared struct, its size then each field's offset, in the order of
// src/cl/types.rs::layouts().
#define PROBE_SIZE(T) out[n++] = (uint)sizeof(T)
#define PROBE_FIELD(T, f) out[n++] = (uint)((size_t)&((T*)0)->f)
kernel void probe_layout(global uint* out) {
    if (get_global_id(0) != 0) return;
    uint n = 0;
    PROBE_SIZE(GpuBvhNode);
    PROBE_FIELD(GpuBvhNode, left_min); PROBE_FIELD(GpuBvhNode, left_max);
    PROBE_FIELD(GpuBvhNode, right_min); PROBE_FIELD(GpuBvhNode, right_max);
    PROBE_SIZE(GpuTriangle);
    PROBE_FIELD(GpuTriangle, v0); PROBE_FIELD(GpuTriangle, v1); PROBE_FIELD(GpuTriangle, v2);
    PROBE_SIZE(GpuInstance);
    PROBE_FIELD(GpuInstance, row0); PROBE_FIELD(GpuInstance, row1);
    PROBE_FIELD(GpuInstance, row2); PROBE_FIELD(GpuInstance, world0);
    PROBE_FIELD(GpuInstance, world1); PROBE_FIELD(GpuInstance, world2);
    PROBE_FIELD(GpuInstance, root); PROBE_FIELD(GpuInstance, wide_root);
    PROBE_FIELD(GpuInstance, id); PROBE_FIELD(GpuInstance, flags);
    PROBE_SIZE(GpuTriShading);
    PROBE_FIELD(GpuTriShading, n);
    PROBE_SIZE(GpuTriUvs);
    PROBE_FIELD(GpuTriUvs, uv01); PROBE_FIELD(GpuTriUvs, uv2); PROBE_FIELD(GpuTriUvs, uv1_12);
    PROBE_SIZE(GpuTriTangents);
    PROBE_FIELD(GpuTriTangents, t0); PROBE_FIELD(GpuTriTangents, t1);
    PROBE_FIELD(GpuTriTangents, t2);
    PROBE_SIZE(GpuTexture);
    PROBE_FIELD(GpuTexture, offset); PROBE_FIELD(GpuTexture, width);
    PROBE_FIELD(GpuTexture, height); PROBE_FIELD(GpuTexture, flags);
    PROBE_SIZE(GpuTexRef);
    PROBE_FIELD(GpuTexRef, m0); PROBE_FIELD(GpuTexRef, m1); PROBE_FIELD(GpuTexRef, info);
    PROBE_SIZE(GpuEnvironment);
    PROBE_FIELD(GpuEnvironment, scale); PROBE_FIELD(GpuEnvironment, rotation);
    PROBE_FIELD(GpuEnvironment, width); PROBE_FIELD(GpuEnvironment, height);
    PROBE_FIELD(GpuEnvironment, light); PROBE_FIELD(GpuEnvironment, pad);
    PROBE_SIZE(GpuMaterial);
    PROBE_FIELD(GpuMaterial, base_color); PROBE_FIELD(GpuMaterial, emission);
    PROBE_FIELD(GpuMaterial, params); PROBE_FIELD(GpuMaterial, specular);
    PROBE_FIELD(GpuMaterial, volume); PROBE_FIELD(GpuMaterial, alpha);
    PROBE_FIELD(GpuMaterial, textures); PROBE_FIELD(GpuMaterial, textures2);
    PROBE_FIELD(GpuMaterial, coat); PROBE_FIELD(GpuMaterial, textures3);
    PROBE_FIELD(GpuMaterial, sheen); PROBE_FIELD(GpuMaterial, aniso);
    PROBE_FIELD(GpuMaterial, iridescence); PROBE_FIELD(GpuMaterial, diffuse_transmission);
    PROBE_FIELD(GpuMaterial, textures4); PROBE_FIELD(GpuMaterial, textures5);
    PROBE_SIZE(GpuLight);
    PROBE_FIELD(GpuLight, position); PROBE_FIELD(GpuLight, intensity);
    PROBE_FIELD(GpuLight, spot); PROBE_FIELD(GpuLight, extra);
    PROBE_SIZE(GpuCamera);
    PROBE_FIELD(GpuCamera, origin); PROBE_FIELD(GpuCamera, forward);
    PROBE_FIELD(GpuCamera, right); PROBE_FIELD(GpuCamera, up);
    PROBE_SIZE(GpuFrame);
    PROBE_FIELD(GpuFrame, width); PROBE_FIELD(GpuFrame, height);
    PROBE_FIELD(GpuFrame, samples_in_wave); PROBE_FIELD(GpuFrame, first_sample);
    PROBE_FIELD(GpuFrame, seed); PROBE_FIELD(GpuFrame, max_bounces);
    PROBE_FIELD(GpuFrame, rr_depth); PROBE_FIELD(GpuFrame, strategy);
    PROBE_FIELD(GpuFrame, sky); PROBE_FIELD(GpuFrame, light_count);
    PROBE_FIELD(GpuFrame, bounce); PROBE_FIELD(GpuFrame, background);
    PROBE_FIELD(GpuFrame, triangles);
    PROBE_SIZE(GpuPath);
    PROBE_FIELD(GpuPath, origin); PROBE_FIELD(GpuPath, direction);
    PROBE_FIELD(GpuPath, throughput); PROBE_FIELD(GpuPath, radiance);
    PROBE_SIZE(GpuHit);
    PROBE_FIELD(GpuHit, t); PROBE_FIELD(GpuHit, u); PROBE_FIELD(GpuHit, v); PROBE_FIELD(GpuHit, prim);
    PROBE_FIELD(GpuHit, instance);
    PROBE_SIZE(GpuShadowRay);
    PROBE_FIELD(GpuShadowRay, origin); PROBE_FIELD(GpuShadowRay, direction);
    PROBE_FIELD(GpuShadowRay, contribution);
    PROBE_SIZE(GpuRay);
    PROBE_FIELD(GpuRay, origin); PROBE_FIELD(GpuRay, direction);
    PROBE_SIZE(GpuWideNode);
    PROBE_FIELD(GpuWideNode, min_x); PROBE_FIELD(GpuWideNode, min_y);
    PROBE_FIELD(GpuWideNode, min_z); PROBE_FIELD(GpuWideNode, max_x);
    PROBE_FIELD(GpuWideNode, max_y); PROBE_FIELD(GpuWideNode, max_z);
    PROBE_FIELD(GpuWideNode, child); PROBE_FIELD(GpuWideNode, count);
    out[n] = 0xffffffffu;
}

// Texture lookups for the tests: query i reads reference (int bits of .w) at uv .xy and level
// of detail .z (the texel-footprint level before the texture's own size is added; -INFINITY
// reads level 0, and a fractional level is rounded down).
kernel void sample_texture_test(global const GpuTexRef* tex_refs, global const GpuTexture* textures,
                                global const uint* texels, global const float4* queries,
                                uint count, global float4* out) {
    uint i = get_global_id(0);
    if (i >= count) return;
#ifdef HAS_TEXTURES
    SceneSurfaces surf;
    surf.refs = tex_refs;
    surf.textures = textures;
    surf.texels = texels;
    float4 q = queries[i];
    TexCoords tc;
    tc.uv0 = q.xy;
    tc.uv1 = q.xy;
    tc.lod0 = q.z;
    tc.lod1 = q.z;
    tc.xi = 1.0f;
    out[i] = texture_sample(&surf, as_int(q.w), &tc);
#else
    out[i] = (float4)(0.0f);
#endif
}

// Environment samples for the tests: direction (.xyz) and pdf (.w) of sample i from the
// uniform pair u[i], and the pdf that env_radiance gives the same direction.
kernel void sample_env_test(GpuEnvironment environment, global const float* env_texels,
                            global const float* env_marginal, global const float* env_conditional,
                            global const float2* u, uint count, global float4* out,
                            global float* eval_pdf) {
    uint i = get_global_id(0);
    if (i >= count) return;
#ifdef HAS_ENV_MAP
    EnvMap env = {environment, env_texels, env_marginal, env_conditional};
    float3 radiance;
    float pdf;
    float3 d = env_sample(&env, u[i].x, u[i].y, &radiance, &pdf);
    out[i] = (float4)(d, pdf);
    float check;
    env_radiance(&env, d, &check);
    eval_pdf[i] = check;
#else
    out[i] = (float4)(0.0f);
    eval_pdf[i] = 0.0f;
#endif
}

// Spawned rays against the kernel's own hit point and offset (pbrt-v4's reintersection test):
// case i spawns from triangle groups[i].x at barycentrics bary[i].xy, offset to the side of
// dirs[i].xyz, and traces a ray along dirs[i].xyz up to dirs[i].w against the groups[i].z
// triangles from groups[i].y; hits[i] = how many of them it hits.
kernel void spawn_test(global const float4* verts, global const uint4* groups,
                       global const float2* bary, global const float4* dirs, uint count,
                       global uint* hits) {
    uint i = get_global_id(0);
    if (i >= count) return;
    uint first = groups[i].x;
    float3 v0 = verts[3 * first].xyz, v1 = verts[3 * first + 1].xyz, v2 = verts[3 * first + 2].xyz;
    float3 ng = triangle_normal(v0, v1, v2);
    float3 d = dirs[i].xyz;
    float3 err;
    float3 p = surface_point(v0, v1, v2, bary[i].x, bary[i].y, &err);
    float3 o = offset_ray(p, err, dot(d, ng) > 0.0f ? ng : -ng);
    RayPrep r = prepare_ray(o, d);
    uint n = 0;
    for (uint k = groups[i].y; k < groups[i].y + groups[i].z; k++) {
        float tmax = dirs[i].w;
        float bu, bv;
        if (intersect_triangle(&r, verts[3 * k], verts[3 * k + 1], verts[3 * k + 2], 0.0f, &tmax,
                               &bu, &bv))
            n++;
    }
    hits[i] = n;
}
