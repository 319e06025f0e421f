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
    PROBE_SIZE(DeviceBvhNode);
    PROBE_FIELD(DeviceBvhNode, left_min); PROBE_FIELD(DeviceBvhNode, left_max);
    PROBE_FIELD(DeviceBvhNode, right_min); PROBE_FIELD(DeviceBvhNode, right_max);
    PROBE_SIZE(DeviceTriangle);
    PROBE_FIELD(DeviceTriangle, v0); PROBE_FIELD(DeviceTriangle, v1); PROBE_FIELD(DeviceTriangle, v2);
    PROBE_SIZE(DeviceInstance);
    PROBE_FIELD(DeviceInstance, row0); PROBE_FIELD(DeviceInstance, row1);
    PROBE_FIELD(DeviceInstance, row2); PROBE_FIELD(DeviceInstance, world0);
    PROBE_FIELD(DeviceInstance, world1); PROBE_FIELD(DeviceInstance, world2);
    PROBE_FIELD(DeviceInstance, root); PROBE_FIELD(DeviceInstance, wide_root);
    PROBE_FIELD(DeviceInstance, id); PROBE_FIELD(DeviceInstance, flags);
    PROBE_SIZE(DeviceTriShading);
    PROBE_FIELD(DeviceTriShading, n);
    PROBE_SIZE(DeviceTriUvs);
    PROBE_FIELD(DeviceTriUvs, uv01); PROBE_FIELD(DeviceTriUvs, uv2); PROBE_FIELD(DeviceTriUvs, uv1_12);
    PROBE_SIZE(DeviceTriTangents);
    PROBE_FIELD(DeviceTriTangents, t0); PROBE_FIELD(DeviceTriTangents, t1);
    PROBE_FIELD(DeviceTriTangents, t2);
    PROBE_SIZE(DeviceTriColors);
    PROBE_FIELD(DeviceTriColors, c0); PROBE_FIELD(DeviceTriColors, c1);
    PROBE_FIELD(DeviceTriColors, c2);
    PROBE_SIZE(DeviceTexture);
    PROBE_FIELD(DeviceTexture, offset); PROBE_FIELD(DeviceTexture, width);
    PROBE_FIELD(DeviceTexture, height); PROBE_FIELD(DeviceTexture, flags);
    PROBE_SIZE(DeviceTexRef);
    PROBE_FIELD(DeviceTexRef, m0); PROBE_FIELD(DeviceTexRef, m1); PROBE_FIELD(DeviceTexRef, info);
    PROBE_SIZE(DeviceEnvironment);
    PROBE_FIELD(DeviceEnvironment, scale); PROBE_FIELD(DeviceEnvironment, rotation);
    PROBE_FIELD(DeviceEnvironment, width); PROBE_FIELD(DeviceEnvironment, height);
    PROBE_FIELD(DeviceEnvironment, light); PROBE_FIELD(DeviceEnvironment, pad);
    PROBE_SIZE(DeviceMaterial);
    PROBE_FIELD(DeviceMaterial, base_color); PROBE_FIELD(DeviceMaterial, emission);
    PROBE_FIELD(DeviceMaterial, params); PROBE_FIELD(DeviceMaterial, specular);
    PROBE_FIELD(DeviceMaterial, volume); PROBE_FIELD(DeviceMaterial, alpha);
    PROBE_FIELD(DeviceMaterial, textures); PROBE_FIELD(DeviceMaterial, textures2);
    PROBE_FIELD(DeviceMaterial, coat); PROBE_FIELD(DeviceMaterial, textures3);
    PROBE_FIELD(DeviceMaterial, sheen); PROBE_FIELD(DeviceMaterial, aniso);
    PROBE_FIELD(DeviceMaterial, iridescence); PROBE_FIELD(DeviceMaterial, diffuse_transmission);
    PROBE_FIELD(DeviceMaterial, textures4); PROBE_FIELD(DeviceMaterial, textures5);
    PROBE_SIZE(DeviceLight);
    PROBE_FIELD(DeviceLight, position); PROBE_FIELD(DeviceLight, intensity);
    PROBE_FIELD(DeviceLight, spot); PROBE_FIELD(DeviceLight, extra);
    PROBE_SIZE(DeviceCamera);
    PROBE_FIELD(DeviceCamera, origin); PROBE_FIELD(DeviceCamera, forward);
    PROBE_FIELD(DeviceCamera, right); PROBE_FIELD(DeviceCamera, up);
    PROBE_SIZE(DeviceFrame);
    PROBE_FIELD(DeviceFrame, width); PROBE_FIELD(DeviceFrame, height);
    PROBE_FIELD(DeviceFrame, samples_in_wave); PROBE_FIELD(DeviceFrame, first_sample);
    PROBE_FIELD(DeviceFrame, seed); PROBE_FIELD(DeviceFrame, max_bounces);
    PROBE_FIELD(DeviceFrame, rr_depth); PROBE_FIELD(DeviceFrame, strategy);
    PROBE_FIELD(DeviceFrame, sky); PROBE_FIELD(DeviceFrame, light_count);
    PROBE_FIELD(DeviceFrame, bounce); PROBE_FIELD(DeviceFrame, background);
    PROBE_FIELD(DeviceFrame, triangles); PROBE_FIELD(DeviceFrame, adaptive);
    PROBE_SIZE(DevicePath);
    PROBE_FIELD(DevicePath, origin); PROBE_FIELD(DevicePath, direction);
    PROBE_FIELD(DevicePath, throughput); PROBE_FIELD(DevicePath, radiance);
    PROBE_SIZE(DeviceHit);
    PROBE_FIELD(DeviceHit, t); PROBE_FIELD(DeviceHit, u); PROBE_FIELD(DeviceHit, v); PROBE_FIELD(DeviceHit, prim);
    PROBE_FIELD(DeviceHit, instance);
    PROBE_SIZE(DeviceShadowRay);
    PROBE_FIELD(DeviceShadowRay, origin); PROBE_FIELD(DeviceShadowRay, direction);
    PROBE_FIELD(DeviceShadowRay, contribution);
    PROBE_SIZE(DeviceRay);
    PROBE_FIELD(DeviceRay, origin); PROBE_FIELD(DeviceRay, direction);
    PROBE_SIZE(DeviceWideNode);
    PROBE_FIELD(DeviceWideNode, min_x); PROBE_FIELD(DeviceWideNode, min_y);
    PROBE_FIELD(DeviceWideNode, min_z); PROBE_FIELD(DeviceWideNode, max_x);
    PROBE_FIELD(DeviceWideNode, max_y); PROBE_FIELD(DeviceWideNode, max_z);
    PROBE_FIELD(DeviceWideNode, child); PROBE_FIELD(DeviceWideNode, count);
    out[n] = 0xffffffffu;
}

// Texture lookups for the tests: query i reads reference (int bits of .w) at uv .xy and level
// of detail .z (the texel-footprint level before the texture's own size is added; -INFINITY
// reads level 0, and a fractional level is rounded down).
kernel void sample_texture_test(global const DeviceTexRef* tex_refs, global const DeviceTexture* textures,
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
kernel void sample_env_test(DeviceEnvironment environment, global const float* env_texels,
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
