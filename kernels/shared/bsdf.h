// Scattering at a surface: the glTF 2.0 metallic-roughness BSDF (specification, appendix B) with
// KHR_materials_specular, _ior, _transmission and _volume. docs/materials.md ("Scattering") says
// what is modelled and what is approximated.
//
// Lobes, in the frame of the shading normal n (wo is always on n's side):
//   diffuse       Lambertian, base color, under the specular layer by albedo scaling:
//                 (1 - A(mu_o)) (1 - A(mu_i)) / (1 - A_avg), A the layer's directional albedo
//   reflection    GGX microfacets, height-correlated Smith G2, Schlick Fresnel: the dielectric
//                 (f0 from ior × specularColor, scaled by specularFactor) and the metal (f0 = base
//                 color) mixed by metallic, with Kulla–Conty multiple scattering (a cosine lobe)
//   transmission  the dielectric's transmitted share, tinted by base color: rough refraction
//                 through a volume (Walter et al. 2007, radiance scaled by 1/eta^2), straight
//                 through a volume of index 1 (a delta lobe whatever the roughness), or through a
//                 thin wall (both faces' Fresnel)
//   clear coat    (HAS_CLEARCOAT, KHR_materials_clearcoat) a GGX dielectric layer of ior 1.5 over
//                 all the above, in the frame of its own normal, single scattering: it reflects
//                 c A_c(mu) (A_c its directional albedo). The diffuse base sees coat and specular
//                 layer as one layer of albedo A_c + (1 - A_c) A, scaled as above; the glossy lobes
//                 are scaled by 1 - c max(A_c(mu_o), A_c(mu_i)) (reciprocal, never gains energy)
//   sheen         (HAS_SHEEN, KHR_materials_sheen) the Charlie distribution (Estevez and Kulla
//                 2017) with their fitted visibility, between the coat and the base: it reflects
//                 sheenColor E_sh(mu) (E_sh tabulated); the diffuse base sees it as one more layer
//                 of albedo s E_sh (s = max3(sheenColor)), the other base lobes are scaled by
//                 1 - s max(E_sh(mu_o), E_sh(mu_i)), the spec's albedo scaling made reciprocal
//   anisotropy    (HAS_ANISOTROPY, KHR_materials_anisotropy) the reflection and transmission
//                 microfacets are anisotropic GGX, alpha_t = mix(alpha, 1, strength^2) along the
//                 anisotropy direction and alpha_b = alpha across it, in the frame of that
//                 direction; its energy tables (ANISO_E) are per direction, over the base
//                 roughness and strength
//   iridescence   (HAS_IRIDESCENCE, KHR_materials_iridescence) a thin film over the specular
//                 layer: the Fresnel of the dielectric and the metal is mixed by iridescenceFactor
//                 with the film's (Belcour and Barla 2017, as the Khronos sample viewer does it);
//                 the diffuse base is layered under it at the film's largest reflectance
//   diffuse transmission (HAS_DIFFUSE_TRANSMISSION, KHR_materials_diffuse_transmission) that
//                 share of the diffuse base leaves through the back, Lambertian and tinted, under
//                 the same albedo scaling (a thin sheet: no volume)
//   dispersion    (HAS_DISPERSION, KHR_materials_dispersion) no lobe of its own: path.h sets a
//                 dispersive volume's ior to that of the path's wavelength (dispersive_ior)
// Below BSDF_DELTA_ALPHA the glossy lobes are perfect mirror and refraction (delta) lobes.
//
// Contract: bsdf_eval returns f(wo, wi) * |cos(n, wi)| and its pdf (solid angle) for the non-delta
// lobes. bsdf_sample returns f * |cos| / pdf for the direction it makes, with that pdf, or 0 when
// it makes none; for a delta lobe it sets *specular and returns the lobe's weight divided by its
// selection probability, which is then the pdf. Reflection is reciprocal; refraction carries
// radiance (wo is the side the path came from, towards the camera).
#ifndef SHARED_BSDF_H
#define SHARED_BSDF_H

#include "shared/types.h"
#include "shared/vec3.h"
#include "shared/rng.h"
#include "shared/bsdf_tables.h"

// The functions shading calls at every vertex (shade_vertex in path.h, sample_light in
// lights.h, bsdf_sample here) are inlined into their callers in the CPU megakernel with lanes
// (MEGA_LANES), where a call's arguments and results went through memory: 5 % of the
// 1 M-triangle scenes' time on Zen 4 (2026-12-03), for about
// 2 s more of a first, uncached kernel build. Elsewhere the compiler decides.
#ifdef MEGA_LANES
#define SHADE_INLINE inline __attribute__((always_inline))
#else
#define SHADE_INLINE inline
#endif

typedef struct {
    float3 base_color;           // linear base color: diffuse albedo, metal f0, transmission tint
    float metallic;
    float roughness;             // perceptual; GGX alpha = roughness^2
    float ior;                   // relative: the medium behind the surface over wo's medium
    float specular_factor;       // KHR_materials_specular; 0 makes a dielectric Lambertian
    float3 specular_color;       // KHR_materials_specular specularColorFactor
    float transmission;          // KHR_materials_transmission factor
    float thickness;             // KHR_materials_volume thickness; 0 = thin-walled
    float3 attenuation;          // KHR_materials_volume attenuationColor
    float attenuation_distance;  // INFINITY: no absorption
#ifdef HAS_CLEARCOAT
    float clearcoat;             // KHR_materials_clearcoat factor; 0: no coat
    float coat_roughness;        // perceptual
    float3 coat_normal;          // the coat's shading normal (world); 0: the shading normal
#endif
#ifdef HAS_SHEEN
    float3 sheen_color;          // KHR_materials_sheen sheenColorFactor; 0: no sheen
    float sheen_roughness;       // perceptual
#endif
#ifdef HAS_DIFFUSE_TRANSMISSION
    float diffuse_transmission;        // KHR_materials_diffuse_transmission factor; 0: none
    float3 diffuse_transmission_color;
#endif
#ifdef HAS_IRIDESCENCE
    float iridescence;           // KHR_materials_iridescence factor; 0: no film
    float iridescence_ior;       // the film's index of refraction
    float iridescence_thickness; // the film's thickness in nanometres
#endif
#ifdef HAS_ANISOTROPY
    float anisotropy;            // KHR_materials_anisotropy strength; 0: isotropic
    float2 aniso_rotation;       // cos, sin of the direction's angle from onb(n)'s t, when
                                 // aniso_dir is 0 (no tangent frame: the BSDF tests)
    float3 aniso_dir;            // the anisotropy direction (world), from the tangent frame
#endif
} SurfaceMaterial;

