#!/bin/sh
# Builds native_lanes: kernels/traverse_lanes.h (the megakernel's walk in AVX-512 lanes)
# compiled by clang 15 for this CPU with PoCL's builtin library, over native_trace's harness
# (main.c): one thread, the rays and tree of a PENUMBRA_DUMP_TRACE dump, every hit checked.
# Run from the repository root: scripts/experiments/lanes/build.sh [clang options]
# then /tmp/native_lanes/native_lanes DUMP 3 (NATIVE_SHUFFLE=1 for random ray order).
# NATIVE_ENTRY=scripts/experiments/lanes/entry_packet.cl: the packet walk (traverse_packet.h)
# over 4x4 blocks of the dump's pixels instead (-DPACKET_SCALAR: the scalar walk, same order).
# -DLANES_GATHERS: the lanes gather their nodes and triangles instead of loading rows.
set -e
D=scripts/experiments/lanes
O=${NATIVE_OUT:-/tmp/native_lanes}
mkdir -p $O
printf '#define TLAS_LEAF 0x80000000u\n#define INSTANCE_MIRRORED 1u\n#define INSTANCE_PIECE_TRIANGLE 2u\n#define MEGA_LANES\n' > $O/consts.h
# defs.cl: vload16/vstore16/atomic_add for private memory, which PoCL's library names
# differently from clang's native mangling.
cat $O/consts.h kernels/types.h $D/defs.cl kernels/rng.h kernels/textures.h kernels/traverse.h \
    kernels/traverse_wide.h kernels/traverse_lanes.h kernels/traverse_packet.h \
    ${NATIVE_ENTRY:-$D/entry_lanes.cl} > $O/all.cl
clang-15 -x cl -cl-std=CL1.2 -target x86_64-pc-linux-gnu -march=native -O3 -fgnu89-inline \
    -Xclang -finclude-default-header -cl-fp32-correctly-rounded-divide-sqrt "$@" \
    -emit-llvm -c $O/all.cl -o $O/trace.bc
llvm-link-15 $O/trace.bc /usr/share/pocl/kernel-x86_64-pc-linux-gnu-avx512.bc --only-needed \
    -o $O/linked.bc
llvm-dis-15 $O/linked.bc -o - | sed 's/spir_func //g' > $O/linked.ll
clang-15 -O3 -march=native -c $O/linked.ll -o $O/trace.o
clang-15 -O2 -march=native ${NATIVE_MAIN:-scripts/experiments/native_trace/main.c} $O/trace.o -lm \
    -o $O/native_lanes
echo $O/native_lanes
