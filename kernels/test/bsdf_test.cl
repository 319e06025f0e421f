// Kernels that run the BSDF on given inputs for tests/bsdf.rs (χ² tests of sampling against the
// pdf, and albedo checks).

#include "shared/types.h"
#include "shared/rng.h"
#include "shared/bsdf.h"
#include "shared/surface.h"

inline SurfaceMaterial bsdf_test_material(global const DeviceMaterial* material, uint inside) {
    SurfaceMaterial m = surface_material(material);
    if (inside != 0u) material_from_inside(&m);
#ifdef HAS_ANISOTROPY
    // A tangent as the shade kernel gives it (not orthogonal to the normal), turned by the
    // rotation: the frame comes from the direction, not from onb's fallback.
    if (m.anisotropy > 0.0f) {
        float3 t = (float3)(0.6f, -0.48f, 0.64f);
        float3 b = (float3)(0.8f, 0.36f, -0.48f);
        m.aniso_dir = m.aniso_rotation.x * t + m.aniso_rotation.y * b;
    }
#endif
    return m;
}

// `count` samples of the BSDF at (wo, n) with random numbers drawn as the shade kernel draws them.
// Writes (wi, pdf) and (weight, 1 for a delta lobe else 0).
kernel void bsdf_sample_test(global const DeviceMaterial* material, float4 wo, float4 n, uint inside,
                             uint count, uint seed, global float4* wi_pdf,
                             global float4* weight_specular) {
    uint i = get_global_id(0);
    if (i >= count) return;
    SurfaceMaterial m = bsdf_test_material(material, inside);
    uint rng = hash_u32(hash_u32(i * 0x9e3779b9u + 1u) ^ hash_u32(seed));
    float u1 = rng_next(&rng);
    float u2 = rng_next(&rng);
    float u3 = rng_next(&rng);
    float3 wi;
    float pdf;
    bool specular;
    float3 weight = bsdf_sample(&m, n.xyz, wo.xyz, (float3)(u1, u2, u3), &wi, &pdf, &specular);
    wi_pdf[i] = (float4)(wi, pdf);
    weight_specular[i] = (float4)(weight, specular ? 1.0f : 0.0f);
}

// bsdf_eval at (wo, n) for `count` directions wi: writes (f * |cos|, pdf).
kernel void bsdf_eval_test(global const DeviceMaterial* material, float4 wo, float4 n, uint inside,
                           uint count, global const float4* wi, global float4* value_pdf) {
    uint i = get_global_id(0);
    if (i >= count) return;
    SurfaceMaterial m = bsdf_test_material(material, inside);
    float pdf;
    float3 f = bsdf_eval(&m, n.xyz, wo.xyz, wi[i].xyz, &pdf);
    value_pdf[i] = (float4)(f, pdf);
}

// As bsdf_eval_test at a normal-mapped vertex whose geometric normal is +Z and whose mapped
// normal is n: the normals bent for wo, then the value for wi with them bent for wi too
// (surface.h, bsdf_eval_bent), as shade_vertex evaluates it.
kernel void bsdf_eval_bent_test(global const DeviceMaterial* material, float4 wo, float4 n,
                                uint inside, uint count, global const float4* wi,
                                global float4* value_pdf) {
    uint i = get_global_id(0);
    if (i >= count) return;
    SurfaceMaterial m = bsdf_test_material(material, inside);
    float3 ng = (float3)(0.0f, 0.0f, 1.0f);
    float3 ns = n.xyz;
#ifdef HAS_CLEARCOAT
    m.coat_normal = n.xyz;
#endif
    bend_normals(&m, ng, wo.xyz, &ns);
    float pdf;
    float3 f = bsdf_eval_bent(&m, ng, ns, wo.xyz, wi[i].xyz, &pdf);
    value_pdf[i] = (float4)(f, pdf);
}
