// The Lambertian BSDF of LAMBERT_ONLY scenes, written once for every lane width
// (DEFINE_LAMBERT_MATHS, shared/vec3.h's convention): bsdf.h's bsdf_eval and bsdf_sample for
// one path, and cpu/shade_lanes.h's batched shading for the lanes.
#ifndef SHARED_LAMBERT_H
#define SHARED_LAMBERT_H

#include "shared/vec3.h"
#include "shared/rng.h"
#include "shared/material.h"

#ifdef LAMBERT_ONLY
// Every material of the scene is an opaque dielectric with no specular layer (specularFactor 0,
// metallic 0, no transmission, coat or sheen): bsdf.h's BSDF reduces exactly to the Lambertian
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
#endif  // LAMBERT_ONLY

#endif  // SHARED_LAMBERT_H
