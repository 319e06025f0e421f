// The U-Net's 3x3 convolution (+ bias + ReLU), with the 2x2 max pool that follows it fused in
// (`conv3x3_pool`) and the decoder's nearest 2x upsampling and skip concatenation fused into
// its reads (`src0` at half resolution). Tensors are planar CHW with a one-pixel zero border
// around every channel (kernels/denoise/tensor.h), so no read needs a bounds test.
//
// A work item computes DN_OCB output channels of DN_PIX pixels: four rows of one column
// (`conv3x3`) or the 2x2 block its pool reduces (`conv3x3_pool`). Neighbouring work items take
// neighbouring columns, so their loads of one input row are contiguous (one vector load on a
// CPU whose compiler vectorises work items across lanes, a coalesced load on a GPU), while the
// DN_OCB weights of one (input channel, tap) are the same for the whole group (a broadcast).
// Each input value loaded feeds up to 9 x DN_OCB multiply-adds of the private accumulators.

#include "denoise/tensor.h"

// Output channels per work item (the host passes -DDN_OCB: 8 on GPUs, 4 on CPUs).
#ifndef DN_OCB
#define DN_OCB 8
#endif

// Pixels per work item.
#define DN_PIX 4

// The input patch a work item reads from one channel: (2 + 2) x (4 + 2) at most.
#define DN_PATCH_W 4
#define DN_PATCH_H 6

// Accumulates the 3x3 convolution of `c` channels of `src` (planes of `w` x `h` pixels; read
// at half the coordinates when `up`) into `acc` for the block whose first pixel is (x0, y0) in
// the convolution's own resolution; `pool` picks the 2x2 block, else four rows of one column.
// `wt` points to the channels' weights: per input channel, 9 taps of DN_OCB values.
inline global const float* conv_channels(global const float* src, int c, int up, int w, int h,
                                         global const float* wt, int x0, int y0, const int pool,
                                         float acc[DN_OCB][DN_PIX]) {
    const int pw = pool ? 4 : 3;
    const int ph = pool ? 4 : 6;
    const int pitch = w + 2;
    const int plane = tensor_plane(w, h);
    for (int ic = 0; ic < c; ++ic) {
        global const float* s = src + (size_t)ic * plane;
        float patch[DN_PATCH_H][DN_PATCH_W];
        for (int r = 0; r < ph; ++r) {
            const int yy = up ? ((y0 - 1 + r) >> 1) : (y0 - 1 + r);
            for (int q = 0; q < pw; ++q) {
                const int xx = up ? ((x0 - 1 + q) >> 1) : (x0 - 1 + q);
                patch[r][q] = s[(yy + 1) * pitch + xx + 1];
            }
        }
        for (int ky = 0; ky < 3; ++ky) {
            for (int kx = 0; kx < 3; ++kx) {
                for (int p = 0; p < DN_PIX; ++p) {
                    const int px = pool ? (p & 1) : 0;
                    const int py = pool ? (p >> 1) : p;
                    const float v = patch[py + ky][px + kx];
                    for (int o = 0; o < DN_OCB; ++o)
                        acc[o][p] = fma(v, wt[(ky * 3 + kx) * DN_OCB + o], acc[o][p]);
                }
            }
        }
        wt += 9 * DN_OCB;
    }
    return wt;
}

// The block's accumulators: the bias, then both sources' channels (src0's first, as the
// weights' input channels are ordered: the upsampled decoder features, then the skip).
inline void conv_block(global const float* src0, int c0, int up0, global const float* src1, int c1,
                       global const float* weights, global const float* bias, int ocb,
                       int width, int height, int x0, int y0, const int pool,
                       float acc[DN_OCB][DN_PIX]) {
    for (int o = 0; o < DN_OCB; ++o)
        for (int p = 0; p < DN_PIX; ++p)
            acc[o][p] = bias[ocb + o];
    global const float* wt = weights + (size_t)ocb * (c0 + c1) * 9;
    const int w0 = up0 ? width / 2 : width;
    const int h0 = up0 ? height / 2 : height;
    wt = conv_channels(src0, c0, up0, w0, h0, wt, x0, y0, pool, acc);
    conv_channels(src1, c1, 0, width, height, wt, x0, y0, pool, acc);
}

// dst = relu(conv3x3(concat(upsample?(src0), src1)) + bias) at `width` x `height`; global size
// (columns, rows / 4, output channels / DN_OCB).
kernel void conv3x3(global const float* src0, int c0, int up0, global const float* src1, int c1,
                    global const float* weights, global const float* bias, global float* dst,
                    int width, int height) {
    const int x = get_global_id(0);
    const int y0 = get_global_id(1) * DN_PIX;
    const int ocb = get_global_id(2) * DN_OCB;
    if (x >= width || y0 >= height)
        return;
    float acc[DN_OCB][DN_PIX];
    conv_block(src0, c0, up0, src1, c1, weights, bias, ocb, width, height, x, y0, 0, acc);
    const int plane = tensor_plane(width, height);
    for (int o = 0; o < DN_OCB; ++o) {
        global float* d = dst + (size_t)(ocb + o) * plane;
        for (int p = 0; p < DN_PIX; ++p)
            if (y0 + p < height)
                d[tensor_at(width, x, y0 + p)] = fmax(acc[o][p], 0.0f);
    }
}

// dst = maxpool2x2(relu(conv3x3(src) + bias)), `width` x `height` being the convolution's
// resolution (even); global size (width / 2, height / 2, output channels / DN_OCB).
kernel void conv3x3_pool(global const float* src0, int c0, int up0, global const float* src1,
                         int c1, global const float* weights, global const float* bias,
                         global float* dst, int width, int height) {
    const int x = get_global_id(0);
    const int y = get_global_id(1);
    const int ocb = get_global_id(2) * DN_OCB;
    if (x >= width / 2 || y >= height / 2)
        return;
    float acc[DN_OCB][DN_PIX];
    conv_block(src0, c0, up0, src1, c1, weights, bias, ocb, width, height, 2 * x, 2 * y, 1, acc);
    const int plane = tensor_plane(width / 2, height / 2);
    for (int o = 0; o < DN_OCB; ++o) {
        const float m = fmax(fmax(acc[o][0], acc[o][1]), fmax(acc[o][2], acc[o][3]));
        dst[(size_t)(ocb + o) * plane + tensor_at(width / 2, x, y)] = fmax(m, 0.0f);
    }
}
