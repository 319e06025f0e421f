// The U-Net's 3x3 convolution (+ bias + ReLU), with the 2x2 max pool that follows it fused in
// (`conv3x3_pool`) and the decoder's nearest 2x upsampling and skip concatenation fused into
// its reads (`conv3x3_up`: `src0` at half resolution). Tensors are planar CHW with a one-pixel
// zero border around every channel (kernels/denoise/tensor.h), so no read needs a bounds test.
//
// A work item computes DN_OCB output channels of a block of DN_VEC columns (one `vfloat`, see
// tensor.h) by DN_ROWS rows (2 where it pools). Per input channel it loads the block's rows
// and the rows above and below, each as three vectors shifted by one column, and every vector
// loaded feeds up to 3 x DN_OCB vector multiply-adds of the private accumulators, while the
// DN_OCB weights of one (input channel, tap) are the same for the whole work-group. On a CPU
// (DN_VEC 16) a vector is the lanes of an AVX-512 register: PoCL does not vectorise work items
// whose body loops over channels, so the kernel does it. On a GPU (DN_VEC 2) neighbouring work
// items load neighbouring columns (coalesced).

#include "denoise/tensor.h"

// Rows of a work item's block where it does not pool.
#define DN_ROWS 4

// Accumulates the 3x3 convolution of `c` channels of `src` (planes of `w` x `h`; read at half
// the coordinates when `up`) for the block of `rows` rows whose top left pixel is (x0, y0) in
// the convolution's resolution. `wt` points to the channels' weights: per input channel, 9
// taps of DN_OCB values. Returns the weights after them.
inline global const float* conv_channels(global const float* src, int c, const int up, int w,
                                         int h, global const float* wt, int x0, int y0,
                                         const int rows, vfloat acc[DN_OCB][DN_ROWS]) {
    const int pitch = w + 2;
    const int plane = tensor_plane(w, h);
    for (int ic = 0; ic < c; ++ic) {
        global const float* s = src + (size_t)ic * plane;
#pragma unroll
        for (int r = 0; r < DN_ROWS + 2; ++r) {
            if (r >= rows + 2)
                break;
            // Input row y0 - 1 + r as three vectors: columns from x0 - 1, x0 and x0 + 1.
            vfloat v[3];
            if (up) {
                const int yy = (y0 - 1 + r) >> 1;
                upsampled_row(s + tensor_at(w, x0 >> 1, yy), v);
            } else {
                global const float* row = s + (y0 + r) * pitch + x0;
                v[0] = vload_row(row);
                v[1] = vload_row(row + 1);
                v[2] = vload_row(row + 2);
            }
            // Row r is tap ky of output row r - ky.
#pragma unroll
            for (int ky = 0; ky < 3; ++ky) {
                const int p = r - ky;
                if (p < 0 || p >= rows)
                    continue;
#pragma unroll
                for (int kx = 0; kx < 3; ++kx)
#pragma unroll
                    for (int o = 0; o < DN_OCB; ++o)
                        acc[o][p] = fma(v[kx], (vfloat)(wt[(ky * 3 + kx) * DN_OCB + o]), acc[o][p]);
            }
        }
        wt += 9 * DN_OCB;
    }
    return wt;
}

// The block's accumulators: the bias, then both sources' channels (src0's first, as the
// weights' input channels are ordered: the upsampled decoder features, then the skip).
inline void conv_block(global const float* src0, int c0, const int up0, global const float* src1,
                       int c1, global const float* weights, global const float* bias, int ocb,
                       int width, int height, int x0, int y0, const int rows,
                       vfloat acc[DN_OCB][DN_ROWS]) {
#pragma unroll
    for (int o = 0; o < DN_OCB; ++o)
#pragma unroll
        for (int p = 0; p < DN_ROWS; ++p)
            acc[o][p] = (vfloat)(bias[ocb + o]);
    global const float* wt = weights + (size_t)ocb * (c0 + c1) * 9;
    const int w0 = up0 ? width / 2 : width;
    const int h0 = up0 ? height / 2 : height;
    wt = conv_channels(src0, c0, up0, w0, h0, wt, x0, y0, rows, acc);
    conv_channels(src1, c1, 0, width, height, wt, x0, y0, rows, acc);
}

// The unpooled convolutions' body, written after the ReLU. `up0` is a constant in each kernel
// below, so that each compiles to its own loads.
inline void conv_rows(global const float* src0, int c0, const int up0, global const float* src1,
                      int c1, global const float* weights, global const float* bias,
                      global float* dst, int width, int height) {
    const int x0 = get_global_id(0) * DN_VEC;
    const int y0 = get_global_id(1) * DN_ROWS;
    const int ocb = get_global_id(2) * DN_OCB;
    if (x0 >= width || y0 >= height)
        return;
    vfloat acc[DN_OCB][DN_ROWS];
    conv_block(src0, c0, up0, src1, c1, weights, bias, ocb, width, height, x0, y0, DN_ROWS, acc);
    const int plane = tensor_plane(width, height);
#pragma unroll
    for (int o = 0; o < DN_OCB; ++o) {
        global float* d = dst + (size_t)(ocb + o) * plane;
#pragma unroll
        for (int p = 0; p < DN_ROWS; ++p)
            if (y0 + p < height)
                store_row(fmax(acc[o][p], 0.0f), d + tensor_at(width, x0, y0 + p), width - x0);
    }
}

// dst = relu(conv3x3(concat(src0, src1)) + bias) at `width` x `height`; global size
// (columns / DN_VEC, rows / DN_ROWS, output channels / DN_OCB).
kernel void conv3x3(global const float* src0, int c0, global const float* src1, int c1,
                    global const float* weights, global const float* bias, global float* dst,
                    int width, int height) {
    conv_rows(src0, c0, 0, src1, c1, weights, bias, dst, width, height);
}

// The same with src0 at half the resolution, upsampled (nearest): the decoder's first
// convolution of each level.
kernel void conv3x3_up(global const float* src0, int c0, global const float* src1, int c1,
                       global const float* weights, global const float* bias, global float* dst,
                       int width, int height) {
    conv_rows(src0, c0, 1, src1, c1, weights, bias, dst, width, height);
}

// dst = maxpool2x2(relu(conv3x3(src) + bias)), `width` x `height` being the convolution's
// resolution (even); global size (width / DN_VEC, height / 2, output channels / DN_OCB).
kernel void conv3x3_pool(global const float* src0, int c0, global const float* src1, int c1,
                         global const float* weights, global const float* bias,
                         global float* dst, int width, int height) {
    const int x0 = get_global_id(0) * DN_VEC;
    const int y0 = get_global_id(1) * 2;
    const int ocb = get_global_id(2) * DN_OCB;
    if (x0 >= width || y0 >= height)
        return;
    vfloat acc[DN_OCB][DN_ROWS];
    conv_block(src0, c0, 0, src1, c1, weights, bias, ocb, width, height, x0, y0, 2, acc);
    const int plane = tensor_plane(width / 2, height / 2);
#pragma unroll
    for (int o = 0; o < DN_OCB; ++o) {
        const vfloat m = fmax(fmax(acc[o][0], acc[o][1]), 0.0f);
        store_half_row(pool_pairs(m), dst + (size_t)(ocb + o) * plane +
                                          tensor_at(width / 2, x0 / 2, y0 / 2),
                       (width - x0) / 2);
    }
}
