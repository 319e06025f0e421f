// The denoiser's tensors: planar CHW, every channel a (width + 2) x (height + 2) plane whose
// one-pixel border stays zero (the host clears each tensor once; kernels write only the
// inside), which is the 3x3 convolutions' zero padding. src/denoise/network.rs allocates them.
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

#endif