// The untextured material.
inline SurfaceMaterial surface_material(global const DeviceMaterial* m) {
    SurfaceMaterial s;
    s.base_color = m->base_color.xyz;
    s.metallic = m->params.x;
    s.roughness = m->params.y;
    s.ior = m->params.z;
    s.specular_factor = m->params.w;
    s.specular_color = m->specular.xyz;
    s.transmission = m->specular.w;
    s.thickness = m->alpha.z;
    s.attenuation = m->volume.xyz;
    s.attenuation_distance = m->volume.w;
#ifdef HAS_CLEARCOAT
    s.clearcoat = m->coat.x;
    s.coat_roughness = m->coat.y;
    s.coat_normal = (float3)(0.0f);
#endif
#ifdef HAS_SHEEN
    s.sheen_color = m->sheen.xyz;
    s.sheen_roughness = m->sheen.w;
#endif
#ifdef HAS_DIFFUSE_TRANSMISSION
    s.diffuse_transmission = m->diffuse_transmission.w;
    s.diffuse_transmission_color = m->diffuse_transmission.xyz;
#endif
#ifdef HAS_IRIDESCENCE
    s.iridescence = m->iridescence.x;
    s.iridescence_ior = m->iridescence.y;
    s.iridescence_thickness = m->iridescence.w;
#endif
#ifdef HAS_ANISOTROPY
    s.anisotropy = m->aniso.x;
    s.aniso_rotation = m->aniso.yz;
    s.aniso_dir = (float3)(0.0f);
#endif
    return s;
}

// Seen from inside its volume, the interface's relative index of refraction inverts (and the
// clear coat is on the other side).
inline void material_from_inside(SurfaceMaterial* m) {
    m->ior = 1.0f / m->ior;
#ifdef HAS_CLEARCOAT
    m->clearcoat = 0.0f;
#endif
#ifdef HAS_SHEEN
    m->sheen_color = (float3)(0.0f);
#endif
#ifdef HAS_IRIDESCENCE
    m->iridescence = 0.0f;
#endif
}

// Beer–Lambert transmittance over a distance t inside the material's volume: attenuationColor
// is what remains after attenuationDistance.
inline float3 volume_transmittance(const SurfaceMaterial* m, float t) {
    if (!(m->attenuation_distance > 0.0f && m->attenuation_distance < INFINITY)) {
        return (float3)(1.0f);
    }
    return pow(fmax(m->attenuation, 0.0f), (float3)(t / m->attenuation_distance));
}

#ifdef HAS_DISPERSION
// KHR_materials_dispersion: a transmitting volume's index of refraction varies with the
// wavelength. A path that meets such a volume picks one wavelength there (path.h) and carries
// from then on what light of that wavelength carries, times the wavelength's RGB response over
// its pdf; every RGB channel's response integrates to 1, so the weight is 1 on average and a
// white, non-dispersive path keeps its colour and energy in expectation.

// The spec's index at wavelength lambda (nm) for index ior at 587.56 nm and dispersion
// 20 / Abbe number (Cauchy's two terms fitted to the Abbe number).
inline float dispersive_ior(float ior, float dispersion, float lambda) {
    float k = (ior - 1.0f) * dispersion * (1.0f / 20.0f);
    return fmax(ior + k * (523655.0f / (lambda * lambda) - 1.5168f), 1.0f);
}

// Wavelengths are sampled on [360, 830] nm by pbrt-v4's visible-wavelength density,
// 0.0039398042 / cosh²(0.0072 (lambda - 538)), inverted in closed form.
inline float sample_wavelength(float u) {
    return 538.0f - 138.888889f * atanh(0.85691062f - 1.82750197f * u);
}

inline float wavelength_pdf(float lambda) {
    float c = cosh(0.0072f * (lambda - 538.0f));
    return 0.0039398042f / (c * c);
}

// A lobe of Wyman, Sloan and Shirley's (2013) fit of the CIE 1931 observer.
inline float cie_lobe(float x, float mu, float s1, float s2) {
    float t = (x - mu) / (x < mu ? s1 : s2);
    return exp(-0.5f * t * t);
}

// The linear sRGB response to wavelength lambda: the CIE 1931 matching functions in linear
// sRGB, negative parts cut, each channel scaled to integrate to 1 over [360, 830] nm
// (tests/bsdf.rs checks the scales by quadrature).
inline float3 wavelength_rgb(float lambda) {
    float x = 1.056f * cie_lobe(lambda, 599.8f, 37.9f, 31.0f) +
              0.362f * cie_lobe(lambda, 442.0f, 16.0f, 26.7f) -
              0.065f * cie_lobe(lambda, 501.1f, 20.4f, 26.2f);
    float y = 0.821f * cie_lobe(lambda, 568.8f, 46.9f, 40.5f) +
              0.286f * cie_lobe(lambda, 530.9f, 16.3f, 31.1f);
    float z = 1.217f * cie_lobe(lambda, 437.0f, 11.8f, 36.0f) +
              0.681f * cie_lobe(lambda, 459.0f, 26.0f, 13.8f);
    float3 rgb = (float3)(3.2404542f * x - 1.5371385f * y - 0.4985314f * z,
                          -0.9692660f * x + 1.8760108f * y + 0.0415560f * z,
                          0.0556434f * x - 0.2040259f * y + 1.0572252f * z);
    return fmax(rgb, 0.0f) * (float3)(0.00567610f, 0.00866617f, 0.00914323f);
}
#endif

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

// The material's lobes as seen from one wo.
typedef struct {
    float roughness;   // clamped perceptual roughness (the energy tables' row)
    float alpha;       // GGX alpha
    float eta;         // relative index of refraction
    float metallic;    // clamped inputs
    float transmission;
    float specular;    // specularFactor
    bool delta;        // glossy lobes are perfect mirror / refraction
    bool thin;         // a thin wall: transmission is the reflection mirrored through it
    bool straight;     // a volume of eta close to 1: every microfacet refracts wo straight on,
                       // so its transmission is a delta lobe along -wo whatever the roughness
    float3 f0;         // dielectric normal-incidence reflectance before specularFactor
    float f0_layer;    // max3(f0): the channel whose specular albedo scales the diffuse layer
    float ms_layer;    // Kulla–Conty colour of the dielectric layer at f0_layer
    float3 diffuse;    // Lambertian lobe: base color x its share x (1 - A(mu_o)) / (1 - A_avg)
    float3 ms;         // multiple scattering: its colour x (1 - E(mu_o)) / (1 - E_avg)
    float p_diffuse;   // probability of the cosine-sampled lobes (diffuse and multiple scattering)
#ifdef HAS_DIFFUSE_TRANSMISSION
    float3 dtrans;     // diffuse transmission: its color x its share x (1 - A(mu_o)) / (1 - A_avg)
    float p_dtrans;    // probability of sampling it (cosine-distributed, below the surface)
#endif
    float albedo;      // estimated albedo at wo of all lobes (luminance)
#ifdef HAS_CLEARCOAT
    float coat;        // clamped clearcoat factor
    float coat_roughness;
#endif
#ifdef HAS_SHEEN
    float3 sheen;           // clamped sheen color; 0: no sheen
    float sheen_max;        // s = max3(sheen)
    float sheen_roughness;  // clamped to [SHEEN_MIN_ROUGHNESS, 1]
    float sheen_o;          // s E_sh(mu_o): what the sheen reflects at wo
#endif
#ifdef HAS_IRIDESCENCE
    float iridescence;  // clamped factor; 0: no film
    float film_ior;
    float film_thickness;  // nanometres
#endif
#ifdef HAS_ANISOTROPY
    bool anisotropic;  // alpha_x > alpha_y, the lobe not a delta
    float alpha_x;     // along the anisotropy direction (the frame's t)
    float alpha_y;     // across it
    float aniso_r;     // the energy tables' base roughness sqrt(alpha_y) (unclamped) and
    float aniso_u;     // stretch (sqrt(alpha_x) - aniso_r) / (1 - aniso_r)
#endif
} BsdfLobes;

