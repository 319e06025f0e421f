// Adaptive sampling's film (docs/adaptive-sampling.md): with frame.adaptive set, beside the film
// (.xyz the sum of a pixel's samples, .w their count or its coverage count) each pixel keeps
//   half:  .xyz the sum of its even-numbered samples (sample index first_sample + j even),
//          .w their count: Cycles' half buffer, the second estimate the error is measured by;
//   state: its samples taken (PIXEL_SAMPLES bits), PIXEL_UNDER when its error was under the
//          threshold at the last check, PIXEL_CONVERGED when it and its eight neighbours were:
//          a converged pixel takes no samples until a check wakes it again;
//   rays:  the rays its samples traced (extension and light-sample rays): what its samples
//          cost, which the cost-weighted rule (ADAPTIVE_COST) weighs its error by; counted
//          under that rule only.
// Every kernel that adds samples to the film adds them here too, in the same order, and skips
// converged pixels; without frame.adaptive nothing here is read or written.
#ifndef SHARED_ADAPTIVE_H
#define SHARED_ADAPTIVE_H

#include "shared/types.h"
#include "shared/film.h"

// Whether the pixel takes no samples in this launch.
inline bool pixel_converged(const DeviceFrame* frame, global const uint* state, uint pixel) {
    return frame->adaptive != 0u && (state[pixel] & PIXEL_CONVERGED) != 0u;
}

// A finite sample of index `sample` into the even-numbered sum; every even sample counted (a
// dropped one as 0, as the film counts it).
inline void half_add(float3 r, uint sample, float3* even, uint* evens) {
    if ((sample & 1u) != 0u) return;
    ++*evens;
    if (all(isfinite(r))) *even += r;
}

// A pixel's `n` new samples, `evens` of them even-numbered with sum `even`, into its half
// buffer and sample count. (The rays they traced go to `rays` where they are counted: the
// megakernels add a pixel's with its samples, the wavefront's `shade` a vertex's at a time.)
inline void half_store(global float4* halves, global uint* state, uint pixel, float3 even,
                       uint evens, uint n) {
    float4 h = halves[pixel];
    halves[pixel] = (float4)(h.xyz + even, h.w + (float)evens);
    state[pixel] += n;
}

// The pixel's relative error (Cycles' formula): |I − A| summed over the channels over
// √(I summed), I the mean of all its samples and A the mean of the even-numbered ones.
inline float pixel_error(float4 film, float4 h, uint state) {
    float n = (float)(state & PIXEL_SAMPLES);
    if (n == 0.0f || h.w == 0.0f) return INFINITY;
    float3 i = film.xyz / n;
    float3 a = h.xyz / h.w;
    float3 d = fabs(i - a);
    // The epsilon keeps a black pixel's error finite (0 when both halves are black).
    return (d.x + d.y + d.z) / (0.0001f + sqrt(fmax(i.x + i.y + i.z, 0.0f)));
}

// The error a pixel may keep. ADAPTIVE_ERROR (Cycles' rule): `threshold`. ADAPTIVE_COST:
// `threshold` · √(rays / min_samples), the rays its samples traced: the threshold at the
// minimum for samples of one ray each, growing as the square root of the samples taken and of
// their mean cost, so that a pixel stops near n ∝ √(variance / cost), the split of samples
// that gives the least squared error for the time (docs/adaptive-sampling.md).
inline float pixel_threshold(const DeviceFrame* frame, float threshold, uint traced,
                             float min_samples) {
    if (frame->adaptive != ADAPTIVE_COST) return threshold;
    return threshold * sqrt((float)traced / min_samples);
}

// The convergence check, first pass: PIXEL_UNDER set where the pixel's error is under its
// threshold (`pixel_threshold`). Pixel 0 zeroes COUNT_ACTIVE for `converge_dilate`.
kernel void converge(DeviceFrame frame, global const ulong4* film, global const float4* halves,
                     global uint* state, global const uint* rays, float threshold,
                     float min_samples, volatile global uint* counters) {
    uint pixel = get_global_id(0);
    if (pixel == 0u) counters[COUNT_ACTIVE] = 0u;
    if (pixel >= frame.width * frame.height) return;
    uint s = state[pixel];
    float limit = pixel_threshold(&frame, threshold, rays[pixel], min_samples);
    bool under = pixel_error(film_float(film[pixel]), halves[pixel], s) < limit;
    state[pixel] = under ? s | PIXEL_UNDER : s & ~PIXEL_UNDER;
}

// The second pass: PIXEL_CONVERGED where the pixel and its eight neighbours are under the
// threshold (neighbours of noisy pixels stay awake, so that a noisy region's edge is not cut
// off by one unlucky estimate); the pixels left active are counted in COUNT_ACTIVE. It reads
// only PIXEL_UNDER, which this pass does not write.
kernel void converge_dilate(DeviceFrame frame, global uint* state,
                            volatile global uint* counters) {
    uint pixel = get_global_id(0);
    if (pixel >= frame.width * frame.height) return;
    int x = (int)(pixel % frame.width), y = (int)(pixel / frame.width);
    bool converged = true;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= (int)frame.width || ny >= (int)frame.height) continue;
            converged &= (state[ny * (int)frame.width + nx] & PIXEL_UNDER) != 0u;
        }
    }
    uint s = state[pixel];
    state[pixel] = converged ? s | PIXEL_CONVERGED : s & ~PIXEL_CONVERGED;
    if (!converged) atomic_inc(&counters[COUNT_ACTIVE]);
}

#endif  // SHARED_ADAPTIVE_H
