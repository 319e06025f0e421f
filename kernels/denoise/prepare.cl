// The denoiser's input and output as Open Image Denoise prepares them for HDR colour with
// albedo and normal (src/denoise/prepare.rs has the host twin and the reasons): the
// autoexposure's block luminances, the network's input tile (exposed colour through the PU
// curve, albedo clamped to [0, 1], normal mapped from [-1, 1] to [0, 1], zero outside the
// image) and the output tile back to linear radiance.

#include "denoise/tensor.h"
#include "denoise/transfer.h"

// Pixel `i` of a film: `scale` times its value, or its value over its sample count (.w) with
// `by_count` (0 where it has no sample).
inline float3 film_value(global const float4* film, int i, float scale, int by_count) {
    const float4 v = film[i];
    if (by_count)
        return v.w > 0.0f ? v.xyz / v.w : (float3)(0.0f);
    return v.xyz * scale;
}

// NaN to zero, then clamped to [lo, hi].
inline float3 sanitize(float3 v, float lo, float hi) {
    return clamp(select(v, (float3)(0.0f), isnan(v)), lo, hi);
}

// The mean luminance of each of `bins_w` x `bins_h` blocks (at most 16 x 16 pixels) of the
// colour, after sanitising; global size: the blocks.
kernel void denoise_exposure_bins(global const float4* color, float scale, int by_count,
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
            const float3 c = sanitize(film_value(color, y * width + x, scale, by_count), 0.0f,
                                      FLT_MAX);
            sum += 0.212671f * c.x + 0.715160f * c.y + 0.072169f * c.z;
        }
    }
    bins[i] = sum / (float)((y1 - y0) * (x1 - x0));
}

// The network's 9-channel input tile (`tile_w` x `tile_h`): the image's pixels from
// (src_x, src_y) on, `w` x `h` of them, placed at (off_x, off_y) in the tile, zero elsewhere.
kernel void denoise_input(global const float4* color, float color_scale, int color_by_count,
                          global const float4* albedo, float albedo_scale, int albedo_by_count,
                          global const float4* normal, float normal_scale, int normal_by_count,
                          int width, int src_x, int src_y, int off_x, int off_y, int w, int h,
                          int tile_w, int tile_h, float exposure, float pu_norm,
                          global float* dst) {
    const int x = get_global_id(0);
    const int y = get_global_id(1);
    if (x >= tile_w || y >= tile_h)
        return;
    const int ix = x - off_x;
    const int iy = y - off_y;
    float3 c = (float3)(0.0f), a = (float3)(0.0f), n = (float3)(0.0f);
    if (ix >= 0 && ix < w && iy >= 0 && iy < h) {
        const int i = (src_y + iy) * width + src_x + ix;
        c = sanitize(film_value(color, i, color_scale, color_by_count) * exposure, 0.0f,
                     FLT_MAX);
        c = (float3)(pu_forward(c.x), pu_forward(c.y), pu_forward(c.z)) * pu_norm;
        a = sanitize(film_value(albedo, i, albedo_scale, albedo_by_count), 0.0f, 1.0f);
        n = sanitize(film_value(normal, i, normal_scale, normal_by_count), -1.0f, 1.0f);
        n = n * 0.5f + 0.5f;
    }
    const int plane = tensor_plane(tile_w, tile_h);
    const int at = tensor_at(tile_w, x, y);
    const float v[9] = {c.x, c.y, c.z, a.x, a.y, a.z, n.x, n.y, n.z};
    for (int k = 0; k < 9; ++k)
        dst[k * plane + at] = v[k];
}

// The image's `w` x `h` pixels from (dst_x, dst_y) on, from the network's output tile
// (`tile_w` x `tile_h`, channels 0-2) from (src_x, src_y) on: clamped to >= 0, through the
// inverse PU curve (`pu_max` = pu_forward(65504)) and divided by the exposure
// (`output_scale`); .w = 1.
kernel void denoise_output(global const float* src, int tile_w, int tile_h, int src_x,
                           int src_y, int dst_x, int dst_y, int w, int h, int width,
                           float pu_max, float output_scale, global float4* out) {
    const int x = get_global_id(0);
    const int y = get_global_id(1);
    if (x >= w || y >= h)
        return;
    const int plane = tensor_plane(tile_w, tile_h);
    const int at = tensor_at(tile_w, src_x + x, src_y + y);
    float3 v = sanitize((float3)(src[at], src[plane + at], src[2 * plane + at]), 0.0f, FLT_MAX);
    v = (float3)(pu_inverse(v.x * pu_max), pu_inverse(v.y * pu_max), pu_inverse(v.z * pu_max));
    out[(dst_y + y) * width + dst_x + x] = (float4)(v * output_scale, 1.0f);
}
