// The layered material as seen from one wo (BsdfLobes, made by bsdf_lobes): its glossy lobes'
// GGX, and what each layer over the diffuse base reflects (the specular layer's albedo, the
// anisotropic energy tables, the sheen, the clear coat and its lobe), from which bsdf.h scales
// the diffuse base and the glossy lobes (the layering of bsdf.h's header).
#ifndef SHARED_BSDF_LAYERS_H
#define SHARED_BSDF_LAYERS_H

#include "shared/types.h"
#include "shared/bsdf_tables.h"
#include "shared/material.h"
#include "shared/microfacet.h"
#include "shared/thin_film.h"

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

// What one crossing of the dielectric's boundary lets through, per channel: a thin wall's base
// color, a volume boundary's square root of it. Light passing through a volume crosses its
// boundary twice, in and out, and so is tinted by base color once, as the Sample Viewer tints it
// and as Cycles' Principled BSDF does (its transmission tint is sqrt(base color)); the volume
// spec's "coloured foil" gives a whole object one colour whatever its thickness
// (docs/materials.md, "Glass, thin walls and volumes").
inline float3 transmission_tint(const SurfaceMaterial* m, const BsdfLobes* l) {
    return l->thin ? m->base_color : sqrt(fmax(m->base_color, 0.0f));
}

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
                  luminance(transmission_tint(m, &l));
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

#endif  // SHARED_BSDF_LAYERS_H
