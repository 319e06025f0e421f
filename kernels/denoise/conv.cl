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
//
// With DN_BLOCKS_FIRST (the host sets it on CPUs) the work-groups that run one after another
// compute the output-channel blocks of the same pixels, so each reads an input tile its
// predecessor left in cache; otherwise they walk the image for one block before the next, and on
// a CPU at 960x600 each input channel's rows were fetched from memory again for every block
// (the convolutions ran at about half the speed).

#include "denoise/tensor.h"

// Rows of a work item's block where it does not pool.
#define DN_ROWS 4

// A work item's accumulators: DN_OCB output channels of DN_ROWS row vectors.
typedef struct {
    vfloat v[DN_OCB][DN_ROWS];
} Acc;

// The 3x3 convolution of concat(src0, src1) plus the bias for the block of `rows` rows whose
// top left pixel is (x0, y0) in the convolution's resolution, before the ReLU. src0 has `c0`
// channels and is read at half the coordinates when `up0`; src1 has `c1` at full resolution
// (the weights' input channels are ordered so: the upsampled decoder features, then the
// skip). `weights` holds, per block of DN_OCB output channels and input channel, 9 taps of
// DN_OCB values. The accumulators are local to this one function so that the compiler keeps
// them in registers: PoCL's CPU compiler treats every pointer as possibly aliasing an array
// whose address is passed on, and stored them after every multiply-add.
inline Acc conv_accumulate(global const float* src0, int c0, const int up0,
                           global const float* src1, int c1, global const float* weights,
                           global const float* bias, int ocb, int width, int height, int x0,
                           int y0, const int rows) {
    Acc acc;
#pragma unroll
    for (int o = 0; o < DN_OCB; ++o)
#pragma unroll
        for (int p = 0; p < DN_ROWS; ++p)
            acc.v[o][p] = (vfloat)(bias[ocb + o]);
    global const float* wt = weights + (size_t)ocb * (c0 + c1) * 9;
    const int w0 = up0 ? width / 2 : width;
    const int h0 = up0 ? height / 2 : height;
    for (int ic = 0; ic < c0 + c1; ++ic) {
        const int from0 = ic < c0;
        const int w = from0 ? w0 : width;
        const int pitch = w + 2;
        global const float* s = from0 ? src0 + (size_t)ic * tensor_plane(w0, h0)
                                      : src1 + (size_t)(ic - c0) * tensor_plane(width, height);
#pragma unroll
        for (int r = 0; r < DN_ROWS + 2; ++r) {
            if (r >= rows + 2)
                continue;
            // Input row y0 - 1 + r as three vectors: columns from x0 - 1, x0 and x0 + 1.
            vfloat v[3];
            if (up0 && from0) {
                upsampled_row(s + tensor_at(w, x0 >> 1, (y0 - 1 + r) >> 1), v);
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
                        acc.v[o][p] = fma(v[kx], (vfloat)(wt[(ky * 3 + kx) * DN_OCB + o]),
                                          acc.v[o][p]);
            }
        }
        wt += 9 * DN_OCB;
    }
    return acc;
}

// The work item's (column vector, row block, output-channel block) in the grid the host sets:
// (columns / DN_VEC, rows / DN_ROWS, output channels / DN_OCB) work items.
inline int3 conv_ids(void) {
#ifdef DN_BLOCKS_FIRST
    // Renumber the work-groups so that the output-channel block varies fastest; a work-group
    // spans the first dimension only.
    const int nx = get_num_groups(0), ny = get_num_groups(1), nz = get_num_groups(2);
    const int g = get_group_id(0) + nx * (get_group_id(1) + ny * get_group_id(2));
    const int pixels = g / nz;
    return (int3)((pixels % nx) * get_local_size(0) + get_local_id(0), pixels / nx, g % nz);
#else
    return (int3)(get_global_id(0), get_global_id(1), get_global_id(2));
#endif
}

// The unpooled convolutions' body, written after the ReLU. `up0` is a constant in each kernel
// below, so that each compiles to its own loads.
inline void conv_rows(global const float* src0, int c0, const int up0, global const float* src1,
                      int c1, global const float* weights, global const float* bias,
                      global float* dst, int width, int height) {
    const int3 id = conv_ids();
    const int x0 = id.x * DN_VEC;
    const int y0 = id.y * DN_ROWS;
    const int ocb = id.z * DN_OCB;
    if (x0 >= width || y0 >= height)
        return;
    const Acc acc = conv_accumulate(src0, c0, up0, src1, c1, weights, bias, ocb, width, height,
                                    x0, y0, DN_ROWS);
    const int plane = tensor_plane(width, height);
#pragma unroll
    for (int o = 0; o < DN_OCB; ++o) {
        global float* d = dst + (size_t)(ocb + o) * plane;
#pragma unroll
        for (int p = 0; p < DN_ROWS; ++p)
            if (y0 + p < height)
                store_row(fmax(acc.v[o][p], 0.0f), d + tensor_at(width, x0, y0 + p), width - x0);
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
    const int3 id = conv_ids();
    const int x0 = id.x * DN_VEC;
    const int y0 = id.y * 2;
    const int ocb = id.z * DN_OCB;
    if (x0 >= width || y0 >= height)
        return;
    const Acc acc = conv_accumulate(src0, c0, 0, src1, c1, weights, bias, ocb, width, height,
                                    x0, y0, 2);
    const int plane = tensor_plane(width / 2, height / 2);
#pragma unroll
    for (int o = 0; o < DN_OCB; ++o) {
        const vfloat m = fmax(fmax(acc.v[o][0], acc.v[o][1]), 0.0f);
        store_half_row(pool_pairs(m), dst + (size_t)(ocb + o) * plane +
                                          tensor_at(width / 2, x0 / 2, y0 / 2),
                       (width - x0) / 2);
    }
}
