// Open Image Denoise's perceptually uniform (PU) transfer function for HDR colour: a fit of the
// PU curve (Aydin et al. 2008) normalised so that 65504 (the largest half) maps to 1. Its host
// twin, used by the tests, is src/denoise/prepare.rs.
#ifndef DENOISE_TRANSFER_H
#define DENOISE_TRANSFER_H

#include "denoise/tensor.h"

#define PU_A 1.41283765e+03f
#define PU_B 1.64593172e+00f
#define PU_C 4.31384981e-01f
#define PU_D (-2.94139609e-03f)
#define PU_E 1.92653254e-01f
#define PU_F 6.26026094e-03f
#define PU_G 9.98620152e-01f
#define PU_Y0 1.57945760e-06f
#define PU_Y1 3.22087631e-02f
#define PU_X0 2.23151711e-03f
#define PU_X1 3.70974749e-01f

// The curve before normalisation, on a row vector of pixels (kernels/denoise/tensor.h: 16 on
// a CPU, where PoCL runs the vector's pow and log as vector code but calls them once per pixel
// when each work item takes one pixel and branches); the kernels scale it by
// 1 / pu_forward(65504), which the host computes once (`prepare::PU_NORM`). Every lane
// computes each piece and keeps its own, so y must be finite and >= 0.
inline vfloat pu_forward(vfloat y) {
    const vfloat low = PU_A * y;
    const vfloat mid = PU_B * pow(fmax(y, PU_Y0), (vfloat)(PU_C)) + PU_D;
    const vfloat high = PU_E * log(y + PU_F) + PU_G;
    return select(select(high, mid, y <= PU_Y1), low, y <= PU_Y0);
}

// The inverse, for x >= 0.
inline vfloat pu_inverse(vfloat x) {
    const vfloat low = x / PU_A;
    const vfloat mid = pow((x - PU_D) / PU_B, (vfloat)(1.0f / PU_C));
    const vfloat high = exp((x - PU_G) / PU_E) - PU_F;
    return select(select(high, mid, x <= PU_X1), low, x <= PU_X0);
}

// The sRGB curve, which OIDN's albedo prefilter (`rt_alb`) works in: its input is the albedo
// encoded, its output decoded. Host twin: `tonemap::srgb_encode` / `srgb_decode`.
inline float srgb_forward(float y) {
    return y <= 0.0031308f ? 12.92f * y : 1.055f * pow(y, 1.0f / 2.4f) - 0.055f;
}

inline float srgb_inverse(float x) {
    return x <= 0.04045f ? x / 12.92f : pow((x + 0.055f) / 1.055f, 2.4f);
}

#endif
