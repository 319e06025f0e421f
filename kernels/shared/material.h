// A surface's material as the BSDF sees it (SurfaceMaterial: the glTF material with its
// textures applied, from surface.h's surface_material and its texture lookups), seen from
// inside its volume, the volume's Beer-Lambert transmittance, and (HAS_DISPERSION) the
// dispersive index and the wavelength sampling of KHR_materials_dispersion; SHADE_INLINE, the
// inlining of the functions shading calls at every vertex.
#ifndef SHARED_MATERIAL_H
#define SHARED_MATERIAL_H

#include "shared/types.h"
#include "shared/vec3.h"

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

#endif  // SHARED_MATERIAL_H
