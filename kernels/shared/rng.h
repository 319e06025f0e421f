// Random numbers (PCG-style hash chain) and sampling warps.
#ifndef SHARED_RNG_H
#define SHARED_RNG_H

#define PI_F 3.14159265358979f
#define INV_PI_F 0.318309886183791f

inline uint hash_u32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// Advances the state and returns a float in [0, 1).
inline float rng_next(uint* state) {
    *state = *state * 747796405u + 2891336453u;
    uint word = ((*state >> ((*state >> 28u) + 4u)) ^ *state) * 277803737u;
    word = (word >> 22u) ^ word;
    return (float)(word >> 8) * (1.0f / 16777216.0f);
}

// An orthonormal basis around unit n (Duff et al. 2017).
inline void onb(float3 n, float3* t, float3* b) {
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z);
    float c = n.x * n.y * a;
    *t = (float3)(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = (float3)(c, s + n.y * n.y * a, -n.y);
}

inline float3 to_world(float3 v_local, float3 n) {
    float3 t, b;
    onb(n, &t, &b);
    return v_local.x * t + v_local.y * b + v_local.z * n;
}

// The point of the unit circle at angle 2 pi u, u in [0, 1): (cos, sin), within a few ulps.
// u is taken to the nearest quarter turn exactly (u - q / 4 is exact: Sterbenz), the rest, at
// most an eighth of a turn, goes through Taylor polynomials (truncation below 2e-9), and the
// point is turned back by q quarters. On PoCL, cospi and sinpi (each reducing its own
// argument) took twice as long.
inline float2 unit_circle(float u) {
    float q = rint(4.0f * u);
    float x = (u - 0.25f * q) * (2.0f * PI_F);  // [-pi / 4, pi / 4]
    float x2 = x * x;
    float s = x + x * x2 * (-1.0f / 6.0f +
                            x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f))));
    float c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f +
                                                         x2 * (1.0f / 40320.0f))));
    uint k = (uint)q & 3u;
    float2 p = (k & 1u) ? (float2)(-s, c) : (float2)(c, s);
    return (k & 2u) ? -p : p;
}

// Cosine-weighted hemisphere around +z; pdf = cos / pi.
inline float3 sample_cosine(float u1, float u2) {
    float r = sqrt(u1);
    float2 c = unit_circle(u2);
    return (float3)(r * c.x, r * c.y, sqrt(fmax(0.0f, 1.0f - u1)));
}

// Uniform direction in a cone around +z given 1 - cos(half-angle) (passed as such so that tiny
// cones keep their precision); pdf = 1 / (2 pi one_minus_cos).
inline float3 sample_cone(float u1, float u2, float one_minus_cos) {
    float x = u1 * one_minus_cos;  // 1 - cos(theta)
    float c = 1.0f - x;
    float s = sqrt(fmax(0.0f, x * (2.0f - x)));
    float2 circle = unit_circle(u2);
    return (float3)(s * circle.x, s * circle.y, c);
}

// Uniform point on a triangle as barycentric weights of vertices 1 and 2.
inline float2 sample_triangle(float u1, float u2) {
    float su = sqrt(u1);
    return (float2)(su * (1.0f - u2), su * u2);
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
