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
//                 through a volume (Walter et al. 2007, radiance scaled by 1/eta^2), or straight
//                 through a thin wall (both faces' Fresnel)
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
#include "shared/rng.h"

// The functions shading calls at every vertex (shade_vertex in path.h, sample_light in
// lights.h, bsdf_sample here) are inlined into their callers in the CPU megakernel with lanes
// (MEGA_LANES), where a call's arguments and results went through memory: 5 % of the
// 1 M-triangle scenes' time on Zen 4 (docs/benchmarks.md, "Twenty-second session"), for about
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
inline SurfaceMaterial surface_material(global const GpuMaterial* m) {
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

// Directional albedo of a GGX reflection lobe (height-correlated Smith G2), the energy tables
// of the multiple-scattering compensation (Kulla and Conty 2017) and of the layering: GGX_E with
// Fresnel 1, GGX_E_SCHLICK with the Schlick weight (1 - wo.h)^5 as the Fresnel, so that a
// Schlick lobe of reflectance f0 reflects f0 E + (1 - f0) E_s. Rows for roughness 0, 1/32 .. 1,
// columns for cos(theta_o) 0, 1/32 .. 1; the _AVG tables hold the cosine-weighted means
// 2∫E(mu) mu dmu per row. tests/bsdf.rs prints them (print_energy_tables) and checks them
// against a Monte Carlo estimate.
constant float GGX_E[1089] = {
    1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    0.97917f, 0.99959f, 0.99994f, 0.99997f, 0.99998f, 0.99999f, 0.99999f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    0.99463f, 0.99067f, 0.99777f, 0.99897f, 0.99961f, 0.99984f, 0.99989f, 0.99992f, 0.99994f, 0.99996f, 0.99996f,
    0.99997f, 0.99998f, 0.99998f, 0.99998f, 0.99999f, 0.99999f, 0.99999f, 0.99999f, 0.99999f, 0.99999f, 0.99999f,
    1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    0.99762f, 0.95694f, 0.98813f, 0.99487f, 0.99717f, 0.99817f, 0.99879f, 0.99904f, 0.99927f, 0.99966f, 0.99981f,
    0.99985f, 0.99988f, 0.99990f, 0.99992f, 0.99993f, 0.99994f, 0.99995f, 0.99996f, 0.99996f, 0.99997f, 0.99997f,
    0.99998f, 0.99998f, 0.99998f, 0.99999f, 0.99999f, 0.99999f, 0.99999f, 1.00000f, 1.00000f, 1.00000f, 1.00000f,
    0.99866f, 0.91354f, 0.96448f, 0.98328f, 0.99067f, 0.99412f, 0.99598f, 0.99706f, 0.99777f, 0.99825f, 0.99867f,
    0.99884f, 0.99898f, 0.99912f, 0.99927f, 0.99946f, 0.99976f, 0.99983f, 0.99986f, 0.99988f, 0.99990f, 0.99992f,
    0.99993f, 0.99994f, 0.99995f, 0.99996f, 0.99997f, 0.99997f, 0.99998f, 0.99999f, 0.99999f, 1.00000f, 1.00000f,
    0.99914f, 0.89265f, 0.93209f, 0.96189f, 0.97721f, 0.98526f, 0.98983f, 0.99260f, 0.99438f, 0.99560f, 0.99648f,
    0.99712f, 0.99760f, 0.99791f, 0.99826f, 0.99856f, 0.99870f, 0.99881f, 0.99891f, 0.99900f, 0.99910f, 0.99922f,
    0.99937f, 0.99962f, 0.99983f, 0.99988f, 0.99991f, 0.99993f, 0.99995f, 0.99996f, 0.99997f, 0.99999f, 1.00000f,
    0.99940f, 0.89387f, 0.90557f, 0.93510f, 0.95665f, 0.97026f, 0.97880f, 0.98431f, 0.98800f, 0.99056f, 0.99241f,
    0.99376f, 0.99479f, 0.99555f, 0.99621f, 0.99667f, 0.99714f, 0.99744f, 0.99768f, 0.99791f, 0.99823f, 0.99841f,
    0.99851f, 0.99859f, 0.99865f, 0.99872f, 0.99880f, 0.99888f, 0.99900f, 0.99919f, 0.99971f, 0.99992f, 0.99997f,
    0.99956f, 0.90456f, 0.89210f, 0.91113f, 0.93291f, 0.95014f, 0.96257f, 0.97135f, 0.97759f, 0.98210f, 0.98543f,
    0.98793f, 0.98983f, 0.99133f, 0.99249f, 0.99344f, 0.99422f, 0.99482f, 0.99537f, 0.99578f, 0.99611f, 0.99649f,
    0.99672f, 0.99688f, 0.99703f, 0.99720f, 0.99747f, 0.99754f, 0.99750f, 0.99740f, 0.99719f, 0.99668f, 0.99606f,
    0.99965f, 0.91654f, 0.88860f, 0.89346f, 0.90930f, 0.92599f, 0.94023f, 0.95153f, 0.96030f, 0.96708f, 0.97231f,
    0.97639f, 0.97961f, 0.98217f, 0.98425f, 0.98594f, 0.98735f, 0.98852f, 0.98950f, 0.99035f, 0.99108f, 0.99172f,
    0.99225f, 0.99278f, 0.99318f, 0.99355f, 0.99400f, 0.99431f, 0.99455f, 0.99478f, 0.99515f, 0.99573f, 0.99593f,
    0.99972f, 0.92682f, 0.89214f, 0.88589f, 0.89382f, 0.90689f, 0.92051f, 0.93281f, 0.94325f, 0.95185f, 0.95887f,
    0.96456f, 0.96920f, 0.97300f, 0.97612f, 0.97871f, 0.98088f, 0.98270f, 0.98425f, 0.98557f, 0.98672f, 0.98771f,
    0.98855f, 0.98933f, 0.98997f, 0.99059f, 0.99108f, 0.99159f, 0.99200f, 0.99229f, 0.99269f, 0.99286f, 0.99188f,
    0.99976f, 0.93548f, 0.89924f, 0.88478f, 0.88462f, 0.89201f, 0.90255f, 0.91374f, 0.92432f, 0.93379f, 0.94201f,
    0.94903f, 0.95497f, 0.96000f, 0.96423f, 0.96781f, 0.97085f, 0.97342f, 0.97562f, 0.97750f, 0.97911f, 0.98049f,
    0.98167f, 0.98268f, 0.98358f, 0.98441f, 0.98526f, 0.98607f, 0.98676f, 0.98747f, 0.98803f, 0.98870f, 0.98870f,
    0.99979f, 0.94257f, 0.90605f, 0.88614f, 0.87909f, 0.88077f, 0.88712f, 0.89572f, 0.90503f, 0.91420f, 0.92276f,
    0.93052f, 0.93743f, 0.94351f, 0.94884f, 0.95348f, 0.95753f, 0.96105f, 0.96413f, 0.96683f, 0.96919f, 0.97127f,
    0.97309f, 0.97469f, 0.97611f, 0.97735f, 0.97845f, 0.97939f, 0.98019f, 0.98097f, 0.98189f, 0.98267f, 0.98261f,
    0.99980f, 0.94760f, 0.91149f, 0.88939f, 0.87793f, 0.87433f, 0.87605f, 0.88106f, 0.88787f, 0.89550f, 0.90331f,
    0.91096f, 0.91817f, 0.92480f, 0.93083f, 0.93628f, 0.94116f, 0.94552f, 0.94942f, 0.95289f, 0.95599f, 0.95876f,
    0.96123f, 0.96343f, 0.96540f, 0.96716f, 0.96872f, 0.97011f, 0.97134f, 0.97253f, 0.97372f, 0.97473f, 0.97579f,
    0.99981f, 0.95091f, 0.91630f, 0.89241f, 0.87760f, 0.87013f, 0.86791f, 0.86941f, 0.87337f, 0.87886f, 0.88517f,
    0.89184f, 0.89853f, 0.90507f, 0.91130f, 0.91712f, 0.92252f, 0.92747f, 0.93201f, 0.93613f, 0.93988f, 0.94329f,
    0.94637f, 0.94916f, 0.95169f, 0.95396f, 0.95603f, 0.95794f, 0.95977f, 0.96143f, 0.96289f, 0.96416f, 0.96549f,
    0.99982f, 0.95275f, 0.91932f, 0.89484f, 0.87781f, 0.86719f, 0.86164f, 0.85985f, 0.86085f, 0.86382f, 0.86815f,
    0.87339f, 0.87909f, 0.88496f, 0.89082f, 0.89652f, 0.90199f, 0.90717f, 0.91204f, 0.91659f, 0.92081f, 0.92471f,
    0.92833f, 0.93167f, 0.93481f, 0.93770f, 0.94036f, 0.94278f, 0.94499f, 0.94703f, 0.94901f, 0.95072f, 0.95248f,
    0.99981f, 0.95343f, 0.92085f, 0.89589f, 0.87765f, 0.86467f, 0.85641f, 0.85172f, 0.84991f, 0.85044f, 0.85263f,
    0.85598f, 0.86013f, 0.86480f, 0.86977f, 0.87486f, 0.87997f, 0.88500f, 0.88993f, 0.89466f, 0.89917f, 0.90343f,
    0.90745f, 0.91121f, 0.91474f, 0.91805f, 0.92119f, 0.92411f, 0.92681f, 0.92932f, 0.93171f, 0.93390f, 0.93598f,
    0.99981f, 0.95362f, 0.92120f, 0.89597f, 0.87652f, 0.86185f, 0.85139f, 0.84425f, 0.84010f, 0.83818f, 0.83805f,
    0.83933f, 0.84177f, 0.84498f, 0.84875f, 0.85289f, 0.85727f, 0.86176f, 0.86629f, 0.87082f, 0.87526f, 0.87958f,
    0.88373f, 0.88771f, 0.89151f, 0.89517f, 0.89865f, 0.90192f, 0.90501f, 0.90797f, 0.91072f, 0.91334f, 0.91586f,
    0.99980f, 0.95289f, 0.92019f, 0.89461f, 0.87424f, 0.85824f, 0.84595f, 0.83694f, 0.83052f, 0.82644f, 0.82421f,
    0.82349f, 0.82401f, 0.82557f, 0.82787f, 0.83074f, 0.83405f, 0.83767f, 0.84154f, 0.84553f, 0.84956f, 0.85359f,
    0.85759f, 0.86155f, 0.86541f, 0.86915f, 0.87277f, 0.87628f, 0.87963f, 0.88286f, 0.88594f, 0.88889f, 0.89173f,
    0.99978f, 0.95135f, 0.91821f, 0.89194f, 0.87074f, 0.85357f, 0.83984f, 0.82903f, 0.82083f, 0.81475f, 0.81058f,
    0.80792f, 0.80663f, 0.80643f, 0.80711f, 0.80854f, 0.81059f, 0.81309f, 0.81594f, 0.81908f, 0.82244f, 0.82592f,
    0.82948f, 0.83309f, 0.83672f, 0.84031f, 0.84387f, 0.84737f, 0.85078f, 0.85412f, 0.85736f, 0.86050f, 0.86353f,
    0.99977f, 0.94922f, 0.91522f, 0.88809f, 0.86598f, 0.84768f, 0.83264f, 0.82039f, 0.81054f, 0.80274f, 0.79675f,
    0.79233f, 0.78926f, 0.78732f, 0.78640f, 0.78629f, 0.78689f, 0.78809f, 0.78975f, 0.79182f, 0.79423f, 0.79688f,
    0.79973f, 0.80275f, 0.80585f, 0.80905f, 0.81228f, 0.81553f, 0.81877f, 0.82199f, 0.82518f, 0.82832f, 0.83141f,
    0.99975f, 0.94677f, 0.91134f, 0.88319f, 0.86002f, 0.84062f, 0.82436f, 0.81073f, 0.79939f, 0.79005f, 0.78243f,
    0.77635f, 0.77162f, 0.76803f, 0.76549f, 0.76382f, 0.76295f, 0.76273f, 0.76308f, 0.76393f, 0.76519f, 0.76682f,
    0.76873f, 0.77089f, 0.77325f, 0.77577f, 0.77842f, 0.78117f, 0.78399f, 0.78686f, 0.78977f, 0.79268f, 0.79561f,
    0.99972f, 0.94373f, 0.90675f, 0.87729f, 0.85291f, 0.83236f, 0.81488f, 0.79996f, 0.78724f, 0.77646f, 0.76736f,
    0.75976f, 0.75346f, 0.74832f, 0.74423f, 0.74105f, 0.73866f, 0.73701f, 0.73597f, 0.73550f, 0.73551f, 0.73595f,
    0.73675f, 0.73788f, 0.73929f, 0.74093f, 0.74278f, 0.74479f, 0.74696f, 0.74924f, 0.75161f, 0.75407f, 0.75659f,
    0.99970f, 0.94020f, 0.90138f, 0.87048f, 0.84480f, 0.82298f, 0.80424f, 0.78805f, 0.77404f, 0.76191f, 0.75141f,
    0.74237f, 0.73463f, 0.72803f, 0.72246f, 0.71781f, 0.71398f, 0.71089f, 0.70846f, 0.70662f, 0.70532f, 0.70449f,
    0.70408f, 0.70405f, 0.70435f, 0.70495f, 0.70581f, 0.70691f, 0.70820f, 0.70968f, 0.71131f, 0.71308f, 0.71497f,
    0.99967f, 0.93651f, 0.89543f, 0.86284f, 0.83571f, 0.81253f, 0.79252f, 0.77505f, 0.75975f, 0.74633f, 0.73451f,
    0.72414f, 0.71503f, 0.70705f, 0.70009f, 0.69404f, 0.68882f, 0.68434f, 0.68055f, 0.67736f, 0.67473f, 0.67260f,
    0.67092f, 0.66966f, 0.66878f, 0.66823f, 0.66799f, 0.66802f, 0.66830f, 0.66881f, 0.66952f, 0.67042f, 0.67148f,
    0.99965f, 0.93236f, 0.88896f, 0.85447f, 0.82575f, 0.80115f, 0.77979f, 0.76103f, 0.74446f, 0.72976f, 0.71668f,
    0.70502f, 0.69462f, 0.68535f, 0.67707f, 0.66971f, 0.66317f, 0.65738f, 0.65227f, 0.64778f, 0.64385f, 0.64044f,
    0.63750f, 0.63499f, 0.63288f, 0.63114f, 0.62973f, 0.62863f, 0.62781f, 0.62724f, 0.62691f, 0.62680f, 0.62688f,
    0.99961f, 0.92791f, 0.88195f, 0.84548f, 0.81504f, 0.78891f, 0.76614f, 0.74606f, 0.72821f, 0.71226f, 0.69795f,
    0.68507f, 0.67344f, 0.66294f, 0.65344f, 0.64485f, 0.63707f, 0.63004f, 0.62369f, 0.61796f, 0.61279f, 0.60815f,
    0.60399f, 0.60027f, 0.59696f, 0.59403f, 0.59145f, 0.58919f, 0.58723f, 0.58555f, 0.58412f, 0.58294f, 0.58196f,
    0.99958f, 0.92327f, 0.87448f, 0.83589f, 0.80363f, 0.77592f, 0.75168f, 0.73025f, 0.71113f, 0.69394f, 0.67843f,
    0.66436f, 0.65157f, 0.63991f, 0.62926f, 0.61951f, 0.61058f, 0.60240f, 0.59489f, 0.58801f, 0.58169f, 0.57590f,
    0.57059f, 0.56573f, 0.56128f, 0.55721f, 0.55350f, 0.55012f, 0.54705f, 0.54427f, 0.54175f, 0.53948f, 0.53745f,
    0.99955f, 0.91826f, 0.86662f, 0.82579f, 0.79163f, 0.76226f, 0.73654f, 0.71373f, 0.69332f, 0.67491f, 0.65822f,
    0.64301f, 0.62911f, 0.61635f, 0.60462f, 0.59380f, 0.58381f, 0.57457f, 0.56600f, 0.55807f, 0.55070f, 0.54385f,
    0.53749f, 0.53158f, 0.52608f, 0.52097f, 0.51621f, 0.51179f, 0.50768f, 0.50386f, 0.50031f, 0.49702f, 0.49398f,
    0.99951f, 0.91317f, 0.85844f, 0.81522f, 0.77912f, 0.74804f, 0.72080f, 0.69661f, 0.67491f, 0.65530f, 0.63746f,
    0.62115f, 0.60619f, 0.59240f, 0.57966f, 0.56785f, 0.55688f, 0.54668f, 0.53716f, 0.52827f, 0.51996f, 0.51217f,
    0.50487f, 0.49802f, 0.49159f, 0.48555f, 0.47986f, 0.47451f, 0.46947f, 0.46473f, 0.46026f, 0.45604f, 0.45207f,
    0.99947f, 0.90779f, 0.84995f, 0.80429f, 0.76616f, 0.73334f, 0.70458f, 0.67899f, 0.65602f, 0.63522f, 0.61627f,
    0.59892f, 0.58295f, 0.56820f, 0.55452f, 0.54181f, 0.52996f, 0.51888f, 0.50851f, 0.49878f, 0.48964f, 0.48103f,
    0.47292f, 0.46526f, 0.45802f, 0.45118f, 0.44469f, 0.43855f, 0.43272f, 0.42718f, 0.42192f, 0.41692f, 0.41216f,
    0.99943f, 0.90228f, 0.84117f, 0.79303f, 0.75283f, 0.71827f, 0.68795f, 0.66099f, 0.63677f, 0.61482f, 0.59481f,
    0.57645f, 0.55954f, 0.54389f, 0.52936f, 0.51583f, 0.50318f, 0.49134f, 0.48022f, 0.46976f, 0.45991f, 0.45060f,
    0.44180f, 0.43346f, 0.42556f, 0.41805f, 0.41091f, 0.40411f, 0.39764f, 0.39146f, 0.38556f, 0.37993f, 0.37454f,
    0.99939f, 0.89658f, 0.83216f, 0.78145f, 0.73920f, 0.70289f, 0.67103f, 0.64272f, 0.61727f, 0.59422f, 0.57319f,
    0.55389f, 0.53610f, 0.51963f, 0.50433f, 0.49006f, 0.47671f, 0.46420f, 0.45244f, 0.44137f, 0.43092f, 0.42103f,
    0.41167f, 0.40279f, 0.39435f, 0.38632f, 0.37867f, 0.37137f, 0.36440f, 0.35774f, 0.35137f, 0.34526f, 0.33941f,
    0.99935f, 0.89074f, 0.82294f, 0.76969f, 0.72534f, 0.68726f, 0.65390f, 0.62427f, 0.59764f, 0.57353f, 0.55154f,
    0.53136f, 0.51277f, 0.49556f, 0.47956f, 0.46464f, 0.45069f, 0.43762f, 0.42532f, 0.41374f, 0.40280f, 0.39246f,
    0.38266f, 0.37337f, 0.36453f, 0.35611f, 0.34809f, 0.34044f, 0.33312f, 0.32613f, 0.31944f, 0.31302f, 0.30685f,
};
constant float GGX_E_SCHLICK[1089] = {
    0.99950f, 0.85322f, 0.72420f, 0.61128f, 0.51291f, 0.42763f, 0.35409f, 0.29104f, 0.23730f, 0.19182f, 0.15359f,
    0.12172f, 0.09537f, 0.07379f, 0.05631f, 0.04232f, 0.03125f, 0.02263f, 0.01603f, 0.01107f, 0.00742f, 0.00480f,
    0.00298f, 0.00176f, 0.00098f, 0.00050f, 0.00023f, 0.00009f, 0.00003f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.95405f, 0.85239f, 0.72396f, 0.61116f, 0.51284f, 0.42759f, 0.35407f, 0.29102f, 0.23730f, 0.19181f, 0.15359f,
    0.12172f, 0.09537f, 0.07380f, 0.05632f, 0.04232f, 0.03125f, 0.02263f, 0.01603f, 0.01107f, 0.00742f, 0.00480f,
    0.00298f, 0.00176f, 0.00098f, 0.00050f, 0.00023f, 0.00009f, 0.00003f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.91500f, 0.83806f, 0.71948f, 0.60895f, 0.51173f, 0.42698f, 0.35370f, 0.29080f, 0.23717f, 0.19175f, 0.15356f,
    0.12172f, 0.09538f, 0.07382f, 0.05634f, 0.04234f, 0.03128f, 0.02266f, 0.01605f, 0.01108f, 0.00743f, 0.00481f,
    0.00299f, 0.00177f, 0.00098f, 0.00050f, 0.00023f, 0.00009f, 0.00003f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.85145f, 0.78784f, 0.70222f, 0.60054f, 0.50679f, 0.42389f, 0.35179f, 0.28957f, 0.23643f, 0.19143f, 0.15345f,
    0.12171f, 0.09544f, 0.07391f, 0.05645f, 0.04245f, 0.03138f, 0.02275f, 0.01613f, 0.01115f, 0.00748f, 0.00485f,
    0.00302f, 0.00179f, 0.00099f, 0.00051f, 0.00024f, 0.00010f, 0.00003f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.78089f, 0.71137f, 0.66381f, 0.58066f, 0.49533f, 0.41687f, 0.34733f, 0.28677f, 0.23467f, 0.19027f, 0.15279f,
    0.12136f, 0.09531f, 0.07392f, 0.05656f, 0.04263f, 0.03162f, 0.02298f, 0.01633f, 0.01132f, 0.00762f, 0.00496f,
    0.00310f, 0.00185f, 0.00104f, 0.00054f, 0.00025f, 0.00011f, 0.00004f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.70897f, 0.63925f, 0.60691f, 0.54607f, 0.47424f, 0.40362f, 0.33883f, 0.28129f, 0.23117f, 0.18809f, 0.15149f,
    0.12071f, 0.09506f, 0.07392f, 0.05672f, 0.04287f, 0.03184f, 0.02320f, 0.01654f, 0.01151f, 0.00779f, 0.00510f,
    0.00322f, 0.00195f, 0.00113f, 0.00060f, 0.00030f, 0.00013f, 0.00005f, 0.00002f, 0.00000f, 0.00000f, 0.00000f,
    0.63876f, 0.57709f, 0.54441f, 0.49963f, 0.44281f, 0.38272f, 0.32495f, 0.27211f, 0.22516f, 0.18424f, 0.14912f,
    0.11935f, 0.09439f, 0.07371f, 0.05678f, 0.04308f, 0.03216f, 0.02355f, 0.01689f, 0.01183f, 0.00808f, 0.00534f,
    0.00340f, 0.00207f, 0.00120f, 0.00065f, 0.00033f, 0.00015f, 0.00006f, 0.00003f, 0.00002f, 0.00001f, 0.00000f,
    0.57209f, 0.52026f, 0.48528f, 0.44852f, 0.40387f, 0.35472f, 0.30534f, 0.25860f, 0.21599f, 0.17816f, 0.14521f,
    0.11695f, 0.09305f, 0.07308f, 0.05662f, 0.04321f, 0.03245f, 0.02392f, 0.01729f, 0.01221f, 0.00840f, 0.00562f,
    0.00363f, 0.00225f, 0.00133f, 0.00074f, 0.00040f, 0.00019f, 0.00009f, 0.00003f, 0.00001f, 0.00000f, 0.00000f,
    0.51003f, 0.46656f, 0.43160f, 0.39855f, 0.36200f, 0.32207f, 0.28099f, 0.24095f, 0.20351f, 0.16954f, 0.13942f,
    0.11322f, 0.09078f, 0.07184f, 0.05607f, 0.04312f, 0.03264f, 0.02427f, 0.01770f, 0.01263f, 0.00880f, 0.00596f,
    0.00391f, 0.00248f, 0.00150f, 0.00087f, 0.00048f, 0.00025f, 0.00012f, 0.00005f, 0.00002f, 0.00001f, 0.00000f,
    0.45312f, 0.41599f, 0.38311f, 0.35258f, 0.32122f, 0.28814f, 0.25412f, 0.22045f, 0.18833f, 0.15861f, 0.13177f,
    0.10804f, 0.08744f, 0.06982f, 0.05498f, 0.04267f, 0.03260f, 0.02448f, 0.01805f, 0.01303f, 0.00920f, 0.00632f,
    0.00422f, 0.00273f, 0.00170f, 0.00101f, 0.00057f, 0.00031f, 0.00016f, 0.00007f, 0.00004f, 0.00001f, 0.00000f,
    0.40155f, 0.36921f, 0.33919f, 0.31106f, 0.28334f, 0.25520f, 0.22673f, 0.19854f, 0.17136f, 0.14585f, 0.12245f,
    0.10145f, 0.08293f, 0.06689f, 0.05321f, 0.04172f, 0.03221f, 0.02446f, 0.01825f, 0.01335f, 0.00955f, 0.00668f,
    0.00454f, 0.00300f, 0.00191f, 0.00117f, 0.00069f, 0.00039f, 0.00021f, 0.00010f, 0.00005f, 0.00002f, 0.00001f,
    0.35527f, 0.32660f, 0.29946f, 0.27381f, 0.24906f, 0.22466f, 0.20047f, 0.17673f, 0.15380f, 0.13212f, 0.11203f,
    0.09376f, 0.07745f, 0.06313f, 0.05076f, 0.04023f, 0.03142f, 0.02414f, 0.01824f, 0.01352f, 0.00982f, 0.00698f,
    0.00483f, 0.00326f, 0.00213f, 0.00134f, 0.00081f, 0.00047f, 0.00026f, 0.00014f, 0.00007f, 0.00003f, 0.00001f,
    0.31407f, 0.28826f, 0.26378f, 0.24064f, 0.21849f, 0.19707f, 0.17623f, 0.15602f, 0.13662f, 0.11824f, 0.10112f,
    0.08542f, 0.07125f, 0.05868f, 0.04769f, 0.03822f, 0.03019f, 0.02349f, 0.01797f, 0.01351f, 0.00996f, 0.00719f,
    0.00507f, 0.00349f, 0.00233f, 0.00150f, 0.00094f, 0.00056f, 0.00032f, 0.00017f, 0.00008f, 0.00004f, 0.00001f,
    0.27761f, 0.25414f, 0.23207f, 0.21120f, 0.19142f, 0.17251f, 0.15439f, 0.13702f, 0.12048f, 0.10486f, 0.09029f,
    0.07688f, 0.06470f, 0.05379f, 0.04416f, 0.03577f, 0.02858f, 0.02250f, 0.01744f, 0.01329f, 0.00995f, 0.00729f,
    0.00523f, 0.00366f, 0.00250f, 0.00165f, 0.00105f, 0.00065f, 0.00038f, 0.00021f, 0.00011f, 0.00005f, 0.00002f,
    0.24553f, 0.22398f, 0.20402f, 0.18526f, 0.16757f, 0.15084f, 0.13498f, 0.11994f, 0.10574f, 0.09240f, 0.07998f,
    0.06854f, 0.05811f, 0.04871f, 0.04036f, 0.03302f, 0.02667f, 0.02124f, 0.01666f, 0.01286f, 0.00976f, 0.00727f,
    0.00530f, 0.00378f, 0.00262f, 0.00177f, 0.00116f, 0.00073f, 0.00043f, 0.00025f, 0.00013f, 0.00006f, 0.00002f,
    0.21742f, 0.19751f, 0.17940f, 0.16249f, 0.14667f, 0.13183f, 0.11789f, 0.10479f, 0.09253f, 0.08107f, 0.07045f,
    0.06067f, 0.05174f, 0.04368f, 0.03648f, 0.03011f, 0.02455f, 0.01976f, 0.01568f, 0.01225f, 0.00942f, 0.00712f,
    0.00527f, 0.00382f, 0.00270f, 0.00186f, 0.00124f, 0.00079f, 0.00049f, 0.00028f, 0.00015f, 0.00007f, 0.00002f,
    0.19287f, 0.17439f, 0.15787f, 0.14261f, 0.12844f, 0.11524f, 0.10295f, 0.09149f, 0.08083f, 0.07094f, 0.06181f,
    0.05342f, 0.04578f, 0.03887f, 0.03267f, 0.02718f, 0.02235f, 0.01815f, 0.01455f, 0.01150f, 0.00895f, 0.00685f,
    0.00514f, 0.00378f, 0.00272f, 0.00190f, 0.00129f, 0.00084f, 0.00053f, 0.00031f, 0.00017f, 0.00008f, 0.00003f,
    0.17149f, 0.15425f, 0.13912f, 0.12531f, 0.11257f, 0.10081f, 0.08993f, 0.07986f, 0.07056f, 0.06198f, 0.05410f,
    0.04688f, 0.04032f, 0.03439f, 0.02906f, 0.02433f, 0.02015f, 0.01650f, 0.01335f, 0.01065f, 0.00838f, 0.00649f,
    0.00494f, 0.00368f, 0.00268f, 0.00191f, 0.00132f, 0.00088f, 0.00056f, 0.00033f, 0.00018f, 0.00009f, 0.00003f,
    0.15291f, 0.13673f, 0.12282f, 0.11027f, 0.09880f, 0.08829f, 0.07863f, 0.06975f, 0.06160f, 0.05412f, 0.04729f,
    0.04105f, 0.03540f, 0.03029f, 0.02571f, 0.02163f, 0.01803f, 0.01486f, 0.01212f, 0.00976f, 0.00775f, 0.00606f,
    0.00467f, 0.00352f, 0.00260f, 0.00188f, 0.00132f, 0.00089f, 0.00058f, 0.00035f, 0.00020f, 0.00010f, 0.00004f,
    0.13677f, 0.12152f, 0.10870f, 0.09724f, 0.08688f, 0.07744f, 0.06884f, 0.06098f, 0.05381f, 0.04727f, 0.04131f,
    0.03591f, 0.03101f, 0.02661f, 0.02266f, 0.01914f, 0.01603f, 0.01329f, 0.01091f, 0.00885f, 0.00709f, 0.00560f,
    0.00435f, 0.00332f, 0.00248f, 0.00182f, 0.00129f, 0.00089f, 0.00058f, 0.00036f, 0.00021f, 0.00010f, 0.00004f,
    0.12279f, 0.10834f, 0.09644f, 0.08596f, 0.07655f, 0.06806f, 0.06037f, 0.05339f, 0.04705f, 0.04130f, 0.03610f,
    0.03139f, 0.02714f, 0.02333f, 0.01992f, 0.01688f, 0.01419f, 0.01182f, 0.00975f, 0.00796f, 0.00642f, 0.00511f,
    0.00401f, 0.00309f, 0.00234f, 0.00173f, 0.00124f, 0.00087f, 0.00058f, 0.00037f, 0.00021f, 0.00011f, 0.00004f,
    0.11066f, 0.09689f, 0.08583f, 0.07618f, 0.06761f, 0.05994f, 0.05304f, 0.04682f, 0.04120f, 0.03613f, 0.03156f,
    0.02744f, 0.02374f, 0.02043f, 0.01747f, 0.01484f, 0.01251f, 0.01046f, 0.00867f, 0.00712f, 0.00577f, 0.00463f,
    0.00366f, 0.00284f, 0.00217f, 0.00162f, 0.00118f, 0.00083f, 0.00056f, 0.00036f, 0.00021f, 0.00011f, 0.00004f,
    0.10015f, 0.08695f, 0.07662f, 0.06771f, 0.05988f, 0.05292f, 0.04670f, 0.04113f, 0.03613f, 0.03164f, 0.02762f,
    0.02400f, 0.02077f, 0.01788f, 0.01531f, 0.01303f, 0.01101f, 0.00923f, 0.00768f, 0.00633f, 0.00516f, 0.00416f,
    0.00331f, 0.00259f, 0.00199f, 0.00150f, 0.00111f, 0.00079f, 0.00054f, 0.00035f, 0.00021f, 0.00011f, 0.00005f,
    0.09104f, 0.07833f, 0.06862f, 0.06036f, 0.05317f, 0.04684f, 0.04122f, 0.03621f, 0.03175f, 0.02776f, 0.02420f,
    0.02101f, 0.01818f, 0.01565f, 0.01341f, 0.01142f, 0.00967f, 0.00813f, 0.00678f, 0.00561f, 0.00459f, 0.00372f,
    0.00297f, 0.00234f, 0.00182f, 0.00138f, 0.00102f, 0.00074f, 0.00051f, 0.00034f, 0.00021f, 0.00011f, 0.00005f,
    0.08314f, 0.07083f, 0.06167f, 0.05398f, 0.04736f, 0.04156f, 0.03646f, 0.03195f, 0.02795f, 0.02439f, 0.02123f,
    0.01842f, 0.01592f, 0.01371f, 0.01174f, 0.01001f, 0.00848f, 0.00714f, 0.00597f, 0.00495f, 0.00407f, 0.00331f,
    0.00266f, 0.00210f, 0.00164f, 0.00126f, 0.00094f, 0.00068f, 0.00048f, 0.00032f, 0.00020f, 0.00011f, 0.00005f,
    0.07628f, 0.06429f, 0.05562f, 0.04843f, 0.04230f, 0.03698f, 0.03234f, 0.02826f, 0.02465f, 0.02147f, 0.01866f,
    0.01616f, 0.01396f, 0.01201f, 0.01029f, 0.00877f, 0.00744f, 0.00627f, 0.00525f, 0.00436f, 0.00359f, 0.00293f,
    0.00236f, 0.00188f, 0.00147f, 0.00114f, 0.00086f, 0.00063f, 0.00044f, 0.00030f, 0.00019f, 0.00011f, 0.00005f,
    0.07032f, 0.05859f, 0.05033f, 0.04359f, 0.03789f, 0.03300f, 0.02875f, 0.02505f, 0.02180f, 0.01894f, 0.01642f,
    0.01421f, 0.01225f, 0.01053f, 0.00902f, 0.00769f, 0.00652f, 0.00550f, 0.00461f, 0.00383f, 0.00316f, 0.00259f,
    0.00209f, 0.00167f, 0.00132f, 0.00102f, 0.00077f, 0.00057f, 0.00041f, 0.00028f, 0.00018f, 0.00010f, 0.00005f,
    0.06514f, 0.05360f, 0.04571f, 0.03936f, 0.03405f, 0.02952f, 0.02563f, 0.02225f, 0.01931f, 0.01674f, 0.01448f,
    0.01250f, 0.01077f, 0.00925f, 0.00791f, 0.00674f, 0.00572f, 0.00482f, 0.00404f, 0.00337f, 0.00278f, 0.00228f,
    0.00185f, 0.00148f, 0.00117f, 0.00091f, 0.00069f, 0.00052f, 0.00037f, 0.00026f, 0.00016f, 0.00010f, 0.00005f,
    0.06062f, 0.04923f, 0.04166f, 0.03565f, 0.03068f, 0.02649f, 0.02290f, 0.01982f, 0.01714f, 0.01482f, 0.01279f,
    0.01102f, 0.00948f, 0.00813f, 0.00695f, 0.00591f, 0.00501f, 0.00423f, 0.00355f, 0.00296f, 0.00245f, 0.00201f,
    0.00163f, 0.00131f, 0.00104f, 0.00081f, 0.00062f, 0.00046f, 0.00034f, 0.00023f, 0.00015f, 0.00009f, 0.00004f,
    0.05667f, 0.04538f, 0.03809f, 0.03239f, 0.02773f, 0.02383f, 0.02052f, 0.01769f, 0.01525f, 0.01315f, 0.01132f,
    0.00974f, 0.00835f, 0.00715f, 0.00610f, 0.00519f, 0.00440f, 0.00371f, 0.00311f, 0.00260f, 0.00215f, 0.00177f,
    0.00144f, 0.00116f, 0.00092f, 0.00072f, 0.00055f, 0.00042f, 0.00030f, 0.00021f, 0.00014f, 0.00008f, 0.00004f,
    0.05322f, 0.04200f, 0.03495f, 0.02952f, 0.02512f, 0.02149f, 0.01842f, 0.01582f, 0.01360f, 0.01169f, 0.01004f,
    0.00861f, 0.00737f, 0.00630f, 0.00537f, 0.00456f, 0.00386f, 0.00326f, 0.00273f, 0.00228f, 0.00189f, 0.00155f,
    0.00127f, 0.00102f, 0.00081f, 0.00064f, 0.00049f, 0.00037f, 0.00027f, 0.00019f, 0.00013f, 0.00008f, 0.00004f,
    0.05020f, 0.03900f, 0.03216f, 0.02698f, 0.02283f, 0.01942f, 0.01658f, 0.01419f, 0.01215f, 0.01041f, 0.00892f,
    0.00763f, 0.00652f, 0.00556f, 0.00473f, 0.00402f, 0.00340f, 0.00286f, 0.00240f, 0.00200f, 0.00166f, 0.00136f,
    0.00111f, 0.00090f, 0.00072f, 0.00057f, 0.00044f, 0.00033f, 0.00024f, 0.00017f, 0.00012f, 0.00007f, 0.00004f,
    0.04755f, 0.03634f, 0.02969f, 0.02472f, 0.02080f, 0.01760f, 0.01496f, 0.01275f, 0.01088f, 0.00929f, 0.00793f,
    0.00677f, 0.00577f, 0.00491f, 0.00418f, 0.00354f, 0.00299f, 0.00252f, 0.00211f, 0.00176f, 0.00146f, 0.00120f,
    0.00098f, 0.00079f, 0.00063f, 0.00050f, 0.00039f, 0.00029f, 0.00022f, 0.00015f, 0.00010f, 0.00006f, 0.00003f,
};
constant float GGX_E_AVG[33] = {
    1.00000f, 1.00000f, 0.99994f, 0.99972f, 0.99919f, 0.99814f, 0.99634f, 0.99345f, 0.98901f, 0.98213f, 0.97164f,
    0.96300f, 0.95188f, 0.93725f, 0.92136f, 0.90285f, 0.88233f, 0.85964f, 0.83496f, 0.80844f, 0.78028f, 0.75071f,
    0.71998f, 0.68838f, 0.65620f, 0.62373f, 0.59123f, 0.55899f, 0.52725f, 0.49623f, 0.46610f, 0.43703f, 0.40914f,
};
constant float GGX_E_SCHLICK_AVG[33] = {
    0.04762f, 0.04762f, 0.04753f, 0.04720f, 0.04653f, 0.04542f, 0.04388f, 0.04191f, 0.03961f, 0.03703f, 0.03429f,
    0.03150f, 0.02870f, 0.02598f, 0.02338f, 0.02094f, 0.01868f, 0.01661f, 0.01474f, 0.01305f, 0.01154f, 0.01020f,
    0.00902f, 0.00797f, 0.00705f, 0.00624f, 0.00552f, 0.00490f, 0.00435f, 0.00387f, 0.00345f, 0.00308f, 0.00276f,
};

// (E, E_s) at cos(theta_o) and perceptual roughness, bilinear in the tables.
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

// The film's reflectance (RGB, in [0, 1]) at cos_1 over a base of normal reflectance f0.
inline float3 film_fresnel(float cos_1, float film_ior, float d, float3 f0) {
    // A vanishing film is no film: the base's own Schlick Fresnel (the sample viewer's blend of
    // the film's index to the outside's would leave a Schlick interface of f0 = 0 there).
    if (d < 0.03f) return f0 + (1.0f - f0) * schlick_weight(cos_1);
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
    float3 r1 = (n3 - n2) / (n3 + n2);
    r1 *= r1;
    float3 r23 = r1 + (1.0f - r1) * schlick_weight(cos_2);
    float3 phi23 = (float3)(n3.x < n2 ? PI_F : 0.0f, n3.y < n2 ? PI_F : 0.0f, n3.z < n2 ? PI_F : 0.0f);
    float opd = 2.0f * n2 * d * cos_2;
    float3 phi = phi21 + phi23;
    float3 r123 = clamp(r12 * r23, 1e-5f, 0.9999f);
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
    bool thin;         // transmission goes straight through (thin wall, or eta close to 1)
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
// The anisotropic lobe's directional albedo, as GGX_E and GGX_E_SCHLICK: rows for the stretch
// u = (sqrt(alpha_x) - r) / (1 - r) 0, 1/4 .. 1 (alpha_x along the direction), then the base
// perceptual roughness r = sqrt(alpha_y) 0, 1/8 .. 1 (across it), then cos² of wo's azimuth from
// the direction 0, 1/4 .. 1; columns for cos(theta_o) 0, 1/16 .. 1. The _AVG tables hold the
// cosine-weighted hemisphere mean of each (u, r) slice as aniso_energy reads it. tests/bsdf.rs
// prints them (print_aniso_tables) and checks them against a Monte Carlo estimate and the
// isotropic tables (aniso_energy_tables_match_monte_carlo).
constant float ANISO_E[3825] = {
    0.99347f, 1.02233f, 1.02237f, 1.01451f, 1.01108f, 1.00839f, 1.00752f, 1.00674f, 1.00627f, 1.00621f, 1.00617f,
    1.00615f, 1.00612f, 1.00612f, 1.00611f, 1.00611f, 1.00608f, 0.99650f, 1.03373f, 1.03378f, 1.02385f, 1.01836f,
    1.01452f, 1.01171f, 1.00938f, 1.00804f, 1.00683f, 1.00662f, 1.00615f, 1.00612f, 1.00612f, 1.00611f, 1.00611f,
    1.00608f, 0.99653f, 1.03373f, 1.03378f, 1.02797f, 1.02156f, 1.01782f, 1.01478f, 1.01223f, 1.00998f, 1.00866f,
    1.00743f, 1.00668f, 1.00641f, 1.00592f, 1.00591f, 1.00600f, 1.00600f, 0.99516f, 1.03319f, 1.03324f, 1.03246f,
    1.02389f, 1.02001f, 1.01681f, 1.01384f, 1.01185f, 1.01004f, 1.00854f, 1.00743f, 1.00671f, 1.00639f, 1.00594f,
    1.00593f, 1.00593f, 0.99514f, 1.03319f, 1.03324f, 1.03246f, 1.02389f, 1.02001f, 1.01681f, 1.01384f, 1.01185f,
    1.01004f, 1.00854f, 1.00743f, 1.00671f, 1.00639f, 1.00594f, 1.00592f, 1.00592f, 1.01250f, 0.98682f, 1.01299f,
    1.01166f, 1.01350f, 1.01334f, 1.01361f, 1.01212f, 1.01159f, 1.01080f, 1.01049f, 1.01024f, 1.01000f, 1.00977f,
    1.00971f, 1.01060f, 1.01061f, 1.01552f, 0.99823f, 1.02438f, 1.01971f, 1.01607f, 1.01525f, 1.01524f, 1.01419f,
    1.01341f, 1.01279f, 1.01199f, 1.01107f, 1.01078f, 1.01011f, 1.00971f, 1.01060f, 1.01061f, 1.01555f, 0.99823f,
    1.02440f, 1.02385f, 1.01928f, 1.01632f, 1.01546f, 1.01475f, 1.01425f, 1.01358f, 1.01299f, 1.01237f, 1.01143f,
    1.01087f, 1.01039f, 1.01058f, 1.01059f, 1.01418f, 0.99769f, 1.02383f, 1.02833f, 1.02161f, 1.01851f, 1.01636f,
    1.01498f, 1.01458f, 1.01401f, 1.01359f, 1.01301f, 1.01245f, 1.01127f, 1.01090f, 1.01053f, 1.01054f, 1.01417f,
    0.99768f, 1.02386f, 1.02834f, 1.02161f, 1.01851f, 1.01636f, 1.01498f, 1.01458f, 1.01401f, 1.01359f, 1.01301f,
    1.01245f, 1.01127f, 1.01090f, 1.01045f, 1.01046f, 1.00014f, 0.90006f, 0.92765f, 0.95901f, 0.97918f, 0.99012f,
    0.99650f, 0.99931f, 1.00222f, 1.00408f, 1.00559f, 1.00629f, 1.00732f, 1.00789f, 1.00785f, 1.00748f, 1.00434f,
    1.00013f, 0.90268f, 0.92887f, 0.96066f, 0.98080f, 0.99202f, 0.99814f, 1.00139f, 1.00348f, 1.00481f, 1.00575f,
    1.00629f, 1.00732f, 1.00788f, 1.00785f, 1.00748f, 1.00434f, 1.00003f, 0.90266f, 0.92885f, 0.96065f, 0.98081f,
    0.99203f, 0.99836f, 1.00195f, 1.00432f, 1.00582f, 1.00707f, 1.00773f, 1.00802f, 1.00752f, 1.00697f, 1.00672f,
    1.00358f, 1.00008f, 0.89702f, 0.92636f, 0.96014f, 0.98028f, 0.99207f, 0.99855f, 1.00218f, 1.00464f, 1.00614f,
    1.00767f, 1.00819f, 1.00898f, 1.00871f, 1.00777f, 1.00683f, 1.00312f, 1.00009f, 0.89699f, 0.92219f, 0.95929f,
    0.98019f, 0.99209f, 0.99855f, 1.00218f, 1.00464f, 1.00615f, 1.00766f, 1.00820f, 1.00898f, 1.00871f, 1.00777f,
    1.00683f, 1.00305f, 0.99992f, 0.91795f, 0.88616f, 0.88445f, 0.89728f, 0.91476f, 0.93052f, 0.94349f, 0.95355f,
    0.96138f, 0.96766f, 0.97243f, 0.97677f, 0.98043f, 0.98375f, 0.98632f, 0.98632f, 0.99991f, 0.91793f, 0.88614f,
    0.88471f, 0.89892f, 0.91580f, 0.93138f, 0.94420f, 0.95427f, 0.96208f, 0.96780f, 0.97243f, 0.97677f, 0.98044f,
    0.98375f, 0.98632f, 0.98632f, 0.99987f, 0.91623f, 0.88298f, 0.88472f, 0.89893f, 0.91580f, 0.93142f, 0.94461f,
    0.95514f, 0.96313f, 0.96914f, 0.97387f, 0.97736f, 0.98013f, 0.98319f, 0.98583f, 0.98623f, 0.99990f, 0.91818f,
    0.88491f, 0.88002f, 0.89601f, 0.91463f, 0.93142f, 0.94461f, 0.95527f, 0.96345f, 0.96972f, 0.97434f, 0.97832f,
    0.98116f, 0.98319f, 0.98583f, 0.98623f, 0.99991f, 0.91820f, 0.88494f, 0.88003f, 0.89370f, 0.91234f, 0.93024f,
    0.94450f, 0.95527f, 0.96345f, 0.96973f, 0.97433f, 0.97832f, 0.98116f, 0.98319f, 0.98577f, 0.98617f, 0.99989f,
    0.92518f, 0.88056f, 0.85575f, 0.84359f, 0.84152f, 0.84619f, 0.85532f, 0.86565f, 0.87611f, 0.88610f, 0.89531f,
    0.90376f, 0.91091f, 0.91745f, 0.92322f, 0.92756f, 0.99989f, 0.92523f, 0.88054f, 0.85572f, 0.84358f, 0.84152f,
    0.84619f, 0.85531f, 0.86566f, 0.87611f, 0.88610f, 0.89531f, 0.90377f, 0.91091f, 0.91745f, 0.92322f, 0.92756f,
    0.99988f, 0.92437f, 0.87975f, 0.85472f, 0.84262f, 0.84039f, 0.84490f, 0.85387f, 0.86443f, 0.87512f, 0.88532f,
    0.89469f, 0.90314f, 0.91060f, 0.91690f, 0.92273f, 0.92747f, 0.99987f, 0.92572f, 0.88103f, 0.85542f, 0.84332f,
    0.84071f, 0.84416f, 0.85282f, 0.86338f, 0.87393f, 0.88429f, 0.89401f, 0.90284f, 0.91049f, 0.91685f, 0.92273f,
    0.92747f, 0.99987f, 0.92567f, 0.88105f, 0.85545f, 0.84332f, 0.84071f, 0.84416f, 0.85202f, 0.86273f, 0.87354f,
    0.88399f, 0.89356f, 0.90218f, 0.91003f, 0.91663f, 0.92267f, 0.92741f, 0.99985f, 0.91534f, 0.86415f, 0.82859f,
    0.80309f, 0.78572f, 0.77471f, 0.76868f, 0.76657f, 0.76758f, 0.77050f, 0.77482f, 0.78044f, 0.78660f, 0.79288f,
    0.79959f, 0.80550f, 0.99984f, 0.91533f, 0.86414f, 0.82859f, 0.80308f, 0.78573f, 0.77471f, 0.76868f, 0.76657f,
    0.76758f, 0.77049f, 0.77482f, 0.78043f, 0.78660f, 0.79288f, 0.79968f, 0.80558f, 0.99984f, 0.91417f, 0.86316f,
    0.82760f, 0.80212f, 0.78485f, 0.77390f, 0.76745f, 0.76564f, 0.76678f, 0.76981f, 0.77434f, 0.78003f, 0.78628f,
    0.79274f, 0.79968f, 0.80558f, 0.99983f, 0.91458f, 0.86389f, 0.82833f, 0.80282f, 0.78527f, 0.77417f, 0.76785f,
    0.76501f, 0.76597f, 0.76911f, 0.77395f, 0.77966f, 0.78591f, 0.79246f, 0.79964f, 0.80554f, 0.99983f, 0.91460f,
    0.86389f, 0.82833f, 0.80282f, 0.78527f, 0.77417f, 0.76784f, 0.76501f, 0.76532f, 0.76866f, 0.77337f, 0.77927f,
    0.78566f, 0.79240f, 0.79947f, 0.80537f, 0.99977f, 0.89106f, 0.82841f, 0.78274f, 0.74741f, 0.71933f, 0.69712f,
    0.67924f, 0.66505f, 0.65419f, 0.64593f, 0.63960f, 0.63513f, 0.63232f, 0.63106f, 0.63074f, 0.63072f, 0.99977f,
    0.89106f, 0.82841f, 0.78274f, 0.74741f, 0.71933f, 0.69712f, 0.67924f, 0.66505f, 0.65419f, 0.64593f, 0.63960f,
    0.63513f, 0.63232f, 0.63106f, 0.63074f, 0.63072f, 0.99977f, 0.89084f, 0.82795f, 0.78240f, 0.74706f, 0.71908f,
    0.69695f, 0.67900f, 0.66494f, 0.65382f, 0.64532f, 0.63924f, 0.63494f, 0.63224f, 0.63103f, 0.63071f, 0.63069f,
    0.99976f, 0.89128f, 0.82830f, 0.78271f, 0.74737f, 0.71950f, 0.69722f, 0.67940f, 0.66528f, 0.65409f, 0.64546f,
    0.63911f, 0.63478f, 0.63218f, 0.63092f, 0.63071f, 0.63069f, 0.99976f, 0.89128f, 0.82830f, 0.78271f, 0.74737f,
    0.71950f, 0.69722f, 0.67940f, 0.66528f, 0.65409f, 0.64546f, 0.63911f, 0.63466f, 0.63215f, 0.63083f, 0.63068f,
    0.63066f, 0.99966f, 0.85968f, 0.78046f, 0.72232f, 0.67648f, 0.63903f, 0.60762f, 0.58088f, 0.55789f, 0.53783f,
    0.52050f, 0.50540f, 0.49211f, 0.48033f, 0.46996f, 0.46074f, 0.45255f, 0.99966f, 0.85968f, 0.78046f, 0.72232f,
    0.67648f, 0.63903f, 0.60762f, 0.58088f, 0.55789f, 0.53783f, 0.52050f, 0.50540f, 0.49211f, 0.48033f, 0.46996f,
    0.46074f, 0.45255f, 0.99966f, 0.85950f, 0.78037f, 0.72218f, 0.67644f, 0.63898f, 0.60760f, 0.58088f, 0.55790f,
    0.53786f, 0.52038f, 0.50532f, 0.49204f, 0.48028f, 0.46990f, 0.46071f, 0.45252f, 0.99966f, 0.85957f, 0.78048f,
    0.72230f, 0.67655f, 0.63910f, 0.60775f, 0.58100f, 0.55799f, 0.53797f, 0.52049f, 0.50526f, 0.49195f, 0.48025f,
    0.46986f, 0.46069f, 0.45251f, 0.99966f, 0.85957f, 0.78048f, 0.72230f, 0.67655f, 0.63910f, 0.60775f, 0.58100f,
    0.55799f, 0.53797f, 0.52049f, 0.50526f, 0.49193f, 0.48021f, 0.46982f, 0.46065f, 0.45246f, 0.99952f, 0.82332f,
    0.72598f, 0.65455f, 0.59826f, 0.55212f, 0.51333f, 0.47993f, 0.45082f, 0.42542f, 0.40287f, 0.38271f, 0.36457f,
    0.34812f, 0.33314f, 0.31947f, 0.30689f, 0.99952f, 0.82332f, 0.72598f, 0.65455f, 0.59826f, 0.55212f, 0.51333f,
    0.47993f, 0.45082f, 0.42542f, 0.40288f, 0.38272f, 0.36458f, 0.34813f, 0.33314f, 0.31947f, 0.30689f, 0.99952f,
    0.82332f, 0.72595f, 0.65454f, 0.59825f, 0.55205f, 0.51320f, 0.47979f, 0.45080f, 0.42544f, 0.40291f, 0.38272f,
    0.36459f, 0.34814f, 0.33317f, 0.31947f, 0.30689f, 0.99952f, 0.82332f, 0.72596f, 0.65456f, 0.59827f, 0.55205f,
    0.51319f, 0.47974f, 0.45081f, 0.42546f, 0.40294f, 0.38278f, 0.36460f, 0.34815f, 0.33319f, 0.31948f, 0.30689f,
    0.99952f, 0.82332f, 0.72596f, 0.65456f, 0.59827f, 0.55205f, 0.51319f, 0.47974f, 0.45081f, 0.42546f, 0.40294f,
    0.38278f, 0.36460f, 0.34815f, 0.33319f, 0.31948f, 0.30689f, 0.99674f, 1.02702f, 1.02725f, 1.01646f, 1.01430f,
    1.01331f, 1.01292f, 1.01270f, 1.01260f, 1.01259f, 1.01259f, 1.01274f, 1.01277f, 1.01277f, 1.01260f, 1.01259f,
    1.01258f, 1.01684f, 0.94707f, 0.99751f, 1.00623f, 1.00814f, 1.00924f, 1.01118f, 1.01205f, 1.01285f, 1.01304f,
    1.01281f, 1.01227f, 1.01221f, 1.01229f, 1.01239f, 1.01245f, 1.01258f, 1.01639f, 0.92909f, 0.97359f, 0.99559f,
    1.00248f, 1.00550f, 1.00741f, 1.00964f, 1.01121f, 1.01191f, 1.01277f, 1.01309f, 1.01258f, 1.01215f, 1.01227f,
    1.01245f, 1.01251f, 1.01515f, 0.92474f, 0.95744f, 0.98771f, 0.99656f, 1.00223f, 1.00459f, 1.00710f, 1.00933f,
    1.01085f, 1.01171f, 1.01254f, 1.01311f, 1.01252f, 1.01221f, 1.01235f, 1.01270f, 1.01516f, 0.92527f, 0.94694f,
    0.97751f, 0.98901f, 0.99700f, 1.00097f, 1.00344f, 1.00743f, 1.00944f, 1.01089f, 1.01183f, 1.01258f, 1.01230f,
    1.01208f, 1.01225f, 1.01270f, 1.01603f, 0.98465f, 1.01147f, 1.00858f, 1.01037f, 1.00950f, 1.00860f, 1.00758f,
    1.00660f, 1.00637f, 1.00606f, 1.00592f, 1.00590f, 1.00591f, 1.00591f, 1.00595f, 1.00583f, 1.01717f, 0.92135f,
    0.94426f, 0.96458f, 0.98064f, 0.99026f, 0.99562f, 0.99853f, 1.00037f, 1.00207f, 1.00302f, 1.00385f, 1.00459f,
    1.00512f, 1.00569f, 1.00589f, 1.00592f, 1.01661f, 0.93008f, 0.92651f, 0.94459f, 0.96038f, 0.97260f, 0.98158f,
    0.98895f, 0.99413f, 0.99760f, 1.00035f, 1.00217f, 1.00290f, 1.00369f, 1.00489f, 1.00574f, 1.00594f, 1.01531f,
    0.93847f, 0.92117f, 0.93599f, 0.94825f, 0.96207f, 0.97217f, 0.98098f, 0.98804f, 0.99315f, 0.99695f, 0.99994f,
    1.00205f, 1.00289f, 1.00390f, 1.00538f, 1.00594f, 1.01530f, 0.94573f, 0.92078f, 0.92850f, 0.93801f, 0.95191f,
    0.96333f, 0.97310f, 0.98228f, 0.98878f, 0.99365f, 0.99747f, 1.00029f, 1.00177f, 1.00316f, 1.00502f, 1.00588f,
    1.00116f, 0.89749f, 0.91704f, 0.93929f, 0.95952f, 0.97016f, 0.97625f, 0.97957f, 0.98149f, 0.98331f, 0.98445f,
    0.98536f, 0.98606f, 0.98680f, 0.98732f, 0.98763f, 0.98741f, 1.00140f, 0.92840f, 0.90551f, 0.90765f, 0.92592f,
    0.94105f, 0.95275f, 0.96128f, 0.96752f, 0.97277f, 0.97668f, 0.97975f, 0.98225f, 0.98412f, 0.98565f, 0.98688f,
    0.98750f, 1.00018f, 0.92720f, 0.89843f, 0.89682f, 0.90799f, 0.92198f, 0.93508f, 0.94604f, 0.95514f, 0.96244f,
    0.96839f, 0.97342f, 0.97775f, 0.98114f, 0.98398f, 0.98604f, 0.98751f, 1.00102f, 0.93329f, 0.90267f, 0.89548f,
    0.90056f, 0.91188f, 0.92419f, 0.93567f, 0.94602f, 0.95473f, 0.96245f, 0.96850f, 0.97366f, 0.97796f, 0.98199f,
    0.98524f, 0.98751f, 1.00104f, 0.94037f, 0.90475f, 0.89630f, 0.89752f, 0.90573f, 0.91642f, 0.92753f, 0.93833f,
    0.94784f, 0.95662f, 0.96377f, 0.96999f, 0.97480f, 0.98001f, 0.98432f, 0.98745f, 1.00013f, 0.91257f, 0.87265f,
    0.85126f, 0.86013f, 0.87581f, 0.89078f, 0.90306f, 0.91306f, 0.92092f, 0.92698f, 0.93179f, 0.93567f, 0.93873f,
    0.94125f, 0.94331f, 0.94499f, 1.00025f, 0.93871f, 0.89573f, 0.86270f, 0.86078f, 0.86942f, 0.88074f, 0.89184f,
    0.90219f, 0.91118f, 0.91872f, 0.92516f, 0.93069f, 0.93517f, 0.93905f, 0.94226f, 0.94499f, 0.99989f, 0.92941f,
    0.88740f, 0.86803f, 0.86355f, 0.86698f, 0.87468f, 0.88426f, 0.89412f, 0.90329f, 0.91152f, 0.91898f, 0.92511f,
    0.93055f, 0.93596f, 0.94080f, 0.94454f, 0.99995f, 0.93842f, 0.89807f, 0.87399f, 0.86519f, 0.86649f, 0.87234f,
    0.87993f, 0.88886f, 0.89787f, 0.90662f, 0.91459f, 0.92210f, 0.92817f, 0.93371f, 0.93985f, 0.94459f, 0.99997f,
    0.94466f, 0.90609f, 0.88090f, 0.86730f, 0.86581f, 0.87031f, 0.87718f, 0.88507f, 0.89354f, 0.90215f, 0.91037f,
    0.91844f, 0.92529f, 0.93148f, 0.93873f, 0.94459f, 0.99989f, 0.90660f, 0.85226f, 0.81918f, 0.79906f, 0.79344f,
    0.79547f, 0.80101f, 0.80983f, 0.81898f, 0.82781f, 0.83592f, 0.84329f, 0.84950f, 0.85531f, 0.86033f, 0.86433f,
    0.99997f, 0.92305f, 0.87258f, 0.83849f, 0.81500f, 0.80524f, 0.80335f, 0.80559f, 0.81189f, 0.81925f, 0.82697f,
    0.83453f, 0.84172f, 0.84805f, 0.85422f, 0.85974f, 0.86433f, 0.99987f, 0.92266f, 0.87547f, 0.84432f, 0.82414f,
    0.81260f, 0.80748f, 0.80860f, 0.81303f, 0.81898f, 0.82584f, 0.83289f, 0.83979f, 0.84646f, 0.85267f, 0.85867f,
    0.86424f, 0.99989f, 0.93141f, 0.88691f, 0.85561f, 0.83496f, 0.82168f, 0.81457f, 0.81186f, 0.81443f, 0.81885f,
    0.82480f, 0.83151f, 0.83837f, 0.84521f, 0.85168f, 0.85810f, 0.86424f, 0.99990f, 0.93754f, 0.89541f, 0.86472f,
    0.84344f, 0.82897f, 0.82026f, 0.81558f, 0.81636f, 0.81971f, 0.82473f, 0.83058f, 0.83685f, 0.84374f, 0.85060f,
    0.85752f, 0.86418f, 0.99977f, 0.88954f, 0.82896f, 0.78757f, 0.75824f, 0.73761f, 0.72383f, 0.71572f, 0.71196f,
    0.71136f, 0.71278f, 0.71565f, 0.71985f, 0.72465f, 0.72962f, 0.73506f, 0.73966f, 0.99982f, 0.90005f, 0.84271f,
    0.80229f, 0.77261f, 0.75087f, 0.73556f, 0.72573f, 0.72022f, 0.71794f, 0.71784f, 0.71939f, 0.72245f, 0.72633f,
    0.73056f, 0.73554f, 0.73975f, 0.99982f, 0.90654f, 0.85159f, 0.81223f, 0.78314f, 0.76161f, 0.74585f, 0.73444f,
    0.72683f, 0.72326f, 0.72193f, 0.72248f, 0.72457f, 0.72765f, 0.73136f, 0.73593f, 0.73975f, 0.99984f, 0.91394f,
    0.86181f, 0.82339f, 0.79438f, 0.77240f, 0.75587f, 0.74332f, 0.73439f, 0.72831f, 0.72576f, 0.72549f, 0.72664f,
    0.72889f, 0.73199f, 0.73627f, 0.73971f, 0.99985f, 0.91970f, 0.86988f, 0.83246f, 0.80367f, 0.78140f, 0.76418f,
    0.75073f, 0.74080f, 0.73365f, 0.72958f, 0.72820f, 0.72862f, 0.73020f, 0.73284f, 0.73649f, 0.73954f, 0.99969f,
    0.87157f, 0.80127f, 0.75104f, 0.71275f, 0.68260f, 0.65885f, 0.63973f, 0.62450f, 0.61273f, 0.60363f, 0.59650f,
    0.59126f, 0.58770f, 0.58567f, 0.58459f, 0.58379f, 0.99972f, 0.87795f, 0.80958f, 0.76006f, 0.72187f, 0.69142f,
    0.66715f, 0.64733f, 0.63130f, 0.61867f, 0.60867f, 0.60064f, 0.59451f, 0.59007f, 0.58721f, 0.58533f, 0.58379f,
    0.99974f, 0.88343f, 0.81669f, 0.76802f, 0.72999f, 0.69943f, 0.67479f, 0.65443f, 0.63782f, 0.62423f, 0.61301f,
    0.60431f, 0.59749f, 0.59232f, 0.58870f, 0.58604f, 0.58376f, 0.99976f, 0.88897f, 0.82394f, 0.77599f, 0.73817f,
    0.70761f, 0.68266f, 0.66197f, 0.64474f, 0.63034f, 0.61839f, 0.60855f, 0.60045f, 0.59456f, 0.59010f, 0.58678f,
    0.58376f, 0.99978f, 0.89360f, 0.83026f, 0.78309f, 0.74553f, 0.71489f, 0.68963f, 0.66850f, 0.65068f, 0.63562f,
    0.62295f, 0.61236f, 0.60348f, 0.59679f, 0.59150f, 0.58748f, 0.58373f, 0.99961f, 0.84954f, 0.76641f, 0.70598f,
    0.65875f, 0.62039f, 0.58838f, 0.56122f, 0.53796f, 0.51771f, 0.50026f, 0.48507f, 0.47173f, 0.45991f, 0.44951f,
    0.44026f, 0.43204f, 0.99963f, 0.85250f, 0.77022f, 0.71006f, 0.66284f, 0.62434f, 0.59209f, 0.56464f, 0.54105f,
    0.52045f, 0.50262f, 0.48705f, 0.47332f, 0.46110f, 0.45030f, 0.44066f, 0.43204f, 0.99965f, 0.85518f, 0.77380f,
    0.71388f, 0.66679f, 0.62816f, 0.59572f, 0.56801f, 0.54411f, 0.52319f, 0.50491f, 0.48894f, 0.47483f, 0.46224f,
    0.45103f, 0.44102f, 0.43201f, 0.99966f, 0.85800f, 0.77748f, 0.71787f, 0.67082f, 0.63208f, 0.59946f, 0.57147f,
    0.54722f, 0.52607f, 0.50746f, 0.49097f, 0.47630f, 0.46339f, 0.45178f, 0.44140f, 0.43200f, 0.99968f, 0.86061f,
    0.78092f, 0.72162f, 0.67462f, 0.63579f, 0.60299f, 0.57474f, 0.55020f, 0.52872f, 0.50977f, 0.49291f, 0.47786f,
    0.46453f, 0.45253f, 0.44175f, 0.43195f, 0.99952f, 0.82332f, 0.72621f, 0.65480f, 0.59859f, 0.55247f, 0.51372f,
    0.48038f, 0.45131f, 0.42574f, 0.40297f, 0.38271f, 0.36457f, 0.34812f, 0.33314f, 0.31947f, 0.30689f, 0.99952f,
    0.82332f, 0.72621f, 0.65480f, 0.59859f, 0.55247f, 0.51372f, 0.48038f, 0.45131f, 0.42574f, 0.40297f, 0.38272f,
    0.36458f, 0.34813f, 0.33314f, 0.31947f, 0.30689f, 0.99952f, 0.82332f, 0.72595f, 0.65454f, 0.59831f, 0.55220f,
    0.51340f, 0.48005f, 0.45102f, 0.42547f, 0.40291f, 0.38275f, 0.36459f, 0.34814f, 0.33317f, 0.31947f, 0.30689f,
    0.99952f, 0.82332f, 0.72596f, 0.65456f, 0.59827f, 0.55205f, 0.51319f, 0.47983f, 0.45083f, 0.42547f, 0.40294f,
    0.38278f, 0.36461f, 0.34816f, 0.33319f, 0.31948f, 0.30689f, 0.99952f, 0.82332f, 0.72596f, 0.65456f, 0.59827f,
    0.55205f, 0.51319f, 0.47974f, 0.45083f, 0.42546f, 0.40294f, 0.38278f, 0.36461f, 0.34816f, 0.33319f, 0.31948f,
    0.30689f, 1.00729f, 1.01092f, 1.01102f, 0.97657f, 0.97571f, 0.97572f, 0.97573f, 0.97574f, 0.97574f, 0.97574f,
    0.97574f, 0.97575f, 0.97575f, 0.97575f, 0.97575f, 0.97575f, 0.97575f, 1.04250f, 0.95802f, 0.92868f, 0.89701f,
    0.90929f, 0.92328f, 0.93523f, 0.94473f, 0.95214f, 0.95790f, 0.96241f, 0.96599f, 0.96876f, 0.97104f, 0.97294f,
    0.97446f, 0.97575f, 1.00002f, 0.93217f, 0.89459f, 0.88194f, 0.88994f, 0.90054f, 0.91165f, 0.92253f, 0.93230f,
    0.94057f, 0.94773f, 0.95351f, 0.95875f, 0.96435f, 0.96888f, 0.97259f, 0.97512f, 1.00070f, 0.94135f, 0.90347f,
    0.88544f, 0.87980f, 0.88878f, 0.89986f, 0.91056f, 0.92064f, 0.93007f, 0.93861f, 0.94629f, 0.95288f, 0.95821f,
    0.96513f, 0.97094f, 0.97472f, 1.00072f, 0.94823f, 0.91128f, 0.89044f, 0.88066f, 0.88048f, 0.89064f, 0.90160f,
    0.91206f, 0.92177f, 0.93103f, 0.93979f, 0.94761f, 0.95386f, 0.96125f, 0.96940f, 0.97442f, 1.03909f, 0.96541f,
    0.99067f, 0.96625f, 0.94638f, 0.94570f, 0.94604f, 0.94635f, 0.94654f, 0.94665f, 0.94676f, 0.94684f, 0.94688f,
    0.94691f, 0.94692f, 0.94695f, 0.94700f, 1.04250f, 0.98001f, 0.94200f, 0.90281f, 0.88524f, 0.89273f, 0.90232f,
    0.91123f, 0.91879f, 0.92508f, 0.93025f, 0.93449f, 0.93797f, 0.94085f, 0.94327f, 0.94531f, 0.94700f, 1.00002f,
    0.93631f, 0.89643f, 0.87582f, 0.87484f, 0.87796f, 0.88376f, 0.89138f, 0.89955f, 0.90725f, 0.91449f, 0.92073f,
    0.92670f, 0.93307f, 0.93853f, 0.94301f, 0.94637f, 1.00103f, 0.94513f, 0.90699f, 0.88390f, 0.87093f, 0.87241f,
    0.87721f, 0.88316f, 0.89002f, 0.89767f, 0.90545f, 0.91307f, 0.92005f, 0.92620f, 0.93413f, 0.94104f, 0.94596f,
    1.00105f, 0.95166f, 0.91544f, 0.89136f, 0.87567f, 0.86872f, 0.87228f, 0.87785f, 0.88407f, 0.89088f, 0.89851f,
    0.90657f, 0.91444f, 0.92130f, 0.92971f, 0.93920f, 0.94567f, 1.01573f, 0.87541f, 0.88601f, 0.88212f, 0.88100f,
    0.88663f, 0.89159f, 0.89423f, 0.89572f, 0.89723f, 0.89818f, 0.89895f, 0.89958f, 0.90020f, 0.90063f, 0.90095f,
    0.90095f, 1.01677f, 0.97932f, 0.93509f, 0.88553f, 0.86159f, 0.85878f, 0.86269f, 0.86763f, 0.87276f, 0.87817f,
    0.88291f, 0.88713f, 0.89090f, 0.89408f, 0.89686f, 0.89918f, 0.90104f, 0.99991f, 0.93428f, 0.89334f, 0.86800f,
    0.85330f, 0.84769f, 0.85003f, 0.85463f, 0.85999f, 0.86593f, 0.87174f, 0.87776f, 0.88343f, 0.88851f, 0.89335f,
    0.89747f, 0.90105f, 1.00102f, 0.94508f, 0.90620f, 0.87864f, 0.86142f, 0.85087f, 0.84577f, 0.84769f, 0.85245f,
    0.85811f, 0.86451f, 0.87053f, 0.87709f, 0.88356f, 0.88984f, 0.89584f, 0.90105f, 1.00104f, 0.95146f, 0.91518f,
    0.88744f, 0.86894f, 0.85640f, 0.84865f, 0.84543f, 0.84747f, 0.85260f, 0.85866f, 0.86532f, 0.87214f, 0.87914f,
    0.88667f, 0.89416f, 0.90100f, 1.01622f, 0.89595f, 0.84402f, 0.80345f, 0.79042f, 0.79188f, 0.80102f, 0.81068f,
    0.81857f, 0.82472f, 0.82942f, 0.83312f, 0.83608f, 0.83838f, 0.84028f, 0.84180f, 0.84310f, 1.01674f, 0.97173f,
    0.92077f, 0.86169f, 0.82773f, 0.81222f, 0.80952f, 0.81175f, 0.81547f, 0.81966f, 0.82382f, 0.82783f, 0.83160f,
    0.83494f, 0.83799f, 0.84064f, 0.84310f, 0.99988f, 0.92754f, 0.88306f, 0.85263f, 0.83252f, 0.81903f, 0.81116f,
    0.81042f, 0.81184f, 0.81446f, 0.81821f, 0.82233f, 0.82660f, 0.83090f, 0.83505f, 0.83916f, 0.84264f, 0.99989f,
    0.93796f, 0.89660f, 0.86700f, 0.84563f, 0.83048f, 0.81976f, 0.81354f, 0.81070f, 0.81197f, 0.81461f, 0.81855f,
    0.82291f, 0.82776f, 0.83308f, 0.83822f, 0.84270f, 0.99991f, 0.94455f, 0.90655f, 0.87797f, 0.85623f, 0.83994f,
    0.82747f, 0.81918f, 0.81403f, 0.81156f, 0.81331f, 0.81645f, 0.82049f, 0.82545f, 0.83138f, 0.83722f, 0.84270f,
    0.99997f, 0.88129f, 0.81329f, 0.77151f, 0.74267f, 0.72577f, 0.71809f, 0.71763f, 0.72271f, 0.72882f, 0.73502f,
    0.74087f, 0.74623f, 0.75094f, 0.75513f, 0.75874f, 0.76192f, 1.00026f, 0.92727f, 0.86853f, 0.82530f, 0.79016f,
    0.76503f, 0.74905f, 0.74108f, 0.73981f, 0.74083f, 0.74310f, 0.74602f, 0.74930f, 0.75260f, 0.75585f, 0.75898f,
    0.76192f, 0.99984f, 0.91456f, 0.86379f, 0.82706f, 0.80015f, 0.78033f, 0.76632f, 0.75695f, 0.75055f, 0.74848f,
    0.74815f, 0.74913f, 0.75109f, 0.75345f, 0.75609f, 0.75897f, 0.76170f, 0.99987f, 0.92605f, 0.87898f, 0.84489f,
    0.81830f, 0.79788f, 0.78236f, 0.77066f, 0.76191f, 0.75599f, 0.75320f, 0.75230f, 0.75274f, 0.75417f, 0.75635f,
    0.75889f, 0.76137f, 0.99989f, 0.93435f, 0.89096f, 0.85787f, 0.83190f, 0.81155f, 0.79502f, 0.78177f, 0.77141f,
    0.76370f, 0.75805f, 0.75559f, 0.75465f, 0.75510f, 0.75668f, 0.75898f, 0.76118f, 0.99972f, 0.86288f, 0.78944f,
    0.74150f, 0.70660f, 0.68147f, 0.66384f, 0.65202f, 0.64454f, 0.64133f, 0.64050f, 0.64102f, 0.64301f, 0.64580f,
    0.64913f, 0.65273f, 0.65586f, 0.99989f, 0.88964f, 0.82302f, 0.77661f, 0.74064f, 0.71299f, 0.69206f, 0.67653f,
    0.66529f, 0.65841f, 0.65417f, 0.65158f, 0.65078f, 0.65115f, 0.65239f, 0.65421f, 0.65586f, 0.99978f, 0.89610f,
    0.83609f, 0.79241f, 0.75877f, 0.73238f, 0.71148f, 0.69533f, 0.68271f, 0.67300f, 0.66558f, 0.66068f, 0.65764f,
    0.65602f, 0.65536f, 0.65566f, 0.65585f, 0.99982f, 0.90735f, 0.85236f, 0.81086f, 0.77785f, 0.75157f, 0.73009f,
    0.71257f, 0.69819f, 0.68644f, 0.67706f, 0.66959f, 0.66424f, 0.66065f, 0.65827f, 0.65709f, 0.65585f, 0.99985f,
    0.91645f, 0.86525f, 0.82570f, 0.79346f, 0.76718f, 0.74514f, 0.72665f, 0.71098f, 0.69772f, 0.68672f, 0.67755f,
    0.67044f, 0.66505f, 0.66113f, 0.65842f, 0.65578f, 0.99962f, 0.85076f, 0.77152f, 0.71614f, 0.67462f, 0.64227f,
    0.61687f, 0.59658f, 0.58035f, 0.56741f, 0.55748f, 0.54969f, 0.54365f, 0.53899f, 0.53591f, 0.53395f, 0.53246f,
    0.99971f, 0.86541f, 0.79001f, 0.73576f, 0.69412f, 0.66092f, 0.63425f, 0.61241f, 0.59446f, 0.57973f, 0.56792f,
    0.55827f, 0.55039f, 0.54397f, 0.53919f, 0.53553f, 0.53247f, 0.99971f, 0.87480f, 0.80328f, 0.75092f, 0.70988f,
    0.67679f, 0.64962f, 0.62694f, 0.60789f, 0.59182f, 0.57827f, 0.56675f, 0.55711f, 0.54898f, 0.54243f, 0.53711f,
    0.53250f, 0.99975f, 0.88453f, 0.81663f, 0.76579f, 0.72547f, 0.69219f, 0.66438f, 0.64086f, 0.62067f, 0.60335f,
    0.58831f, 0.57530f, 0.56401f, 0.55417f, 0.54574f, 0.53870f, 0.53254f, 0.99978f, 0.89262f, 0.82779f, 0.77845f,
    0.73869f, 0.70540f, 0.67718f, 0.65293f, 0.63180f, 0.61337f, 0.59708f, 0.58273f, 0.57002f, 0.55872f, 0.54879f,
    0.54022f, 0.53254f, 0.99957f, 0.83866f, 0.75153f, 0.68886f, 0.64025f, 0.60105f, 0.56861f, 0.54127f, 0.51788f,
    0.49769f, 0.48011f, 0.46469f, 0.45106f, 0.43920f, 0.42878f, 0.41955f, 0.41132f, 0.99961f, 0.84497f, 0.75946f,
    0.69725f, 0.64857f, 0.60900f, 0.57603f, 0.54806f, 0.52398f, 0.50306f, 0.48473f, 0.46854f, 0.45416f, 0.44154f,
    0.43033f, 0.42031f, 0.41133f, 0.99963f, 0.85037f, 0.76658f, 0.70483f, 0.65615f, 0.61632f, 0.58292f, 0.55438f,
    0.52968f, 0.50812f, 0.48915f, 0.47230f, 0.45731f, 0.44393f, 0.43190f, 0.42107f, 0.41133f, 0.99966f, 0.85586f,
    0.77384f, 0.71279f, 0.66422f, 0.62416f, 0.59031f, 0.56123f, 0.53588f, 0.51362f, 0.49392f, 0.47635f, 0.46056f,
    0.44637f, 0.43355f, 0.42193f, 0.41133f, 0.99968f, 0.86081f, 0.78039f, 0.71996f, 0.67151f, 0.63129f, 0.59707f,
    0.56751f, 0.54160f, 0.51872f, 0.49835f, 0.48007f, 0.46356f, 0.44863f, 0.43507f, 0.42268f, 0.41132f, 0.99952f,
    0.82372f, 0.72659f, 0.65530f, 0.59909f, 0.55299f, 0.51426f, 0.48095f, 0.45193f, 0.42639f, 0.40367f, 0.38330f,
    0.36487f, 0.34813f, 0.33313f, 0.31946f, 0.30688f, 0.99952f, 0.82372f, 0.72659f, 0.65530f, 0.59909f, 0.55299f,
    0.51426f, 0.48095f, 0.45193f, 0.42639f, 0.40367f, 0.38330f, 0.36487f, 0.34813f, 0.33314f, 0.31946f, 0.30688f,
    0.99952f, 0.82332f, 0.72602f, 0.65478f, 0.59862f, 0.55251f, 0.51373f, 0.48052f, 0.45150f, 0.42602f, 0.40332f,
    0.38299f, 0.36463f, 0.34814f, 0.33317f, 0.31945f, 0.30687f, 0.99952f, 0.82348f, 0.72627f, 0.65483f, 0.59850f,
    0.55228f, 0.51347f, 0.48018f, 0.45121f, 0.42569f, 0.40301f, 0.38277f, 0.36461f, 0.34816f, 0.33318f, 0.31948f,
    0.30687f, 0.99952f, 0.82348f, 0.72627f, 0.65483f, 0.59850f, 0.55228f, 0.51339f, 0.48000f, 0.45100f, 0.42550f,
    0.40293f, 0.38277f, 0.36461f, 0.34816f, 0.33318f, 0.31948f, 0.30687f, 1.00570f, 0.90440f, 0.90450f, 0.85283f,
    0.82487f, 0.80864f, 0.80281f, 0.80282f, 0.80282f, 0.80282f, 0.80282f, 0.80282f, 0.80282f, 0.80282f, 0.80283f,
    0.80283f, 0.80283f, 1.09128f, 1.01802f, 0.96663f, 0.88403f, 0.83775f, 0.81111f, 0.79981f, 0.79725f, 0.79646f,
    0.79658f, 0.79722f, 0.79814f, 0.79914f, 0.80013f, 0.80109f, 0.80197f, 0.80283f, 0.99988f, 0.92758f, 0.88177f,
    0.85035f, 0.82787f, 0.81213f, 0.80035f, 0.79265f, 0.78876f, 0.78896f, 0.78975f, 0.79163f, 0.79353f, 0.79605f,
    0.79846f, 0.80058f, 0.80220f, 0.99989f, 0.93637f, 0.89503f, 0.86422f, 0.84089f, 0.82352f, 0.81037f, 0.80039f,
    0.79322f, 0.78794f, 0.78659f, 0.78806f, 0.78987f, 0.79292f, 0.79627f, 0.79954f, 0.80179f, 0.99990f, 0.94227f,
    0.90485f, 0.87518f, 0.85144f, 0.83315f, 0.81888f, 0.80767f, 0.79874f, 0.79176f, 0.78707f, 0.78591f, 0.78775f,
    0.79016f, 0.79409f, 0.79865f, 0.80150f, 1.08047f, 0.85252f, 0.86799f, 0.82511f, 0.79718f, 0.77927f, 0.77153f,
    0.77175f, 0.77188f, 0.77196f, 0.77202f, 0.77205f, 0.77208f, 0.77212f, 0.77214f, 0.77215f, 0.77217f, 1.09125f,
    1.01319f, 0.95913f, 0.87925f, 0.82893f, 0.79718f, 0.78110f, 0.77626f, 0.77347f, 0.77197f, 0.77124f, 0.77102f,
    0.77104f, 0.77122f, 0.77151f, 0.77183f, 0.77217f, 0.99986f, 0.92374f, 0.87582f, 0.84248f, 0.81803f, 0.80010f,
    0.78604f, 0.77609f, 0.77001f, 0.76818f, 0.76705f, 0.76722f, 0.76758f, 0.76869f, 0.76986f, 0.77095f, 0.77154f,
    0.99987f, 0.93290f, 0.88980f, 0.85742f, 0.83246f, 0.81337f, 0.79831f, 0.78632f, 0.77706f, 0.76971f, 0.76631f,
    0.76577f, 0.76568f, 0.76696f, 0.76860f, 0.77036f, 0.77113f, 0.99989f, 0.93907f, 0.90002f, 0.86900f, 0.84386f,
    0.82409f, 0.80819f, 0.79516f, 0.78436f, 0.77533f, 0.76856f, 0.76539f, 0.76507f, 0.76538f, 0.76731f, 0.76989f,
    0.77084f, 1.03529f, 0.80573f, 0.79830f, 0.76629f, 0.74747f, 0.73575f, 0.72923f, 0.72771f, 0.72913f, 0.72987f,
    0.73050f, 0.73114f, 0.73167f, 0.73218f, 0.73255f, 0.73283f, 0.73294f, 1.03835f, 1.00688f, 0.94915f, 0.86599f,
    0.81248f, 0.77838f, 0.75733f, 0.74635f, 0.74151f, 0.73809f, 0.73587f, 0.73467f, 0.73389f, 0.73348f, 0.73325f,
    0.73311f, 0.73294f, 0.99984f, 0.91709f, 0.86713f, 0.83136f, 0.80461f, 0.78397f, 0.76797f, 0.75545f, 0.74605f,
    0.74096f, 0.73752f, 0.73531f, 0.73400f, 0.73318f, 0.73276f, 0.73294f, 0.73246f, 0.99986f, 0.92673f, 0.88217f,
    0.84782f, 0.82075f, 0.79934f, 0.78231f, 0.76849f, 0.75725f, 0.74782f, 0.74103f, 0.73724f, 0.73494f, 0.73343f,
    0.73277f, 0.73276f, 0.73194f, 0.99987f, 0.93351f, 0.89263f, 0.85988f, 0.83343f, 0.81145f, 0.79378f, 0.77893f,
    0.76647f, 0.75545f, 0.74680f, 0.74003f, 0.73631f, 0.73424f, 0.73310f, 0.73273f, 0.73164f, 1.02822f, 0.84566f,
    0.77870f, 0.72179f, 0.69123f, 0.67777f, 0.67321f, 0.67242f, 0.67429f, 0.67795f, 0.68065f, 0.68296f, 0.68474f,
    0.68602f, 0.68696f, 0.68795f, 0.68869f, 1.02960f, 0.98821f, 0.92471f, 0.84549f, 0.78809f, 0.75068f, 0.72692f,
    0.71150f, 0.70254f, 0.69818f, 0.69498f, 0.69295f, 0.69151f, 0.69037f, 0.68945f, 0.68903f, 0.68869f, 0.99982f,
    0.90953f, 0.85546f, 0.81647f, 0.78673f, 0.76359f, 0.74521f, 0.73005f, 0.71855f, 0.70990f, 0.70378f, 0.69918f,
    0.69560f, 0.69297f, 0.69123f, 0.68981f, 0.68843f, 0.99984f, 0.92006f, 0.87246f, 0.83546f, 0.80624f, 0.78248f,
    0.76291f, 0.74619f, 0.73286f, 0.72165f, 0.71226f, 0.70555f, 0.70022f, 0.69598f, 0.69296f, 0.69084f, 0.68838f,
    0.99986f, 0.92808f, 0.88335f, 0.84906f, 0.82081f, 0.79716f, 0.77648f, 0.75919f, 0.74463f, 0.73198f, 0.72098f,
    0.71193f, 0.70476f, 0.69928f, 0.69489f, 0.69166f, 0.68817f, 1.00386f, 0.84257f, 0.75958f, 0.70411f, 0.66500f,
    0.64052f, 0.62668f, 0.61968f, 0.61683f, 0.61719f, 0.61981f, 0.62322f, 0.62639f, 0.62910f, 0.63172f, 0.63393f,
    0.63580f, 1.00456f, 0.92905f, 0.85847f, 0.79935f, 0.75027f, 0.71348f, 0.68713f, 0.66856f, 0.65551f, 0.64716f,
    0.64249f, 0.63991f, 0.63820f, 0.63695f, 0.63638f, 0.63602f, 0.63580f, 0.99979f, 0.89787f, 0.83852f, 0.79446f,
    0.76059f, 0.73368f, 0.71192f, 0.69436f, 0.68016f, 0.66901f, 0.65989f, 0.65310f, 0.64789f, 0.64370f, 0.64034f,
    0.63785f, 0.63569f, 0.99982f, 0.91158f, 0.85766f, 0.81716f, 0.78425f, 0.75731f, 0.73493f, 0.71599f, 0.69978f,
    0.68622f, 0.67450f, 0.66483f, 0.65653f, 0.64981f, 0.64422f, 0.63953f, 0.63541f, 0.99985f, 0.92067f, 0.87132f,
    0.83302f, 0.80148f, 0.77537f, 0.75259f, 0.73273f, 0.71524f, 0.70009f, 0.68657f, 0.67488f, 0.66449f, 0.65560f,
    0.64795f, 0.64139f, 0.63535f, 0.99972f, 0.83139f, 0.74537f, 0.68798f, 0.64676f, 0.61731f, 0.59649f, 0.58190f,
    0.57202f, 0.56570f, 0.56194f, 0.56053f, 0.56067f, 0.56179f, 0.56343f, 0.56544f, 0.56724f, 1.00008f, 0.87970f,
    0.80288f, 0.74626f, 0.70220f, 0.66811f, 0.64179f, 0.62134f, 0.60563f, 0.59366f, 0.58495f, 0.57882f, 0.57451f,
    0.57147f, 0.56938f, 0.56821f, 0.56728f, 0.99975f, 0.88340f, 0.81535f, 0.76582f, 0.72695f, 0.69550f, 0.66989f,
    0.64843f, 0.63114f, 0.61682f, 0.60494f, 0.59511f, 0.58705f, 0.58046f, 0.57509f, 0.57093f, 0.56734f, 0.99979f,
    0.89752f, 0.83607f, 0.78962f, 0.75202f, 0.72105f, 0.69486f, 0.67254f, 0.65326f, 0.63650f, 0.62206f, 0.60948f,
    0.59847f, 0.58889f, 0.58062f, 0.57357f, 0.56738f, 0.99982f, 0.90838f, 0.85215f, 0.80823f, 0.77202f, 0.74141f,
    0.71488f, 0.69168f, 0.67109f, 0.65270f, 0.63635f, 0.62166f, 0.60839f, 0.59642f, 0.58567f, 0.57611f, 0.56738f,
    0.99957f, 0.82838f, 0.74061f, 0.67986f, 0.63487f, 0.60032f, 0.57341f, 0.55209f, 0.53505f, 0.52146f, 0.51087f,
    0.50248f, 0.49584f, 0.49098f, 0.48745f, 0.48494f, 0.48288f, 0.99974f, 0.85311f, 0.77067f, 0.71093f, 0.66511f,
    0.62879f, 0.59961f, 0.57574f, 0.55598f, 0.53969f, 0.52628f, 0.51525f, 0.50616f, 0.49857f, 0.49238f, 0.48728f,
    0.48292f, 0.99968f, 0.86566f, 0.78901f, 0.73240f, 0.68802f, 0.65188f, 0.62170f, 0.59663f, 0.57528f, 0.55701f,
    0.54134f, 0.52771f, 0.51600f, 0.50592f, 0.49721f, 0.48964f, 0.48300f, 0.99974f, 0.87861f, 0.80690f, 0.75272f,
    0.70917f, 0.67308f, 0.64243f, 0.61608f, 0.59318f, 0.57308f, 0.55539f, 0.53961f, 0.52566f, 0.51312f, 0.50196f,
    0.49204f, 0.48314f, 0.99978f, 0.88933f, 0.82185f, 0.76977f, 0.72710f, 0.69110f, 0.65997f, 0.63273f, 0.60861f,
    0.58705f, 0.56770f, 0.55010f, 0.53422f, 0.51963f, 0.50637f, 0.49426f, 0.48314f, 0.99954f, 0.82765f, 0.73636f,
    0.67148f, 0.62165f, 0.58179f, 0.54901f, 0.52150f, 0.49800f, 0.47784f, 0.46030f, 0.44496f, 0.43145f, 0.41955f,
    0.40920f, 0.40004f, 0.39189f, 0.99961f, 0.83764f, 0.74869f, 0.68432f, 0.63422f, 0.59370f, 0.56003f, 0.53151f,
    0.50693f, 0.48567f, 0.46700f, 0.45052f, 0.43588f, 0.42291f, 0.41144f, 0.40119f, 0.39196f, 0.99961f, 0.84560f,
    0.75921f, 0.69569f, 0.64555f, 0.60451f, 0.57006f, 0.54066f, 0.51521f, 0.49292f, 0.47330f, 0.45587f, 0.44032f,
    0.42636f, 0.41373f, 0.40235f, 0.39200f, 0.99965f, 0.85386f, 0.76998f, 0.70734f, 0.65730f, 0.61590f, 0.58084f,
    0.55059f, 0.52417f, 0.50089f, 0.48020f, 0.46162f, 0.44492f, 0.42983f, 0.41608f, 0.40354f, 0.39205f, 0.99969f,
    0.86088f, 0.77931f, 0.71759f, 0.66776f, 0.62614f, 0.59057f, 0.55964f, 0.53240f, 0.50821f, 0.48655f, 0.46696f,
    0.44922f, 0.43306f, 0.41825f, 0.40462f, 0.39205f, 0.99954f, 0.82430f, 0.72724f, 0.65591f, 0.59968f, 0.55358f,
    0.51485f, 0.48159f, 0.45254f, 0.42708f, 0.40438f, 0.38404f, 0.36567f, 0.34898f, 0.33376f, 0.31975f, 0.30691f,
    0.99954f, 0.82430f, 0.72724f, 0.65591f, 0.59968f, 0.55358f, 0.51485f, 0.48159f, 0.45254f, 0.42708f, 0.40438f,
    0.38404f, 0.36567f, 0.34898f, 0.33376f, 0.31975f, 0.30691f, 0.99952f, 0.82360f, 0.72635f, 0.65522f, 0.59910f,
    0.55300f, 0.51427f, 0.48103f, 0.45211f, 0.42664f, 0.40399f, 0.38371f, 0.36540f, 0.34875f, 0.33357f, 0.31964f,
    0.30688f, 0.99952f, 0.82400f, 0.72676f, 0.65532f, 0.59903f, 0.55284f, 0.51400f, 0.48068f, 0.45179f, 0.42631f,
    0.40368f, 0.38343f, 0.36513f, 0.34853f, 0.33341f, 0.31954f, 0.30687f, 0.99952f, 0.82400f, 0.72676f, 0.65532f,
    0.59903f, 0.55284f, 0.51400f, 0.48064f, 0.45161f, 0.42615f, 0.40347f, 0.38320f, 0.36493f, 0.34834f, 0.33326f,
    0.31948f, 0.30687f, 0.90762f, 0.65392f, 0.65395f, 0.60227f, 0.57430f, 0.55806f, 0.54852f, 0.54221f, 0.53864f,
    0.53645f, 0.53508f, 0.53408f, 0.53397f, 0.53391f, 0.53391f, 0.53384f, 0.53383f, 1.09102f, 0.96208f, 0.88137f,
    0.77490f, 0.70719f, 0.66112f, 0.62883f, 0.60480f, 0.58804f, 0.57506f, 0.56538f, 0.55728f, 0.55018f, 0.54505f,
    0.54057f, 0.53705f, 0.53404f, 0.99969f, 0.87993f, 0.81243f, 0.76156f, 0.72159f, 0.68933f, 0.66177f, 0.63892f,
    0.61940f, 0.60304f, 0.58836f, 0.57538f, 0.56480f, 0.55489f, 0.54708f, 0.54003f, 0.53404f, 0.99974f, 0.89395f,
    0.83193f, 0.78521f, 0.74671f, 0.71471f, 0.68729f, 0.66326f, 0.64214f, 0.62317f, 0.60657f, 0.59103f, 0.57675f,
    0.56455f, 0.55279f, 0.54295f, 0.53409f, 0.99977f, 0.90382f, 0.84568f, 0.80164f, 0.76493f, 0.73327f, 0.70594f,
    0.68158f, 0.65941f, 0.63896f, 0.62068f, 0.60322f, 0.58681f, 0.57229f, 0.55804f, 0.54566f, 0.53409f, 1.06523f,
    0.64533f, 0.65141f, 0.60659f, 0.57800f, 0.55977f, 0.54930f, 0.54321f, 0.53903f, 0.53680f, 0.53536f, 0.53447f,
    0.53385f, 0.53380f, 0.53381f, 0.53375f, 0.53376f, 1.09101f, 0.96206f, 0.88139f, 0.78035f, 0.71145f, 0.66321f,
    0.62984f, 0.60602f, 0.58796f, 0.57496f, 0.56529f, 0.55717f, 0.55012f, 0.54498f, 0.54050f, 0.53697f, 0.53396f,
    0.99969f, 0.87993f, 0.81246f, 0.76157f, 0.72159f, 0.68930f, 0.66170f, 0.63889f, 0.61932f, 0.60298f, 0.58830f,
    0.57532f, 0.56473f, 0.55482f, 0.54700f, 0.53994f, 0.53396f, 0.99974f, 0.89395f, 0.83196f, 0.78519f, 0.74668f,
    0.71468f, 0.68726f, 0.66320f, 0.64210f, 0.62311f, 0.60649f, 0.59096f, 0.57669f, 0.56447f, 0.55271f, 0.54287f,
    0.53402f, 0.99977f, 0.90383f, 0.84568f, 0.80164f, 0.76492f, 0.73326f, 0.70592f, 0.68155f, 0.65937f, 0.63892f,
    0.62063f, 0.60316f, 0.58674f, 0.57223f, 0.55797f, 0.54559f, 0.53402f, 1.03098f, 0.66003f, 0.63701f, 0.59436f,
    0.56936f, 0.55408f, 0.54544f, 0.54036f, 0.53732f, 0.53498f, 0.53412f, 0.53318f, 0.53278f, 0.53268f, 0.53283f,
    0.53280f, 0.53262f, 1.03815f, 0.96176f, 0.88064f, 0.77928f, 0.71018f, 0.66229f, 0.62910f, 0.60521f, 0.58755f,
    0.57363f, 0.56354f, 0.55518f, 0.54863f, 0.54344f, 0.53936f, 0.53578f, 0.53262f, 0.99969f, 0.87903f, 0.81063f,
    0.75967f, 0.71951f, 0.68671f, 0.65935f, 0.63615f, 0.61667f, 0.60036f, 0.58594f, 0.57315f, 0.56269f, 0.55326f,
    0.54526f, 0.53858f, 0.53255f, 0.99974f, 0.89302f, 0.83036f, 0.78336f, 0.74458f, 0.71225f, 0.68469f, 0.66072f,
    0.63960f, 0.62050f, 0.60399f, 0.58877f, 0.57451f, 0.56251f, 0.55087f, 0.54109f, 0.53243f, 0.99977f, 0.90309f,
    0.84433f, 0.79984f, 0.76290f, 0.73103f, 0.70351f, 0.67905f, 0.65706f, 0.63659f, 0.61836f, 0.60110f, 0.58462f,
    0.57041f, 0.55617f, 0.54373f, 0.53243f, 1.02647f, 0.73611f, 0.65815f, 0.59510f, 0.55903f, 0.54073f, 0.53214f,
    0.52813f, 0.52636f, 0.52521f, 0.52538f, 0.52538f, 0.52604f, 0.52650f, 0.52713f, 0.52765f, 0.52794f, 1.02943f,
    0.95070f, 0.86774f, 0.77373f, 0.70389f, 0.65558f, 0.62220f, 0.59830f, 0.58069f, 0.56692f, 0.55699f, 0.54910f,
    0.54289f, 0.53791f, 0.53405f, 0.53079f, 0.52794f, 0.99970f, 0.87784f, 0.80815f, 0.75630f, 0.71551f, 0.68245f,
    0.65491f, 0.63113f, 0.61154f, 0.59439f, 0.58015f, 0.56793f, 0.55757f, 0.54823f, 0.54042f, 0.53377f, 0.52788f,
    0.99974f, 0.89207f, 0.82910f, 0.78032f, 0.74163f, 0.70886f, 0.68089f, 0.65596f, 0.63466f, 0.61572f, 0.59868f,
    0.58348f, 0.57002f, 0.55748f, 0.54651f, 0.53664f, 0.52788f, 0.99977f, 0.90202f, 0.84321f, 0.79757f, 0.76008f,
    0.72811f, 0.70001f, 0.67502f, 0.65272f, 0.63238f, 0.61360f, 0.59639f, 0.58070f, 0.56571f, 0.55210f, 0.53947f,
    0.52786f, 1.00302f, 0.76490f, 0.66935f, 0.60918f, 0.56719f, 0.54020f, 0.52391f, 0.51452f, 0.50938f, 0.50761f,
    0.50734f, 0.50795f, 0.50904f, 0.51007f, 0.51133f, 0.51274f, 0.51377f, 1.00442f, 0.89810f, 0.81202f, 0.74183f,
    0.68383f, 0.63955f, 0.60663f, 0.58215f, 0.56378f, 0.55062f, 0.54066f, 0.53332f, 0.52727f, 0.52255f, 0.51899f,
    0.51621f, 0.51377f, 0.99970f, 0.87410f, 0.80178f, 0.74762f, 0.70522f, 0.67070f, 0.64205f, 0.61807f, 0.59782f,
    0.58083f, 0.56633f, 0.55384f, 0.54328f, 0.53390f, 0.52618f, 0.51960f, 0.51381f, 0.99974f, 0.89005f, 0.82462f,
    0.77489f, 0.73413f, 0.69992f, 0.67091f, 0.64580f, 0.62335f, 0.60391f, 0.58640f, 0.57081f, 0.55694f, 0.54435f,
    0.53296f, 0.52299f, 0.51395f, 0.99978f, 0.90065f, 0.84064f, 0.79346f, 0.75440f, 0.72133f, 0.69223f, 0.66632f,
    0.64317f, 0.62225f, 0.60281f, 0.58499f, 0.56868f, 0.55338f, 0.53912f, 0.52613f, 0.51395f, 0.99929f, 0.78058f,
    0.68293f, 0.62082f, 0.57725f, 0.54637f, 0.52445f, 0.50884f, 0.49794f, 0.49057f, 0.48571f, 0.48301f, 0.48192f,
    0.48176f, 0.48213f, 0.48294f, 0.48373f, 0.99996f, 0.85450f, 0.76598f, 0.70164f, 0.65193f, 0.61338f, 0.58335f,
    0.55965f, 0.54099f, 0.52631f, 0.51497f, 0.50622f, 0.49947f, 0.49413f, 0.48983f, 0.48651f, 0.48373f, 0.99968f,
    0.86610f, 0.78857f, 0.73181f, 0.68699f, 0.65039f, 0.62020f, 0.59455f, 0.57338f, 0.55542f, 0.54009f, 0.52679f,
    0.51541f, 0.50557f, 0.49718f, 0.49003f, 0.48377f, 0.99974f, 0.88351f, 0.81381f, 0.76086f, 0.71754f, 0.68126f,
    0.65044f, 0.62370f, 0.60017f, 0.57945f, 0.56108f, 0.54454f, 0.52971f, 0.51637f, 0.50422f, 0.49356f, 0.48391f,
    0.99978f, 0.89590f, 0.83177f, 0.78230f, 0.74071f, 0.70502f, 0.67414f, 0.64654f, 0.62165f, 0.59913f, 0.57862f,
    0.55965f, 0.54215f, 0.52592f, 0.51072f, 0.49687f, 0.48391f, 0.99937f, 0.79919f, 0.70311f, 0.63855f, 0.59162f,
    0.55602f, 0.52851f, 0.50681f, 0.48950f, 0.47567f, 0.46485f, 0.45621f, 0.44929f, 0.44412f, 0.44024f, 0.43736f,
    0.43489f, 0.99966f, 0.83564f, 0.74563f, 0.68115f, 0.63209f, 0.59340f, 0.56239f, 0.53700f, 0.51596f, 0.49852f,
    0.48405f, 0.47201f, 0.46194f, 0.45339f, 0.44626f, 0.44022f, 0.43493f, 0.99964f, 0.85447f, 0.77167f, 0.71058f,
    0.66265f, 0.62354f, 0.59082f, 0.56351f, 0.54014f, 0.52000f, 0.50259f, 0.48730f, 0.47399f, 0.46237f, 0.45214f,
    0.44310f, 0.43502f, 0.99971f, 0.87082f, 0.79433f, 0.73618f, 0.68918f, 0.65000f, 0.61652f, 0.58754f, 0.56216f,
    0.53969f, 0.51974f, 0.50178f, 0.48572f, 0.47110f, 0.45792f, 0.44601f, 0.43515f, 0.99976f, 0.88358f, 0.81228f,
    0.75675f, 0.71090f, 0.67190f, 0.63790f, 0.60786f, 0.58102f, 0.55678f, 0.53481f, 0.51463f, 0.49619f, 0.47909f,
    0.46332f, 0.44874f, 0.43515f, 0.99946f, 0.81526f, 0.71991f, 0.65302f, 0.60211f, 0.56168f, 0.52861f, 0.50098f,
    0.47747f, 0.45737f, 0.43991f, 0.42468f, 0.41128f, 0.39950f, 0.38926f, 0.38020f, 0.37215f, 0.99956f, 0.82929f,
    0.73685f, 0.67038f, 0.61889f, 0.57739f, 0.54302f, 0.51398f, 0.48899f, 0.46739f, 0.44845f, 0.43174f, 0.41689f,
    0.40372f, 0.39206f, 0.38163f, 0.37222f, 0.99959f, 0.84036f, 0.75117f, 0.68567f, 0.63401f, 0.59174f, 0.55626f,
    0.52599f, 0.49978f, 0.47681f, 0.45658f, 0.43857f, 0.42249f, 0.40803f, 0.39491f, 0.38307f, 0.37226f, 0.99964f,
    0.85096f, 0.76504f, 0.70066f, 0.64909f, 0.60632f, 0.57001f, 0.53862f, 0.51114f, 0.48687f, 0.46525f, 0.44579f,
    0.42825f, 0.41235f, 0.39783f, 0.38453f, 0.37231f, 0.99969f, 0.85982f, 0.77689f, 0.71373f, 0.66244f, 0.61940f,
    0.58245f, 0.55017f, 0.52164f, 0.49619f, 0.47332f, 0.45256f, 0.43368f, 0.41643f, 0.40054f, 0.38588f, 0.37231f,
    0.99954f, 0.82430f, 0.72724f, 0.65591f, 0.59968f, 0.55358f, 0.51485f, 0.48159f, 0.45254f, 0.42708f, 0.40438f,
    0.38404f, 0.36567f, 0.34898f, 0.33376f, 0.31975f, 0.30691f, 0.99954f, 0.82430f, 0.72724f, 0.65591f, 0.59968f,
    0.55358f, 0.51485f, 0.48159f, 0.45254f, 0.42708f, 0.40438f, 0.38404f, 0.36567f, 0.34898f, 0.33376f, 0.31975f,
    0.30691f, 0.99952f, 0.82360f, 0.72635f, 0.65522f, 0.59910f, 0.55300f, 0.51427f, 0.48103f, 0.45211f, 0.42664f,
    0.40399f, 0.38371f, 0.36540f, 0.34875f, 0.33357f, 0.31964f, 0.30688f, 0.99952f, 0.82400f, 0.72676f, 0.65532f,
    0.59903f, 0.55284f, 0.51400f, 0.48068f, 0.45179f, 0.42631f, 0.40368f, 0.38343f, 0.36513f, 0.34853f, 0.33341f,
    0.31954f, 0.30687f, 0.99952f, 0.82400f, 0.72676f, 0.65532f, 0.59903f, 0.55284f, 0.51400f, 0.48064f, 0.45161f,
    0.42615f, 0.40347f, 0.38320f, 0.36493f, 0.34834f, 0.33326f, 0.31948f, 0.30687f,
};
constant float ANISO_E_SCHLICK[3825] = {
    1.01977f, 0.78957f, 0.55744f, 0.37540f, 0.24810f, 0.15861f, 0.09790f, 0.05735f, 0.03163f, 0.01621f, 0.00753f,
    0.00306f, 0.00102f, 0.00026f, 0.00005f, 0.00002f, 0.00001f, 1.03777f, 0.80760f, 0.58287f, 0.39429f, 0.25911f,
    0.16521f, 0.10120f, 0.05890f, 0.03231f, 0.01638f, 0.00758f, 0.00311f, 0.00107f, 0.00028f, 0.00007f, 0.00002f,
    0.00001f, 1.04334f, 0.81314f, 0.59483f, 0.40306f, 0.26544f, 0.16915f, 0.10368f, 0.06043f, 0.03307f, 0.01673f,
    0.00760f, 0.00311f, 0.00107f, 0.00030f, 0.00007f, 0.00003f, 0.00001f, 1.04455f, 0.81437f, 0.59886f, 0.40899f,
    0.26938f, 0.17216f, 0.10552f, 0.06142f, 0.03372f, 0.01706f, 0.00769f, 0.00307f, 0.00106f, 0.00030f, 0.00008f,
    0.00003f, 0.00001f, 1.04457f, 0.81437f, 0.59886f, 0.40899f, 0.26938f, 0.17216f, 0.10552f, 0.06142f, 0.03372f,
    0.01706f, 0.00769f, 0.00305f, 0.00104f, 0.00029f, 0.00008f, 0.00003f, 0.00001f, 0.84652f, 0.72945f, 0.53997f,
    0.36867f, 0.24939f, 0.16172f, 0.10049f, 0.05915f, 0.03279f, 0.01681f, 0.00779f, 0.00319f, 0.00113f, 0.00033f,
    0.00012f, 0.00006f, 0.00002f, 0.86451f, 0.74748f, 0.56538f, 0.38755f, 0.25651f, 0.16531f, 0.10312f, 0.06088f,
    0.03370f, 0.01734f, 0.00804f, 0.00328f, 0.00113f, 0.00033f, 0.00012f, 0.00006f, 0.00002f, 0.87008f, 0.75301f,
    0.57736f, 0.39634f, 0.26284f, 0.16833f, 0.10438f, 0.06178f, 0.03440f, 0.01773f, 0.00827f, 0.00340f, 0.00115f,
    0.00033f, 0.00011f, 0.00005f, 0.00002f, 0.87128f, 0.75426f, 0.58137f, 0.40226f, 0.26677f, 0.17134f, 0.10566f,
    0.06244f, 0.03487f, 0.01806f, 0.00849f, 0.00353f, 0.00120f, 0.00033f, 0.00011f, 0.00005f, 0.00002f, 0.87132f,
    0.75425f, 0.58139f, 0.40227f, 0.26678f, 0.17134f, 0.10566f, 0.06244f, 0.03487f, 0.01806f, 0.00849f, 0.00353f,
    0.00120f, 0.00033f, 0.00011f, 0.00004f, 0.00002f, 0.51548f, 0.45015f, 0.38097f, 0.29992f, 0.21828f, 0.14843f,
    0.09579f, 0.05857f, 0.03431f, 0.01874f, 0.00939f, 0.00419f, 0.00163f, 0.00056f, 0.00019f, 0.00008f, 0.00003f,
    0.52921f, 0.45971f, 0.39011f, 0.30771f, 0.22338f, 0.15202f, 0.09842f, 0.06030f, 0.03474f, 0.01903f, 0.00957f,
    0.00429f, 0.00170f, 0.00056f, 0.00019f, 0.00008f, 0.00003f, 0.52922f, 0.45969f, 0.39009f, 0.30770f, 0.22465f,
    0.15370f, 0.09968f, 0.06120f, 0.03544f, 0.01924f, 0.00972f, 0.00439f, 0.00174f, 0.00058f, 0.00019f, 0.00007f,
    0.00003f, 0.51710f, 0.45400f, 0.38784f, 0.30678f, 0.22508f, 0.15484f, 0.10055f, 0.06186f, 0.03590f, 0.01945f,
    0.00986f, 0.00449f, 0.00181f, 0.00061f, 0.00019f, 0.00006f, 0.00003f, 0.51023f, 0.44812f, 0.38400f, 0.30296f,
    0.22509f, 0.15484f, 0.10054f, 0.06186f, 0.03590f, 0.01945f, 0.00986f, 0.00449f, 0.00181f, 0.00061f, 0.00019f,
    0.00006f, 0.00003f, 0.31579f, 0.26777f, 0.22249f, 0.17960f, 0.13964f, 0.10411f, 0.07421f, 0.05006f, 0.03187f,
    0.01901f, 0.01055f, 0.00543f, 0.00255f, 0.00106f, 0.00040f, 0.00015f, 0.00004f, 0.32218f, 0.27190f, 0.22579f,
    0.18316f, 0.14312f, 0.10641f, 0.07542f, 0.05086f, 0.03228f, 0.01931f, 0.01073f, 0.00547f, 0.00258f, 0.00108f,
    0.00040f, 0.00015f, 0.00004f, 0.32218f, 0.27192f, 0.22580f, 0.18316f, 0.14312f, 0.10641f, 0.07552f, 0.05107f,
    0.03256f, 0.01952f, 0.01087f, 0.00556f, 0.00259f, 0.00109f, 0.00039f, 0.00013f, 0.00004f, 0.31554f, 0.26633f,
    0.22188f, 0.18016f, 0.14159f, 0.10608f, 0.07552f, 0.05107f, 0.03264f, 0.01966f, 0.01102f, 0.00566f, 0.00263f,
    0.00110f, 0.00040f, 0.00013f, 0.00004f, 0.31418f, 0.26566f, 0.22038f, 0.17722f, 0.13964f, 0.10485f, 0.07499f,
    0.05085f, 0.03264f, 0.01966f, 0.01102f, 0.00566f, 0.00263f, 0.00110f, 0.00040f, 0.00013f, 0.00004f, 0.19310f,
    0.15853f, 0.12915f, 0.10365f, 0.08151f, 0.06246f, 0.04641f, 0.03319f, 0.02286f, 0.01507f, 0.00943f, 0.00550f,
    0.00294f, 0.00141f, 0.00058f, 0.00020f, 0.00004f, 0.19545f, 0.16045f, 0.13031f, 0.10462f, 0.08237f, 0.06320f,
    0.04700f, 0.03366f, 0.02307f, 0.01519f, 0.00947f, 0.00554f, 0.00297f, 0.00143f, 0.00059f, 0.00020f, 0.00004f,
    0.19545f, 0.16040f, 0.13032f, 0.10464f, 0.08237f, 0.06320f, 0.04700f, 0.03366f, 0.02307f, 0.01519f, 0.00950f,
    0.00555f, 0.00299f, 0.00144f, 0.00060f, 0.00020f, 0.00004f, 0.19302f, 0.15813f, 0.12868f, 0.10306f, 0.08104f,
    0.06240f, 0.04652f, 0.03341f, 0.02306f, 0.01519f, 0.00949f, 0.00556f, 0.00300f, 0.00146f, 0.00061f, 0.00020f,
    0.00004f, 0.19288f, 0.15803f, 0.12865f, 0.10306f, 0.08088f, 0.06186f, 0.04591f, 0.03310f, 0.02287f, 0.01508f,
    0.00948f, 0.00556f, 0.00300f, 0.00146f, 0.00061f, 0.00020f, 0.00004f, 0.12279f, 0.09675f, 0.07685f, 0.06065f,
    0.04731f, 0.03633f, 0.02734f, 0.02008f, 0.01433f, 0.00987f, 0.00652f, 0.00411f, 0.00244f, 0.00133f, 0.00063f,
    0.00024f, 0.00005f, 0.12354f, 0.09720f, 0.07720f, 0.06079f, 0.04745f, 0.03641f, 0.02742f, 0.02015f, 0.01439f,
    0.00992f, 0.00655f, 0.00411f, 0.00244f, 0.00133f, 0.00063f, 0.00024f, 0.00005f, 0.12354f, 0.09721f, 0.07720f,
    0.06079f, 0.04746f, 0.03641f, 0.02742f, 0.02015f, 0.01439f, 0.00992f, 0.00655f, 0.00412f, 0.00244f, 0.00133f,
    0.00063f, 0.00024f, 0.00005f, 0.12282f, 0.09653f, 0.07666f, 0.06048f, 0.04711f, 0.03615f, 0.02716f, 0.01998f,
    0.01428f, 0.00986f, 0.00652f, 0.00412f, 0.00244f, 0.00133f, 0.00064f, 0.00024f, 0.00005f, 0.12282f, 0.09650f,
    0.07666f, 0.06048f, 0.04711f, 0.03615f, 0.02716f, 0.01994f, 0.01419f, 0.00980f, 0.00650f, 0.00411f, 0.00244f,
    0.00133f, 0.00064f, 0.00024f, 0.00005f, 0.08315f, 0.06171f, 0.04740f, 0.03657f, 0.02805f, 0.02132f, 0.01601f,
    0.01182f, 0.00854f, 0.00601f, 0.00410f, 0.00268f, 0.00166f, 0.00095f, 0.00049f, 0.00021f, 0.00005f, 0.08338f,
    0.06192f, 0.04761f, 0.03661f, 0.02805f, 0.02132f, 0.01601f, 0.01182f, 0.00854f, 0.00601f, 0.00410f, 0.00268f,
    0.00166f, 0.00095f, 0.00049f, 0.00021f, 0.00005f, 0.08338f, 0.06192f, 0.04761f, 0.03661f, 0.02802f, 0.02129f,
    0.01598f, 0.01179f, 0.00853f, 0.00601f, 0.00410f, 0.00268f, 0.00166f, 0.00096f, 0.00049f, 0.00021f, 0.00005f,
    0.08318f, 0.06171f, 0.04740f, 0.03651f, 0.02797f, 0.02124f, 0.01593f, 0.01175f, 0.00849f, 0.00598f, 0.00408f,
    0.00267f, 0.00166f, 0.00096f, 0.00049f, 0.00021f, 0.00005f, 0.08318f, 0.06171f, 0.04740f, 0.03651f, 0.02797f,
    0.02124f, 0.01593f, 0.01175f, 0.00849f, 0.00597f, 0.00407f, 0.00266f, 0.00165f, 0.00095f, 0.00049f, 0.00021f,
    0.00005f, 0.06063f, 0.04169f, 0.03072f, 0.02295f, 0.01718f, 0.01282f, 0.00950f, 0.00696f, 0.00503f, 0.00356f,
    0.00246f, 0.00164f, 0.00105f, 0.00062f, 0.00034f, 0.00015f, 0.00004f, 0.06069f, 0.04172f, 0.03074f, 0.02295f,
    0.01718f, 0.01282f, 0.00950f, 0.00696f, 0.00503f, 0.00356f, 0.00246f, 0.00164f, 0.00105f, 0.00062f, 0.00034f,
    0.00015f, 0.00004f, 0.06069f, 0.04172f, 0.03074f, 0.02294f, 0.01716f, 0.01281f, 0.00949f, 0.00695f, 0.00502f,
    0.00355f, 0.00245f, 0.00164f, 0.00104f, 0.00062f, 0.00034f, 0.00015f, 0.00004f, 0.06065f, 0.04169f, 0.03072f,
    0.02294f, 0.01715f, 0.01280f, 0.00948f, 0.00695f, 0.00502f, 0.00355f, 0.00245f, 0.00163f, 0.00104f, 0.00062f,
    0.00034f, 0.00015f, 0.00004f, 0.06065f, 0.04169f, 0.03072f, 0.02294f, 0.01715f, 0.01280f, 0.00948f, 0.00695f,
    0.00502f, 0.00355f, 0.00245f, 0.00163f, 0.00104f, 0.00062f, 0.00034f, 0.00015f, 0.00004f, 0.04756f, 0.02972f,
    0.02083f, 0.01497f, 0.01089f, 0.00794f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f,
    0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04757f, 0.02972f, 0.02083f, 0.01497f, 0.01089f, 0.00794f, 0.00578f,
    0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04757f,
    0.02972f, 0.02083f, 0.01497f, 0.01088f, 0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f,
    0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04757f, 0.02972f, 0.02083f, 0.01497f, 0.01088f, 0.00793f,
    0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f,
    0.04757f, 0.02972f, 0.02083f, 0.01497f, 0.01088f, 0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f,
    0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 1.02629f, 0.78965f, 0.55849f, 0.37688f, 0.24969f,
    0.16011f, 0.09965f, 0.05945f, 0.03335f, 0.01739f, 0.00826f, 0.00346f, 0.00123f, 0.00035f, 0.00007f, 0.00002f,
    0.00001f, 0.75252f, 0.65112f, 0.52525f, 0.37085f, 0.24956f, 0.16186f, 0.10123f, 0.06121f, 0.03513f, 0.01861f,
    0.00904f, 0.00391f, 0.00146f, 0.00045f, 0.00011f, 0.00003f, 0.00001f, 0.67938f, 0.59046f, 0.49695f, 0.36000f,
    0.24669f, 0.16175f, 0.10157f, 0.06125f, 0.03564f, 0.01938f, 0.00965f, 0.00429f, 0.00167f, 0.00056f, 0.00015f,
    0.00004f, 0.00001f, 0.63162f, 0.55048f, 0.47094f, 0.34945f, 0.24243f, 0.16099f, 0.10192f, 0.06120f, 0.03572f,
    0.01978f, 0.01007f, 0.00462f, 0.00187f, 0.00064f, 0.00019f, 0.00004f, 0.00001f, 0.59578f, 0.52051f, 0.44724f,
    0.33531f, 0.23499f, 0.15744f, 0.10044f, 0.06075f, 0.03572f, 0.01993f, 0.01026f, 0.00474f, 0.00195f, 0.00069f,
    0.00021f, 0.00004f, 0.00001f, 0.87022f, 0.72880f, 0.54053f, 0.37047f, 0.25171f, 0.16409f, 0.10267f, 0.06131f,
    0.03449f, 0.01821f, 0.00883f, 0.00381f, 0.00142f, 0.00045f, 0.00016f, 0.00008f, 0.00003f, 0.61141f, 0.52676f,
    0.43958f, 0.32527f, 0.22726f, 0.15281f, 0.09871f, 0.06050f, 0.03561f, 0.01945f, 0.00981f, 0.00447f, 0.00180f,
    0.00062f, 0.00021f, 0.00009f, 0.00003f, 0.52707f, 0.46023f, 0.39251f, 0.29512f, 0.21125f, 0.14419f, 0.09450f,
    0.05914f, 0.03551f, 0.02013f, 0.01050f, 0.00496f, 0.00210f, 0.00078f, 0.00025f, 0.00009f, 0.00003f, 0.47505f,
    0.41757f, 0.35957f, 0.27424f, 0.19830f, 0.13772f, 0.09105f, 0.05778f, 0.03494f, 0.02035f, 0.01098f, 0.00539f,
    0.00237f, 0.00092f, 0.00031f, 0.00009f, 0.00003f, 0.43776f, 0.38627f, 0.33316f, 0.25419f, 0.18492f, 0.12977f,
    0.08685f, 0.05589f, 0.03430f, 0.02030f, 0.01114f, 0.00558f, 0.00250f, 0.00100f, 0.00034f, 0.00010f, 0.00003f,
    0.54051f, 0.45402f, 0.38159f, 0.30057f, 0.21954f, 0.15014f, 0.09780f, 0.06068f, 0.03604f, 0.02007f, 0.01030f,
    0.00481f, 0.00199f, 0.00073f, 0.00027f, 0.00011f, 0.00004f, 0.40266f, 0.34901f, 0.29391f, 0.23919f, 0.18131f,
    0.12893f, 0.08720f, 0.05584f, 0.03373f, 0.01951f, 0.01059f, 0.00526f, 0.00234f, 0.00092f, 0.00033f, 0.00013f,
    0.00004f, 0.33038f, 0.29057f, 0.24547f, 0.20178f, 0.15653f, 0.11421f, 0.07911f, 0.05198f, 0.03236f, 0.01907f,
    0.01066f, 0.00556f, 0.00263f, 0.00109f, 0.00039f, 0.00013f, 0.00004f, 0.27362f, 0.24763f, 0.21239f, 0.17651f,
    0.13922f, 0.10356f, 0.07286f, 0.04878f, 0.03104f, 0.01865f, 0.01065f, 0.00574f, 0.00283f, 0.00124f, 0.00046f,
    0.00014f, 0.00004f, 0.23555f, 0.21536f, 0.18665f, 0.15522f, 0.12620f, 0.09460f, 0.06724f, 0.04562f, 0.02950f,
    0.01806f, 0.01054f, 0.00582f, 0.00295f, 0.00132f, 0.00051f, 0.00015f, 0.00004f, 0.33692f, 0.27422f, 0.22437f,
    0.18012f, 0.13978f, 0.10438f, 0.07471f, 0.05078f, 0.03259f, 0.01966f, 0.01104f, 0.00574f, 0.00276f, 0.00118f,
    0.00046f, 0.00017f, 0.00005f, 0.26813f, 0.22235f, 0.18234f, 0.14731f, 0.11595f, 0.08763f, 0.06361f, 0.04419f,
    0.02900f, 0.01802f, 0.01047f, 0.00563f, 0.00283f, 0.00126f, 0.00051f, 0.00019f, 0.00005f, 0.22234f, 0.18590f,
    0.15287f, 0.12390f, 0.09819f, 0.07496f, 0.05530f, 0.03924f, 0.02642f, 0.01684f, 0.01007f, 0.00558f, 0.00287f,
    0.00135f, 0.00055f, 0.00019f, 0.00005f, 0.18474f, 0.15497f, 0.12834f, 0.10449f, 0.08410f, 0.06551f, 0.04910f,
    0.03534f, 0.02427f, 0.01586f, 0.00975f, 0.00556f, 0.00292f, 0.00140f, 0.00059f, 0.00020f, 0.00005f, 0.16093f,
    0.13564f, 0.11158f, 0.08938f, 0.07278f, 0.05740f, 0.04381f, 0.03207f, 0.02247f, 0.01492f, 0.00934f, 0.00544f,
    0.00292f, 0.00144f, 0.00062f, 0.00021f, 0.00005f, 0.20899f, 0.16492f, 0.13192f, 0.10475f, 0.08179f, 0.06235f,
    0.04613f, 0.03293f, 0.02258f, 0.01491f, 0.00936f, 0.00548f, 0.00295f, 0.00143f, 0.00060f, 0.00021f, 0.00005f,
    0.17530f, 0.14041f, 0.11243f, 0.08944f, 0.07008f, 0.05376f, 0.04016f, 0.02902f, 0.02015f, 0.01352f, 0.00863f,
    0.00519f, 0.00287f, 0.00143f, 0.00062f, 0.00021f, 0.00005f, 0.14957f, 0.12100f, 0.09721f, 0.07753f, 0.06094f,
    0.04696f, 0.03532f, 0.02574f, 0.01808f, 0.01231f, 0.00802f, 0.00491f, 0.00279f, 0.00143f, 0.00063f, 0.00022f,
    0.00005f, 0.12801f, 0.10383f, 0.08380f, 0.06675f, 0.05250f, 0.04084f, 0.03102f, 0.02290f, 0.01640f, 0.01132f,
    0.00749f, 0.00468f, 0.00272f, 0.00143f, 0.00065f, 0.00023f, 0.00005f, 0.11317f, 0.09212f, 0.07447f, 0.05943f,
    0.04668f, 0.03606f, 0.02736f, 0.02047f, 0.01485f, 0.01039f, 0.00702f, 0.00447f, 0.00264f, 0.00142f, 0.00066f,
    0.00024f, 0.00005f, 0.13357f, 0.10077f, 0.07848f, 0.06111f, 0.04722f, 0.03598f, 0.02691f, 0.01967f, 0.01397f,
    0.00958f, 0.00630f, 0.00396f, 0.00235f, 0.00128f, 0.00061f, 0.00024f, 0.00005f, 0.11750f, 0.08992f, 0.07035f,
    0.05487f, 0.04252f, 0.03249f, 0.02438f, 0.01789f, 0.01279f, 0.00885f, 0.00588f, 0.00374f, 0.00225f, 0.00124f,
    0.00061f, 0.00024f, 0.00005f, 0.10406f, 0.08056f, 0.06333f, 0.04947f, 0.03843f, 0.02940f, 0.02215f, 0.01635f,
    0.01176f, 0.00820f, 0.00550f, 0.00353f, 0.00215f, 0.00121f, 0.00060f, 0.00024f, 0.00005f, 0.09243f, 0.07207f,
    0.05688f, 0.04465f, 0.03464f, 0.02659f, 0.02004f, 0.01486f, 0.01077f, 0.00757f, 0.00514f, 0.00335f, 0.00207f,
    0.00118f, 0.00059f, 0.00024f, 0.00005f, 0.08345f, 0.06545f, 0.05183f, 0.04077f, 0.03169f, 0.02438f, 0.01843f,
    0.01368f, 0.00991f, 0.00701f, 0.00481f, 0.00317f, 0.00198f, 0.00115f, 0.00059f, 0.00024f, 0.00005f, 0.08951f,
    0.06395f, 0.04828f, 0.03673f, 0.02790f, 0.02103f, 0.01568f, 0.01150f, 0.00827f, 0.00580f, 0.00394f, 0.00257f,
    0.00158f, 0.00091f, 0.00047f, 0.00020f, 0.00005f, 0.08240f, 0.05962f, 0.04523f, 0.03445f, 0.02624f, 0.01982f,
    0.01481f, 0.01089f, 0.00785f, 0.00552f, 0.00376f, 0.00247f, 0.00153f, 0.00089f, 0.00046f, 0.00020f, 0.00005f,
    0.07599f, 0.05558f, 0.04235f, 0.03234f, 0.02462f, 0.01864f, 0.01396f, 0.01029f, 0.00745f, 0.00526f, 0.00360f,
    0.00237f, 0.00148f, 0.00087f, 0.00046f, 0.00020f, 0.00005f, 0.07017f, 0.05177f, 0.03958f, 0.03032f, 0.02317f,
    0.01756f, 0.01317f, 0.00972f, 0.00705f, 0.00499f, 0.00344f, 0.00228f, 0.00143f, 0.00084f, 0.00045f, 0.00020f,
    0.00005f, 0.06521f, 0.04848f, 0.03720f, 0.02857f, 0.02188f, 0.01661f, 0.01248f, 0.00924f, 0.00672f, 0.00477f,
    0.00329f, 0.00219f, 0.00138f, 0.00082f, 0.00044f, 0.00020f, 0.00005f, 0.06343f, 0.04257f, 0.03101f, 0.02297f,
    0.01709f, 0.01269f, 0.00936f, 0.00684f, 0.00492f, 0.00347f, 0.00239f, 0.00159f, 0.00101f, 0.00060f, 0.00033f,
    0.00015f, 0.00004f, 0.06095f, 0.04119f, 0.03009f, 0.02233f, 0.01663f, 0.01237f, 0.00914f, 0.00668f, 0.00482f,
    0.00340f, 0.00235f, 0.00156f, 0.00100f, 0.00060f, 0.00032f, 0.00015f, 0.00004f, 0.05856f, 0.03985f, 0.02919f,
    0.02170f, 0.01617f, 0.01204f, 0.00890f, 0.00651f, 0.00470f, 0.00333f, 0.00230f, 0.00153f, 0.00098f, 0.00059f,
    0.00032f, 0.00015f, 0.00004f, 0.05629f, 0.03853f, 0.02830f, 0.02109f, 0.01574f, 0.01173f, 0.00868f, 0.00636f,
    0.00459f, 0.00326f, 0.00225f, 0.00151f, 0.00097f, 0.00058f, 0.00032f, 0.00015f, 0.00004f, 0.05417f, 0.03729f,
    0.02747f, 0.02050f, 0.01533f, 0.01143f, 0.00847f, 0.00622f, 0.00450f, 0.00319f, 0.00221f, 0.00148f, 0.00095f,
    0.00057f, 0.00031f, 0.00015f, 0.00004f, 0.04756f, 0.02972f, 0.02083f, 0.01497f, 0.01089f, 0.00794f, 0.00578f,
    0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04760f,
    0.02972f, 0.02083f, 0.01497f, 0.01089f, 0.00794f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f,
    0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04760f, 0.02972f, 0.02083f, 0.01497f, 0.01088f, 0.00793f,
    0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f,
    0.04759f, 0.02972f, 0.02083f, 0.01497f, 0.01088f, 0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f,
    0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04759f, 0.02972f, 0.02083f, 0.01497f, 0.01088f,
    0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f,
    0.00003f, 1.00346f, 0.75046f, 0.53246f, 0.36475f, 0.24733f, 0.16315f, 0.10393f, 0.06350f, 0.03686f, 0.02011f,
    0.01016f, 0.00467f, 0.00194f, 0.00073f, 0.00025f, 0.00008f, 0.00002f, 0.41219f, 0.35311f, 0.28001f, 0.21229f,
    0.15940f, 0.11673f, 0.08108f, 0.05309f, 0.03306f, 0.01919f, 0.01040f, 0.00519f, 0.00235f, 0.00098f, 0.00038f,
    0.00012f, 0.00003f, 0.26173f, 0.22684f, 0.18838f, 0.15333f, 0.12191f, 0.09314f, 0.06714f, 0.04609f, 0.03008f,
    0.01855f, 0.01062f, 0.00560f, 0.00270f, 0.00117f, 0.00047f, 0.00016f, 0.00003f, 0.21123f, 0.18252f, 0.15156f,
    0.12107f, 0.09801f, 0.07641f, 0.05735f, 0.04088f, 0.02750f, 0.01766f, 0.01061f, 0.00588f, 0.00297f, 0.00134f,
    0.00055f, 0.00018f, 0.00004f, 0.17942f, 0.15370f, 0.12739f, 0.10164f, 0.08144f, 0.06483f, 0.04940f, 0.03642f,
    0.02538f, 0.01671f, 0.01031f, 0.00589f, 0.00308f, 0.00143f, 0.00060f, 0.00020f, 0.00004f, 0.88919f, 0.68200f,
    0.50600f, 0.35435f, 0.24548f, 0.16245f, 0.10358f, 0.06340f, 0.03718f, 0.02055f, 0.01057f, 0.00498f, 0.00213f,
    0.00084f, 0.00030f, 0.00010f, 0.00003f, 0.35880f, 0.30751f, 0.24128f, 0.18416f, 0.14179f, 0.10242f, 0.07205f,
    0.04812f, 0.03064f, 0.01823f, 0.01017f, 0.00525f, 0.00248f, 0.00108f, 0.00044f, 0.00014f, 0.00003f, 0.21187f,
    0.18378f, 0.15220f, 0.12400f, 0.09948f, 0.07714f, 0.05655f, 0.03967f, 0.02657f, 0.01687f, 0.00999f, 0.00547f,
    0.00277f, 0.00126f, 0.00053f, 0.00018f, 0.00004f, 0.16563f, 0.14314f, 0.11847f, 0.09419f, 0.07708f, 0.06101f,
    0.04674f, 0.03409f, 0.02353f, 0.01560f, 0.00971f, 0.00560f, 0.00297f, 0.00142f, 0.00061f, 0.00021f, 0.00004f,
    0.13759f, 0.11767f, 0.09718f, 0.07707f, 0.06213f, 0.05038f, 0.03915f, 0.02966f, 0.02124f, 0.01443f, 0.00923f,
    0.00549f, 0.00301f, 0.00150f, 0.00066f, 0.00023f, 0.00004f, 0.58332f, 0.44011f, 0.36427f, 0.28621f, 0.21007f,
    0.14473f, 0.09533f, 0.06011f, 0.03628f, 0.02070f, 0.01097f, 0.00536f, 0.00238f, 0.00097f, 0.00035f, 0.00011f,
    0.00003f, 0.25995f, 0.22671f, 0.18856f, 0.15348f, 0.11891f, 0.08666f, 0.06077f, 0.04098f, 0.02662f, 0.01648f,
    0.00966f, 0.00523f, 0.00258f, 0.00114f, 0.00046f, 0.00015f, 0.00004f, 0.17086f, 0.14342f, 0.11750f, 0.09481f,
    0.07501f, 0.05788f, 0.04337f, 0.03132f, 0.02150f, 0.01406f, 0.00876f, 0.00511f, 0.00274f, 0.00130f, 0.00054f,
    0.00019f, 0.00004f, 0.13013f, 0.10828f, 0.08856f, 0.07124f, 0.05641f, 0.04388f, 0.03350f, 0.02500f, 0.01799f,
    0.01238f, 0.00802f, 0.00493f, 0.00280f, 0.00142f, 0.00062f, 0.00021f, 0.00004f, 0.10622f, 0.08797f, 0.07197f,
    0.05795f, 0.04581f, 0.03566f, 0.02744f, 0.02080f, 0.01535f, 0.01093f, 0.00742f, 0.00472f, 0.00277f, 0.00146f,
    0.00066f, 0.00023f, 0.00004f, 0.36952f, 0.27609f, 0.21933f, 0.17345f, 0.13349f, 0.09946f, 0.07127f, 0.04860f,
    0.03137f, 0.01907f, 0.01083f, 0.00571f, 0.00279f, 0.00123f, 0.00047f, 0.00015f, 0.00004f, 0.20020f, 0.16564f,
    0.13409f, 0.10651f, 0.08282f, 0.06328f, 0.04706f, 0.03351f, 0.02268f, 0.01453f, 0.00874f, 0.00495f, 0.00261f,
    0.00125f, 0.00053f, 0.00018f, 0.00004f, 0.13636f, 0.11192f, 0.09078f, 0.07236f, 0.05664f, 0.04338f, 0.03277f,
    0.02398f, 0.01697f, 0.01150f, 0.00739f, 0.00443f, 0.00252f, 0.00129f, 0.00058f, 0.00020f, 0.00004f, 0.10316f,
    0.08479f, 0.06878f, 0.05498f, 0.04321f, 0.03337f, 0.02522f, 0.01872f, 0.01357f, 0.00947f, 0.00638f, 0.00406f,
    0.00242f, 0.00131f, 0.00062f, 0.00023f, 0.00004f, 0.08353f, 0.06855f, 0.05557f, 0.04452f, 0.03518f, 0.02734f,
    0.02083f, 0.01552f, 0.01138f, 0.00817f, 0.00564f, 0.00374f, 0.00232f, 0.00130f, 0.00064f, 0.00024f, 0.00004f,
    0.23167f, 0.16993f, 0.13170f, 0.10243f, 0.07885f, 0.05958f, 0.04382f, 0.03115f, 0.02132f, 0.01407f, 0.00880f,
    0.00517f, 0.00280f, 0.00136f, 0.00058f, 0.00020f, 0.00005f, 0.14956f, 0.11802f, 0.09354f, 0.07345f, 0.05688f,
    0.04330f, 0.03220f, 0.02326f, 0.01627f, 0.01108f, 0.00718f, 0.00440f, 0.00249f, 0.00128f, 0.00057f, 0.00021f,
    0.00005f, 0.10780f, 0.08592f, 0.06844f, 0.05406f, 0.04219f, 0.03233f, 0.02428f, 0.01782f, 0.01274f, 0.00885f,
    0.00591f, 0.00375f, 0.00221f, 0.00120f, 0.00056f, 0.00022f, 0.00005f, 0.08326f, 0.06694f, 0.05360f, 0.04252f,
    0.03327f, 0.02564f, 0.01947f, 0.01445f, 0.01042f, 0.00733f, 0.00500f, 0.00326f, 0.00201f, 0.00113f, 0.00056f,
    0.00022f, 0.00005f, 0.06784f, 0.05478f, 0.04393f, 0.03488f, 0.02742f, 0.02125f, 0.01620f, 0.01214f, 0.00887f,
    0.00631f, 0.00437f, 0.00291f, 0.00183f, 0.00107f, 0.00056f, 0.00023f, 0.00005f, 0.14743f, 0.10462f, 0.07917f,
    0.06050f, 0.04605f, 0.03470f, 0.02574f, 0.01869f, 0.01320f, 0.00901f, 0.00591f, 0.00368f, 0.00217f, 0.00118f,
    0.00056f, 0.00022f, 0.00005f, 0.10952f, 0.08187f, 0.06312f, 0.04874f, 0.03736f, 0.02832f, 0.02114f, 0.01547f,
    0.01103f, 0.00763f, 0.00508f, 0.00324f, 0.00196f, 0.00110f, 0.00054f, 0.00022f, 0.00005f, 0.08531f, 0.06508f,
    0.05063f, 0.03933f, 0.03031f, 0.02309f, 0.01735f, 0.01278f, 0.00921f, 0.00646f, 0.00438f, 0.00286f, 0.00176f,
    0.00101f, 0.00051f, 0.00021f, 0.00005f, 0.06896f, 0.05345f, 0.04196f, 0.03280f, 0.02539f, 0.01948f, 0.01469f,
    0.01091f, 0.00794f, 0.00563f, 0.00386f, 0.00255f, 0.00160f, 0.00094f, 0.00049f, 0.00021f, 0.00005f, 0.05757f,
    0.04505f, 0.03552f, 0.02788f, 0.02167f, 0.01670f, 0.01264f, 0.00946f, 0.00694f, 0.00496f, 0.00344f, 0.00230f,
    0.00147f, 0.00087f, 0.00047f, 0.00021f, 0.00005f, 0.09695f, 0.06615f, 0.04883f, 0.03660f, 0.02747f, 0.02052f,
    0.01518f, 0.01107f, 0.00792f, 0.00552f, 0.00373f, 0.00242f, 0.00149f, 0.00085f, 0.00044f, 0.00019f, 0.00005f,
    0.08095f, 0.05704f, 0.04267f, 0.03224f, 0.02434f, 0.01826f, 0.01357f, 0.00994f, 0.00715f, 0.00502f, 0.00342f,
    0.00224f, 0.00139f, 0.00081f, 0.00042f, 0.00018f, 0.00005f, 0.06865f, 0.04951f, 0.03736f, 0.02833f, 0.02148f,
    0.01619f, 0.01208f, 0.00888f, 0.00642f, 0.00454f, 0.00312f, 0.00206f, 0.00130f, 0.00077f, 0.00041f, 0.00018f,
    0.00005f, 0.05901f, 0.04333f, 0.03299f, 0.02518f, 0.01919f, 0.01451f, 0.01088f, 0.00804f, 0.00584f, 0.00416f,
    0.00287f, 0.00192f, 0.00122f, 0.00073f, 0.00039f, 0.00018f, 0.00005f, 0.05150f, 0.03832f, 0.02936f, 0.02251f,
    0.01723f, 0.01308f, 0.00984f, 0.00731f, 0.00534f, 0.00382f, 0.00266f, 0.00179f, 0.00115f, 0.00069f, 0.00038f,
    0.00017f, 0.00005f, 0.06644f, 0.04344f, 0.03126f, 0.02296f, 0.01696f, 0.01253f, 0.00920f, 0.00669f, 0.00480f,
    0.00338f, 0.00232f, 0.00154f, 0.00098f, 0.00058f, 0.00032f, 0.00014f, 0.00004f, 0.06114f, 0.04062f, 0.02941f,
    0.02169f, 0.01608f, 0.01191f, 0.00877f, 0.00639f, 0.00460f, 0.00324f, 0.00223f, 0.00149f, 0.00095f, 0.00057f,
    0.00031f, 0.00014f, 0.00004f, 0.05641f, 0.03801f, 0.02768f, 0.02048f, 0.01522f, 0.01130f, 0.00834f, 0.00609f,
    0.00439f, 0.00311f, 0.00215f, 0.00144f, 0.00092f, 0.00055f, 0.00030f, 0.00014f, 0.00004f, 0.05219f, 0.03560f,
    0.02607f, 0.01937f, 0.01444f, 0.01075f, 0.00795f, 0.00582f, 0.00421f, 0.00299f, 0.00207f, 0.00139f, 0.00089f,
    0.00054f, 0.00030f, 0.00014f, 0.00004f, 0.04846f, 0.03341f, 0.02460f, 0.01834f, 0.01371f, 0.01023f, 0.00759f,
    0.00557f, 0.00403f, 0.00287f, 0.00199f, 0.00134f, 0.00087f, 0.00053f, 0.00029f, 0.00014f, 0.00004f, 0.04756f,
    0.02971f, 0.02083f, 0.01497f, 0.01089f, 0.00794f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f,
    0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04760f, 0.02973f, 0.02083f, 0.01497f, 0.01089f, 0.00794f,
    0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f,
    0.04760f, 0.02973f, 0.02082f, 0.01496f, 0.01088f, 0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f,
    0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04759f, 0.02972f, 0.02082f, 0.01497f, 0.01088f,
    0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f,
    0.00003f, 0.04759f, 0.02972f, 0.02082f, 0.01497f, 0.01088f, 0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f,
    0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.96325f, 0.63542f, 0.44805f, 0.30986f,
    0.21264f, 0.14240f, 0.09244f, 0.05781f, 0.03456f, 0.01958f, 0.01040f, 0.00512f, 0.00232f, 0.00098f, 0.00037f,
    0.00013f, 0.00004f, 0.25507f, 0.21912f, 0.16037f, 0.11689f, 0.08749f, 0.06432f, 0.04591f, 0.03160f, 0.02084f,
    0.01308f, 0.00775f, 0.00430f, 0.00227f, 0.00109f, 0.00048f, 0.00017f, 0.00004f, 0.11423f, 0.09406f, 0.07630f,
    0.06060f, 0.04733f, 0.03612f, 0.02689f, 0.01941f, 0.01375f, 0.00941f, 0.00616f, 0.00383f, 0.00220f, 0.00117f,
    0.00055f, 0.00021f, 0.00005f, 0.08138f, 0.06697f, 0.05430f, 0.04323f, 0.03407f, 0.02634f, 0.01995f, 0.01477f,
    0.01063f, 0.00747f, 0.00514f, 0.00335f, 0.00208f, 0.00119f, 0.00060f, 0.00023f, 0.00005f, 0.06361f, 0.05228f,
    0.04240f, 0.03374f, 0.02671f, 0.02085f, 0.01593f, 0.01199f, 0.00881f, 0.00630f, 0.00443f, 0.00302f, 0.00195f,
    0.00116f, 0.00062f, 0.00025f, 0.00005f, 0.91889f, 0.58103f, 0.42289f, 0.29607f, 0.20696f, 0.13870f, 0.08996f,
    0.05603f, 0.03360f, 0.01912f, 0.01021f, 0.00506f, 0.00231f, 0.00098f, 0.00038f, 0.00013f, 0.00004f, 0.24161f,
    0.20749f, 0.15066f, 0.10999f, 0.08476f, 0.06160f, 0.04350f, 0.02952f, 0.01951f, 0.01230f, 0.00734f, 0.00411f,
    0.00219f, 0.00107f, 0.00048f, 0.00017f, 0.00005f, 0.10376f, 0.08520f, 0.06894f, 0.05476f, 0.04277f, 0.03265f,
    0.02435f, 0.01759f, 0.01250f, 0.00862f, 0.00570f, 0.00358f, 0.00208f, 0.00112f, 0.00054f, 0.00021f, 0.00005f,
    0.07262f, 0.05959f, 0.04825f, 0.03840f, 0.03018f, 0.02335f, 0.01773f, 0.01315f, 0.00950f, 0.00674f, 0.00468f,
    0.00309f, 0.00195f, 0.00113f, 0.00058f, 0.00023f, 0.00005f, 0.05627f, 0.04615f, 0.03735f, 0.02967f, 0.02348f,
    0.01834f, 0.01403f, 0.01058f, 0.00782f, 0.00562f, 0.00399f, 0.00276f, 0.00180f, 0.00109f, 0.00060f, 0.00024f,
    0.00005f, 0.63544f, 0.39152f, 0.31419f, 0.24426f, 0.17877f, 0.12356f, 0.08211f, 0.05220f, 0.03173f, 0.01831f,
    0.00991f, 0.00501f, 0.00232f, 0.00099f, 0.00038f, 0.00013f, 0.00004f, 0.17950f, 0.15111f, 0.12500f, 0.10147f,
    0.07824f, 0.05687f, 0.04026f, 0.02744f, 0.01807f, 0.01141f, 0.00682f, 0.00387f, 0.00203f, 0.00099f, 0.00044f,
    0.00016f, 0.00004f, 0.09451f, 0.07741f, 0.06249f, 0.04958f, 0.03868f, 0.02959f, 0.02196f, 0.01596f, 0.01122f,
    0.00762f, 0.00501f, 0.00315f, 0.00185f, 0.00100f, 0.00048f, 0.00019f, 0.00005f, 0.06507f, 0.05326f, 0.04300f,
    0.03417f, 0.02683f, 0.02075f, 0.01578f, 0.01170f, 0.00849f, 0.00598f, 0.00407f, 0.00269f, 0.00168f, 0.00098f,
    0.00050f, 0.00021f, 0.00005f, 0.05003f, 0.04092f, 0.03305f, 0.02624f, 0.02075f, 0.01618f, 0.01239f, 0.00937f,
    0.00695f, 0.00502f, 0.00349f, 0.00237f, 0.00155f, 0.00094f, 0.00051f, 0.00022f, 0.00005f, 0.41210f, 0.26416f,
    0.20084f, 0.15536f, 0.11796f, 0.08714f, 0.06204f, 0.04215f, 0.02720f, 0.01661f, 0.00947f, 0.00505f, 0.00247f,
    0.00109f, 0.00043f, 0.00015f, 0.00004f, 0.15156f, 0.12339f, 0.09862f, 0.07737f, 0.05952f, 0.04524f, 0.03359f,
    0.02397f, 0.01636f, 0.01065f, 0.00652f, 0.00378f, 0.00203f, 0.00100f, 0.00044f, 0.00017f, 0.00004f, 0.08610f,
    0.06981f, 0.05603f, 0.04430f, 0.03451f, 0.02642f, 0.01966f, 0.01441f, 0.01019f, 0.00699f, 0.00460f, 0.00288f,
    0.00169f, 0.00092f, 0.00045f, 0.00018f, 0.00004f, 0.05896f, 0.04788f, 0.03849f, 0.03063f, 0.02394f, 0.01855f,
    0.01410f, 0.01053f, 0.00765f, 0.00541f, 0.00369f, 0.00241f, 0.00150f, 0.00087f, 0.00046f, 0.00019f, 0.00004f,
    0.04510f, 0.03667f, 0.02948f, 0.02340f, 0.01846f, 0.01440f, 0.01103f, 0.00835f, 0.00619f, 0.00447f, 0.00314f,
    0.00211f, 0.00136f, 0.00082f, 0.00045f, 0.00020f, 0.00004f, 0.26016f, 0.17017f, 0.12642f, 0.09590f, 0.07262f,
    0.05416f, 0.03945f, 0.02784f, 0.01890f, 0.01240f, 0.00771f, 0.00451f, 0.00243f, 0.00118f, 0.00050f, 0.00018f,
    0.00004f, 0.12713f, 0.09821f, 0.07666f, 0.05940f, 0.04549f, 0.03425f, 0.02528f, 0.01819f, 0.01267f, 0.00864f,
    0.00563f, 0.00348f, 0.00199f, 0.00104f, 0.00047f, 0.00018f, 0.00004f, 0.07813f, 0.06188f, 0.04906f, 0.03832f,
    0.02979f, 0.02275f, 0.01699f, 0.01255f, 0.00894f, 0.00621f, 0.00416f, 0.00268f, 0.00161f, 0.00090f, 0.00044f,
    0.00018f, 0.00004f, 0.05458f, 0.04362f, 0.03473f, 0.02744f, 0.02138f, 0.01647f, 0.01253f, 0.00936f, 0.00683f,
    0.00486f, 0.00334f, 0.00220f, 0.00138f, 0.00080f, 0.00042f, 0.00018f, 0.00004f, 0.04187f, 0.03365f, 0.02685f,
    0.02117f, 0.01661f, 0.01293f, 0.00988f, 0.00747f, 0.00553f, 0.00400f, 0.00282f, 0.00190f, 0.00123f, 0.00074f,
    0.00040f, 0.00018f, 0.00004f, 0.16413f, 0.10721f, 0.07836f, 0.05852f, 0.04384f, 0.03261f, 0.02395f, 0.01723f,
    0.01208f, 0.00819f, 0.00534f, 0.00331f, 0.00194f, 0.00105f, 0.00050f, 0.00019f, 0.00005f, 0.10194f, 0.07406f,
    0.05618f, 0.04279f, 0.03244f, 0.02435f, 0.01804f, 0.01310f, 0.00931f, 0.00642f, 0.00427f, 0.00273f, 0.00165f,
    0.00093f, 0.00046f, 0.00019f, 0.00005f, 0.07000f, 0.05301f, 0.04083f, 0.03143f, 0.02413f, 0.01828f, 0.01372f,
    0.01008f, 0.00728f, 0.00513f, 0.00349f, 0.00229f, 0.00142f, 0.00082f, 0.00042f, 0.00018f, 0.00005f, 0.05169f,
    0.03987f, 0.03114f, 0.02426f, 0.01878f, 0.01435f, 0.01088f, 0.00808f, 0.00591f, 0.00422f, 0.00292f, 0.00195f,
    0.00124f, 0.00073f, 0.00039f, 0.00017f, 0.00004f, 0.04050f, 0.03168f, 0.02491f, 0.01946f, 0.01509f, 0.01164f,
    0.00885f, 0.00665f, 0.00492f, 0.00355f, 0.00250f, 0.00170f, 0.00110f, 0.00067f, 0.00037f, 0.00017f, 0.00004f,
    0.10542f, 0.06810f, 0.04904f, 0.03612f, 0.02678f, 0.01981f, 0.01453f, 0.01052f, 0.00747f, 0.00519f, 0.00349f,
    0.00226f, 0.00138f, 0.00079f, 0.00040f, 0.00017f, 0.00005f, 0.07925f, 0.05448f, 0.04017f, 0.03001f, 0.02245f,
    0.01673f, 0.01235f, 0.00900f, 0.00644f, 0.00452f, 0.00307f, 0.00201f, 0.00125f, 0.00073f, 0.00038f, 0.00017f,
    0.00005f, 0.06186f, 0.04416f, 0.03307f, 0.02497f, 0.01884f, 0.01414f, 0.01051f, 0.00772f, 0.00558f, 0.00394f,
    0.00271f, 0.00180f, 0.00114f, 0.00068f, 0.00036f, 0.00016f, 0.00005f, 0.04979f, 0.03645f, 0.02762f, 0.02104f,
    0.01599f, 0.01208f, 0.00905f, 0.00669f, 0.00487f, 0.00347f, 0.00242f, 0.00162f, 0.00104f, 0.00063f, 0.00034f,
    0.00016f, 0.00005f, 0.04100f, 0.03058f, 0.02341f, 0.01793f, 0.01374f, 0.01043f, 0.00786f, 0.00585f, 0.00429f,
    0.00309f, 0.00217f, 0.00147f, 0.00096f, 0.00058f, 0.00032f, 0.00015f, 0.00004f, 0.06966f, 0.04430f, 0.03145f,
    0.02289f, 0.01680f, 0.01234f, 0.00902f, 0.00654f, 0.00467f, 0.00328f, 0.00224f, 0.00149f, 0.00094f, 0.00056f,
    0.00030f, 0.00014f, 0.00004f, 0.06127f, 0.04002f, 0.02873f, 0.02105f, 0.01553f, 0.01145f, 0.00840f, 0.00611f,
    0.00438f, 0.00308f, 0.00212f, 0.00141f, 0.00090f, 0.00054f, 0.00029f, 0.00014f, 0.00004f, 0.05445f, 0.03642f,
    0.02629f, 0.01936f, 0.01433f, 0.01061f, 0.00781f, 0.00570f, 0.00410f, 0.00290f, 0.00200f, 0.00134f, 0.00086f,
    0.00052f, 0.00029f, 0.00013f, 0.00004f, 0.04859f, 0.03310f, 0.02411f, 0.01788f, 0.01333f, 0.00990f, 0.00732f,
    0.00536f, 0.00387f, 0.00275f, 0.00191f, 0.00128f, 0.00083f, 0.00050f, 0.00028f, 0.00013f, 0.00004f, 0.04351f,
    0.03006f, 0.02215f, 0.01651f, 0.01236f, 0.00922f, 0.00684f, 0.00502f, 0.00364f, 0.00260f, 0.00181f, 0.00122f,
    0.00079f, 0.00049f, 0.00027f, 0.00013f, 0.00004f, 0.04756f, 0.02971f, 0.02083f, 0.01497f, 0.01089f, 0.00794f,
    0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f,
    0.04760f, 0.02973f, 0.02083f, 0.01497f, 0.01089f, 0.00794f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f,
    0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04773f, 0.02985f, 0.02082f, 0.01497f, 0.01088f,
    0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f,
    0.00003f, 0.04773f, 0.02985f, 0.02086f, 0.01501f, 0.01091f, 0.00796f, 0.00579f, 0.00419f, 0.00300f, 0.00212f,
    0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04766f, 0.02979f, 0.02086f, 0.01501f,
    0.01091f, 0.00796f, 0.00579f, 0.00419f, 0.00300f, 0.00212f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f,
    0.00010f, 0.00003f, 0.86775f, 0.45217f, 0.29963f, 0.20750f, 0.14280f, 0.09610f, 0.06273f, 0.03948f, 0.02385f,
    0.01370f, 0.00741f, 0.00373f, 0.00174f, 0.00074f, 0.00029f, 0.00010f, 0.00003f, 0.17644f, 0.15108f, 0.08654f,
    0.06065f, 0.04454f, 0.03252f, 0.02320f, 0.01605f, 0.01076f, 0.00692f, 0.00425f, 0.00246f, 0.00133f, 0.00067f,
    0.00030f, 0.00012f, 0.00003f, 0.05396f, 0.04348f, 0.03459f, 0.02701f, 0.02092f, 0.01593f, 0.01191f, 0.00867f,
    0.00617f, 0.00422f, 0.00280f, 0.00176f, 0.00104f, 0.00058f, 0.00030f, 0.00012f, 0.00003f, 0.03422f, 0.02772f,
    0.02218f, 0.01736f, 0.01361f, 0.01054f, 0.00804f, 0.00606f, 0.00444f, 0.00320f, 0.00222f, 0.00148f, 0.00094f,
    0.00055f, 0.00029f, 0.00013f, 0.00003f, 0.02518f, 0.02045f, 0.01647f, 0.01285f, 0.01014f, 0.00796f, 0.00611f,
    0.00467f, 0.00352f, 0.00260f, 0.00183f, 0.00128f, 0.00086f, 0.00052f, 0.00029f, 0.00013f, 0.00003f, 0.92800f,
    0.43503f, 0.29416f, 0.20932f, 0.14630f, 0.09825f, 0.06375f, 0.03996f, 0.02396f, 0.01370f, 0.00742f, 0.00374f,
    0.00174f, 0.00074f, 0.00029f, 0.00010f, 0.00003f, 0.17641f, 0.15103f, 0.08657f, 0.06481f, 0.04910f, 0.03518f,
    0.02446f, 0.01663f, 0.01090f, 0.00693f, 0.00425f, 0.00247f, 0.00134f, 0.00067f, 0.00030f, 0.00012f, 0.00003f,
    0.05420f, 0.04366f, 0.03480f, 0.02732f, 0.02112f, 0.01608f, 0.01193f, 0.00873f, 0.00617f, 0.00423f, 0.00280f,
    0.00177f, 0.00105f, 0.00059f, 0.00030f, 0.00012f, 0.00003f, 0.03423f, 0.02772f, 0.02221f, 0.01746f, 0.01361f,
    0.01055f, 0.00806f, 0.00605f, 0.00444f, 0.00320f, 0.00222f, 0.00148f, 0.00094f, 0.00055f, 0.00029f, 0.00013f,
    0.00003f, 0.02519f, 0.02046f, 0.01648f, 0.01285f, 0.01014f, 0.00796f, 0.00611f, 0.00467f, 0.00352f, 0.00260f,
    0.00183f, 0.00128f, 0.00086f, 0.00052f, 0.00029f, 0.00013f, 0.00003f, 0.67803f, 0.31553f, 0.24038f, 0.18319f,
    0.13277f, 0.09143f, 0.06051f, 0.03860f, 0.02371f, 0.01378f, 0.00750f, 0.00380f, 0.00178f, 0.00076f, 0.00029f,
    0.00010f, 0.00003f, 0.12817f, 0.10273f, 0.08087f, 0.06437f, 0.04883f, 0.03503f, 0.02441f, 0.01668f, 0.01119f,
    0.00715f, 0.00432f, 0.00247f, 0.00134f, 0.00067f, 0.00030f, 0.00011f, 0.00003f, 0.05480f, 0.04424f, 0.03531f,
    0.02772f, 0.02148f, 0.01641f, 0.01215f, 0.00888f, 0.00629f, 0.00430f, 0.00284f, 0.00179f, 0.00106f, 0.00058f,
    0.00029f, 0.00012f, 0.00003f, 0.03435f, 0.02783f, 0.02227f, 0.01751f, 0.01368f, 0.01059f, 0.00809f, 0.00604f,
    0.00445f, 0.00320f, 0.00221f, 0.00148f, 0.00094f, 0.00055f, 0.00029f, 0.00013f, 0.00003f, 0.02526f, 0.02049f,
    0.01649f, 0.01294f, 0.01020f, 0.00798f, 0.00613f, 0.00467f, 0.00352f, 0.00260f, 0.00185f, 0.00128f, 0.00085f,
    0.00052f, 0.00029f, 0.00013f, 0.00003f, 0.45611f, 0.23531f, 0.16930f, 0.12681f, 0.09526f, 0.06967f, 0.04917f,
    0.03319f, 0.02131f, 0.01295f, 0.00738f, 0.00394f, 0.00195f, 0.00087f, 0.00034f, 0.00012f, 0.00003f, 0.11614f,
    0.09042f, 0.07067f, 0.05386f, 0.04141f, 0.03124f, 0.02301f, 0.01634f, 0.01110f, 0.00721f, 0.00443f, 0.00260f,
    0.00144f, 0.00073f, 0.00032f, 0.00012f, 0.00003f, 0.05568f, 0.04464f, 0.03553f, 0.02785f, 0.02158f, 0.01649f,
    0.01223f, 0.00901f, 0.00639f, 0.00442f, 0.00296f, 0.00188f, 0.00113f, 0.00062f, 0.00030f, 0.00012f, 0.00003f,
    0.03490f, 0.02816f, 0.02246f, 0.01779f, 0.01381f, 0.01072f, 0.00817f, 0.00615f, 0.00451f, 0.00324f, 0.00224f,
    0.00149f, 0.00095f, 0.00056f, 0.00030f, 0.00013f, 0.00003f, 0.02560f, 0.02068f, 0.01660f, 0.01307f, 0.01028f,
    0.00805f, 0.00617f, 0.00470f, 0.00352f, 0.00258f, 0.00185f, 0.00127f, 0.00084f, 0.00052f, 0.00029f, 0.00013f,
    0.00003f, 0.29216f, 0.16435f, 0.11611f, 0.08521f, 0.06313f, 0.04637f, 0.03337f, 0.02337f, 0.01587f, 0.01031f,
    0.00639f, 0.00371f, 0.00198f, 0.00096f, 0.00041f, 0.00014f, 0.00004f, 0.10753f, 0.08118f, 0.06229f, 0.04710f,
    0.03546f, 0.02640f, 0.01923f, 0.01380f, 0.00959f, 0.00650f, 0.00424f, 0.00262f, 0.00151f, 0.00079f, 0.00037f,
    0.00014f, 0.00004f, 0.05676f, 0.04467f, 0.03518f, 0.02726f, 0.02109f, 0.01604f, 0.01194f, 0.00884f, 0.00631f,
    0.00440f, 0.00298f, 0.00192f, 0.00117f, 0.00066f, 0.00033f, 0.00014f, 0.00003f, 0.03640f, 0.02893f, 0.02291f,
    0.01806f, 0.01404f, 0.01080f, 0.00823f, 0.00617f, 0.00453f, 0.00325f, 0.00226f, 0.00152f, 0.00097f, 0.00058f,
    0.00031f, 0.00014f, 0.00003f, 0.02671f, 0.02136f, 0.01705f, 0.01338f, 0.01046f, 0.00815f, 0.00624f, 0.00474f,
    0.00354f, 0.00258f, 0.00185f, 0.00127f, 0.00084f, 0.00052f, 0.00029f, 0.00013f, 0.00003f, 0.18313f, 0.10808f,
    0.07593f, 0.05521f, 0.04059f, 0.02977f, 0.02161f, 0.01541f, 0.01072f, 0.00722f, 0.00468f, 0.00290f, 0.00169f,
    0.00090f, 0.00043f, 0.00016f, 0.00004f, 0.09393f, 0.06670f, 0.04979f, 0.03727f, 0.02785f, 0.02065f, 0.01514f,
    0.01092f, 0.00773f, 0.00533f, 0.00355f, 0.00227f, 0.00137f, 0.00077f, 0.00039f, 0.00016f, 0.00004f, 0.05696f,
    0.04284f, 0.03275f, 0.02504f, 0.01912f, 0.01442f, 0.01079f, 0.00791f, 0.00571f, 0.00403f, 0.00276f, 0.00182f,
    0.00114f, 0.00066f, 0.00035f, 0.00015f, 0.00004f, 0.03886f, 0.02988f, 0.02325f, 0.01806f, 0.01396f, 0.01065f,
    0.00808f, 0.00601f, 0.00441f, 0.00316f, 0.00221f, 0.00149f, 0.00096f, 0.00058f, 0.00031f, 0.00014f, 0.00004f,
    0.02899f, 0.02265f, 0.01776f, 0.01385f, 0.01073f, 0.00829f, 0.00631f, 0.00475f, 0.00354f, 0.00257f, 0.00183f,
    0.00125f, 0.00083f, 0.00051f, 0.00029f, 0.00014f, 0.00004f, 0.11483f, 0.06966f, 0.04882f, 0.03533f, 0.02583f,
    0.01890f, 0.01375f, 0.00988f, 0.00698f, 0.00482f, 0.00323f, 0.00208f, 0.00127f, 0.00072f, 0.00037f, 0.00016f,
    0.00004f, 0.07729f, 0.05186f, 0.03770f, 0.02784f, 0.02063f, 0.01524f, 0.01118f, 0.00810f, 0.00577f, 0.00403f,
    0.00273f, 0.00179f, 0.00112f, 0.00065f, 0.00034f, 0.00015f, 0.00004f, 0.05543f, 0.03922f, 0.02917f, 0.02189f,
    0.01643f, 0.01228f, 0.00910f, 0.00667f, 0.00481f, 0.00340f, 0.00234f, 0.00156f, 0.00099f, 0.00059f, 0.00032f,
    0.00014f, 0.00004f, 0.04189f, 0.03058f, 0.02311f, 0.01755f, 0.01331f, 0.01004f, 0.00751f, 0.00556f, 0.00405f,
    0.00290f, 0.00202f, 0.00137f, 0.00089f, 0.00054f, 0.00030f, 0.00014f, 0.00004f, 0.03289f, 0.02455f, 0.01879f,
    0.01437f, 0.01101f, 0.00835f, 0.00630f, 0.00470f, 0.00346f, 0.00250f, 0.00176f, 0.00121f, 0.00079f, 0.00049f,
    0.00028f, 0.00013f, 0.00004f, 0.07308f, 0.04510f, 0.03159f, 0.02277f, 0.01660f, 0.01212f, 0.00882f, 0.00636f,
    0.00453f, 0.00317f, 0.00217f, 0.00143f, 0.00090f, 0.00054f, 0.00029f, 0.00013f, 0.00004f, 0.06131f, 0.03938f,
    0.02803f, 0.02040f, 0.01498f, 0.01099f, 0.00804f, 0.00583f, 0.00417f, 0.00293f, 0.00201f, 0.00134f, 0.00085f,
    0.00051f, 0.00028f, 0.00013f, 0.00004f, 0.05231f, 0.03471f, 0.02492f, 0.01827f, 0.01348f, 0.00995f, 0.00732f,
    0.00533f, 0.00383f, 0.00271f, 0.00187f, 0.00125f, 0.00081f, 0.00049f, 0.00027f, 0.00013f, 0.00004f, 0.04503f,
    0.03061f, 0.02223f, 0.01646f, 0.01225f, 0.00909f, 0.00671f, 0.00491f, 0.00355f, 0.00252f, 0.00175f, 0.00118f,
    0.00077f, 0.00047f, 0.00026f, 0.00012f, 0.00004f, 0.03907f, 0.02702f, 0.01991f, 0.01484f, 0.01111f, 0.00828f,
    0.00615f, 0.00452f, 0.00328f, 0.00234f, 0.00164f, 0.00111f, 0.00072f, 0.00045f, 0.00025f, 0.00012f, 0.00004f,
    0.04756f, 0.02971f, 0.02082f, 0.01497f, 0.01089f, 0.00794f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f,
    0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04757f, 0.02971f, 0.02082f, 0.01497f, 0.01089f,
    0.00794f, 0.00578f, 0.00418f, 0.00299f, 0.00211f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f,
    0.00003f, 0.04773f, 0.02985f, 0.02082f, 0.01497f, 0.01088f, 0.00793f, 0.00578f, 0.00418f, 0.00299f, 0.00211f,
    0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f, 0.04773f, 0.02985f, 0.02086f, 0.01501f,
    0.01091f, 0.00796f, 0.00579f, 0.00419f, 0.00300f, 0.00212f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f,
    0.00010f, 0.00003f, 0.04766f, 0.02979f, 0.02086f, 0.01501f, 0.01091f, 0.00796f, 0.00579f, 0.00419f, 0.00300f,
    0.00212f, 0.00146f, 0.00098f, 0.00063f, 0.00039f, 0.00022f, 0.00010f, 0.00003f,
};
constant float ANISO_E_AVG[45] = {
    1.00000f, 0.99999f, 0.99610f, 0.96343f, 0.89180f, 0.78654f, 0.65903f, 0.52826f, 0.40964f, 0.99895f, 0.99338f,
    0.96719f, 0.91560f, 0.83768f, 0.73789f, 0.62504f, 0.51235f, 0.40970f, 0.95235f, 0.92412f, 0.88232f, 0.82959f,
    0.76060f, 0.67814f, 0.58751f, 0.49606f, 0.40991f, 0.80433f, 0.78028f, 0.74860f, 0.71223f, 0.66752f, 0.61269f,
    0.54907f, 0.48016f, 0.41040f, 0.58971f, 0.58986f, 0.58792f, 0.58266f, 0.56949f, 0.54527f, 0.50948f, 0.46340f,
    0.41040f,
};
constant float ANISO_E_SCHLICK_AVG[45] = {
    0.05318f, 0.05237f, 0.04324f, 0.03019f, 0.01918f, 0.01173f, 0.00713f, 0.00440f, 0.00279f, 0.04885f, 0.04351f,
    0.03365f, 0.02318f, 0.01516f, 0.00977f, 0.00632f, 0.00415f, 0.00279f, 0.03129f, 0.02790f, 0.02249f, 0.01663f,
    0.01175f, 0.00812f, 0.00561f, 0.00392f, 0.00279f, 0.01902f, 0.01789f, 0.01545f, 0.01218f, 0.00920f, 0.00680f,
    0.00500f, 0.00371f, 0.00279f, 0.01110f, 0.01124f, 0.01036f, 0.00881f, 0.00719f, 0.00569f, 0.00446f, 0.00351f,
    0.00279f,
};

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

// Directional albedo of a white Charlie sheen lobe with the fitted visibility, which exceeds 1
// at grazing angles (2.0 at cos 0 for the narrowest lobe): SHEEN_E_CHARLIE. The lobe used is
// that one times k(mu_o) k(mu_i), k = 1 / max(1, E_charlie(mu)) (reciprocal, and never above 1);
// SHEEN_E is its albedo E_sh, SHEEN_E_AVG its cosine-weighted mean 2∫E_sh mu dmu. Rows for
// roughness 0, 1/32 .. 1 (those below SHEEN_MIN_ROUGHNESS repeat it), columns for cos(theta_o)
// (0/32)², (1/32)² .. 1 (dense near grazing, where the lobe changes fastest). tests/bsdf.rs computes them by quadrature (print_sheen_tables) and checks them
// (sheen_albedo_tables_match_quadrature).
constant float SHEEN_E_CHARLIE[1089] = {
    2.02299f, 2.22389f, 2.22580f, 2.05872f, 1.82416f, 1.56907f, 1.31747f, 1.08217f, 0.86989f, 0.68379f, 0.52484f,
    0.39250f, 0.28525f, 0.20080f, 0.13641f, 0.08903f, 0.05553f, 0.03290f, 0.01839f, 0.00961f, 0.00465f, 0.00205f,
    0.00082f, 0.00029f, 0.00009f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    2.02299f, 2.22389f, 2.22580f, 2.05872f, 1.82416f, 1.56907f, 1.31747f, 1.08217f, 0.86989f, 0.68379f, 0.52484f,
    0.39250f, 0.28525f, 0.20080f, 0.13641f, 0.08903f, 0.05553f, 0.03290f, 0.01839f, 0.00961f, 0.00465f, 0.00205f,
    0.00082f, 0.00029f, 0.00009f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    2.02299f, 2.22389f, 2.22580f, 2.05872f, 1.82416f, 1.56907f, 1.31747f, 1.08217f, 0.86989f, 0.68379f, 0.52484f,
    0.39250f, 0.28525f, 0.20080f, 0.13641f, 0.08903f, 0.05553f, 0.03290f, 0.01839f, 0.00961f, 0.00465f, 0.00205f,
    0.00082f, 0.00029f, 0.00009f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    2.02299f, 2.22389f, 2.22580f, 2.05872f, 1.82416f, 1.56907f, 1.31747f, 1.08217f, 0.86989f, 0.68379f, 0.52484f,
    0.39250f, 0.28525f, 0.20080f, 0.13641f, 0.08903f, 0.05553f, 0.03290f, 0.01839f, 0.00961f, 0.00465f, 0.00205f,
    0.00082f, 0.00029f, 0.00009f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    1.54484f, 1.71053f, 1.74171f, 1.64782f, 1.50047f, 1.33244f, 1.16063f, 0.99425f, 0.83846f, 0.69609f, 0.56856f,
    0.45642f, 0.35958f, 0.27752f, 0.20937f, 0.15402f, 0.11016f, 0.07633f, 0.05103f, 0.03275f, 0.02007f, 0.01165f,
    0.00636f, 0.00322f, 0.00150f, 0.00062f, 0.00023f, 0.00007f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    1.26395f, 1.40639f, 1.44820f, 1.39013f, 1.28793f, 1.16682f, 1.03980f, 0.91401f, 0.79352f, 0.68066f, 0.57675f,
    0.48248f, 0.39813f, 0.32368f, 0.25891f, 0.20342f, 0.15667f, 0.11802f, 0.08672f, 0.06195f, 0.04286f, 0.02859f,
    0.01827f, 0.01111f, 0.00638f, 0.00341f, 0.00167f, 0.00073f, 0.00027f, 0.00008f, 0.00002f, 0.00000f, 0.00000f,
    1.08205f, 1.20850f, 1.25460f, 1.21670f, 1.14097f, 1.04813f, 0.94880f, 0.84884f, 0.75158f, 0.65899f, 0.57219f,
    0.49186f, 0.41833f, 0.35174f, 0.29209f, 0.23927f, 0.19306f, 0.15318f, 0.11929f, 0.09096f, 0.06772f, 0.04906f,
    0.03444f, 0.02331f, 0.01514f, 0.00935f, 0.00541f, 0.00289f, 0.00138f, 0.00056f, 0.00018f, 0.00003f, 0.00000f,
    0.95699f, 1.07210f, 1.12006f, 1.09466f, 1.03583f, 0.96136f, 0.88035f, 0.79780f, 0.71656f, 0.63831f, 0.56404f,
    0.49434f, 0.42954f, 0.36982f, 0.31524f, 0.26580f, 0.22144f, 0.18204f, 0.14745f, 0.11746f, 0.09183f, 0.07027f,
    0.05246f, 0.03807f, 0.02678f, 0.01812f, 0.01169f, 0.00708f, 0.00394f, 0.00195f, 0.00080f, 0.00023f, 0.00002f,
    0.86770f, 0.97463f, 1.02350f, 1.00642f, 0.95904f, 0.89719f, 0.82891f, 0.75861f, 0.68882f, 0.62102f, 0.55608f,
    0.49451f, 0.43662f, 0.38259f, 0.33249f, 0.28638f, 0.24423f, 0.20603f, 0.17170f, 0.14115f, 0.11427f, 0.09090f,
    0.07088f, 0.05401f, 0.04015f, 0.02897f, 0.02012f, 0.01330f, 0.00822f, 0.00463f, 0.00225f, 0.00083f, 0.00013f,
    0.80250f, 0.90346f, 0.95292f, 0.94170f, 0.90246f, 0.84962f, 0.79050f, 0.72912f, 0.66775f, 0.60773f, 0.54985f,
    0.49455f, 0.44213f, 0.39273f, 0.34644f, 0.30330f, 0.26334f, 0.22655f, 0.19292f, 0.16240f, 0.13496f, 0.11052f,
    0.08900f, 0.07031f, 0.05445f, 0.04116f, 0.03016f, 0.02124f, 0.01416f, 0.00875f, 0.00480f, 0.00212f, 0.00051f,
    0.75441f, 0.85100f, 0.90099f, 0.89412f, 0.86086f, 0.81466f, 0.76233f, 0.70758f, 0.65254f, 0.59842f, 0.54595f,
    0.49554f, 0.44744f, 0.40179f, 0.35865f, 0.31809f, 0.28011f, 0.24472f, 0.21194f, 0.18175f, 0.15414f, 0.12910f,
    0.10657f, 0.08656f, 0.06915f, 0.05416f, 0.04135f, 0.03053f, 0.02155f, 0.01428f, 0.00858f, 0.00433f, 0.00141f,
    0.71899f, 0.81243f, 0.86302f, 0.85948f, 0.83074f, 0.78955f, 0.74234f, 0.69263f, 0.64240f, 0.59282f, 0.54454f,
    0.49796f, 0.45329f, 0.41065f, 0.37011f, 0.33171f, 0.29546f, 0.26137f, 0.22945f, 0.19971f, 0.17215f, 0.14678f,
    0.12358f, 0.10259f, 0.08401f, 0.06766f, 0.05333f, 0.04087f, 0.03015f, 0.02108f, 0.01359f, 0.00762f, 0.00307f,
    0.69329f, 0.78451f, 0.83581f, 0.83494f, 0.80969f, 0.77233f, 0.72904f, 0.68318f, 0.63666f, 0.59058f, 0.54558f,
    0.50200f, 0.46005f, 0.41984f, 0.38142f, 0.34481f, 0.31002f, 0.27707f, 0.24595f, 0.21668f, 0.18927f, 0.16374f,
    0.14009f, 0.11837f, 0.09887f, 0.08143f, 0.06586f, 0.05199f, 0.03972f, 0.02900f, 0.01978f, 0.01202f, 0.00571f,
    0.67530f, 0.76500f, 0.81715f, 0.81846f, 0.79596f, 0.76156f, 0.72129f, 0.67840f, 0.63475f, 0.59139f, 0.54893f,
    0.50771f, 0.46792f, 0.42965f, 0.39293f, 0.35779f, 0.32422f, 0.29223f, 0.26182f, 0.23299f, 0.20577f, 0.18015f,
    0.15618f, 0.13390f, 0.11368f, 0.09537f, 0.07875f, 0.06369f, 0.05008f, 0.03786f, 0.02702f, 0.01754f, 0.00942f,
    0.66356f, 0.75230f, 0.80542f, 0.80857f, 0.78824f, 0.75615f, 0.71820f, 0.67760f, 0.63616f, 0.59490f, 0.55443f,
    0.51506f, 0.47696f, 0.44022f, 0.40487f, 0.37091f, 0.33833f, 0.30714f, 0.27731f, 0.24887f, 0.22181f, 0.19616f,
    0.17194f, 0.14922f, 0.12841f, 0.10938f, 0.09191f, 0.07583f, 0.06105f, 0.04752f, 0.03519f, 0.02410f, 0.01423f,
    0.65700f, 0.74520f, 0.79941f, 0.80413f, 0.78554f, 0.75524f, 0.71908f, 0.68022f, 0.64047f, 0.60083f, 0.56188f,
    0.52393f, 0.48715f, 0.45161f, 0.41733f, 0.38430f, 0.35252f, 0.32196f, 0.29261f, 0.26447f, 0.23756f, 0.21187f,
    0.18744f, 0.16435f, 0.14305f, 0.12342f, 0.10522f, 0.08828f, 0.07250f, 0.05780f, 0.04417f, 0.03160f, 0.02012f,
    0.65482f, 0.74278f, 0.79817f, 0.80426f, 0.78706f, 0.75814f, 0.72332f, 0.68578f, 0.64729f, 0.60887f, 0.57107f,
    0.53420f, 0.49843f, 0.46380f, 0.43035f, 0.39804f, 0.36686f, 0.33679f, 0.30781f, 0.27990f, 0.25308f, 0.22735f,
    0.20272f, 0.17930f, 0.15758f, 0.13743f, 0.11861f, 0.10094f, 0.08429f, 0.06859f, 0.05380f, 0.03993f, 0.02698f,
    0.65636f, 0.74432f, 0.80095f, 0.80824f, 0.79214f, 0.76425f, 0.73043f, 0.69385f, 0.65628f, 0.61874f, 0.58178f,
    0.54572f, 0.51068f, 0.47674f, 0.44389f, 0.41212f, 0.38139f, 0.35168f, 0.32295f, 0.29520f, 0.26842f, 0.24262f,
    0.21780f, 0.19407f, 0.17197f, 0.15138f, 0.13202f, 0.11372f, 0.09632f, 0.07975f, 0.06396f, 0.04894f, 0.03471f,
    0.66109f, 0.74918f, 0.80711f, 0.81543f, 0.80019f, 0.77306f, 0.73994f, 0.70402f, 0.66709f, 0.63016f, 0.59379f,
    0.55828f, 0.52377f, 0.49031f, 0.45790f, 0.42650f, 0.39608f, 0.36661f, 0.33805f, 0.31037f, 0.28358f, 0.25768f,
    0.23267f, 0.20864f, 0.18620f, 0.16520f, 0.14538f, 0.12652f, 0.10848f, 0.09116f, 0.07450f, 0.05850f, 0.04316f,
    0.66854f, 0.75683f, 0.81606f, 0.82528f, 0.81070f, 0.78409f, 0.75142f, 0.71592f, 0.67939f, 0.64285f, 0.60685f,
    0.57170f, 0.53753f, 0.50438f, 0.47225f, 0.44109f, 0.41086f, 0.38153f, 0.35304f, 0.32539f, 0.29854f, 0.27251f,
    0.24729f, 0.22298f, 0.20021f, 0.17885f, 0.15860f, 0.13926f, 0.12066f, 0.10270f, 0.08530f, 0.06847f, 0.05219f,
    0.67827f, 0.76677f, 0.82727f, 0.83728f, 0.82316f, 0.79688f, 0.76445f, 0.72916f, 0.69284f, 0.65649f, 0.62070f,
    0.58574f, 0.55176f, 0.51878f, 0.48680f, 0.45577f, 0.42563f, 0.39635f, 0.36788f, 0.34018f, 0.31323f, 0.28704f,
    0.26161f, 0.23702f, 0.21394f, 0.19225f, 0.17163f, 0.15186f, 0.13277f, 0.11425f, 0.09624f, 0.07870f, 0.06164f,
    0.68984f, 0.77850f, 0.84023f, 0.85089f, 0.83710f, 0.81096f, 0.77861f, 0.74337f, 0.70708f, 0.67078f, 0.63504f,
    0.60015f, 0.56623f, 0.53331f, 0.50138f, 0.47038f, 0.44026f, 0.41096f, 0.38244f, 0.35465f, 0.32758f, 0.30121f,
    0.27555f, 0.25069f, 0.22733f, 0.20532f, 0.18437f, 0.16422f, 0.14472f, 0.12573f, 0.10719f, 0.08907f, 0.07137f,
    0.70282f, 0.79154f, 0.85442f, 0.86561f, 0.85200f, 0.82587f, 0.79346f, 0.75813f, 0.72176f, 0.68539f, 0.64959f,
    0.61465f, 0.58070f, 0.54776f, 0.51579f, 0.48476f, 0.45459f, 0.42522f, 0.39661f, 0.36870f, 0.34147f, 0.31491f,
    0.28903f, 0.26391f, 0.24028f, 0.21799f, 0.19674f, 0.17627f, 0.15640f, 0.13702f, 0.11804f, 0.09944f, 0.08123f,
    0.71671f, 0.80536f, 0.86928f, 0.88090f, 0.86736f, 0.84113f, 0.80855f, 0.77303f, 0.73647f, 0.69994f, 0.66400f,
    0.62895f, 0.59490f, 0.56186f, 0.52982f, 0.49870f, 0.46843f, 0.43896f, 0.41023f, 0.38218f, 0.35479f, 0.32805f,
    0.30195f, 0.27659f, 0.25271f, 0.23017f, 0.20865f, 0.18790f, 0.16773f, 0.14802f, 0.12869f, 0.10972f, 0.09111f,
    0.73101f, 0.81943f, 0.88426f, 0.89620f, 0.88263f, 0.85622f, 0.82339f, 0.78761f, 0.75082f, 0.71407f, 0.67794f,
    0.64272f, 0.60853f, 0.57537f, 0.54320f, 0.51197f, 0.48160f, 0.45201f, 0.42314f, 0.39495f, 0.36740f, 0.34048f,
    0.31419f, 0.28861f, 0.26451f, 0.24176f, 0.22002f, 0.19904f, 0.17862f, 0.15865f, 0.13904f, 0.11978f, 0.10087f,
    0.74512f, 0.83316f, 0.89874f, 0.91090f, 0.89724f, 0.87060f, 0.83748f, 0.80142f, 0.76435f, 0.72737f, 0.69103f,
    0.65563f, 0.62128f, 0.58798f, 0.55570f, 0.52435f, 0.49386f, 0.46416f, 0.43517f, 0.40685f, 0.37917f, 0.35209f,
    0.32563f, 0.29987f, 0.27560f, 0.25267f, 0.23075f, 0.20959f, 0.18898f, 0.16881f, 0.14900f, 0.12952f, 0.11042f,
    0.75843f, 0.84592f, 0.91208f, 0.92437f, 0.91059f, 0.88369f, 0.85030f, 0.81395f, 0.77663f, 0.73941f, 0.70288f,
    0.66732f, 0.63282f, 0.59941f, 0.56702f, 0.53557f, 0.50500f, 0.47520f, 0.44613f, 0.41771f, 0.38992f, 0.36273f,
    0.33614f, 0.31025f, 0.28585f, 0.26280f, 0.24076f, 0.21947f, 0.19873f, 0.17843f, 0.15848f, 0.13887f, 0.11964f,
    0.77025f, 0.85703f, 0.92360f, 0.93596f, 0.92204f, 0.89492f, 0.86127f, 0.82469f, 0.78716f, 0.74976f, 0.71309f,
    0.67740f, 0.64282f, 0.60933f, 0.57688f, 0.54538f, 0.51476f, 0.48493f, 0.45581f, 0.42735f, 0.39950f, 0.37226f,
    0.34560f, 0.31964f, 0.29516f, 0.27205f, 0.24994f, 0.22859f, 0.20779f, 0.18742f, 0.16740f, 0.14773f, 0.12846f,
    0.77985f, 0.86580f, 0.93259f, 0.94498f, 0.93094f, 0.90366f, 0.86984f, 0.83311f, 0.79545f, 0.75797f, 0.72122f,
    0.68551f, 0.65090f, 0.61741f, 0.58498f, 0.55351f, 0.52291f, 0.49311f, 0.46402f, 0.43558f, 0.40775f, 0.38052f,
    0.35387f, 0.32790f, 0.30343f, 0.28031f, 0.25821f, 0.23686f, 0.21607f, 0.19570f, 0.17570f, 0.15604f, 0.13678f,
    0.78647f, 0.87150f, 0.93833f, 0.95071f, 0.93663f, 0.90929f, 0.87542f, 0.83867f, 0.80102f, 0.76356f, 0.72687f,
    0.69123f, 0.65672f, 0.62334f, 0.59101f, 0.55966f, 0.52919f, 0.49951f, 0.47054f, 0.44221f, 0.41449f, 0.38736f,
    0.36080f, 0.33491f, 0.31052f, 0.28749f, 0.26547f, 0.24420f, 0.22349f, 0.20321f, 0.18328f, 0.16370f, 0.14454f,
    0.78935f, 0.87343f, 0.94011f, 0.95249f, 0.93844f, 0.91118f, 0.87744f, 0.84083f, 0.80335f, 0.76608f, 0.72961f,
    0.69419f, 0.65991f, 0.62676f, 0.59468f, 0.56358f, 0.53334f, 0.50390f, 0.47515f, 0.44705f, 0.41955f, 0.39261f,
    0.36624f, 0.34054f, 0.31632f, 0.29347f, 0.27162f, 0.25053f, 0.22998f, 0.20986f, 0.19009f, 0.17067f, 0.15167f,
    0.78778f, 0.87089f, 0.93722f, 0.94962f, 0.93575f, 0.90875f, 0.87533f, 0.83907f, 0.80196f, 0.76509f, 0.72901f,
    0.69399f, 0.66011f, 0.62736f, 0.59568f, 0.56496f, 0.53511f, 0.50603f, 0.47765f, 0.44990f, 0.42273f, 0.39612f,
    0.37006f, 0.34465f, 0.32072f, 0.29814f, 0.27657f, 0.25573f, 0.23545f, 0.21557f, 0.19604f, 0.17686f, 0.15810f,
    0.78109f, 0.86325f, 0.92905f, 0.94149f, 0.92795f, 0.90144f, 0.86857f, 0.83290f, 0.79641f, 0.76014f, 0.72468f,
    0.69026f, 0.65697f, 0.62481f, 0.59369f, 0.56353f, 0.53423f, 0.50568f, 0.47781f, 0.45056f, 0.42387f, 0.39772f,
    0.37210f, 0.34710f, 0.32357f, 0.30139f, 0.28019f, 0.25973f, 0.23980f, 0.22027f, 0.20107f, 0.18221f, 0.16377f,
};
constant float SHEEN_E[1089] = {
    0.86668f, 0.90101f, 0.91368f, 0.92507f, 0.93420f, 0.94120f, 0.94642f, 0.95022f, 0.82889f, 0.65276f, 0.50153f,
    0.37520f, 0.27260f, 0.19174f, 0.13007f, 0.08473f, 0.05272f, 0.03114f, 0.01734f, 0.00902f, 0.00434f, 0.00191f,
    0.00075f, 0.00026f, 0.00008f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    0.86668f, 0.90101f, 0.91368f, 0.92507f, 0.93420f, 0.94120f, 0.94642f, 0.95022f, 0.82889f, 0.65276f, 0.50153f,
    0.37520f, 0.27260f, 0.19174f, 0.13007f, 0.08473f, 0.05272f, 0.03114f, 0.01734f, 0.00902f, 0.00434f, 0.00191f,
    0.00075f, 0.00026f, 0.00008f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    0.86668f, 0.90101f, 0.91368f, 0.92507f, 0.93420f, 0.94120f, 0.94642f, 0.95022f, 0.82889f, 0.65276f, 0.50153f,
    0.37520f, 0.27260f, 0.19174f, 0.13007f, 0.08473f, 0.05272f, 0.03114f, 0.01734f, 0.00902f, 0.00434f, 0.00191f,
    0.00075f, 0.00026f, 0.00008f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    0.86668f, 0.90101f, 0.91368f, 0.92507f, 0.93420f, 0.94120f, 0.94642f, 0.95022f, 0.82889f, 0.65276f, 0.50153f,
    0.37520f, 0.27260f, 0.19174f, 0.13007f, 0.08473f, 0.05272f, 0.03114f, 0.01734f, 0.00902f, 0.00434f, 0.00191f,
    0.00075f, 0.00026f, 0.00008f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    0.91292f, 0.94847f, 0.95629f, 0.96319f, 0.96865f, 0.97280f, 0.97591f, 0.97260f, 0.82164f, 0.68299f, 0.55837f,
    0.44851f, 0.35347f, 0.27284f, 0.20583f, 0.15138f, 0.10822f, 0.07494f, 0.05006f, 0.03210f, 0.01965f, 0.01139f,
    0.00620f, 0.00314f, 0.00145f, 0.00061f, 0.00022f, 0.00007f, 0.00002f, 0.00000f, 0.00000f, 0.00000f, 0.00000f,
    0.93868f, 0.97501f, 0.97952f, 0.98337f, 0.98630f, 0.98848f, 0.99008f, 0.90602f, 0.78727f, 0.67575f, 0.57287f,
    0.47940f, 0.39569f, 0.32175f, 0.25739f, 0.20223f, 0.15576f, 0.11732f, 0.08619f, 0.06156f, 0.04258f, 0.02839f,
    0.01814f, 0.01103f, 0.00633f, 0.00338f, 0.00166f, 0.00072f, 0.00027f, 0.00008f, 0.00002f, 0.00000f, 0.00000f,
    0.95254f, 0.98945f, 0.99174f, 0.99359f, 0.99493f, 0.99588f, 0.94553f, 0.84632f, 0.74962f, 0.65744f, 0.57097f,
    0.49088f, 0.41754f, 0.35111f, 0.29158f, 0.23886f, 0.19273f, 0.15293f, 0.11909f, 0.09080f, 0.06760f, 0.04897f,
    0.03438f, 0.02326f, 0.01511f, 0.00932f, 0.00540f, 0.00288f, 0.00138f, 0.00056f, 0.00018f, 0.00003f, 0.00000f,
    0.95342f, 0.99677f, 0.99762f, 0.99826f, 0.99869f, 0.96038f, 0.87962f, 0.79725f, 0.71613f, 0.63797f, 0.56378f,
    0.49413f, 0.42937f, 0.36967f, 0.31512f, 0.26571f, 0.22136f, 0.18198f, 0.14740f, 0.11742f, 0.09180f, 0.07025f,
    0.05245f, 0.03806f, 0.02677f, 0.01812f, 0.01168f, 0.00708f, 0.00394f, 0.00195f, 0.00080f, 0.00023f, 0.00002f,
    0.86748f, 0.97442f, 0.99985f, 0.99990f, 0.95897f, 0.89714f, 0.82887f, 0.75858f, 0.68880f, 0.62100f, 0.55606f,
    0.49450f, 0.43661f, 0.38258f, 0.33249f, 0.28637f, 0.24423f, 0.20603f, 0.17170f, 0.14115f, 0.11427f, 0.09090f,
    0.07088f, 0.05401f, 0.04015f, 0.02897f, 0.02012f, 0.01330f, 0.00822f, 0.00463f, 0.00225f, 0.00083f, 0.00013f,
    0.80250f, 0.90346f, 0.95292f, 0.94170f, 0.90246f, 0.84962f, 0.79050f, 0.72912f, 0.66775f, 0.60773f, 0.54985f,
    0.49455f, 0.44213f, 0.39273f, 0.34644f, 0.30330f, 0.26334f, 0.22655f, 0.19292f, 0.16240f, 0.13496f, 0.11052f,
    0.08900f, 0.07031f, 0.05445f, 0.04116f, 0.03016f, 0.02124f, 0.01416f, 0.00875f, 0.00480f, 0.00212f, 0.00051f,
    0.75441f, 0.85100f, 0.90099f, 0.89412f, 0.86086f, 0.81466f, 0.76233f, 0.70758f, 0.65254f, 0.59842f, 0.54595f,
    0.49554f, 0.44744f, 0.40179f, 0.35865f, 0.31809f, 0.28011f, 0.24472f, 0.21194f, 0.18175f, 0.15414f, 0.12910f,
    0.10657f, 0.08656f, 0.06915f, 0.05416f, 0.04135f, 0.03053f, 0.02155f, 0.01428f, 0.00858f, 0.00433f, 0.00141f,
    0.71899f, 0.81243f, 0.86302f, 0.85948f, 0.83074f, 0.78955f, 0.74234f, 0.69263f, 0.64240f, 0.59282f, 0.54454f,
    0.49796f, 0.45329f, 0.41065f, 0.37011f, 0.33171f, 0.29546f, 0.26137f, 0.22945f, 0.19971f, 0.17215f, 0.14678f,
    0.12358f, 0.10259f, 0.08401f, 0.06766f, 0.05333f, 0.04087f, 0.03015f, 0.02108f, 0.01359f, 0.00762f, 0.00307f,
    0.69329f, 0.78451f, 0.83581f, 0.83494f, 0.80969f, 0.77233f, 0.72904f, 0.68318f, 0.63666f, 0.59058f, 0.54558f,
    0.50200f, 0.46005f, 0.41984f, 0.38142f, 0.34481f, 0.31002f, 0.27707f, 0.24595f, 0.21668f, 0.18927f, 0.16374f,
    0.14009f, 0.11837f, 0.09887f, 0.08143f, 0.06586f, 0.05199f, 0.03972f, 0.02900f, 0.01978f, 0.01202f, 0.00571f,
    0.67530f, 0.76500f, 0.81715f, 0.81846f, 0.79596f, 0.76156f, 0.72129f, 0.67840f, 0.63475f, 0.59139f, 0.54893f,
    0.50771f, 0.46792f, 0.42965f, 0.39293f, 0.35779f, 0.32422f, 0.29223f, 0.26182f, 0.23299f, 0.20577f, 0.18015f,
    0.15618f, 0.13390f, 0.11368f, 0.09537f, 0.07875f, 0.06369f, 0.05008f, 0.03786f, 0.02702f, 0.01754f, 0.00942f,
    0.66356f, 0.75230f, 0.80542f, 0.80857f, 0.78824f, 0.75615f, 0.71820f, 0.67760f, 0.63616f, 0.59490f, 0.55443f,
    0.51506f, 0.47696f, 0.44022f, 0.40487f, 0.37091f, 0.33833f, 0.30714f, 0.27731f, 0.24887f, 0.22181f, 0.19616f,
    0.17194f, 0.14922f, 0.12841f, 0.10938f, 0.09191f, 0.07583f, 0.06105f, 0.04752f, 0.03519f, 0.02410f, 0.01423f,
    0.65700f, 0.74520f, 0.79941f, 0.80413f, 0.78554f, 0.75524f, 0.71908f, 0.68022f, 0.64047f, 0.60083f, 0.56188f,
    0.52393f, 0.48715f, 0.45161f, 0.41733f, 0.38430f, 0.35252f, 0.32196f, 0.29261f, 0.26447f, 0.23756f, 0.21187f,
    0.18744f, 0.16435f, 0.14305f, 0.12342f, 0.10522f, 0.08828f, 0.07250f, 0.05780f, 0.04417f, 0.03160f, 0.02012f,
    0.65482f, 0.74278f, 0.79817f, 0.80426f, 0.78706f, 0.75814f, 0.72332f, 0.68578f, 0.64729f, 0.60887f, 0.57107f,
    0.53420f, 0.49843f, 0.46380f, 0.43035f, 0.39804f, 0.36686f, 0.33679f, 0.30781f, 0.27990f, 0.25308f, 0.22735f,
    0.20272f, 0.17930f, 0.15758f, 0.13743f, 0.11861f, 0.10094f, 0.08429f, 0.06859f, 0.05380f, 0.03993f, 0.02698f,
    0.65636f, 0.74432f, 0.80095f, 0.80824f, 0.79214f, 0.76425f, 0.73043f, 0.69385f, 0.65628f, 0.61874f, 0.58178f,
    0.54572f, 0.51068f, 0.47674f, 0.44389f, 0.41212f, 0.38139f, 0.35168f, 0.32295f, 0.29520f, 0.26842f, 0.24262f,
    0.21780f, 0.19407f, 0.17197f, 0.15138f, 0.13202f, 0.11372f, 0.09632f, 0.07975f, 0.06396f, 0.04894f, 0.03471f,
    0.66109f, 0.74918f, 0.80711f, 0.81543f, 0.80019f, 0.77306f, 0.73994f, 0.70402f, 0.66709f, 0.63016f, 0.59379f,
    0.55828f, 0.52377f, 0.49031f, 0.45790f, 0.42650f, 0.39608f, 0.36661f, 0.33805f, 0.31037f, 0.28358f, 0.25768f,
    0.23267f, 0.20864f, 0.18620f, 0.16520f, 0.14538f, 0.12652f, 0.10848f, 0.09116f, 0.07450f, 0.05850f, 0.04316f,
    0.66854f, 0.75683f, 0.81606f, 0.82528f, 0.81070f, 0.78409f, 0.75142f, 0.71592f, 0.67939f, 0.64285f, 0.60685f,
    0.57170f, 0.53753f, 0.50438f, 0.47225f, 0.44109f, 0.41086f, 0.38153f, 0.35304f, 0.32539f, 0.29854f, 0.27251f,
    0.24729f, 0.22298f, 0.20021f, 0.17885f, 0.15860f, 0.13926f, 0.12066f, 0.10270f, 0.08530f, 0.06847f, 0.05219f,
    0.67827f, 0.76677f, 0.82727f, 0.83728f, 0.82316f, 0.79688f, 0.76445f, 0.72916f, 0.69284f, 0.65649f, 0.62070f,
    0.58574f, 0.55176f, 0.51878f, 0.48680f, 0.45577f, 0.42563f, 0.39635f, 0.36788f, 0.34018f, 0.31323f, 0.28704f,
    0.26161f, 0.23702f, 0.21394f, 0.19225f, 0.17163f, 0.15186f, 0.13277f, 0.11425f, 0.09624f, 0.07870f, 0.06164f,
    0.68984f, 0.77850f, 0.84023f, 0.85089f, 0.83710f, 0.81096f, 0.77861f, 0.74337f, 0.70708f, 0.67078f, 0.63504f,
    0.60015f, 0.56623f, 0.53331f, 0.50138f, 0.47038f, 0.44026f, 0.41096f, 0.38244f, 0.35465f, 0.32758f, 0.30121f,
    0.27555f, 0.25069f, 0.22733f, 0.20532f, 0.18437f, 0.16422f, 0.14472f, 0.12573f, 0.10719f, 0.08907f, 0.07137f,
    0.70282f, 0.79154f, 0.85442f, 0.86561f, 0.85200f, 0.82587f, 0.79346f, 0.75813f, 0.72176f, 0.68539f, 0.64959f,
    0.61465f, 0.58070f, 0.54776f, 0.51579f, 0.48476f, 0.45459f, 0.42522f, 0.39661f, 0.36870f, 0.34147f, 0.31491f,
    0.28903f, 0.26391f, 0.24028f, 0.21799f, 0.19674f, 0.17627f, 0.15640f, 0.13702f, 0.11804f, 0.09944f, 0.08123f,
    0.71671f, 0.80536f, 0.86928f, 0.88090f, 0.86736f, 0.84113f, 0.80855f, 0.77303f, 0.73647f, 0.69994f, 0.66400f,
    0.62895f, 0.59490f, 0.56186f, 0.52982f, 0.49870f, 0.46843f, 0.43896f, 0.41023f, 0.38218f, 0.35479f, 0.32805f,
    0.30195f, 0.27659f, 0.25271f, 0.23017f, 0.20865f, 0.18790f, 0.16773f, 0.14802f, 0.12869f, 0.10972f, 0.09111f,
    0.73101f, 0.81943f, 0.88426f, 0.89620f, 0.88263f, 0.85622f, 0.82339f, 0.78761f, 0.75082f, 0.71407f, 0.67794f,
    0.64272f, 0.60853f, 0.57537f, 0.54320f, 0.51197f, 0.48160f, 0.45201f, 0.42314f, 0.39495f, 0.36740f, 0.34048f,
    0.31419f, 0.28861f, 0.26451f, 0.24176f, 0.22002f, 0.19904f, 0.17862f, 0.15865f, 0.13904f, 0.11978f, 0.10087f,
    0.74512f, 0.83316f, 0.89874f, 0.91090f, 0.89724f, 0.87060f, 0.83748f, 0.80142f, 0.76435f, 0.72737f, 0.69103f,
    0.65563f, 0.62128f, 0.58798f, 0.55570f, 0.52435f, 0.49386f, 0.46416f, 0.43517f, 0.40685f, 0.37917f, 0.35209f,
    0.32563f, 0.29987f, 0.27560f, 0.25267f, 0.23075f, 0.20959f, 0.18898f, 0.16881f, 0.14900f, 0.12952f, 0.11042f,
    0.75843f, 0.84592f, 0.91208f, 0.92437f, 0.91059f, 0.88369f, 0.85030f, 0.81395f, 0.77663f, 0.73941f, 0.70288f,
    0.66732f, 0.63282f, 0.59941f, 0.56702f, 0.53557f, 0.50500f, 0.47520f, 0.44613f, 0.41771f, 0.38992f, 0.36273f,
    0.33614f, 0.31025f, 0.28585f, 0.26280f, 0.24076f, 0.21947f, 0.19873f, 0.17843f, 0.15848f, 0.13887f, 0.11964f,
    0.77025f, 0.85703f, 0.92360f, 0.93596f, 0.92204f, 0.89492f, 0.86127f, 0.82469f, 0.78716f, 0.74976f, 0.71309f,
    0.67740f, 0.64282f, 0.60933f, 0.57688f, 0.54538f, 0.51476f, 0.48493f, 0.45581f, 0.42735f, 0.39950f, 0.37226f,
    0.34560f, 0.31964f, 0.29516f, 0.27205f, 0.24994f, 0.22859f, 0.20779f, 0.18742f, 0.16740f, 0.14773f, 0.12846f,
    0.77985f, 0.86580f, 0.93259f, 0.94498f, 0.93094f, 0.90366f, 0.86984f, 0.83311f, 0.79545f, 0.75797f, 0.72122f,
    0.68551f, 0.65090f, 0.61741f, 0.58498f, 0.55351f, 0.52291f, 0.49311f, 0.46402f, 0.43558f, 0.40775f, 0.38052f,
    0.35387f, 0.32790f, 0.30343f, 0.28031f, 0.25821f, 0.23686f, 0.21607f, 0.19570f, 0.17570f, 0.15604f, 0.13678f,
    0.78647f, 0.87150f, 0.93833f, 0.95071f, 0.93663f, 0.90929f, 0.87542f, 0.83867f, 0.80102f, 0.76356f, 0.72687f,
    0.69123f, 0.65672f, 0.62334f, 0.59101f, 0.55966f, 0.52919f, 0.49951f, 0.47054f, 0.44221f, 0.41449f, 0.38736f,
    0.36080f, 0.33491f, 0.31052f, 0.28749f, 0.26547f, 0.24420f, 0.22349f, 0.20321f, 0.18328f, 0.16370f, 0.14454f,
    0.78935f, 0.87343f, 0.94011f, 0.95249f, 0.93844f, 0.91118f, 0.87744f, 0.84083f, 0.80335f, 0.76608f, 0.72961f,
    0.69419f, 0.65991f, 0.62676f, 0.59468f, 0.56358f, 0.53334f, 0.50390f, 0.47515f, 0.44705f, 0.41955f, 0.39261f,
    0.36624f, 0.34054f, 0.31632f, 0.29347f, 0.27162f, 0.25053f, 0.22998f, 0.20986f, 0.19009f, 0.17067f, 0.15167f,
    0.78778f, 0.87089f, 0.93722f, 0.94962f, 0.93575f, 0.90875f, 0.87533f, 0.83907f, 0.80196f, 0.76509f, 0.72901f,
    0.69399f, 0.66011f, 0.62736f, 0.59568f, 0.56496f, 0.53511f, 0.50603f, 0.47765f, 0.44990f, 0.42273f, 0.39612f,
    0.37006f, 0.34465f, 0.32072f, 0.29814f, 0.27657f, 0.25573f, 0.23545f, 0.21557f, 0.19604f, 0.17686f, 0.15810f,
    0.78109f, 0.86325f, 0.92905f, 0.94149f, 0.92795f, 0.90144f, 0.86857f, 0.83290f, 0.79641f, 0.76014f, 0.72468f,
    0.69026f, 0.65697f, 0.62481f, 0.59369f, 0.56353f, 0.53423f, 0.50568f, 0.47781f, 0.45056f, 0.42387f, 0.39772f,
    0.37210f, 0.34710f, 0.32357f, 0.30139f, 0.28019f, 0.25973f, 0.23980f, 0.22027f, 0.20107f, 0.18221f, 0.16377f,
};
constant float SHEEN_E_AVG[33] = {
    0.01823f, 0.01823f, 0.01823f, 0.01823f, 0.02611f, 0.03394f, 0.04183f, 0.04993f, 0.05836f, 0.06723f, 0.07659f,
    0.08646f, 0.09683f, 0.10768f, 0.11897f, 0.13066f, 0.14268f, 0.15496f, 0.16742f, 0.17995f, 0.19247f, 0.20486f,
    0.21700f, 0.22880f, 0.24012f, 0.25086f, 0.26090f, 0.27011f, 0.27837f, 0.28557f, 0.29160f, 0.29631f, 0.29960f,
};

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
    l.thin = m->thickness <= 0.0f || fabs(l.eta - 1.0f) < 1e-3f;
    float r = (l.eta - 1.0f) / (l.eta + 1.0f);
    l.f0 = fmin(r * r * m->specular_color, 1.0f);
    l.f0_layer = bsdf_max3(l.f0);
#ifdef HAS_IRIDESCENCE
    // The diffuse base lies under the film at its largest reflectance (any thickness), so it
    // never takes light the film reflects.
    l.iridescence = clamp(m->iridescence, 0.0f, 1.0f);
    l.film_ior = fmax(m->iridescence_ior, 1.0f);
    l.film_thickness = fmax(m->iridescence_thickness, 0.0f);
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
    if (wi.z > 0.0f || l->thin) {
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
// base_color / pi, sampled by its cosine, and is evaluated as such.
inline float3 bsdf_eval(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 wi_world,
                        float* pdf) {
    float cos_i = dot(wi_world, n);
    bool lit = dot(wo_world, n) > 0.0f && cos_i > 0.0f;
    *pdf = lit ? cos_i * INV_PI_F : 0.0f;
    return lit ? m->base_color * (cos_i * INV_PI_F) : (float3)(0.0f);
}

SHADE_INLINE float3 bsdf_sample(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 u,
                                float3* wi_world, float* pdf, bool* specular) {
    *specular = false;
    *wi_world = n;
    *pdf = 0.0f;
    if (dot(wo_world, n) <= 0.0f) return (float3)(0.0f);
    float3 wi = sample_cosine(u.x, u.y);
    if (!(wi.z > 0.0f)) return (float3)(0.0f);
    float3 t, b;
    onb(n, &t, &b);
    // Unit within rounding (an orthonormal frame and a unit vector in it): not normalized again.
    *wi_world = wi.x * t + wi.y * b + wi.z * n;
    // The pdf of the direction as evaluated (cos(n, wi) / pi), so that the weight is exact.
    float cos_i = dot(*wi_world, n);
    if (!(cos_i > 0.0f)) return (float3)(0.0f);
    *pdf = cos_i * INV_PI_F;
    return m->base_color;
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
        if (reflect || l.thin) {
            wi = 2.0f * cos_oh * h - wo;
            if (wi.z <= 0.0f) return (float3)(0.0f);
            if (!reflect) wi.z = -wi.z;
        } else {
            float c2 = refracted_cos2(cos_oh, l.eta);
            if (c2 <= 0.0f) return (float3)(0.0f);
            wi = (cos_oh / l.eta - sqrt(c2)) * h - wo / l.eta;
            if (wi.z >= 0.0f) return (float3)(0.0f);
        }
        if (l.delta) {
            float chosen = (1.0f - p_cos) * (reflect ? pr : 1.0f - pr);
            if (!(chosen > 0.0f)) return (float3)(0.0f);
            *wi_world = normalize(wi.x * t + wi.y * b + wi.z * n);
            *pdf = chosen;
            *specular = true;
            float3 w = (reflect ? refl : trans) / chosen;
            w = reflect || l.thin ? w : w / (l.eta * l.eta);
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
