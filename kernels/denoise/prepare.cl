// The denoiser's input and output as Open Image Denoise prepares them for HDR colour with
// albedo and normal (src/denoise/prepare.rs has the host twin and the reasons): the
// autoexposure's block luminances, the network's input tile (exposed colour through the PU
// curve, albedo clamped to [0, 1], normal mapped from [-1, 1] to [0, 1], zero outside the
// image) and the output tile back to linear radiance.
//
// The colour is read from a float image or straight from the renderer's film, and the guides
// from sums over a count; src/cl/kernels/denoise.rs (`ColorSource`) sets the arguments.

#include "shared/film.h"
#include "denoise/tensor.h"
#include "denoise/transfer.h"

// Where the colour comes from (`color_mode`): the image's .xyz, or the film's fixed-point sum
// (kernels/shared/film.h) over the pixel's own sample count, which is the film's .w, `taken`
// (every pixel took as many; the film's .w counts the hits), or the samples adaptive sampling's
// state records (kernels/shared/adaptive.h).
#define DN_COLOR_IMAGE 0
#define DN_COLOR_FILM 1
#define DN_COLOR_TAKEN 2
#define DN_COLOR_STATE 3

// Pixel `i`'s colour, the mean of its samples (0 where it has none).
inline float3 color_value(global const float4* image, global const ulong4* film,
                          global const uint* state, int mode, float taken, int i) {
    if (mode == DN_COLOR_IMAGE)
        return image[i].xyz;
    const float4 sum = film_float(film[i]);
    const float n = mode == DN_COLOR_FILM    ? sum.w
                    : mode == DN_COLOR_TAKEN ? taken
                                             : (float)(state[i] & PIXEL_SAMPLES);
    return sum.xyz / fmax(n, 1.0f);
}

// Pixel `i`'s guide: its sum over the sample count in `counts[i].w` (the albedo sums' .w;
// 1 for an image of means).
inline float3 guide_value(global const float4* sums, global const float4* counts, int i) {
    return sums[i].xyz / fmax(counts[i].w, 1.0f);
}

// NaN to zero, then clamped to [lo, hi].
inline float3 sanitize(float3 v, float lo, float hi) {
    return clamp(select(v, (float3)(0.0f), isnan(v)), lo, hi);
}

// The mean luminance of each of `bins_w` x `bins_h` blocks (at most 16 x 16 pixels) of the
// colour, after sanitising; global size: the blocks.
kernel void denoise_exposure_bins(global const float4* image, global const ulong4* film,
                                  global const uint* state, int color_mode, float taken,
                                  int width, int height, int bins_w, int bins_h,
                                  global float* bins) {
    const int i = get_global_id(0);
    if (i >= bins_w * bins_h)
        return;
    const int by = i / bins_w;
    const int bx = i % bins_w;
    const int y0 = (int)((long)by * height / bins_h);
    const int y1 = (int)((long)(by + 1) * height / bins_h);
    const int x0 = (int)((long)bx * width / bins_w);
    const int x1 = (int)((long)(bx + 1) * width / bins_w);
    float sum = 0.0f;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
            const float3 c = sanitize(
                color_value(image, film, state, color_mode, taken, y * width + x), 0.0f, FLT_MAX);
            sum += 0.212671f * c.x + 0.715160f * c.y + 0.072169f * c.z;
        }
    }
    bins[i] = sum / (float)((y1 - y0) * (x1 - x0));
}

// The network's 9-channel input tile (`tile_w` x `tile_h`, tile_w a multiple of DN_VEC): the
// image's pixels from (src_x, src_y) on, `w` x `h` of them, placed at (off_x, off_y) in the tile,
// zero elsewhere. A work item writes DN_VEC neighbouring pixels of a row: it gathers them
// pixel by pixel, then curves the colour as one vector; global size (tile_w / DN_VEC, tile_h).
kernel void denoise_input(global const float4* image, global const ulong4* film,
                          global const uint* state, int color_mode, float taken,
                          global const float4* albedo, global const float4* normal, int width,
                          int src_x, int src_y, int off_x, int off_y, int w, int h, int tile_w,
                          int tile_h, float exposure, float pu_norm, global float* dst) {
    const int x0 = get_global_id(0) * DN_VEC;
    const int y = get_global_id(1);
    if (x0 >= tile_w || y >= tile_h)
        return;
    const int iy = y - off_y;
    // The 9 channels' lanes: colour (exposed, not yet curved), albedo, normal.
    float lanes[9][DN_VEC];
    for (int l = 0; l < DN_VEC; ++l) {
        const int ix = x0 + l - off_x;
        float3 c = (float3)(0.0f), a = (float3)(0.0f), n = (float3)(0.0f);
        if (ix >= 0 && ix < w && iy >= 0 && iy < h) {
            const int i = (src_y + iy) * width + src_x + ix;
            c = sanitize(color_value(image, film, state, color_mode, taken, i) * exposure, 0.0f,
                         FLT_MAX);
            a = sanitize(guide_value(albedo, albedo, i), 0.0f, 1.0f);
            n = sanitize(guide_value(normal, albedo, i), -1.0f, 1.0f);
            n = n * 0.5f + 0.5f;
        }
        const float v[9] = {c.x, c.y, c.z, a.x, a.y, a.z, n.x, n.y, n.z};
        for (int k = 0; k < 9; ++k)
            lanes[k][l] = v[k];
    }
    const int plane = tensor_plane(tile_w, tile_h);
    global float* d = dst + tensor_at(tile_w, x0, y);
    for (int k = 0; k < 3; ++k)
        vstore_row(pu_forward(vload_row(lanes[k])) * pu_norm, d + k * plane);
    for (int k = 3; k < 9; ++k)
        vstore_row(vload_row(lanes[k]), d + k * plane);
}

