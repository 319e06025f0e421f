// The denoiser's program root: Open Image Denoise's U-Net (src/denoise/network.rs) as OpenCL
// kernels, built once per device apart from the path tracer's program.
#include "denoise/transfer.h"
#include "denoise/conv.cl"
#include "denoise/prepare.cl"
