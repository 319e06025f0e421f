#!/bin/sh
# Builds native_trace: kernels/traverse_wide.h compiled by clang 15 (PoCL's LLVM) for this CPU,
# with PoCL's own builtin library linked in, and the C harness main.c. Run from the repository
# root: scripts/experiments/native_trace/build.sh [extra clang options for the kernel code]
set -e
D=scripts/experiments/native_trace
O=${NATIVE_OUT:-/tmp/native_trace}
mkdir -p $O
K=${NATIVE_KERNELS:-kernels}
# Constants the program prepends from src/cl/types.rs that the walk uses.
printf '#define TLAS_LEAF 0x80000000u\n#define INSTANCE_MIRRORED 1u\n#define INSTANCE_PIECE_TRIANGLE 2u\n' > $O/consts.h
cat $O/consts.h $K/types.h $K/rng.h $K/textures.h $K/traverse.h $K/traverse_wide.h \
    $D/entry.cl > $O/all.cl
# NATIVE_QUANT=1: also the quantised-node walk (quant.cl, from scripts/experiments/
# quantised-nodes.patch: git apply it first; run with NATIVE_QUANT=1 too).
if [ -n "$NATIVE_QUANT" ]; then cat $D/quant.cl >> $O/all.cl; fi
# NATIVE_COUNT=1: count node visits and triangle tests (calls into main.c; slower).
if [ -n "$NATIVE_COUNT" ]; then
    sed -i -e 's/^\(inline bool intersect_triangle(.*\)$/void count_tri(void);\n\1/' \
        -e 's/^\(inline int4 wide_reach(.*\)$/void count_node(void);\n\1/' \
        -e 's/^\(    float4 x0 = (WIDE_PLANE(n, w->nx) - w->ox) \* w->ix;\)$/    count_node();\n\1/' \
        -e 's/^\(    float4 o = (float4)(r->origin, 0.0f);\)$/    count_tri();\n\1/' $O/all.cl
    grep -c 'count_' $O/all.cl
fi
# -fgnu89-inline: traverse_wide_bvh is a plain `inline` function called from two places, which
# C99 rules leave without an out-of-line definition (an undefined symbol at link time).
clang-15 -x cl -cl-std=CL1.2 -target x86_64-pc-linux-gnu -march=native -O3 -fgnu89-inline \
    -Xclang -finclude-default-header -cl-denorms-are-zero \
    -cl-fp32-correctly-rounded-divide-sqrt "$@" -emit-llvm -c $O/all.cl -o $O/trace.bc
llvm-link-15 $O/trace.bc /usr/share/pocl/kernel-x86_64-pc-linux-gnu-avx512.bc --only-needed \
    -o $O/linked.bc
# PoCL's library marks its builtins spir_func; calls from this x86 build use the C convention,
# which LLVM would turn into unreachable code.
llvm-dis-15 $O/linked.bc -o - | sed 's/spir_func //g' > $O/linked.ll
clang-15 -O3 -march=native -c $O/linked.ll -o $O/trace.o
clang-15 -O2 -march=native $D/main.c $O/trace.o -lm -o $O/native_trace
echo $O/native_trace
