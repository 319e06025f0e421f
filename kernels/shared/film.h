// The film: per pixel .xyz the sum of its samples' radiance and .w their count (or, with the
// background counted or cut out, the count of samples whose camera ray hit), every lane a 64-bit
// integer; the radiance in fixed point, 2^FILM_FRACTION_BITS to one unit (src/render/film.rs).
// Integer addition is associative, so a pixel's sum is the same however its samples were split
// among launches, shards (`render --sample-start`, `penumbra merge`) or devices: a float sum
// depends on its order. A sample is rounded to the nearest step of 2^-FILM_FRACTION_BITS (a
// float's step just under 1) and the sum saturates at 2^(64 − FILM_FRACTION_BITS); saturating
// addition of non-negative numbers is associative too.
#ifndef SHARED_FILM_H
#define SHARED_FILM_H

#include "shared/types.h"

#define FILM_ONE ((float)(1u << FILM_FRACTION_BITS))

// A finite sample in the film's fixed point (a negative channel, which no kernel makes, is 0).
inline ulong3 film_fixed(float3 radiance) {
    return convert_ulong3_sat_rte(radiance * FILM_ONE);
}

// `radiance` added to the pixel's sum.
inline void film_add(ulong3* sum, float3 radiance) {
    *sum = add_sat(*sum, film_fixed(radiance));
}

// The pixel's sum in radiance units, and its count.
inline float4 film_float(ulong4 p) {
    return (float4)(convert_float3(p.xyz) / FILM_ONE, (float)p.w);
}

#endif  // SHARED_FILM_H