// The GGX distribution, Smith's Lambda and visible-normal sampling of the glossy lobes.
inline float lobe_d(const BsdfLobes* l, float3 h) {
#ifdef HAS_ANISOTROPY
    return ggx_d_aniso(h, l->alpha_x, l->alpha_y);
#else
    return ggx_d(h, l->alpha * l->alpha);
#endif
}

inline float lobe_lambda(const BsdfLobes* l, float3 w) {
#ifdef HAS_ANISOTROPY
    return ggx_lambda_aniso(w, l->alpha_x, l->alpha_y);
#else
    return ggx_lambda(w, l->alpha * l->alpha);
#endif
}

inline float3 lobe_sample_vndf(const BsdfLobes* l, float3 wo, float u1, float u2) {
#ifdef HAS_ANISOTROPY
    return ggx_sample_vndf_aniso(wo, l->alpha_x, l->alpha_y, u1, u2);
#else
    return ggx_sample_vndf(wo, l->alpha, u1, u2);
#endif
}

// A(mu): what the dielectric specular layer reflects at one cosine, single and multiple
// scattering (e = (E, E_s) there), times specularFactor.
inline float layer_albedo(const BsdfLobes* l, float2 e) {
    float f0 = l->f0_layer;
    return l->specular * (f0 * e.x + (1.0f - f0) * e.y + l->ms_layer * (1.0f - e.x));
}

// 8-point Gauss–Legendre quadrature on [0, 1] of the cosine-weighted means 2∫g(mu) mu dmu of
// the layers' cross terms: sum GL_W[k >> 1] * mu * g(mu) over mu = gl_mu(k), k = 0..7.
constant float GL_X[4] = {0.1834346425f, 0.5255324099f, 0.7966664774f, 0.9602898565f};
constant float GL_W[4] = {0.3626837834f, 0.3137066459f, 0.2223810345f, 0.1012285363f};
inline float gl_mu(int k) {
    return 0.5f + ((k & 1) ? 0.5f : -0.5f) * GL_X[k >> 1];
}

#ifdef HAS_ANISOTROPY

// (E, E_s) of the anisotropic lobe at local w (the frame's t along the anisotropy direction):
// ANISO_E / ANISO_E_SCHLICK as GGX_E / GGX_E_SCHLICK, but per direction, multilinear over
// cos(theta) (0, 1/16 .. 1), cos² of the azimuth from the direction (0, 1/4 .. 1), the base
// perceptual roughness r (0, 1/8 .. 1) and the stretch (sqrt(alpha_x) - r) / (1 - r)
// (0, 1/4 .. 1).
inline float2 aniso_energy(const BsdfLobes* l, float3 w) {
    float r2 = w.x * w.x + w.y * w.y;
    float x[4] = {clamp(w.z, 0.0f, 1.0f) * 16.0f, (r2 > 0.0f ? w.x * w.x / r2 : 1.0f) * 4.0f,
                  l->aniso_r * 8.0f, l->aniso_u * 4.0f};
    int i[4];
    float f[4];
    int top[4] = {15, 3, 7, 3};
    for (int d = 0; d < 4; ++d) {
        i[d] = clamp((int)x[d], 0, top[d]);
        f[d] = clamp(x[d] - (float)i[d], 0.0f, 1.0f);
    }
    float2 sum = (float2)(0.0f);
    for (int k = 0; k < 16; ++k) {
        int m = i[0] + (k & 1);
        int c = i[1] + ((k >> 1) & 1);
        int r = i[2] + ((k >> 2) & 1);
        int t = i[3] + ((k >> 3) & 1);
        float wt = ((k & 1) ? f[0] : 1.0f - f[0]) * (((k >> 1) & 1) ? f[1] : 1.0f - f[1]) *
                   (((k >> 2) & 1) ? f[2] : 1.0f - f[2]) * (((k >> 3) & 1) ? f[3] : 1.0f - f[3]);
        int idx = ((t * 9 + r) * 5 + c) * 17 + m;
        sum += wt * (float2)(ANISO_E[idx], ANISO_E_SCHLICK[idx]);
    }
    // The tables are an upper envelope of the albedo, raised where it is concave (tests/bsdf.rs,
    // aniso_tables), and may exceed 1 there.
    return fmin(sum, 1.0f);
}

// The cosine-weighted hemisphere means of aniso_energy (ANISO_E_AVG: those of the tables as
// read, bilinear over the base roughness and stretch, which commutes with the mean), so that
// the multiple-scattering lobe integrates to at most 1 - E_avg.
inline float2 aniso_energy_avg(const BsdfLobes* l) {
    float x = l->aniso_r * 8.0f;
    float y = l->aniso_u * 4.0f;
    int i = clamp((int)x, 0, 7);
    int j = clamp((int)y, 0, 3);
    float fx = x - (float)i;
    float fy = y - (float)j;
    int k = j * 9 + i;
    float2 a = mix((float2)(ANISO_E_AVG[k], ANISO_E_SCHLICK_AVG[k]),
                   (float2)(ANISO_E_AVG[k + 1], ANISO_E_SCHLICK_AVG[k + 1]), fx);
    float2 b = mix((float2)(ANISO_E_AVG[k + 9], ANISO_E_SCHLICK_AVG[k + 9]),
                   (float2)(ANISO_E_AVG[k + 10], ANISO_E_SCHLICK_AVG[k + 10]), fx);
    return mix(a, b, fy);
}
#endif

#ifdef HAS_SHEEN
// Sheen roughness below this is taken as this (narrower lobes are not tabulated).
#define SHEEN_MIN_ROUGHNESS (3.0f / 32.0f)

// A sheen table at cos(theta_o) and perceptual roughness, bilinear in (sqrt(cos), roughness).
inline float sheen_table(constant float* table, float cos_o, float roughness) {
    float x = sqrt(clamp(cos_o, 0.0f, 1.0f)) * 32.0f;
    float y = clamp(roughness, 0.0f, 1.0f) * 32.0f;
    int i = min((int)x, 31);
    int j = min((int)y, 31);
    int k = j * 33 + i;
    float fx = x - (float)i;
    return mix(mix(table[k], table[k + 1], fx), mix(table[k + 33], table[k + 34], fx),
               y - (float)j);
}

// What the sheen reflects at cos(theta) = mu, by its strongest channel: s E_sh(mu).
inline float sheen_albedo(const BsdfLobes* l, float mu) {
    return l->sheen_max * sheen_table(SHEEN_E, mu, l->sheen_roughness);
}

// Estevez and Kulla's fitted Lambda of the sheen visibility at cos(theta) = c.
inline float sheen_lambda_fit(float x, float t) {
    float a = mix(21.5473f, 25.3245f, t);
    float b = mix(3.82987f, 3.32435f, t);
    float c = mix(0.19823f, 0.16801f, t);
    float d = mix(-1.97760f, -1.27393f, t);
    float e = mix(-4.32054f, -4.85967f, t);
    return a / (1.0f + b * pow(x, c)) + d * x + e;
}
inline float sheen_lambda(float c, float alpha) {
    float t = (1.0f - alpha) * (1.0f - alpha);
    return c < 0.5f ? exp(sheen_lambda_fit(c, t))
                    : exp(2.0f * sheen_lambda_fit(0.5f, t) - sheen_lambda_fit(1.0f - c, t));
}

