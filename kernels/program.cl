// The production program: every kernel the renderer launches, on every device; the scene's
// features and the device choose by -D what is compiled (src/cl/program.rs). The host expands
// the includes (src/cl/source.rs).
//
// Each file includes what it uses; this list fixes the order in which they are compiled, and
// that order matters beyond declarations: traverse.h's `#pragma OPENCL FP_CONTRACT OFF` holds
// for every file after it.

// Shared by every device: the host's structs, sampling, textures, traversal of the binary and
// the 4-wide BVH.
#include "shared/types.h"
#include "shared/rng.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"
// The CPU megakernel's rays in vector lanes (MEGA_LANES only).
#include "cpu/traverse_lanes.h"
#include "cpu/traverse_packet.h"
// Shared: scattering, surfaces, the environment map, lights, one path vertex.
#include "shared/bsdf.h"
#include "shared/surface.h"
#include "shared/env.h"
#include "shared/lights.h"
// Guide buffers for a denoiser (with AOVS): each path's albedo, normal and depth record.
#include "shared/aovs.h"
#include "shared/path.h"
// Adaptive sampling: the half buffer, the error estimate and the convergence check.
#include "shared/film.h"
#include "shared/adaptive.h"
// The CPU lanes' batched shading (LANES_SHADE only).
#include "cpu/shade_lanes.h"
// The wavefront stages (GPUs; CPUs with --kernel wavefront).
#include "gpu/stages.cl"
// The megakernel: with its rays in lanes (MEGA_LANES), or one path at a time.
#include "cpu/megakernel_lanes.cl"
#include "cpu/megakernel.cl"
// Traversal alone, for `bench trace` and the device agreement tests.
#include "tools.cl"
