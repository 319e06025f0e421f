// Scattering at a surface: the glTF 2.0 metallic-roughness BSDF (specification, appendix B) with
// KHR_materials_specular, _ior, _transmission and _volume. docs/materials.md ("Scattering") says
// what is modelled and what is approximated.
//
// Lobes, in the frame of the shading normal n (wo is always on n's side):
//   diffuse       Lambertian, base color, scaled by what the specular layer lets through
//   reflection    GGX microfacets, height-correlated Smith G2, Schlick Fresnel: the dielectric
//                 (f0 from ior × specularColor, scaled by specularFactor) and the metal (f0 = base
//                 color) mixed by metallic
//   transmission  the dielectric's transmitted share, tinted by base color: rough refraction
//                 through a volume (Walter et al. 2007), or straight through a thin wall
// Below BSDF_DELTA_ALPHA the glossy lobes are perfect mirror and refraction (delta) lobes.
//
// Contract: bsdf_eval returns f(wo, wi) * |cos(n, wi)| and its pdf (solid angle) for the non-delta
// lobes. bsdf_sample returns f * |cos| / pdf for the direction it makes, with that pdf, or 0 when
// it makes none; for a delta lobe it sets *specular and returns the lobe's weight divided by its
// selection probability, which is then the pdf. Scattering is not reciprocal: wo is the side the
// path came from (towards the camera).

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
    return s;
}

// Seen from inside its volume, the interface's relative index of refraction inverts.
inline void material_from_inside(SurfaceMaterial* m) {
    m->ior = 1.0f / m->ior;
}

// Beer–Lambert transmittance over a distance t inside the material's volume: attenuationColor
// is what remains after attenuationDistance.
inline float3 volume_transmittance(const SurfaceMaterial* m, float t) {
    if (!(m->attenuation_distance > 0.0f && m->attenuation_distance < INFINITY)) {
        return (float3)(1.0f);
    }
    return pow(fmax(m->attenuation, 0.0f), (float3)(t / m->attenuation_distance));
}

// GGX lobes with alpha below this are delta lobes.
#define BSDF_DELTA_ALPHA 1e-3f