// The image's `w` x `h` pixels from (dst_x, dst_y) on, from the network's output tile
// (`tile_w` x `tile_h`, channels 0-2) from (src_x, src_y) on: clamped to >= 0, through the
// inverse PU curve (`pu_max` = pu_forward(65504)) and divided by the exposure
// (`output_scale`); .w = 1. A work item takes DN_VEC neighbouring pixels of a row, curved as
// one vector; global size (w / DN_VEC rounded up, h).
kernel void denoise_output(global const float* src, int tile_w, int tile_h, int src_x,
                           int src_y, int dst_x, int dst_y, int w, int h, int width,
                           float pu_max, float output_scale, global float4* out) {
    const int x0 = get_global_id(0) * DN_VEC;
    const int y = get_global_id(1);
    if (x0 >= w || y >= h)
        return;
    const int plane = tensor_plane(tile_w, tile_h);
    global const float* s = src + tensor_at(tile_w, src_x + x0, src_y + y);
    float lanes[3][DN_VEC];
    for (int k = 0; k < 3; ++k) {
        // Lanes past the region read the border or the next row (the tensor has room) and are
        // not written.
        const vfloat v = vload_row(s + k * plane);
        const vfloat clean = fmax(select(v, (vfloat)(0.0f), isnan(v)), 0.0f);
        vstore_row(pu_inverse(fmin(clean, FLT_MAX) * pu_max) * output_scale, lanes[k]);
    }
    global float4* o = out + (dst_y + y) * width + dst_x + x0;
    for (int l = 0; l < DN_VEC && x0 + l < w; ++l)
        o[l] = (float4)(lanes[0][l], lanes[1][l], lanes[2][l], 1.0f);
}

// How `denoise_planes` maps a value: as it is, into the sRGB curve, or out of it.
#define DN_PLANES_LINEAR 0
#define DN_PLANES_TO_SRGB 1
#define DN_PLANES_FROM_SRGB 2

// Three planes of a `tile_w` x `tile_h` tensor, from `src`'s plane `src_first` on into `dst`'s
// plane `dst_first` on, each value capped at `hi` and mapped by `curve` (DN_PLANES_*), inside
// the window of the image (`w` x `h` from (x0, y0)) and zero outside it: a guide into its
// prefilter's input, and the prefilter's output back into the denoising network's input. OIDN
// filters the albedo in sRGB and clamps its output to [0, 1]; the normal linearly, mapping
// its output x to 2x - 1 clamped to [-1, 1], which the input maps back: min(x, 1), as the ReLU
// leaves x >= 0.
kernel void denoise_planes(global const float* src, int src_first, global float* dst,
                           int dst_first, int tile_w, int tile_h, int x0, int y0, int w, int h,
                           float hi, int curve) {
    const int x = get_global_id(0);
    const int y = get_global_id(1);
    if (x >= tile_w || y >= tile_h)
        return;
    const int plane = tensor_plane(tile_w, tile_h);
    const int at = tensor_at(tile_w, x, y);
    const bool inside = x >= x0 && x < x0 + w && y >= y0 && y < y0 + h;
    for (int k = 0; k < 3; ++k) {
        float v = fmin(src[(src_first + k) * plane + at], hi);
        if (curve == DN_PLANES_TO_SRGB)
            v = srgb_forward(v);
        else if (curve == DN_PLANES_FROM_SRGB)
            v = srgb_inverse(v);
        dst[(dst_first + k) * plane + at] = inside ? v : 0.0f;
    }
}
