// The GGX microfacet maths of the glossy lobes: the energy tables' lookups (E, E_s and their
// means, Kulla-Conty's multiple-scattering colour), Schlick's and the dielectric's Fresnel
// weights, the distribution, Smith's Lambda and visible-normal sampling (isotropic, and
// HAS_ANISOTROPY's stretched forms), and the lobes' frame and largest alpha.
#ifndef SHARED_MICROFACET_H
#define SHARED_MICROFACET_H

#include "shared/types.h"
#include "shared/vec3.h"
#include "shared/rng.h"
#include "shared/bsdf_tables.h"
#include "shared/material.h"

// GGX lobes with alpha below this are delta lobes.
#define BSDF_DELTA_ALPHA 1e-3f

// (E, E_s) at cos(theta_o) and perceptual roughness, bilinear in GGX_E and GGX_E_SCHLICK.
inline float2 ggx_energy(float cos_o, float roughness) {
    float x = clamp(cos_o, 0.0f, 1.0f) * 32.0f;
    float y = clamp(roughness, 0.0f, 1.0f) * 32.0f;
    int i = min((int)x, 31);
    int j = min((int)y, 31);
    int k = j * 33 + i;
    float fx = x - (float)i;
    float fy = y - (float)j;
    float2 a = mix((float2)(GGX_E[k], GGX_E_SCHLICK[k]), (float2)(GGX_E[k + 1], GGX_E_SCHLICK[k + 1]), fx);
    float2 b = mix((float2)(GGX_E[k + 33], GGX_E_SCHLICK[k + 33]),
                   (float2)(GGX_E[k + 34], GGX_E_SCHLICK[k + 34]), fx);
    return mix(a, b, fy);
}

// The cosine-weighted means (E_avg, E_s avg) at a perceptual roughness.
inline float2 ggx_energy_avg(float roughness) {
    float y = clamp(roughness, 0.0f, 1.0f) * 32.0f;
    int j = min((int)y, 31);
    return mix((float2)(GGX_E_AVG[j], GGX_E_SCHLICK_AVG[j]),
               (float2)(GGX_E_AVG[j + 1], GGX_E_SCHLICK_AVG[j + 1]), y - (float)j);
}