// The sheen lobe's f * cos at local wo, wi (both above the surface): sheenColor D V cos_i
// k(mu_o) k(mu_i), D the Charlie distribution (2 + 1/alpha) sin^(1/alpha)(theta_h) / 2pi.
inline float3 sheen_eval(const BsdfLobes* l, float3 wo, float3 wi) {
    float alpha = l->sheen_roughness * l->sheen_roughness;
    float inv = 1.0f / alpha;
    float3 h = normalize(wo + wi);
    float sin2 = h.x * h.x + h.y * h.y;
    float d = (2.0f + inv) * pow(sin2, 0.5f * inv) * (0.5f * INV_PI_F);
    // V cos_i = cos_i / ((1 + Lambda_o + Lambda_i) 4 cos_o cos_i).
    float v = 1.0f / ((1.0f + sheen_lambda(wo.z, alpha) + sheen_lambda(wi.z, alpha)) * 4.0f * wo.z);
    float k = 1.0f / (fmax(1.0f, sheen_table(SHEEN_E_CHARLIE, wo.z, l->sheen_roughness)) *
                      fmax(1.0f, sheen_table(SHEEN_E_CHARLIE, wi.z, l->sheen_roughness)));
    return l->sheen * (d * v * k);
}

// What the sheen leaves of the glossy base lobes between cosines mu_o and mu_i:
// 1 - s max(E_sh(mu_o), E_sh(mu_i)).
inline float sheen_gloss_scale(const BsdfLobes* l, float mu_i) {
    if (!(l->sheen_max > 0.0f)) return 1.0f;
    return 1.0f - fmax(l->sheen_o, sheen_albedo(l, mu_i));
}

// The probability of sampling the sheen (cosine-distributed) among the sheen and the base.
inline float sheen_probability(const BsdfLobes* l) {
    return l->sheen_o > 0.0f ? l->sheen_o / (l->sheen_o + (1.0f - l->sheen_o) * l->albedo) : 0.0f;
}

// The cosine-weighted mean of the sheen over the specular layer, a_avg being the specular
// layer's: a_avg + s E_sh,avg - ∫ s E_sh A 2mu dmu (0 over a specularFactor 0 base).
inline float sheen_layer_albedo_avg(const BsdfLobes* l, float a_avg) {
    float cross = 0.0f;
    if (l->specular > 0.0f) {
        for (int k = 0; k < 8; ++k) {
            float mu = gl_mu(k);
            float a = layer_albedo(l, ggx_energy(mu, l->roughness));
            cross += GL_W[k >> 1] * mu * sheen_albedo(l, mu) * a;
        }
    }
    float y = l->sheen_roughness * 32.0f;
    int j = min((int)y, 31);
    float e_avg = mix(SHEEN_E_AVG[j], SHEEN_E_AVG[j + 1], y - (float)j);
    return a_avg + l->sheen_max * e_avg - cross;
}
#endif

// What the layers over the diffuse base but under the coat reflect at mu, a being the specular
// layer's albedo there: the sheen over the specular layer.
inline float under_coat_albedo(const BsdfLobes* l, float mu, float a) {
#ifdef HAS_SHEEN
    if (l->sheen_max > 0.0f) {
        float as = sheen_albedo(l, mu);
        return as + (1.0f - as) * a;
    }
#endif
    return a;
}

#ifdef HAS_CLEARCOAT
// The clear coat's normal-incidence reflectance (ior 1.5).
#define COAT_F0 0.04f

// What the clear coat reflects at cos(theta) = mu: GGX single scattering with Schlick's Fresnel,
// f0 E + (1 - f0) E_s; for a smooth coat the Fresnel itself.
inline float coat_albedo(float mu, float roughness) {
    if (roughness * roughness < BSDF_DELTA_ALPHA) {
        return COAT_F0 + (1.0f - COAT_F0) * schlick_weight(mu);
    }
    float2 e = ggx_energy(mu, roughness);
    return COAT_F0 * e.x + (1.0f - COAT_F0) * e.y;
}

// What coat and specular layer together reflect over the diffuse base at mu, a being the
// specular layer's albedo there.
inline float coated_layer_albedo(const BsdfLobes* l, float mu, float a) {
    float ac = l->coat * coat_albedo(mu, l->coat_roughness);
    return ac + (1.0f - ac) * a;
}

// Its cosine-weighted mean, a_avg being the mean of what lies under the coat: a_avg + c A_c,avg
// - c ∫A_c A 2mu dmu, the last term by quadrature (0 over a specularFactor 0 base, no sheen).
inline float coated_layer_albedo_avg(const BsdfLobes* l, float a_avg) {
    float ac_avg;
    if (l->coat_roughness * l->coat_roughness < BSDF_DELTA_ALPHA) {
        ac_avg = COAT_F0 + (1.0f - COAT_F0) * (1.0f / 21.0f);
    } else {
        float2 e = ggx_energy_avg(l->coat_roughness);
        ac_avg = COAT_F0 * e.x + (1.0f - COAT_F0) * e.y;
    }
    float cross = 0.0f;
    bool layered = l->specular > 0.0f;
#ifdef HAS_SHEEN
    layered = layered || l->sheen_max > 0.0f;
#endif
    if (layered) {
        for (int k = 0; k < 8; ++k) {
            float mu = gl_mu(k);
            float a = under_coat_albedo(l, mu, layer_albedo(l, ggx_energy(mu, l->roughness)));
            cross += GL_W[k >> 1] * mu * coat_albedo(mu, l->coat_roughness) * a;
        }
    }
    return a_avg + l->coat * (ac_avg - cross);
}
#endif

// The cosine-sampled lobes at wi (wi_cos > 0), f * cos: the diffuse base under the specular
// layer, scaled by (1 - A(mu_o)) (1 - A(mu_i)) / (1 - A_avg) (albedo scaling of the glTF
// appendix, made reciprocal: it integrates to exactly 1 - A(mu_o)), and the Kulla–Conty
// multiple-scattering lobe (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg) of the GGX reflection,
// times the clear coat's scaling of the glossy lobes, gs.
// What all layers over the diffuse base reflect towards local wi (wi.z > 0), and E there.
inline float layers_albedo_at(const BsdfLobes* l, float3 wi, float* e) {
    float wi_cos = wi.z;
#ifdef HAS_ANISOTROPY
    float2 e_i = l->anisotropic ? aniso_energy(l, wi) : ggx_energy(wi_cos, l->roughness);
#else
    float2 e_i = ggx_energy(wi_cos, l->roughness);
#endif
    float a_i = under_coat_albedo(l, wi_cos, layer_albedo(l, e_i));
#ifdef HAS_CLEARCOAT
    if (l->coat > 0.0f) a_i = coated_layer_albedo(l, wi_cos, a_i);
#endif
    *e = e_i.x;
    return a_i;
}

inline float3 cosine_lobes(const BsdfLobes* l, float3 wi, float gs) {
    float e_i;
    float a_i = layers_albedo_at(l, wi, &e_i);
    return (l->diffuse * (1.0f - a_i) + l->ms * ((1.0f - e_i) * gs)) * (wi.z * INV_PI_F);
}

