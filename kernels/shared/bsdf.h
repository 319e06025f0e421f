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
//   transmission  the dielectric's transmitted share, tinted by base color (a volume's boundary
//                 by its square root at each crossing: once a traversal): rough refraction
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
//
// Its parts: material.h (the material as shading sees it, volumes, dispersion), microfacet.h
// (GGX, Fresnel and the energy tables' lookups), thin_film.h (iridescence), bsdf_layers.h (the
// lobes seen from wo and the layers' albedos), lambert.h (LAMBERT_ONLY's Lambertian BSDF, for
// every lane width); here, the glossy layer's Fresnel, the base lobes, bsdf_eval and bsdf_sample.
#ifndef SHARED_BSDF_H
#define SHARED_BSDF_H

#include "shared/types.h"
#include "shared/vec3.h"
#include "shared/rng.h"
#include "shared/bsdf_tables.h"
#include "shared/material.h"
#include "shared/microfacet.h"
#include "shared/thin_film.h"
#include "shared/bsdf_layers.h"

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
                       transmission_tint(m, l);
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

// Included next to the LAMBERT_ONLY form that uses it, after the general BSDF's parts.
#include "shared/lambert.h"

#ifdef LAMBERT_ONLY
// Every material of the scene is an opaque dielectric with no specular layer: the BSDF above
// reduces exactly to lambert.h's Lambertian base_color / pi, sampled by its cosine.

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