// Kulla–Conty: the colour of the multiply scattered light of a lobe whose cosine-weighted mean
// Fresnel is f_avg (Schlick: f0 + (1 - f0) / 21) and mean single-scattering albedo e_avg.
inline float3 multiple_scattering_color(float3 f0, float e_avg) {
    float3 f_avg = f0 + (1.0f - f0) * (1.0f / 21.0f);
    return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

inline float bsdf_max3(float3 c) {
    return fmax(c.x, fmax(c.y, c.z));
}

inline float schlick_weight(float c) {
    float m = clamp(1.0f - c, 0.0f, 1.0f);
    float m2 = m * m;
    return m2 * m2 * m;
}

// cos^2 of the refracted direction at a microfacet seen at cos_oh, relative index eta; <= 0 means
// total internal reflection.
inline float refracted_cos2(float cos_oh, float eta) {
    return 1.0f - (1.0f - cos_oh * cos_oh) / (eta * eta);
}

// The Schlick weight of a dielectric interface: leaving the denser medium (eta < 1) it takes the
// cosine on the far side, and is 1 under total internal reflection.
inline float dielectric_schlick(float cos_oh, float eta) {
    if (eta >= 1.0f) return schlick_weight(cos_oh);
    float c2 = refracted_cos2(cos_oh, eta);
    return c2 > 0.0f ? schlick_weight(sqrt(c2)) : 1.0f;
}

// GGX normal distribution for a unit local h, a2 = alpha^2 (sin^2 from x, y keeps its precision
// for narrow lobes).
inline float ggx_d(float3 h, float a2) {
    float d = h.x * h.x + h.y * h.y + h.z * h.z * a2;
    return a2 / (PI_F * d * d);
}

// Smith's Lambda for GGX, in a form without cancellation; infinite at the horizon.
inline float ggx_lambda(float3 w, float a2) {
    float x = a2 * (w.x * w.x + w.y * w.y) / (w.z * w.z);
    return x < INFINITY ? x / (2.0f * (sqrt(1.0f + x) + 1.0f)) : INFINITY;
}

// A GGX visible normal for local wo (wo.z > 0) by spherical caps (Dupuy and Benyoub 2023); its
// density is G1(wo) max(0, wo.h) D(h) / wo.z.
inline float3 ggx_sample_vndf(float3 wo, float alpha, float u1, float u2) {
    float3 v = normalize((float3)(alpha * wo.x, alpha * wo.y, wo.z));
    float phi = 2.0f * PI_F * u1;
    float z = (1.0f - u2) * (1.0f + v.z) - v.z;
    float s = sqrt(clamp(1.0f - z * z, 0.0f, 1.0f));
    float3 h = (float3)(s * cos(phi), s * sin(phi), z) + v;
    h = (float3)(alpha * h.x, alpha * h.y, fmax(h.z, 0.0f));
    float len2 = dot(h, h);
    return len2 > 0.0f ? h * rsqrt(len2) : (float3)(0.0f, 0.0f, 1.0f);
}

#ifdef HAS_ANISOTROPY
// Anisotropic GGX (alpha_x along the frame's t, alpha_y along b): the distribution, Smith's
// Lambda and the visible normals as above, with the axes stretched.
inline float ggx_d_aniso(float3 h, float ax, float ay) {
    float x = h.x / ax;
    float y = h.y / ay;
    float d = x * x + y * y + h.z * h.z;
    return 1.0f / (PI_F * ax * ay * d * d);
}

inline float ggx_lambda_aniso(float3 w, float ax, float ay) {
    float x = (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / (w.z * w.z);
    return x < INFINITY ? x / (2.0f * (sqrt(1.0f + x) + 1.0f)) : INFINITY;
}

inline float3 ggx_sample_vndf_aniso(float3 wo, float ax, float ay, float u1, float u2) {
    float3 v = normalize((float3)(ax * wo.x, ay * wo.y, wo.z));
    float phi = 2.0f * PI_F * u1;
    float z = (1.0f - u2) * (1.0f + v.z) - v.z;
    float s = sqrt(clamp(1.0f - z * z, 0.0f, 1.0f));
    float3 h = (float3)(s * cos(phi), s * sin(phi), z) + v;
    h = (float3)(ax * h.x, ay * h.y, fmax(h.z, 0.0f));
    float len2 = dot(h, h);
    return len2 > 0.0f ? h * rsqrt(len2) : (float3)(0.0f, 0.0f, 1.0f);
}
#endif

// The lobes' frame about n: onb's, or (anisotropic) t along the anisotropy direction.
inline void bsdf_frame(const SurfaceMaterial* m, float3 n, float3* t, float3* b) {
    onb(n, t, b);
#ifdef HAS_ANISOTROPY
    if (m->anisotropy > 0.0f) {
        float3 d = m->aniso_dir - n * dot(n, m->aniso_dir);
        float len = length(d);
        d = len > 1e-6f ? d / len : m->aniso_rotation.x * *t + m->aniso_rotation.y * *b;
        *t = d;
        *b = cross(n, d);
    }
#endif
}

// The largest GGX alpha of the glossy lobes (anisotropy stretches one axis).
inline float bsdf_alpha_max(const SurfaceMaterial* m) {
    float alpha = m->roughness * m->roughness;
#ifdef HAS_ANISOTROPY
    float s = clamp(m->anisotropy, 0.0f, 1.0f);
    if (s > 0.0f) alpha = mix(alpha, 1.0f, s * s);
#endif
    return alpha;
}

#endif  // SHARED_MICROFACET_H