#ifdef HAS_DIFFUSE_TRANSMISSION
// The diffuse transmission lobe at local wi below the surface (wi.z < 0), f * |cos|: the diffuse
// base's transmitted share under the same layering as its reflection, seen from the mirrored
// direction (reciprocal, and integrating to exactly its share of 1 - A(mu_o)).
inline float3 diffuse_transmission_lobe(const BsdfLobes* l, float3 wi) {
    float e_i;
    float a_i = layers_albedo_at(l, (float3)(wi.x, wi.y, -wi.z), &e_i);
    return l->dtrans * ((1.0f - a_i) * (-wi.z * INV_PI_F));
}
#endif

// The lobes at local wo (in the frame of bsdf_frame).
inline BsdfLobes bsdf_lobes(const SurfaceMaterial* m, float3 wo) {
    float cos_o = wo.z;
    BsdfLobes l;
    l.roughness = clamp(m->roughness, 0.0f, 1.0f);
    l.alpha = l.roughness * l.roughness;
    l.delta = l.alpha < BSDF_DELTA_ALPHA;
#ifdef HAS_ANISOTROPY
    // Anisotropy stretches the lobe along its direction. Its energy tables are the anisotropic
    // ones (aniso_energy); what else reads a roughness takes the geometric mean alpha (the
    // isotropic lobe of the same peak density).
    float s = clamp(m->anisotropy, 0.0f, 1.0f);
    l.alpha_x = mix(l.alpha, 1.0f, s * s);
    l.delta = l.alpha_x < BSDF_DELTA_ALPHA;
    l.alpha_y = fmax(l.alpha, BSDF_DELTA_ALPHA);
    l.alpha_x = fmax(l.alpha_x, BSDF_DELTA_ALPHA);
    l.anisotropic = s > 0.0f && !l.delta;
    l.aniso_r = l.roughness;
    l.aniso_u = l.roughness < 1.0f ? (sqrt(l.alpha_x) - l.roughness) / (1.0f - l.roughness) : 0.0f;
    if (l.anisotropic) {
        l.alpha = sqrt(l.alpha_x * l.alpha_y);
        l.roughness = sqrt(l.alpha);
    }
#endif
    l.eta = fmax(m->ior, 1e-3f);
    l.metallic = clamp(m->metallic, 0.0f, 1.0f);
    l.transmission = clamp(m->transmission, 0.0f, 1.0f);
    l.specular = clamp(m->specular_factor, 0.0f, 1.0f);
    l.thin = m->thickness <= 0.0f;
    l.straight = !l.thin && fabs(l.eta - 1.0f) < 1e-3f;
    float r = (l.eta - 1.0f) / (l.eta + 1.0f);
    l.f0 = fmin(r * r * m->specular_color, 1.0f);
    l.f0_layer = bsdf_max3(l.f0);
#ifdef HAS_IRIDESCENCE
    // The diffuse base lies under the film at its largest reflectance (any thickness), so it
    // never takes light the film reflects. A vanishing film leaves the plain material.
    l.film_thickness = fmax(m->iridescence_thickness, 0.0f);
    l.iridescence = l.film_thickness < FILM_MIN_THICKNESS ? 0.0f : clamp(m->iridescence, 0.0f, 1.0f);
    l.film_ior = fmax(m->iridescence_ior, 1.0f);
    if (l.iridescence > 0.0f) {
        float f_max = fmax(l.f0_layer, film_max_reflectance(l.film_ior, l.f0_layer));
        l.f0_layer = mix(l.f0_layer, f_max, l.iridescence);
    }
#endif
    float dielectric = 1.0f - l.metallic;
    float opaque = dielectric * (1.0f - l.transmission);
    float2 e_o = ggx_energy(cos_o, l.roughness);
    float2 e_avg = ggx_energy_avg(l.roughness);
#ifdef HAS_ANISOTROPY
    if (l.anisotropic) {
        e_o = aniso_energy(&l, wo);
        e_avg = aniso_energy_avg(&l);
    }
#endif
    // Multiple scattering of the metal and of the opaque dielectric's reflection (transmitting
    // interfaces are single-scattering only); a delta lobe loses nothing.
    l.ms_layer = 0.0f;
    l.ms = (float3)(0.0f);
    if (!l.delta && e_avg.x < 0.9999f) {
        l.ms_layer = multiple_scattering_color((float3)(l.f0_layer), e_avg.x).x;
        float3 color = l.metallic * multiple_scattering_color(m->base_color, e_avg.x) +
                       (opaque * l.specular) * multiple_scattering_color(l.f0, e_avg.x);
        l.ms = color * ((1.0f - e_o.x) / (1.0f - e_avg.x));
    }
    float a_o = layer_albedo(&l, e_o);
    float a_avg = layer_albedo(&l, e_avg);
#ifdef HAS_SHEEN
    l.sheen = clamp(m->sheen_color, 0.0f, 1.0f);
    l.sheen_max = bsdf_max3(l.sheen);
    l.sheen_roughness = clamp(m->sheen_roughness, SHEEN_MIN_ROUGHNESS, 1.0f);
    l.sheen_o = 0.0f;
    if (l.sheen_max > 0.0f) {
        l.sheen_o = sheen_albedo(&l, cos_o);
        a_avg = sheen_layer_albedo_avg(&l, a_avg);
        a_o = l.sheen_o + (1.0f - l.sheen_o) * a_o;
    }
#endif
#ifdef HAS_CLEARCOAT
    l.coat = clamp(m->clearcoat, 0.0f, 1.0f);
    l.coat_roughness = clamp(m->coat_roughness, 0.0f, 1.0f);
    if (l.coat > 0.0f) {
        a_o = coated_layer_albedo(&l, cos_o, a_o);
        a_avg = coated_layer_albedo_avg(&l, a_avg);
    }
#endif
    l.diffuse = a_avg < 1.0f ? (opaque * ((1.0f - a_o) / (1.0f - a_avg))) * m->base_color
                             : (float3)(0.0f);
    // Pick lobes by their estimated albedo (luminance); inside a volume the dielectric reflects
    // by the smooth-interface Fresnel, total internal reflection included.
    float q = l.thin || l.eta >= 1.0f ? e_o.y : dielectric_schlick(cos_o, l.eta) * e_o.x;
    float3 spec_dielectric = l.specular * (l.f0 * e_o.x + (1.0f - l.f0) * q);
    float3 spec_metal = m->base_color * e_o.x + (1.0f - m->base_color) * e_o.y;
    float d_est = luminance(l.diffuse) * (1.0f - a_avg) + luminance(l.ms) * (1.0f - e_avg.x);
    float r_est = luminance(dielectric * spec_dielectric + l.metallic * spec_metal);
    float t_est = dielectric * l.transmission * (1.0f - bsdf_max3(spec_dielectric)) *
                  luminance(m->base_color);
#ifdef HAS_DIFFUSE_TRANSMISSION
    // KHR_materials_diffuse_transmission: that share of the diffuse base goes through, tinted.
    float dt = clamp(m->diffuse_transmission, 0.0f, 1.0f);
    l.dtrans = (float3)(0.0f);
    l.p_dtrans = 0.0f;
    float dt_est = 0.0f;
    if (dt > 0.0f && a_avg < 1.0f) {
        l.dtrans = (opaque * dt * ((1.0f - a_o) / (1.0f - a_avg))) *
                   clamp(m->diffuse_transmission_color, 0.0f, 1.0f);
        l.diffuse *= 1.0f - dt;
        d_est = luminance(l.diffuse) * (1.0f - a_avg) + luminance(l.ms) * (1.0f - e_avg.x);
        dt_est = luminance(l.dtrans) * (1.0f - a_avg);
    }
    float total = d_est + r_est + t_est + dt_est;
    l.p_dtrans = total > 0.0f ? dt_est / total : 0.0f;
#else
    float total = d_est + r_est + t_est;
#endif
    l.p_diffuse = total > 0.0f ? d_est / total : 0.0f;
    l.albedo = total;
    return l;
}

