// Thin-film interference for KHR_materials_iridescence (HAS_IRIDESCENCE): the film's Fresnel
// over a base reflectance and its largest normal-incidence reflectance, which the layering
// (bsdf_layers.h) and the glossy lobes (bsdf.h's bsdf_gloss) take.
#ifndef SHARED_THIN_FILM_H
#define SHARED_THIN_FILM_H

#include "shared/material.h"

#ifdef HAS_IRIDESCENCE
// Thin-film interference (Belcour and Barla 2017, "A Practical Extension to Microfacet Theory for
// the Modeling of Varying Iridescence"), as the Khronos glTF sample viewer evaluates it for
// KHR_materials_iridescence: air over a film of index film_ior and thickness d (nm) over a base
// of normal reflectance f0, seen at cos_1; Schlick's Fresnel at both interfaces, the spectral
// integral of the first two orders against the CIE XYZ curves in Fourier form, then linear sRGB.

// The XYZ sensitivity (Fourier form) at optical path difference opd (nm) and phase shift.
inline float3 film_sensitivity(float opd, float3 shift) {
    float phase = 2.0f * PI_F * opd * 1.0e-9f;
    float3 val = (float3)(5.4856e-13f, 4.4201e-13f, 5.2481e-13f);
    float3 pos = (float3)(1.6810e+06f, 1.7953e+06f, 2.2084e+06f);
    float3 var = (float3)(4.3278e+09f, 9.3046e+09f, 6.6121e+09f);
    float3 xyz = val * sqrt(2.0f * PI_F * var) * cos(pos * phase + shift) * exp(-phase * phase * var);
    xyz.x += 9.7470e-14f * sqrt(2.0f * PI_F * 4.5282e+09f) * cos(2.2399e+06f * phase + shift.x) *
             exp(-4.5282e+09f * phase * phase);
    xyz /= 1.0685e-7f;
    return (float3)(3.2404542f * xyz.x - 1.5371385f * xyz.y - 0.4985314f * xyz.z,
                    -0.9692660f * xyz.x + 1.8760108f * xyz.y + 0.0415560f * xyz.z,
                    0.0556434f * xyz.x - 0.2040259f * xyz.y + 1.0572252f * xyz.z);
}

inline float film_sq(float x) {
    return x * x;
}

// Below this thickness (nm) a film is no film: the base alone (the sample viewer's blend of the
// film's index to the outside's would leave a Schlick interface of f0 = 0 there).
#define FILM_MIN_THICKNESS 0.03f

// The exact (unpolarised) Fresnel reflectance of an interface from index n_i to n_t (per
// channel), seen at cos_i: 0 at every angle where the indices are equal, 1 past the critical
// angle.
inline float3 film_interface(float cos_i, float n_i, float3 n_t) {
    float3 eta = n_t / n_i;
    float3 sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    float3 cos_t = sqrt(fmax(1.0f - sin2_t, 0.0f));
    float3 rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float3 rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float3 f = 0.5f * (rs * rs + rp * rp);
    return (float3)(sin2_t.x >= 1.0f ? 1.0f : f.x, sin2_t.y >= 1.0f ? 1.0f : f.y,
                    sin2_t.z >= 1.0f ? 1.0f : f.z);
}

// The film's reflectance (RGB, in [0, 1]) at cos_1 over a base of normal reflectance f0.
inline float3 film_fresnel(float cos_1, float film_ior, float d, float3 f0) {
    if (d < FILM_MIN_THICKNESS) return f0 + (1.0f - f0) * schlick_weight(cos_1);
    float n2 = film_ior;
    float sin2_2 = film_sq(1.0f / n2) * (1.0f - cos_1 * cos_1);
    float cos2_2 = 1.0f - sin2_2;
    if (cos2_2 < 0.0f) return (float3)(1.0f);
    float cos_2 = sqrt(cos2_2);
    // First interface (air to film).
    float r0 = film_sq((n2 - 1.0f) / (n2 + 1.0f));
    float r12 = r0 + (1.0f - r0) * schlick_weight(cos_1);
    float t121 = 1.0f - r12;
    float phi12 = n2 < 1.0f ? PI_F : 0.0f;
    float phi21 = PI_F - phi12;
    // Second interface (film to base); the base's index from its reflectance.
    float3 sf0 = sqrt(clamp(f0, 0.0f, 0.9999f));
    float3 n3 = (1.0f + sf0) / (1.0f - sf0);
    // The film's lower face by the exact Fresnel (the sample viewer's Schlick leaves
    // (1 - cos)^5 where film and base have one index, and fringes of 2 % at grazing angles).
    float3 r23 = film_interface(cos_2, n2, n3);
    float3 phi23 = (float3)(n3.x < n2 ? PI_F : 0.0f, n3.y < n2 ? PI_F : 0.0f, n3.z < n2 ? PI_F : 0.0f);
    float opd = 2.0f * n2 * d * cos_2;
    float3 phi = phi21 + phi23;
    // No floor on r12 r23 (the sample viewer's 1e-5 keeps fringes of ±0.6 % where the film's
    // index is the base's and there is no second interface to interfere with).
    float3 r123 = clamp(r12 * r23, 0.0f, 0.9999f);
    float3 s123 = sqrt(r123);
    float3 rs = t121 * t121 * r23 / (1.0f - r123);
    float3 color = r12 + rs;
    float3 cm = rs - t121;
    for (int m = 1; m <= 2; ++m) {
        cm *= s123;
        color += cm * 2.0f * film_sensitivity((float)m * opd, (float)m * phi);
    }
    return clamp(color, 0.0f, 1.0f);
}

// The largest normal-incidence reflectance of a film of index n2 over a base of reflectance f0
// (its thickness a quarter or a half wave): (|r12| + |r23|)² / (1 + |r12 r23|)².
inline float film_max_reflectance(float n2, float f0) {
    float sf0 = sqrt(clamp(f0, 0.0f, 0.9999f));
    float n3 = (1.0f + sf0) / (1.0f - sf0);
    float a = fabs((n2 - 1.0f) / (n2 + 1.0f));
    float b = fabs((n3 - n2) / (n3 + n2));
    return film_sq((a + b) / (1.0f + a * b));
}
#endif

#endif  // SHARED_THIN_FILM_H