// The mean over GGX's visible normals of the Schlick weight (1 - wo.h)^5 (how much Fresnel
// reflection a rough surface shows at cos(theta_o)), rows for roughness 0, 1/16 .. 1, columns for
// cos(theta_o) 0, 1/32 .. 1. tests/bsdf.rs recomputes it by quadrature.
constant float GGX_SCHLICK_AVERAGE[17 * 33] = {
    1.00000f, 0.85322f, 0.72420f, 0.61128f, 0.51291f, 0.42763f, 0.35409f, 0.29104f, 0.23730f, 0.19182f, 0.15359f,
    0.12172f, 0.09537f, 0.07379f, 0.05631f, 0.04232f, 0.03125f, 0.02263f, 0.01603f, 0.01107f, 0.00742f, 0.00480f,
    0.00298f, 0.00176f, 0.00098f, 0.00050f, 0.00023f, 0.00009f, 0.00003f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.91921f, 0.84646f, 0.72128f, 0.60969f, 0.51197f, 0.42705f, 0.35374f, 0.29082f, 0.23718f, 0.19176f, 0.15357f,
    0.12172f, 0.09539f, 0.07382f, 0.05634f, 0.04234f, 0.03128f, 0.02266f, 0.01605f, 0.01108f, 0.00743f, 0.00481f,
    0.00299f, 0.00177f, 0.00098f, 0.00050f, 0.00023f, 0.00009f, 0.00003f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.78163f, 0.78900f, 0.69266f, 0.59290f, 0.50148f, 0.42036f, 0.34948f, 0.28819f, 0.23564f, 0.19096f, 0.15326f,
    0.12173f, 0.09559f, 0.07414f, 0.05671f, 0.04272f, 0.03164f, 0.02298f, 0.01633f, 0.01132f, 0.00762f, 0.00496f,
    0.00310f, 0.00185f, 0.00104f, 0.00054f, 0.00025f, 0.00011f, 0.00004f, 0.00001f, 0.00000f, 0.00000f, 0.00000f,
    0.63903f, 0.66998f, 0.62029f, 0.54697f, 0.47138f, 0.40041f, 0.33633f, 0.27971f, 0.23041f, 0.18799f, 0.15186f,
    0.12139f, 0.09595f, 0.07492f, 0.05773f, 0.04384f, 0.03276f, 0.02404f, 0.01729f, 0.01215f, 0.00833f, 0.00554f,
    0.00356f, 0.00220f, 0.00130f, 0.00073f, 0.00039f, 0.00019f, 0.00009f, 0.00004f, 0.00002f, 0.00001f, 0.00000f,
    0.51017f, 0.53495f, 0.51661f, 0.47293f, 0.41932f, 0.36411f, 0.31135f, 0.26291f, 0.21952f, 0.18137f, 0.14828f,
    0.11995f, 0.09596f, 0.07588f, 0.05927f, 0.04568f, 0.03470f, 0.02595f, 0.01908f, 0.01378f, 0.00975f, 0.00675f,
    0.00457f, 0.00303f, 0.00196f, 0.00125f, 0.00079f, 0.00050f, 0.00032f, 0.00021f, 0.00014f, 0.00009f, 0.00006f,
    0.40165f, 0.41615f, 0.40991f, 0.38674f, 0.35322f, 0.31494f, 0.27566f, 0.23769f, 0.20231f, 0.17020f, 0.14161f,
    0.11656f, 0.09492f, 0.07645f, 0.06089f, 0.04793f, 0.03727f, 0.02861f, 0.02167f, 0.01620f, 0.01194f, 0.00868f,
    0.00624f, 0.00444f, 0.00314f, 0.00222f, 0.00158f, 0.00115f, 0.00086f, 0.00065f, 0.00051f, 0.00040f, 0.00032f,
    0.31415f, 0.32109f, 0.31800f, 0.30544f, 0.28558f, 0.26103f, 0.23414f, 0.20669f, 0.17996f, 0.15477f, 0.13160f,
    0.11070f, 0.09216f, 0.07596f, 0.06197f, 0.05005f, 0.04002f, 0.03167f, 0.02482f, 0.01926f, 0.01481f, 0.01129f,
    0.00856f, 0.00646f, 0.00488f, 0.00370f, 0.00284f, 0.00221f, 0.00176f, 0.00144f, 0.00120f, 0.00103f, 0.00091f,
    0.24560f, 0.24797f, 0.24532f, 0.23768f, 0.22567f, 0.21033f, 0.19279f, 0.17409f, 0.15513f, 0.13657f, 0.11891f,
    0.10248f, 0.08746f, 0.07395f, 0.06197f, 0.05148f, 0.04241f, 0.03466f, 0.02811f, 0.02264f, 0.01812f, 0.01443f,
    0.01145f, 0.00908f, 0.00720f, 0.00574f, 0.00462f, 0.00376f, 0.00311f, 0.00263f, 0.00228f, 0.00205f, 0.00191f,
    0.19294f, 0.19281f, 0.19011f, 0.18481f, 0.17709f, 0.16733f, 0.15601f, 0.14365f, 0.13074f, 0.11771f, 0.10491f,
    0.09264f, 0.08109f, 0.07039f, 0.06063f, 0.05183f, 0.04401f, 0.03712f, 0.03113f, 0.02596f, 0.02156f, 0.01784f,
    0.01473f, 0.01215f, 0.01004f, 0.00832f, 0.00694f, 0.00584f, 0.00498f, 0.00432f, 0.00384f, 0.00354f, 0.00343f,
    0.15296f, 0.15161f, 0.14894f, 0.14492f, 0.13960f, 0.13313f, 0.12571f, 0.11755f, 0.10890f, 0.10000f, 0.09106f,
    0.08226f, 0.07375f, 0.06566f, 0.05807f, 0.05103f, 0.04460f, 0.03876f, 0.03353f, 0.02889f, 0.02480f, 0.02123f,
    0.01814f, 0.01550f, 0.01325f, 0.01135f, 0.00977f, 0.00846f, 0.00740f, 0.00657f, 0.00596f, 0.00560f, 0.00558f,
    0.12284f, 0.12099f, 0.11847f, 0.11526f, 0.11139f, 0.10690f, 0.10188f, 0.09641f, 0.09061f, 0.08458f, 0.07845f,
    0.07230f, 0.06623f, 0.06033f, 0.05466f, 0.04928f, 0.04422f, 0.03950f, 0.03516f, 0.03118f, 0.02758f, 0.02434f,
    0.02145f, 0.01889f, 0.01663f, 0.01467f, 0.01299f, 0.01155f, 0.01036f, 0.00941f, 0.00871f, 0.00833f, 0.00850f,
    0.10021f, 0.09825f, 0.09596f, 0.09334f, 0.09040f, 0.08716f, 0.08364f, 0.07988f, 0.07593f, 0.07183f, 0.06764f,
    0.06340f, 0.05916f, 0.05497f, 0.05088f, 0.04690f, 0.04308f, 0.03945f, 0.03601f, 0.03278f, 0.02977f, 0.02699f,
    0.02444f, 0.02211f, 0.02001f, 0.01813f, 0.01647f, 0.01502f, 0.01379f, 0.01280f, 0.01210f, 0.01180f, 0.01230f,
    0.08320f, 0.08131f, 0.07929f, 0.07713f, 0.07484f, 0.07241f, 0.06986f, 0.06721f, 0.06446f, 0.06163f, 0.05875f,
    0.05584f, 0.05291f, 0.05000f, 0.04711f, 0.04427f, 0.04149f, 0.03880f, 0.03621f, 0.03372f, 0.03135f, 0.02911f,
    0.02700f, 0.02504f, 0.02322f, 0.02155f, 0.02005f, 0.01872f, 0.01759f, 0.01670f, 0.01613f, 0.01605f, 0.01710f,
    0.07038f, 0.06865f, 0.06689f, 0.06510f, 0.06327f, 0.06141f, 0.05951f, 0.05758f, 0.05563f, 0.05365f, 0.05165f,
    0.04964f, 0.04763f, 0.04562f, 0.04363f, 0.04166f, 0.03972f, 0.03781f, 0.03595f, 0.03414f, 0.03239f, 0.03070f,
    0.02910f, 0.02757f, 0.02614f, 0.02481f, 0.02360f, 0.02254f, 0.02166f, 0.02102f, 0.02075f, 0.02109f, 0.02299f,
    0.06068f, 0.05913f, 0.05761f, 0.05612f, 0.05464f, 0.05318f, 0.05174f, 0.05030f, 0.04888f, 0.04746f, 0.04606f,
    0.04467f, 0.04330f, 0.04194f, 0.04059f, 0.03926f, 0.03796f, 0.03667f, 0.03542f, 0.03419f, 0.03300f, 0.03185f,
    0.03074f, 0.02969f, 0.02871f, 0.02781f, 0.02701f, 0.02634f, 0.02586f, 0.02565f, 0.02588f, 0.02690f, 0.03001f,
    0.05329f, 0.05192f, 0.05062f, 0.04936f, 0.04816f, 0.04699f, 0.04587f, 0.04478f, 0.04373f, 0.04271f, 0.04171f,
    0.04075f, 0.03982f, 0.03891f, 0.03803f, 0.03717f, 0.03634f, 0.03554f, 0.03477f, 0.03402f, 0.03331f, 0.03264f,
    0.03202f, 0.03144f, 0.03093f, 0.03050f, 0.03019f, 0.03003f, 0.03009f, 0.03049f, 0.03144f, 0.03343f, 0.03820f,
    0.04762f, 0.04642f, 0.04530f, 0.04424f, 0.04325f, 0.04231f, 0.04142f, 0.04058f, 0.03979f, 0.03905f, 0.03835f,
    0.03768f, 0.03706f, 0.03647f, 0.03593f, 0.03542f, 0.03494f, 0.03451f, 0.03411f, 0.03376f, 0.03345f, 0.03319f,
    0.03299f, 0.03287f, 0.03283f, 0.03290f, 0.03312f, 0.03354f, 0.03426f, 0.03542f, 0.03733f, 0.04059f, 0.04755f,
};