#ifdef HAS_CLEARCOAT
// The clear coat as seen from one wo: its frame, its reflection at wo and its sampling share.
typedef struct {
    float c;          // clearcoat factor; 0: no coat
    float roughness;  // perceptual
    float alpha;
    bool delta;       // a perfect mirror
    float3 n, t, b;   // the coat's frame
    float a_o;        // c A_c(mu_o): what it reflects at wo
    float p;          // probability of sampling it
} CoatLobe;

inline CoatLobe coat_lobe(const SurfaceMaterial* m, const BsdfLobes* l, float3 n, float3 wo) {
    CoatLobe c;
    c.c = l->coat;
    c.roughness = l->coat_roughness;
    c.alpha = c.roughness * c.roughness;
    c.delta = c.alpha < BSDF_DELTA_ALPHA;
    c.n = dot(m->coat_normal, m->coat_normal) > 0.0f ? m->coat_normal : n;
    onb(c.n, &c.t, &c.b);
    float cos_o = dot(wo, c.n);
    c.a_o = c.c > 0.0f && cos_o > 0.0f ? c.c * coat_albedo(cos_o, c.roughness) : 0.0f;
    c.p = c.a_o > 0.0f ? c.a_o / (c.a_o + (1.0f - c.a_o) * l->albedo) : 0.0f;
    return c;
}

// What the coat leaves of the glossy lobes between wo and wi: 1 - c max(A_c(mu_o), A_c(mu_i)).
inline float coat_gloss_scale(const CoatLobe* c, float3 wi) {
    if (!(c->c > 0.0f)) return 1.0f;
    float a_i = c->c * coat_albedo(fabs(dot(wi, c->n)), c->roughness);
    return 1.0f - fmax(c->a_o, a_i);
}

