// The environment map: an equirectangular radiance image around the scene, importance-sampled
// by a 2D table over luminance x sin(theta) (src/scene/environment.rs builds it and states the
// direction convention). Radiance is looked up at the nearest texel, so the sampling pdf,
// constant per texel in (u, v), is exactly f(texel) * norm / sin(theta) per solid angle.
#ifndef SHARED_ENV_H
#define SHARED_ENV_H

#include "shared/types.h"
#include "shared/rng.h"

typedef struct {
    DeviceEnvironment info;
    global const float* texels;       // RGB triples, row 0 at the top
    global const float* marginal;     // cumulative row probabilities
    global const float* conditional;  // cumulative column probabilities per row
} EnvMap;

#ifdef HAS_ENV_MAP

// The map coordinates (u, v in [0, 1]) of world direction d (unit), and its cos(theta).
inline float3 env_uv(const EnvMap* e, float3 d) {
    float c = e->info.rotation.x;
    float s = e->info.rotation.y;
    // Into the map's frame: undo the rotation about +Y.
    float3 m = (float3)(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    float u = atan2(m.x, -m.z) * (0.5f * INV_PI_F) + 0.5f;
    float cos_theta = clamp(m.y, -1.0f, 1.0f);
    float v = acos(cos_theta) * INV_PI_F;
    return (float3)(u, v, cos_theta);
}

// Radiance arriving from world direction d (unit), and the solid-angle pdf of sampling it.
inline float3 env_radiance(const EnvMap* e, float3 d, float* pdf) {
    float3 uv = env_uv(e, d);
    float u = uv.x;
    float v = uv.y;
    float cos_theta = uv.z;
    uint w = e->info.width;
    uint h = e->info.height;
    uint x = min((uint)(fmax(u, 0.0f) * (float)w), w - 1u);
    uint y = min((uint)(fmax(v, 0.0f) * (float)h), h - 1u);
    uint i = 3u * (y * w + x);
    float3 radiance = (float3)(e->texels[i], e->texels[i + 1u], e->texels[i + 2u]);
    float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
    float sin_centre = sinpi(((float)y + 0.5f) / (float)h);
    *pdf = sin_theta > 0.0f
               ? luminance(radiance) * sin_centre * e->info.scale.y / sin_theta
               : 0.0f;
    return radiance * e->info.scale.x;
}

inline float3 env_texel(const EnvMap* e, uint x, uint y) {
    uint i = 3u * (y * e->info.width + x);
    return (float3)(e->texels[i], e->texels[i + 1u], e->texels[i + 2u]);
}

// The map seen directly (by a camera ray): bilinearly filtered, so that a small map does not
// show its texels as blocks. Lighting reads it unfiltered (env_radiance), as it samples it.
inline float3 env_background(const EnvMap* e, float3 d) {
    float3 uv = env_uv(e, d);
    int w = (int)e->info.width;
    int h = (int)e->info.height;
    float fx = uv.x * (float)w - 0.5f;
    float fy = uv.y * (float)h - 0.5f;
    float x0f = floor(fx);
    float y0f = floor(fy);
    float tx = fx - x0f;
    float ty = fy - y0f;
    int x0 = (((int)x0f % w) + w) % w;
    uint xa = (uint)x0;
    uint xb = (uint)((x0 + 1) % w);
    uint ya = (uint)clamp((int)y0f, 0, h - 1);
    uint yb = (uint)clamp((int)y0f + 1, 0, h - 1);
    float3 top = mix(env_texel(e, xa, ya), env_texel(e, xb, ya), tx);
    float3 bottom = mix(env_texel(e, xa, yb), env_texel(e, xb, yb), tx);
    return mix(top, bottom, ty) * e->info.scale.x;
}

// Samples a world direction in proportion to luminance x sin(theta); returns it with its
// radiance and solid-angle pdf.
inline float3 env_sample(const EnvMap* e, float u1, float u2, float3* radiance, float* pdf) {
    uint w = e->info.width;
    uint h = e->info.height;
    uint y = cdf_search(e->marginal, h, u1);
    float lo = y > 0u ? e->marginal[y - 1u] : 0.0f;
    float fy = clamp((u1 - lo) / fmax(e->marginal[y] - lo, 1e-12f), 0.0f, 0.99999994f);
    global const float* row = e->conditional + y * w;
    uint x = cdf_search(row, w, u2);
    lo = x > 0u ? row[x - 1u] : 0.0f;
    float fx = clamp((u2 - lo) / fmax(row[x] - lo, 1e-12f), 0.0f, 0.99999994f);
    float u = ((float)x + fx) / (float)w;
    float v = ((float)y + fy) / (float)h;
    float phi = 2.0f * PI_F * (u - 0.5f);
    float sin_theta = sinpi(v);
    float3 m = (float3)(sin_theta * sin(phi), cospi(v), -sin_theta * cos(phi));
    float c = e->info.rotation.x;
    float s = e->info.rotation.y;
    float3 d = (float3)(c * m.x + s * m.z, m.y, -s * m.x + c * m.z);
    *radiance = env_radiance(e, d, pdf);
    return d;
}

#endif

#endif  // SHARED_ENV_H
