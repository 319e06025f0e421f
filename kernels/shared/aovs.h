// Guide buffers for a denoiser (docs/aovs.md), compiled in with AOVS only: each path records
// the albedo and the world-space shading normal of the first surface it meets that is not
// near-specular, and the camera distance of its first hit. Cycles' rule: a surface most of whose
// weight is a smooth mirror or refraction (metal or transmission at roughness under
// AOV_SPECULAR_ROUGHNESS) is looked through: its colour tints what the path meets next.
// An escaped path records the environment it sees (clamped to 1, OIDN's convention) and a zero
// normal; a path that ends before it records anything adds zeros.
//
// Per pixel the film's AOV buffers hold sums over samples, averaged on readback:
//   albedo: .xyz the sum of the albedos, .w the samples added;
//   normal: .xyz the sum of the normals, .w 0;
//   depth:  .x the sum of the first hits' distances, .y the samples whose camera ray hit.
#ifndef SHARED_AOVS_H
#define SHARED_AOVS_H

#include "shared/bsdf.h"

// Below this perceptual roughness a metal or transmission lobe counts as near-specular.
#define AOV_SPECULAR_ROUGHNESS 0.1f

// A path's record, beside its state.
typedef struct {
    float3 albedo;  // the tint of the near-specular surfaces passed until `done`, then the albedo
    float3 normal;  // the shading normal recorded (0 until `done`, and for an escaped path)
    float depth;    // camera distance of the first hit; 0 when the camera ray escaped
    float done;     // 1 once recorded (a float, to ride in a DevicePath-like float4)
} PathAov;

inline PathAov aov_start(void) {
    PathAov a;
    a.albedo = (float3)(1.0f);
    a.normal = (float3)(0.0f);
    a.depth = 0.0f;
    a.done = 0.0f;
    return a;
}

// The share of a surface's weight that is near-specular: its metal and transmission lobes
// when they are smooth.
inline float aov_specular_share(const SurfaceMaterial* m) {
    if (m->roughness >= AOV_SPECULAR_ROUGHNESS) return 0.0f;
    float metallic = clamp(m->metallic, 0.0f, 1.0f);
    return metallic + (1.0f - metallic) * clamp(m->transmission, 0.0f, 1.0f);
}

// A surface the path meets with shading normal ns: recorded unless most (Cycles: more than
// three quarters) of its weight is near-specular, which only tints the record to come.
inline void aov_surface(PathAov* a, const SurfaceMaterial* m, float3 ns) {
    if (a->done != 0.0f) return;
    float3 color = clamp(m->base_color, 0.0f, 1.0f);
    a->albedo *= color;
    if (aov_specular_share(m) > 0.75f) return;
    a->normal = ns;
    a->done = 1.0f;
}

// A surface recorded as it is: an unlit material's colour, facing normal n.
inline void aov_plain(PathAov* a, float3 color, float3 n) {
    if (a->done != 0.0f) return;
    a->albedo *= clamp(color, 0.0f, 1.0f);
    a->normal = n;
    a->done = 1.0f;
}

// An escaped path that sees `background`.
inline void aov_escape(PathAov* a, float3 background) {
    aov_plain(a, background, (float3)(0.0f));
}

// The wavefront keeps each slot's record in two float4s: (albedo, depth), (normal, done).
inline PathAov aov_load(global const float4* records, uint slot) {
    float4 a = records[2u * slot];
    float4 n = records[2u * slot + 1u];
    PathAov r;
    r.albedo = a.xyz;
    r.depth = a.w;
    r.normal = n.xyz;
    r.done = n.w;
    return r;
}

inline void aov_save(global float4* records, uint slot, const PathAov* r) {
    records[2u * slot] = (float4)(r->albedo, r->depth);
    records[2u * slot + 1u] = (float4)(r->normal, r->done);
}

// A finished path's record into the pixel's sums: an unrecorded one adds zeros.
inline void aov_add(const PathAov* a, float3* albedo, float3* normal, float2* depth) {
    if (a->done != 0.0f) {
        *albedo += a->albedo;
        *normal += a->normal;
    }
    if (a->depth > 0.0f) *depth += (float2)(a->depth, 1.0f);
}

// A pixel's `n` new samples' sums into its AOV buffers.
inline void aov_store(global float4* albedos, global float4* normals, global float2* depths,
                      uint pixel, float3 albedo, float3 normal, float2 depth, uint n) {
    float4 a = albedos[pixel];
    albedos[pixel] = (float4)(a.xyz + albedo, a.w + (float)n);
    normals[pixel] += (float4)(normal, 0.0f);
    depths[pixel] += depth;
}

#endif  // SHARED_AOVS_H