// The coat's reflection f * cos at (wo, wi) and its visible-normal pdf, for a rough coat.
inline float coat_eval(const CoatLobe* c, float3 wo_world, float3 wi_world, float* pdf) {
    *pdf = 0.0f;
    float3 wo = (float3)(dot(wo_world, c->t), dot(wo_world, c->b), dot(wo_world, c->n));
    float3 wi = (float3)(dot(wi_world, c->t), dot(wi_world, c->b), dot(wi_world, c->n));
    if (c->delta || !(c->c > 0.0f) || wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    float a2 = c->alpha * c->alpha;
    float3 h = normalize(wo + wi);
    float d = ggx_d(h, a2);
    float lambda_o = ggx_lambda(wo, a2);
    float g2 = 1.0f / (1.0f + lambda_o + ggx_lambda(wi, a2));
    float fresnel = COAT_F0 + (1.0f - COAT_F0) * schlick_weight(dot(wo, h));
    *pdf = 0.25f * d / ((1.0f + lambda_o) * wo.z);
    return c->c * fresnel * 0.25f * d * g2 / wo.z;
}
#endif

// Reflectance and transmittance of the glossy layer at a microfacet seen at cos_oh from wo. A
// thin wall has two faces: light passing between them reflects 2F / (1 + F) in all and
// transmits (1 - F) / (1 + F).
inline void bsdf_gloss(const SurfaceMaterial* m, const BsdfLobes* l, float cos_oh, float3* refl,
                       float3* trans) {
    float sw = l->thin ? schlick_weight(cos_oh) : dielectric_schlick(cos_oh, l->eta);
    float3 fr = l->f0 + (1.0f - l->f0) * sw;
#ifdef HAS_IRIDESCENCE
    // The film over the dielectric (its f0 with the specular color), seen from outside.
    if (l->iridescence > 0.0f) {
        fr = mix(fr, film_fresnel(cos_oh, l->film_ior, l->film_thickness, l->f0), l->iridescence);
    }
#endif
    float3 fr_trans = fr;
    float3 fr_refl = fr;
    if (l->thin && l->transmission > 0.0f) {
        fr_trans = 2.0f * fr / (1.0f + fr);
        fr_refl = mix(fr, fr_trans, l->transmission);
    }
    float3 metal = m->base_color + (1.0f - m->base_color) * schlick_weight(cos_oh);
#ifdef HAS_IRIDESCENCE
    // The film over the metal (its f0 the base color).
    if (l->iridescence > 0.0f && l->metallic > 0.0f) {
        metal = mix(metal, film_fresnel(cos_oh, l->film_ior, l->film_thickness, m->base_color),
                    l->iridescence);
    }
#endif
    float dielectric = 1.0f - l->metallic;
    *refl = (dielectric * l->specular) * fr_refl + l->metallic * metal;
    bool tir = !l->thin && refracted_cos2(cos_oh, l->eta) <= 0.0f;
    *trans = tir ? (float3)(0.0f)
                 : (dielectric * l->transmission * (1.0f - l->specular * bsdf_max3(fr_trans))) *
                       m->base_color;
}

// Whether the surface lets light straight through (a smooth thin wall that transmits), so that
// shadow rays pass it, tinted by thin_wall_transmittance.
inline bool bsdf_passes_straight(const SurfaceMaterial* m) {
    return m->transmission > 0.0f && m->thickness <= 0.0f && m->metallic < 1.0f &&
           bsdf_alpha_max(m) < BSDF_DELTA_ALPHA;
}

// What a smooth thin wall lets straight through at cos(theta) = cos_o: the expected weight of
// bsdf_sample's straight-through lobe.
inline float3 thin_wall_transmittance(const SurfaceMaterial* m, float cos_o) {
    BsdfLobes l = bsdf_lobes(m, (float3)(sqrt(fmax(1.0f - cos_o * cos_o, 0.0f)), 0.0f, cos_o));
    float3 refl, trans;
    bsdf_gloss(m, &l, cos_o, &refl, &trans);
#ifdef HAS_CLEARCOAT
    trans *= 1.0f - l.coat * coat_albedo(cos_o, l.coat_roughness);
#endif
#ifdef HAS_SHEEN
    trans *= sheen_gloss_scale(&l, cos_o);
#endif
    return trans;
}

// Probability of reflecting (rather than transmitting) at a sampled microfacet.
inline float reflect_probability(float3 refl, float3 trans) {
    float r = luminance(refl);
    float t = luminance(trans);
    return r + t > 0.0f ? r / (r + t) : 1.0f;
}

// The probability of the cosine-sampled lobes (diffuse, multiple scattering and diffuse
// transmission).
inline float lobes_p_cosine(const BsdfLobes* l) {
#ifdef HAS_DIFFUSE_TRANSMISSION
    return l->p_diffuse + l->p_dtrans;
#else
    return l->p_diffuse;
#endif
}

// The base lobes (all but the coat) at local wo, wi: f * cos with the glossy ones scaled by gs,
// and their mixture pdf.
inline float3 base_eval(const SurfaceMaterial* m, const BsdfLobes* l, float3 wo, float3 wi,
                        float gs, float* pdf) {
    float3 f = (float3)(0.0f);
    float p = 0.0f;
    if (wi.z > 0.0f) {
        f = cosine_lobes(l, wi, gs);
        p = l->p_diffuse * (wi.z * INV_PI_F);
    }
#ifdef HAS_DIFFUSE_TRANSMISSION
    else if (l->p_dtrans > 0.0f) {
        f = diffuse_transmission_lobe(l, wi);
        p = l->p_dtrans * (-wi.z * INV_PI_F);
    }
#endif
    float p_gloss = 1.0f - lobes_p_cosine(l);
    if (l->delta || !(p_gloss > 0.0f)) {
        *pdf = p;
        return f;
    }
    float lambda_o = lobe_lambda(l, wo);
    float g1 = 1.0f / (1.0f + lambda_o);
    float inv_cos_o = 1.0f / fmax(wo.z, 1e-20f);
    float3 refl, trans;
    if (wi.z < 0.0f && l->straight) {
        // Straight transmission is a delta lobe: nothing to evaluate.
    } else if (wi.z > 0.0f || l->thin) {
        // Reflection, or thin-wall transmission: the reflection mirrored through the surface.
        float3 wr = (float3)(wi.x, wi.y, fabs(wi.z));
        float3 h = normalize(wo + wr);
        bsdf_gloss(m, l, dot(wo, h), &refl, &trans);
        float d = lobe_d(l, h);
        float g2 = 1.0f / (1.0f + lambda_o + lobe_lambda(l, wr));
        float pr = reflect_probability(refl, trans);
        float3 c = wi.z > 0.0f ? refl : trans;
        f += c * (0.25f * d * g2 * inv_cos_o) * gs;
        p += p_gloss * (wi.z > 0.0f ? pr : 1.0f - pr) * (0.25f * g1 * d * inv_cos_o);
    } else {
        // Refraction through the generalized half vector h ~ wo + eta wi (Walter et al. 2007).
        float3 h = wo + l->eta * wi;
        float len = length(h);
        if (!(len > 0.0f)) {
            *pdf = p;
            return f;
        }
        h = (h.z < 0.0f ? -h : h) / len;
        float cos_oh = dot(wo, h);
        float cos_ih = dot(wi, h);
        if (cos_oh > 0.0f && cos_ih < 0.0f) {
            bsdf_gloss(m, l, cos_oh, &refl, &trans);
            float d = lobe_d(l, h);
            float g2 = 1.0f / (1.0f + lambda_o + lobe_lambda(l, wi));
            // dwh/dwi; |wo.h + eta wi.h| = len.
            float jacobian = l->eta * l->eta * -cos_ih / (len * len);
            float vndf = g1 * d * cos_oh * inv_cos_o;
            // Radiance crossing into a medium eta times denser is compressed by eta^2.
            f += trans * (vndf * jacobian * g2 / g1) / (l->eta * l->eta) * gs;
            p += p_gloss * (1.0f - reflect_probability(refl, trans)) * vndf * jacobian;
        }
    }
    *pdf = p;
    return f;
}

#ifdef LAMBERT_ONLY
// Every material of the scene is an opaque dielectric with no specular layer (specularFactor 0,
// metallic 0, no transmission, coat or sheen): the BSDF above reduces exactly to the Lambertian
// base_color / pi, sampled by its cosine, and is evaluated as such, for every lane width
// (shared/vec3.h):
//   f##lambert_eval(base, n, wo, wi, *pdf)  the BSDF times the cosine at wi, and the pdf of
//       sampling wi; 0 where wo or wi is below the surface;
//   f##lambert_sample(base, n, wo, u1, u2, *wi, *weight)  a direction by the cosine around n
//       from the numbers u1, u2 and its pdf, returned, with the BSDF times the cosine over the
//       pdf in *weight (0, with pdf 0, where wo is below the surface or the direction is not
//       above it; *wi is then n where the local sample is not above). The pdf is that of the
//       direction as evaluated (cos(n, wi) / pi), so that the weight is exact; wi is unit within
//       rounding (an orthonormal frame and a unit vector in it): not normalized again.
#define DEFINE_LAMBERT_MATHS(Q, f, F, I, U, V, v)                                                 \
    Q V f##lambert_eval(V base, V n, V wo, V wi, F* pdf) {                                         \
        F cos_i = v##_dot(wi, n);                                                                  \
        I lit = (v##_dot(wo, n) > 0.0f) & (cos_i > 0.0f);                                          \
        F value = cos_i * INV_PI_F;                                                                \
        *pdf = select((F)(0.0f), value, lit);                                                      \
        return v##_select(v##_splat((F)(0.0f)), v##_scale(base, value), lit);                      \
    }                                                                                              \
    Q F f##lambert_sample(V base, V n, V wo, F u1, F u2, V* wi, V* weight) {                       \
        I ok = !(v##_dot(wo, n) <= 0.0f);                                                          \
        V around = f##sample_cosine(u1, u2);                                                       \
        ok = ok & (around.z > 0.0f);                                                               \
        V t, b;                                                                                    \
        f##onb(n, &t, &b);                                                                         \
        V world = v##_add(v##_add(v##_scale(t, around.x), v##_scale(b, around.y)),                 \
                          v##_scale(n, around.z));                                                 \
        *wi = v##_select(n, world, ok);                                                            \
        F cos_i = v##_dot(*wi, n);                                                                 \
        ok = ok & (cos_i > 0.0f);                                                                  \
        *weight = v##_select(v##_splat((F)(0.0f)), base, ok);                                      \
        return select((F)(0.0f), cos_i * INV_PI_F, ok);                                            \
    }

DEFINE_LAMBERT_MATHS(SHADE_INLINE, , float, int, uint, float3, f3)

inline float3 bsdf_eval(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 wi_world,
                        float* pdf) {
    return lambert_eval(m->base_color, n, wo_world, wi_world, pdf);
}

SHADE_INLINE float3 bsdf_sample(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 u,
                                float3* wi_world, float* pdf, bool* specular) {
    *specular = false;
    float3 weight;
    *pdf = lambert_sample(m->base_color, n, wo_world, u.x, u.y, wi_world, &weight);
    return weight;
}
#else
inline float3 bsdf_eval(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 wi_world,
                        float* pdf) {
    *pdf = 0.0f;
    float3 t, b;
    bsdf_frame(m, n, &t, &b);
    float3 wo = (float3)(dot(wo_world, t), dot(wo_world, b), dot(wo_world, n));
    float3 wi = (float3)(dot(wi_world, t), dot(wi_world, b), dot(wi_world, n));
#ifdef HAS_DIFFUSE_TRANSMISSION
    bool passes = m->transmission > 0.0f || m->diffuse_transmission > 0.0f;
#else
    bool passes = m->transmission > 0.0f;
#endif
    if (wo.z <= 0.0f || wi.z == 0.0f || (wi.z < 0.0f && !passes)) {
        return (float3)(0.0f);
    }
    BsdfLobes l = bsdf_lobes(m, wo);
#if defined(HAS_CLEARCOAT) || defined(HAS_SHEEN)
    // The coat over the sheen over the base: each scales the glossy lobes under it and is
    // sampled by its share.
    float cs = 1.0f;
    float q_coat = 0.0f;
    float p_coat = 0.0f;
    float3 f_coat = (float3)(0.0f);
    bool layered = false;
#ifdef HAS_CLEARCOAT
    if (l.coat > 0.0f) {
        layered = true;
        CoatLobe c = coat_lobe(m, &l, n, wo_world);
        cs = coat_gloss_scale(&c, wi_world);
        f_coat = coat_eval(&c, wo_world, wi_world, &p_coat);
        q_coat = c.p;
    }
#endif
    float ss = 1.0f;
    float q_sheen = 0.0f;
    float p_sheen = 0.0f;
    float3 f_sheen = (float3)(0.0f);
#ifdef HAS_SHEEN
    if (l.sheen_max > 0.0f) {
        layered = true;
        ss = sheen_gloss_scale(&l, fabs(wi.z));
        q_sheen = sheen_probability(&l);
        if (wi.z > 0.0f) {
            f_sheen = sheen_eval(&l, wo, wi);
            p_sheen = wi.z * INV_PI_F;
        }
    }
#endif
    if (layered) {
        float p_base;
        float3 f = base_eval(m, &l, wo, wi, cs * ss, &p_base) + f_sheen * cs + f_coat;
        *pdf = (1.0f - q_coat) * ((1.0f - q_sheen) * p_base + q_sheen * p_sheen) + q_coat * p_coat;
        return f;
    }
#endif
    return base_eval(m, &l, wo, wi, 1.0f, pdf);
}

SHADE_INLINE float3 bsdf_sample(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 u,
                                float3* wi_world, float* pdf, bool* specular) {
    *pdf = 0.0f;
    *specular = false;
    *wi_world = n;
    float3 t, b;
    bsdf_frame(m, n, &t, &b);
    float3 wo = (float3)(dot(wo_world, t), dot(wo_world, b), dot(wo_world, n));
    if (wo.z <= 0.0f) return (float3)(0.0f);
    BsdfLobes l = bsdf_lobes(m, wo);
    float3 wi;
#ifdef HAS_CLEARCOAT
    // The share of the base lobes (all but the coat).
    float p_base = 1.0f;
    CoatLobe c;
    c.c = 0.0f;
    if (l.coat > 0.0f) {
        c = coat_lobe(m, &l, n, wo_world);
        if (u.x < c.p) {
            // The coat: a visible microfacet of its normal distribution, in its own frame.
            float3 wo_c = (float3)(dot(wo_world, c.t), dot(wo_world, c.b), dot(wo_world, c.n));
            float uc = fmin(u.x / c.p, 0x1.fffffep-1f);
            float3 h = c.delta ? (float3)(0.0f, 0.0f, 1.0f) : ggx_sample_vndf(wo_c, c.alpha, uc, u.y);
            float3 wi_c = 2.0f * dot(wo_c, h) * h - wo_c;
            if (wi_c.z <= 0.0f) return (float3)(0.0f);
            *wi_world = normalize(wi_c.x * c.t + wi_c.y * c.b + wi_c.z * c.n);
            if (c.delta) {
                *pdf = c.p;
                *specular = true;
                return (float3)(c.c * (COAT_F0 + (1.0f - COAT_F0) * schlick_weight(wo_c.z)) / c.p);
            }
            float3 f = bsdf_eval(m, n, wo_world, *wi_world, pdf);
            if (!(*pdf > 0.0f)) {
                *pdf = 0.0f;
                return (float3)(0.0f);
            }
            return f / *pdf;
        }
        p_base = 1.0f - c.p;
        u.x = fmin((u.x - c.p) / p_base, 0x1.fffffep-1f);
    }
#endif
#ifdef HAS_SHEEN
    // The sheen's share (of what the coat leaves), cosine-distributed.
    float p_under_sheen = 1.0f;
    if (l.sheen_max > 0.0f) {
        float q = sheen_probability(&l);
        if (u.x < q) {
            wi = sample_cosine(fmin(u.x / q, 0x1.fffffep-1f), u.y);
            *wi_world = normalize(wi.x * t + wi.y * b + wi.z * n);
            float3 f = bsdf_eval(m, n, wo_world, *wi_world, pdf);
            if (!(*pdf > 0.0f)) {
                *pdf = 0.0f;
                return (float3)(0.0f);
            }
            return f / *pdf;
        }
        p_under_sheen = 1.0f - q;
        u.x = fmin((u.x - q) / p_under_sheen, 0x1.fffffep-1f);
    }
#endif
    float p_cos = lobes_p_cosine(&l);
    if (u.x < l.p_diffuse) {
        wi = sample_cosine(u.x / l.p_diffuse, u.y);
    }
#ifdef HAS_DIFFUSE_TRANSMISSION
    else if (u.x < p_cos) {
        // Diffuse transmission: the cosine lobe below the surface.
        wi = sample_cosine(fmin((u.x - l.p_diffuse) / l.p_dtrans, 0x1.fffffep-1f), u.y);
        wi.z = -wi.z;
    }
#endif
    else {
        // A visible microfacet, then reflection or transmission by their share at it.
        float ug = fmin((u.x - p_cos) / (1.0f - p_cos), 0x1.fffffep-1f);
        float3 h = l.delta ? (float3)(0.0f, 0.0f, 1.0f) : lobe_sample_vndf(&l, wo, ug, u.y);
        float cos_oh = dot(wo, h);
        float3 refl, trans;
        bsdf_gloss(m, &l, cos_oh, &refl, &trans);
        float pr = reflect_probability(refl, trans);
        bool reflect = u.z < pr;
        bool delta = l.delta || (l.straight && !reflect);
        if (reflect || l.thin) {
            wi = 2.0f * cos_oh * h - wo;
            if (wi.z <= 0.0f) return (float3)(0.0f);
            if (!reflect) wi.z = -wi.z;
        } else if (l.straight) {
            wi = -wo;
        } else {
            float c2 = refracted_cos2(cos_oh, l.eta);
            if (c2 <= 0.0f) return (float3)(0.0f);
            wi = (cos_oh / l.eta - sqrt(c2)) * h - wo / l.eta;
            if (wi.z >= 0.0f) return (float3)(0.0f);
        }
        if (delta) {
            // A delta lobe: its weight is the chosen share's, over the probability of choosing
            // it (for a straight lobe under a rough surface, on average over the microfacets).
            float chosen = (1.0f - p_cos) * (reflect ? pr : 1.0f - pr);
            if (!(chosen > 0.0f)) return (float3)(0.0f);
            *wi_world = normalize(wi.x * t + wi.y * b + wi.z * n);
            *pdf = chosen;
            *specular = true;
            float3 w = (reflect ? refl : trans) / chosen;
            w = reflect || l.thin || l.straight ? w : w / (l.eta * l.eta);
#ifdef HAS_SHEEN
            if (l.sheen_max > 0.0f) {
                *pdf *= p_under_sheen;
                w *= sheen_gloss_scale(&l, fabs(wi.z)) / p_under_sheen;
            }
#endif
#ifdef HAS_CLEARCOAT
            if (c.c > 0.0f) {
                *pdf *= p_base;
                w *= coat_gloss_scale(&c, *wi_world) / p_base;
            }
#endif
            return w;
        }
    }
    *wi_world = normalize(wi.x * t + wi.y * b + wi.z * n);
    float3 f = bsdf_eval(m, n, wo_world, *wi_world, pdf);
    if (!(*pdf > 0.0f)) {
        *pdf = 0.0f;
        return (float3)(0.0f);
    }
    return f / *pdf;
}
#endif  // LAMBERT_ONLY

#endif  // SHARED_BSDF_H