inline float ggx_schlick_average(float cos_o, float roughness) {
    float x = clamp(cos_o, 0.0f, 1.0f) * 32.0f;
    float y = clamp(roughness, 0.0f, 1.0f) * 16.0f;
    int i = min((int)x, 31);
    int j = min((int)y, 15);
    int k = j * 33 + i;
    float a = mix(GGX_SCHLICK_AVERAGE[k], GGX_SCHLICK_AVERAGE[k + 1], x - (float)i);
    float b = mix(GGX_SCHLICK_AVERAGE[k + 33], GGX_SCHLICK_AVERAGE[k + 34], x - (float)i);
    return mix(a, b, y - (float)j);
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

// The material's lobes as seen from one wo.
typedef struct {
    float alpha;       // GGX alpha
    float eta;         // relative index of refraction
    float metallic;    // clamped inputs
    float transmission;
    float specular;    // specularFactor
    bool delta;        // glossy lobes are perfect mirror / refraction
    bool thin;         // transmission goes straight through (thin wall, or eta close to 1)
    float3 f0;         // dielectric normal-incidence reflectance before specularFactor
    float3 diffuse;    // Lambertian albedo left by the specular layer
    float p_diffuse;   // probability of sampling the diffuse lobe (else the glossy ones)
} BsdfLobes;

inline BsdfLobes bsdf_lobes(const SurfaceMaterial* m, float cos_o) {
    BsdfLobes l;
    float roughness = clamp(m->roughness, 0.0f, 1.0f);
    l.alpha = roughness * roughness;
    l.delta = l.alpha < BSDF_DELTA_ALPHA;
    l.eta = fmax(m->ior, 1e-3f);
    l.metallic = clamp(m->metallic, 0.0f, 1.0f);
    l.transmission = clamp(m->transmission, 0.0f, 1.0f);
    l.specular = clamp(m->specular_factor, 0.0f, 1.0f);
    l.thin = m->thickness <= 0.0f || fabs(l.eta - 1.0f) < 1e-3f;
    float r = (l.eta - 1.0f) / (l.eta + 1.0f);
    l.f0 = fmin(r * r * m->specular_color, 1.0f);
    // Expected Fresnel over the visible microfacets sets the diffuse lobe's share (spec: 1 -
    // specularFactor * max(F)), so the two together never exceed 1; inside a volume, the
    // smooth-interface value.
    float q = ggx_schlick_average(cos_o, roughness);
    float q_dielectric = l.thin || l.eta >= 1.0f ? q : dielectric_schlick(cos_o, l.eta);
    float3 spec_dielectric = l.specular * (l.f0 + (1.0f - l.f0) * q_dielectric);
    float3 spec_metal = m->base_color + (1.0f - m->base_color) * q;
    float layer = 1.0f - bsdf_max3(spec_dielectric);
    float dielectric = 1.0f - l.metallic;
    l.diffuse = (dielectric * (1.0f - l.transmission) * layer) * m->base_color;
    // Pick lobes by their estimated albedo (luminance).
    float d_est = luminance(l.diffuse);
    float r_est = luminance(dielectric * spec_dielectric + l.metallic * spec_metal);
    float t_est = dielectric * l.transmission * layer * luminance(m->base_color);
    float total = d_est + r_est + t_est;
    l.p_diffuse = total > 0.0f ? d_est / total : 0.0f;
    return l;
}

// Reflectance and transmittance of the glossy layer at a microfacet seen at cos_oh from wo.
inline void bsdf_gloss(const SurfaceMaterial* m, const BsdfLobes* l, float cos_oh, float3* refl,
                       float3* trans) {
    float sw = l->thin ? schlick_weight(cos_oh) : dielectric_schlick(cos_oh, l->eta);
    float3 fr = l->f0 + (1.0f - l->f0) * sw;
    float3 metal = m->base_color + (1.0f - m->base_color) * schlick_weight(cos_oh);
    float dielectric = 1.0f - l->metallic;
    *refl = (dielectric * l->specular) * fr + l->metallic * metal;
    bool tir = !l->thin && refracted_cos2(cos_oh, l->eta) <= 0.0f;
    *trans = tir ? (float3)(0.0f)
                 : (dielectric * l->transmission * (1.0f - l->specular * bsdf_max3(fr))) *
                       m->base_color;
}

// Probability of reflecting (rather than transmitting) at a sampled microfacet.
inline float reflect_probability(float3 refl, float3 trans) {
    float r = luminance(refl);
    float t = luminance(trans);
    return r + t > 0.0f ? r / (r + t) : 1.0f;
}

inline float3 bsdf_eval(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 wi_world,
                        float* pdf) {
    *pdf = 0.0f;
    float3 t, b;
    onb(n, &t, &b);
    float3 wo = (float3)(dot(wo_world, t), dot(wo_world, b), dot(wo_world, n));
    float3 wi = (float3)(dot(wi_world, t), dot(wi_world, b), dot(wi_world, n));
    if (wo.z <= 0.0f || wi.z == 0.0f || (wi.z < 0.0f && !(m->transmission > 0.0f))) {
        return (float3)(0.0f);
    }
    BsdfLobes l = bsdf_lobes(m, wo.z);
    float3 f = (float3)(0.0f);
    float p = 0.0f;
    if (wi.z > 0.0f) {
        f = l.diffuse * (wi.z * INV_PI_F);
        p = l.p_diffuse * (wi.z * INV_PI_F);
    }
    float p_gloss = 1.0f - l.p_diffuse;
    if (l.delta || !(p_gloss > 0.0f)) {
        *pdf = p;
        return f;
    }
    float a2 = l.alpha * l.alpha;
    float lambda_o = ggx_lambda(wo, a2);
    float g1 = 1.0f / (1.0f + lambda_o);
    float inv_cos_o = 1.0f / fmax(wo.z, 1e-20f);
    float3 refl, trans;
    if (wi.z > 0.0f || l.thin) {
        // Reflection, or thin-wall transmission: the reflection mirrored through the surface.
        float3 wr = (float3)(wi.x, wi.y, fabs(wi.z));
        float3 h = normalize(wo + wr);
        bsdf_gloss(m, &l, dot(wo, h), &refl, &trans);
        float d = ggx_d(h, a2);
        float g2 = 1.0f / (1.0f + lambda_o + ggx_lambda(wr, a2));
        float pr = reflect_probability(refl, trans);
        float3 c = wi.z > 0.0f ? refl : trans;
        f += c * (0.25f * d * g2 * inv_cos_o);
        p += p_gloss * (wi.z > 0.0f ? pr : 1.0f - pr) * (0.25f * g1 * d * inv_cos_o);
    } else {
        // Refraction through the generalized half vector h ~ wo + eta wi (Walter et al. 2007).
        float3 h = wo + l.eta * wi;
        float len = length(h);
        if (!(len > 0.0f)) {
            *pdf = p;
            return f;
        }
        h = (h.z < 0.0f ? -h : h) / len;
        float cos_oh = dot(wo, h);
        float cos_ih = dot(wi, h);
        if (cos_oh > 0.0f && cos_ih < 0.0f) {
            bsdf_gloss(m, &l, cos_oh, &refl, &trans);
            float d = ggx_d(h, a2);
            float g2 = 1.0f / (1.0f + lambda_o + ggx_lambda(wi, a2));
            // dwh/dwi; |wo.h + eta wi.h| = len.
            float jacobian = l.eta * l.eta * -cos_ih / (len * len);
            float vndf = g1 * d * cos_oh * inv_cos_o;
            f += trans * (vndf * jacobian * g2 / g1);
            p += p_gloss * (1.0f - reflect_probability(refl, trans)) * vndf * jacobian;
        }
    }
    *pdf = p;
    return f;
}

inline float3 bsdf_sample(const SurfaceMaterial* m, float3 n, float3 wo_world, float3 u,
                          float3* wi_world, float* pdf, bool* specular) {
    *pdf = 0.0f;
    *specular = false;
    *wi_world = n;
    float3 t, b;
    onb(n, &t, &b);
    float3 wo = (float3)(dot(wo_world, t), dot(wo_world, b), dot(wo_world, n));
    if (wo.z <= 0.0f) return (float3)(0.0f);
    BsdfLobes l = bsdf_lobes(m, wo.z);
    float3 wi;
    if (u.x < l.p_diffuse) {
        wi = sample_cosine(u.x / l.p_diffuse, u.y);
    } else {
        // A visible microfacet, then reflection or transmission by their share at it.
        float ug = fmin((u.x - l.p_diffuse) / (1.0f - l.p_diffuse), 0x1.fffffep-1f);
        float3 h = l.delta ? (float3)(0.0f, 0.0f, 1.0f) : ggx_sample_vndf(wo, l.alpha, ug, u.y);
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
            float chosen = (1.0f - l.p_diffuse) * (reflect ? pr : 1.0f - pr);
            if (!(chosen > 0.0f)) return (float3)(0.0f);
            *wi_world = normalize(wi.x * t + wi.y * b + wi.z * n);
            *pdf = chosen;
            *specular = true;
            return (reflect ? refl : trans) / chosen;
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
