// The denoiser's tensors and the vectors its convolutions compute in.
//
// A tensor is planar CHW, every channel a (width + 2) x (height + 2) plane whose one-pixel
// border stays zero (the host clears each tensor once; kernels write only the inside), which
// is the 3x3 convolutions' zero padding; src/denoise/network.rs allocates them, with room
// after the last plane for a block's reads past it.
//
// `vfloat` is DN_VEC neighbouring columns of one row (the host passes -DDN_VEC: 16 on CPUs,
// one AVX-512 register; 2 on GPUs, where neighbouring work items make the vector).
#ifndef DENOISE_TENSOR_H
#define DENOISE_TENSOR_H

// Floats in one channel's plane.
inline int tensor_plane(int width, int height) {
    return (width + 2) * (height + 2);
}

// The index of pixel (x, y) within a plane.
inline int tensor_at(int width, int x, int y) {
    return (y + 1) * (width + 2) + x + 1;
}

#ifndef DN_VEC
#define DN_VEC 2
#endif

#if DN_VEC == 16
typedef float16 vfloat;
typedef float8 hfloat;
typedef uint16 vmask;
typedef float16 ufloat; // the source an upsampled row's vectors are shuffled from
#define vload_row(p) vload16(0, (p))
#define vstore_row(v, p) vstore16((v), 0, (p))
#define vstore_pooled(v, p) vstore8((v), 0, (p))
// Source lanes of the upsampled row's three vectors (see upsampled_row).
#define UP_LEFT (vmask)(0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8)
#define UP_CENTRE (vmask)(1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8)
#define UP_RIGHT (vmask)(1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9)
#define UP_LOAD(p) vload16(0, (p))
#elif DN_VEC == 2
typedef float2 vfloat;
typedef float hfloat;
typedef uint2 vmask;
typedef float4 ufloat;
#define vload_row(p) vload2(0, (p))
#define vstore_row(v, p) vstore2((v), 0, (p))
#define vstore_pooled(v, p) (*(p) = (v))
#define UP_LEFT (vmask)(0, 1)
#define UP_CENTRE (vmask)(1, 1)
#define UP_RIGHT (vmask)(1, 2)
#define UP_LOAD(p) vload4(0, (p))
#else
#error "DN_VEC must be 16 or 2"
#endif

// The three shifted vectors of an upsampled row from its half-resolution source: `source` points
// at the source pixel under the block's first column, x0 / 2 (x0 even); lane i of the vector
// starting at column x0 + d - 1 is source column (x0 + d - 1 + i) >> 1.
inline void upsampled_row(global const float* source, vfloat v[3]) {
    const ufloat s = UP_LOAD(source - 1);
    v[0] = shuffle(s, UP_LEFT);
    v[1] = shuffle(s, UP_CENTRE);
    v[2] = shuffle(s, UP_RIGHT);
}

// Stores the first `n` lanes (all when n >= DN_VEC) of a row's vector.
inline void store_row(vfloat v, global float* p, int n) {
    if (n >= DN_VEC) {
        vstore_row(v, p);
        return;
    }
    float lanes[DN_VEC];
    vstore_row(v, lanes);
    for (int i = 0; i < n; ++i)
        p[i] = lanes[i];
}

// The larger of each pair of neighbouring lanes: the horizontal half of a 2x2 max pool.
inline hfloat pool_pairs(vfloat v) {
    return fmax(v.even, v.odd);
}

// Stores the first `n` lanes of a pooled half vector.
inline void store_half_row(hfloat v, global float* p, int n) {
    if (n >= DN_VEC / 2) {
        vstore_pooled(v, p);
        return;
    }
    float lanes[DN_VEC / 2];
    vstore_pooled(v, lanes);
    for (int i = 0; i < n; ++i)
        p[i] = lanes[i];
}

#endif
