// Random numbers (PCG-style hash chain) and sampling warps; what the CPU lanes use of them is
// written once for both widths (DEFINE_SAMPLING_MATHS).
#ifndef SHARED_RNG_H
#define SHARED_RNG_H

#define PI_F 3.14159265358979f
#define INV_PI_F 0.318309886183791f

#include "shared/vec3.h"

inline uint hash_u32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Sampling's arithmetic for every lane width (shared/vec3.h): f##rng_advance(s) the random
// state after s, f##rng_value(s) the float in [0, 1) that state s gives; f##onb(n, *t, *b) an
// orthonormal basis around unit n (Duff et al. 2017); f##unit_circle(u, *c, *s) the point of
// the unit circle at angle 2 pi u, u in [0, 1), within a few ulps: u is taken to the nearest
// quarter turn exactly (u - q / 4 is exact: Sterbenz), the rest, at most an eighth of a turn,
// goes through Taylor polynomials (truncation below 2e-9), and the point is turned back by q
// quarters (on PoCL, cospi and sinpi, each reducing its own argument, took twice as long);
// f##sample_cosine(u1, u2) a cosine-weighted direction around +z (pdf = cos / pi);
// f##sample_triangle(u1, u2, *b1, *b2) a uniform point on a triangle as the barycentric
// weights of its vertices 1 and 2. This file is compiled with contraction on: the products the
// compiler fuses in the scalar form are written fma().
#define DEFINE_SAMPLING_MATHS(Q, f, F, I, U, V, v)                                                \
    Q U f##rng_advance(U state) { return state * 747796405u + 2891336453u; }                       \
    Q F f##rng_value(U state) {                                                                    \
        U word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;                         \
        word = (word >> 22u) ^ word;                                                               \
        return convert_##F(word >> 8u) * (1.0f / 16777216.0f);                                     \
    }                                                                                              \
    Q void f##onb(V n, V* t, V* b) {                                                               \
        F sign = select((F)(-1.0f), (F)(1.0f), n.z >= 0.0f);                                       \
        F a = -1.0f / (sign + n.z);                                                                \
        F c = n.x * n.y * a;                                                                       \
        *t = v##_make(fma(sign * n.x * n.x, a, (F)(1.0f)), sign * c, -sign * n.x);                 \
        *b = v##_make(c, fma(n.y * n.y, a, sign), -n.y);                                           \
    }                                                                                              \
    Q void f##unit_circle(F u, F* cos_u, F* sin_u) {                                               \
        F q = rint(4.0f * u);                                                                      \
        F x = fma(q, (F)(-0.25f), u) * (2.0f * PI_F); /* [-pi / 4, pi / 4] */                      \
        F x2 = x * x;                                                                              \
        F s = fma(x * x2,                                                                          \
                  fma(x2, fma(x2, fma(x2, (F)(1.0f / 362880.0f), (F)(-1.0f / 5040.0f)),            \
                              (F)(1.0f / 120.0f)),                                                 \
                      (F)(-1.0f / 6.0f)),                                                          \
                  x);                                                                              \
        F c = fma(x2,                                                                              \
                  fma(x2, fma(x2, fma(x2, (F)(1.0f / 40320.0f), (F)(-1.0f / 720.0f)),              \
                              (F)(1.0f / 24.0f)),                                                  \
                      (F)(-0.5f)),                                                                 \
                  (F)(1.0f));                                                                      \
        U k = convert_##U(q) & 3u;                                                                 \
        I odd = (k & 1u) != 0u, back = (k & 2u) != 0u;                                             \
        F px = select(c, -s, odd), py = select(s, c, odd);                                         \
        *cos_u = select(px, -px, back);                                                            \
        *sin_u = select(py, -py, back);                                                            \
    }                                                                                              \
    Q V f##sample_cosine(F u1, F u2) {                                                             \
        F r = sqrt(u1);                                                                            \
        F cx, cy;                                                                                  \
        f##unit_circle(u2, &cx, &cy);                                                              \
        return v##_make(r * cx, r * cy, sqrt(fmax((F)(0.0f), 1.0f - u1)));                         \
    }                                                                                              \
    Q void f##sample_triangle(F u1, F u2, F* b1, F* b2) {                                          \
        F su = sqrt(u1);                                                                           \
        *b1 = su * (1.0f - u2);                                                                    \
        *b2 = su * u2;                                                                             \
    }

DEFINE_SAMPLING_MATHS(inline, , float, int, uint, float3, f3)

// Advances the state and returns a float in [0, 1).
inline float rng_next(uint* state) {
    *state = rng_advance(*state);
    return rng_value(*state);
}

inline float3 to_world(float3 v_local, float3 n) {
    float3 t, b;
    onb(n, &t, &b);
    return v_local.x * t + v_local.y * b + v_local.z * n;
}

// Uniform direction in a cone around +z given 1 - cos(half-angle) (passed as such so that tiny
// cones keep their precision); pdf = 1 / (2 pi one_minus_cos).
inline float3 sample_cone(float u1, float u2, float one_minus_cos) {
    float x = u1 * one_minus_cos;  // 1 - cos(theta)
    float c = 1.0f - x;
    float s = sqrt(fmax(0.0f, x * (2.0f - x)));
    float cx, cy;
    unit_circle(u2, &cx, &cy);
    return (float3)(s * cx, s * cy, c);
}

inline float luminance(float3 c) {
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}

// First index i in [0, n) with u < cdf[i]: samples a discrete distribution from its
// cumulative table (light selection, environment map rows and columns).
inline uint cdf_search(global const float* cdf, uint n, float u) {
    uint lo = 0, hi = n - 1;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        if (u < cdf[mid]) hi = mid; else lo = mid + 1;
    }
    return lo;
}

#endif  // SHARED_RNG_H
