// Rays in vector lanes, for the CPU megakernel (MEGA_LANES: set by the host on CPU devices with
// AVX-512 or AVX2, for flat scenes without alpha that are not small; src/cl/program.rs,
// lanes_megakernel): sixteen independent rays walk the 4-wide BVH together, one ray a lane,
// each at its own node, the lanes' nodes and triangles loaded as rows and transposed into
// vectors (lanes_rows8; LANES_GATHERS: by gathers). One ray at a time, a walk
// waits on memory at nearly every node it visits in a large scene (about 45 % of a diffuse
// ray's time waited for nodes and triangles, 2026-12-01); sixteen walks keep sixteen loads in flight, and a lane whose ray is done takes its
// path's next ray while the others go on.
//
// The rays are extension rays, from tmin 0 to infinity, for the nearest hit, or shadow rays, from
// tmin 0 to their light, for any hit (`any`: such a lane is done at its first). Each lane computes
// traverse_wide.h's slab test and intersect_leaf4's watertight arithmetic, so that the hit is
// traverse_wide's (of equally near hits the two walks may keep different triangles), and the
// scalar test's rare cases (an edge function of zero, a hit within the rounding-error bound)
// go to intersect_leaf itself. Leaves are stack items, as in Embree's walk, tested once enough
// lanes have reached one; a node's reached children are sorted by entry distance in every
// lane, the nearest entered and the others pushed farthest first.
#ifndef CPU_TRAVERSE_LANES_H
#define CPU_TRAVERSE_LANES_H

#include "shared/types.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"

#ifdef MEGA_LANES
// The lanes: sixteen, or eight where the CPU has AVX2 but not AVX-512 (-DLANES=16 or 8 chooses):
// sixteen lanes there are two 256-bit halves to every vector operation and half as many vectors
// in its sixteen registers, and eight took 7-8 % less time on AMD's Zen 3 (2026-12-04).
// Below, "sixteen" is LANES.
#ifndef LANES
#if defined(__AVX2__) && !defined(__AVX512F__) && defined(__x86_64__)
#define LANES 8
#else
#define LANES 16
#endif
#endif
#define LANES_STACK (WIDE_STACK_SIZE + 1)
// A lane's stack is LANES_STACK entries and three more, which a push of three entries in one
// 32-byte store (LANES_PUSH3) may write past its top.
#define LANES_STACK_STRIDE (LANES_STACK + 3)
// The word offset of each lane's stack entry sp (a lane's entries side by side).
#define LANES_ENTRY(sp) ((LANE_IDS * (lanes_i)(LANES_STACK_STRIDE) + (sp)) * (lanes_i)(2))
#define LANES_INLINE inline __attribute__((always_inline))
#if LANES == 16
typedef float16 lanes_f;
typedef int16 lanes_i;
#define as_lanes_f as_float16
#define as_lanes_i as_int16
#define lanes_vload vload16
#define lanes_vstore vstore16
#define LANE_IDS ((lanes_i)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))
// A vector's words in pairs, as 8-byte words (typed: not through an int pointer, which
// the compiler may take for another object).
#define lanes_vstore_pairs(v, p) vstore8(as_long8(v), 0, (p))
#elif LANES == 8
typedef float8 lanes_f;
typedef int8 lanes_i;
#define as_lanes_f as_float8
#define as_lanes_i as_int8
#define lanes_vload vload8
#define lanes_vstore vstore8
#define LANE_IDS ((lanes_i)(0, 1, 2, 3, 4, 5, 6, 7))
#define lanes_vstore_pairs(v, p) vstore4(as_long4(v), 0, (p))
#else
#error "LANES is 8 or 16"
#endif

// x's lanes folded to eight by F (sixteen lanes: F of the halves).
#if LANES == 16
#define LANES_FOLD8(x, F) F((x).lo, (x).hi)
#else
#define LANES_FOLD8(x, F) (x)
#endif
#define LANES_OR(a, b) ((a) | (b))
#define LANES_ADD(a, b) ((a) + (b))

// Whether any lane of a mask (all bits of a lane set or clear) is set.
inline bool lanes_any(lanes_i m) {
    int8 a = LANES_FOLD8(m, LANES_OR);
    int4 b = a.lo | a.hi;
    int2 c = b.lo | b.hi;
    return (c.x | c.y) != 0;
}

// The number of set lanes of a mask.
inline int lanes_count(lanes_i m) {
    lanes_i b = m & (lanes_i)(1);
    int8 a = LANES_FOLD8(b, LANES_ADD);
    int4 c = a.lo + a.hi;
    int2 d = c.lo + c.hi;
    return d.x + d.y;
}

// The greatest lane.
inline int lanes_max(lanes_i x) {
    int8 a = LANES_FOLD8(x, max);
    int4 b = max(a.lo, a.hi);
    int2 c = max(b.lo, b.hi);
    return max(c.x, c.y);
}

#if LANES == 16
// The even words of lo and hi (in order) in A, the odd ones in B; and the opposite, A and B
// interleaved into lo (their lanes 0-7) and hi (8-15), which it declares.
#define LANES_DEINTERLEAVE(lo, hi, A, B)                                                           \
    A = __builtin_shufflevector(lo, hi, 0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30); \
    B = __builtin_shufflevector(lo, hi, 1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
#define LANES_INTERLEAVE(A, B, lo, hi)                                                            \
    lanes_f lo = __builtin_shufflevector(A, B, 0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, \
                                         23);                                                     \
    lanes_f hi = __builtin_shufflevector(A, B, 8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14,  \
                                         30, 15, 31);
#else
#define LANES_DEINTERLEAVE(lo, hi, A, B)                              \
    A = __builtin_shufflevector(lo, hi, 0, 2, 4, 6, 8, 10, 12, 14); \
    B = __builtin_shufflevector(lo, hi, 1, 3, 5, 7, 9, 11, 13, 15);
#define LANES_INTERLEAVE(A, B, lo, hi)                                       \
    lanes_f lo = __builtin_shufflevector(A, B, 0, 8, 1, 9, 2, 10, 3, 11); \
    lanes_f hi = __builtin_shufflevector(A, B, 4, 12, 5, 13, 6, 14, 7, 15);
#endif

// Gathers and scatters: base[idx] in each lane of a mask (others 0); with AVX-512 one
// instruction, with AVX2 two gathers or a loop over the mask's lanes (below), else lane by lane.
#if LANES == 16 && defined(__AVX512F__) && defined(__x86_64__)
inline ushort lanes_kmask(lanes_i m) {
    return __builtin_ia32_cmpd512_mask(m, (lanes_i)(0), 4, (ushort)0xffff);  // m != 0
}
#define LANES_GATHER_F(base, idx, m)                                                          \
    as_lanes_f(__builtin_ia32_gathersiv16sf((lanes_f)(0.0f), (const void*)(ulong)(base), (idx), \
                                            lanes_kmask(m), 4))
// Two neighbouring words at word offset idx of each lane of mask km (lanes_kmask): the first
// in A, the second in B (8-byte gathers, eight lanes each: half the elements of two gathers).
#define LANES_GATHER_PAIR(base, idx, km, A, B)                                                    \
    {                                                                                            \
        lanes_f lo_ = as_lanes_f(__builtin_ia32_gathersiv8di(                                     \
            (long8)(0), (const void*)(ulong)(base), (idx).lo, (uchar)(km), 4));                   \
        lanes_f hi_ = as_lanes_f(__builtin_ia32_gathersiv8di(                                     \
            (long8)(0), (const void*)(ulong)(base), (idx).hi, (uchar)((km) >> 8), 4));            \
        LANES_DEINTERLEAVE(lo_, hi_, A, B)                                                       \
    }
// The opposite: A and B stored side by side at word offset idx of each lane of km.
#define LANES_SCATTER_PAIR(base, idx, km, A, B)                                                   \
    {                                                                                            \
        LANES_INTERLEAVE(A, B, lo_, hi_)                                                         \
        __builtin_ia32_scattersiv8di((void*)(base), (uchar)(km), (idx).lo, as_long8(lo_), 4);     \
        __builtin_ia32_scattersiv8di((void*)(base), (uchar)((km) >> 8), (idx).hi, as_long8(hi_),  \
                                     4);                                                         \
    }
#elif defined(__AVX2__) && defined(__x86_64__)
// AVX2 (no AVX-512): masks by movmskps, gathers by AVX2's eight-lane gathers (pairs of words by
// its four-lane 8-byte ones); AVX2 has no scatter.
inline ushort lanes_kmask(lanes_i m) {
    lanes_i t = m != (lanes_i)(0);
#if LANES == 16
    return (ushort)(__builtin_ia32_movmskps256(as_float8(t.lo)) |
                    (__builtin_ia32_movmskps256(as_float8(t.hi)) << 8));
#else
    return (ushort)__builtin_ia32_movmskps256(as_float8(t));
#endif
}
#define LANES_GATHER8(base, idx8, m8)                                                       \
    __builtin_ia32_gatherd_ps256((float8)(0.0f), (const void*)(ulong)(base), (idx8),        \
                                 as_float8((m8) != (int8)(0)), 4)
// Four lanes' 8-byte words at word offsets idx4, for the lanes of the low four bits.
#define LANES_GATHER4Q(base, idx4, bits)                                                    \
    as_float8(__builtin_ia32_gatherd_q256(                                                  \
        (long4)(0), (const void*)(ulong)(base), (idx4),                                     \
        as_long4(((long4)(1, 2, 4, 8) & (long4)((long)(bits))) != (long4)(0)), 4))
#if LANES == 16
#define LANES_GATHER_F(base, idx, m) \
    ((lanes_f)(LANES_GATHER8(base, (idx).lo, (m).lo), LANES_GATHER8(base, (idx).hi, (m).hi)))
#define LANES_GATHER_HALVES(base, idx, km, lo_, hi_)                                  \
    lanes_f lo_ = (lanes_f)(LANES_GATHER4Q(base, (idx).lo.lo, (km)),                  \
                            LANES_GATHER4Q(base, (idx).lo.hi, (km) >> 4));            \
    lanes_f hi_ = (lanes_f)(LANES_GATHER4Q(base, (idx).hi.lo, (km) >> 8),             \
                            LANES_GATHER4Q(base, (idx).hi.hi, (km) >> 12));
#else
#define LANES_GATHER_F(base, idx, m) LANES_GATHER8(base, idx, m)
#define LANES_GATHER_HALVES(base, idx, km, lo_, hi_)      \
    lanes_f lo_ = LANES_GATHER4Q(base, (idx).lo, (km)); \
    lanes_f hi_ = LANES_GATHER4Q(base, (idx).hi, (km) >> 4);
#endif
#define LANES_GATHER_PAIR(base, idx, km, A, B)       \
    {                                               \
        LANES_GATHER_HALVES(base, idx, km, lo_, hi_) \
        LANES_DEINTERLEAVE(lo_, hi_, A, B)           \
    }
// A push (LANES_PUSH_PAIR, below) without a scatter: every lane stores, one 8-byte store after
// another, those outside km into their free entry (the one at their stack pointer, which no
// walk reads: their pushes and pops leave it above the top). A loop over km's lanes alone cost
// a branch a lane and a mispredicted exit a push; the stores in every lane took 4-5 % less time
// on the 1 M-triangle scenes (AMD Zen 3, 2026-12-04).
#define LANES_PUSH_PAIR(base, idx, km, A, B)                            \
    {                                                                   \
        LANES_INTERLEAVE(A, B, lo_, hi_)                                \
        long q_[LANES];                                                 \
        int i_[LANES];                                                  \
        lanes_vstore_pairs(lo_, q_);                                    \
        lanes_vstore_pairs(hi_, q_ + LANES / 2);                        \
        lanes_vstore((idx), 0, i_);                                     \
        _Pragma("unroll") for (int l_ = 0; l_ < LANES; ++l_)            \
            *(long*)((float*)(base) + i_[l_]) = q_[l_];                \
    }
#else
inline ushort lanes_kmask(lanes_i m) {
    int k[LANES];
    lanes_vstore(m, 0, k);
    ushort bits = 0;
    for (int l = 0; l < LANES; ++l) bits |= k[l] ? (ushort)(1 << l) : (ushort)0;
    return bits;
}
inline lanes_f lanes_gather_f(const float* base, lanes_i idx, ushort km) {
    int i[LANES];
    float out[LANES];
    lanes_vstore(idx, 0, i);
    for (int l = 0; l < LANES; ++l) out[l] = (km >> l) & 1 ? base[i[l]] : 0.0f;
    return lanes_vload(0, out);
}
inline void lanes_scatter_f(float* base, lanes_i idx, lanes_f v, ushort km) {
    int i[LANES];
    float x[LANES];
    lanes_vstore(idx, 0, i);
    lanes_vstore(v, 0, x);
    for (int l = 0; l < LANES; ++l)
        if ((km >> l) & 1) base[i[l]] = x[l];
}
#define LANES_GATHER_F(base, idx, m) \
    lanes_gather_f((const float*)(ulong)(base), (idx), lanes_kmask(m))
#define LANES_GATHER_PAIR(base, idx, km, A, B)                            \
    {                                                                    \
        A = lanes_gather_f((const float*)(ulong)(base), (idx), (km));     \
        B = lanes_gather_f((const float*)(ulong)(base), (idx) + 1, (km)); \
    }
#define LANES_SCATTER_PAIR(base, idx, km, A, B)              \
    {                                                       \
        lanes_scatter_f((float*)(base), (idx), (A), (km));     \
        lanes_scatter_f((float*)(base), (idx) + 1, (B), (km)); \
    }
#endif

#if defined(__AVX2__) && (LANES == 8 || !defined(__AVX512F__)) && defined(__x86_64__)
// For eight mask bits, the indices of the set ones in order, four bits each (others 0).
constant uint LANES_COMPRESS8[256] = {
    0x00000000u, 0x00000000u, 0x00000001u, 0x00000010u, 0x00000002u, 0x00000020u, 0x00000021u, 0x00000210u,
    0x00000003u, 0x00000030u, 0x00000031u, 0x00000310u, 0x00000032u, 0x00000320u, 0x00000321u, 0x00003210u,
    0x00000004u, 0x00000040u, 0x00000041u, 0x00000410u, 0x00000042u, 0x00000420u, 0x00000421u, 0x00004210u,
    0x00000043u, 0x00000430u, 0x00000431u, 0x00004310u, 0x00000432u, 0x00004320u, 0x00004321u, 0x00043210u,
    0x00000005u, 0x00000050u, 0x00000051u, 0x00000510u, 0x00000052u, 0x00000520u, 0x00000521u, 0x00005210u,
    0x00000053u, 0x00000530u, 0x00000531u, 0x00005310u, 0x00000532u, 0x00005320u, 0x00005321u, 0x00053210u,
    0x00000054u, 0x00000540u, 0x00000541u, 0x00005410u, 0x00000542u, 0x00005420u, 0x00005421u, 0x00054210u,
    0x00000543u, 0x00005430u, 0x00005431u, 0x00054310u, 0x00005432u, 0x00054320u, 0x00054321u, 0x00543210u,
    0x00000006u, 0x00000060u, 0x00000061u, 0x00000610u, 0x00000062u, 0x00000620u, 0x00000621u, 0x00006210u,
    0x00000063u, 0x00000630u, 0x00000631u, 0x00006310u, 0x00000632u, 0x00006320u, 0x00006321u, 0x00063210u,
    0x00000064u, 0x00000640u, 0x00000641u, 0x00006410u, 0x00000642u, 0x00006420u, 0x00006421u, 0x00064210u,
    0x00000643u, 0x00006430u, 0x00006431u, 0x00064310u, 0x00006432u, 0x00064320u, 0x00064321u, 0x00643210u,
    0x00000065u, 0x00000650u, 0x00000651u, 0x00006510u, 0x00000652u, 0x00006520u, 0x00006521u, 0x00065210u,
    0x00000653u, 0x00006530u, 0x00006531u, 0x00065310u, 0x00006532u, 0x00065320u, 0x00065321u, 0x00653210u,
    0x00000654u, 0x00006540u, 0x00006541u, 0x00065410u, 0x00006542u, 0x00065420u, 0x00065421u, 0x00654210u,
    0x00006543u, 0x00065430u, 0x00065431u, 0x00654310u, 0x00065432u, 0x00654320u, 0x00654321u, 0x06543210u,
    0x00000007u, 0x00000070u, 0x00000071u, 0x00000710u, 0x00000072u, 0x00000720u, 0x00000721u, 0x00007210u,
    0x00000073u, 0x00000730u, 0x00000731u, 0x00007310u, 0x00000732u, 0x00007320u, 0x00007321u, 0x00073210u,
    0x00000074u, 0x00000740u, 0x00000741u, 0x00007410u, 0x00000742u, 0x00007420u, 0x00007421u, 0x00074210u,
    0x00000743u, 0x00007430u, 0x00007431u, 0x00074310u, 0x00007432u, 0x00074320u, 0x00074321u, 0x00743210u,
    0x00000075u, 0x00000750u, 0x00000751u, 0x00007510u, 0x00000752u, 0x00007520u, 0x00007521u, 0x00075210u,
    0x00000753u, 0x00007530u, 0x00007531u, 0x00075310u, 0x00007532u, 0x00075320u, 0x00075321u, 0x00753210u,
    0x00000754u, 0x00007540u, 0x00007541u, 0x00075410u, 0x00007542u, 0x00075420u, 0x00075421u, 0x00754210u,
    0x00007543u, 0x00075430u, 0x00075431u, 0x00754310u, 0x00075432u, 0x00754320u, 0x00754321u, 0x07543210u,
    0x00000076u, 0x00000760u, 0x00000761u, 0x00007610u, 0x00000762u, 0x00007620u, 0x00007621u, 0x00076210u,
    0x00000763u, 0x00007630u, 0x00007631u, 0x00076310u, 0x00007632u, 0x00076320u, 0x00076321u, 0x00763210u,
    0x00000764u, 0x00007640u, 0x00007641u, 0x00076410u, 0x00007642u, 0x00076420u, 0x00076421u, 0x00764210u,
    0x00007643u, 0x00076430u, 0x00076431u, 0x00764310u, 0x00076432u, 0x00764320u, 0x00764321u, 0x07643210u,
    0x00000765u, 0x00007650u, 0x00007651u, 0x00076510u, 0x00007652u, 0x00076520u, 0x00076521u, 0x00765210u,
    0x00007653u, 0x00076530u, 0x00076531u, 0x00765310u, 0x00076532u, 0x00765320u, 0x00765321u, 0x07653210u,
    0x00007654u, 0x00076540u, 0x00076541u, 0x00765410u, 0x00076542u, 0x00765420u, 0x00765421u, 0x07654210u,
    0x00076543u, 0x00765430u, 0x00765431u, 0x07654310u, 0x00765432u, 0x07654320u, 0x07654321u, 0x76543210u,
};
inline int8 lanes_compress8_index(uint km8) {
    return ((int8)((int)LANES_COMPRESS8[km8 & 255u]) >> (int8)(0, 4, 8, 12, 16, 20, 24, 28)) &
           (int8)(7);
}
#endif

// A lane's push of A and B side by side at word offset idx, for the lanes of km: a scatter,
// unless the form above stores in every lane.
#ifndef LANES_PUSH_PAIR
#define LANES_PUSH_PAIR LANES_SCATTER_PAIR
#endif

// A pop, the words at idx and idx + 1 of each lane into A and B (lanes outside km read their
// entry too, which no walk uses): with eight lanes by one 8-byte load a lane, which took 1-4 %
// less time than AVX2's two four-lane 8-byte gathers on Zen 3; else a gather.
#if LANES == 8
#define LANES_POP_PAIR(base, idx, km, A, B)                                            \
    {                                                                                  \
        int i_[LANES];                                                                 \
        long q_[LANES];                                                                \
        lanes_vstore((idx), 0, i_);                                                    \
        _Pragma("unroll") for (int l_ = 0; l_ < LANES; ++l_)                           \
            q_[l_] = *(const long*)((const float*)(base) + i_[l_]);                    \
        lanes_f lo_ = as_float8(vload4(0, q_)), hi_ = as_float8(vload4(1, q_));         \
        LANES_DEINTERLEAVE(lo_, hi_, A, B)                                             \
    }
#else
#define LANES_POP_PAIR LANES_GATHER_PAIR
#endif

// The lanes of mask km of v, in order, in the first lanes (the others 0); and the lanes of v
// named by idx.
#if LANES == 16 && defined(__AVX512F__) && defined(__x86_64__)
#define lanes_compress(v, km) __builtin_ia32_compresssi512_mask((v), (lanes_i)(0), (km))
#define lanes_permute(v, idx) __builtin_ia32_permvarsf512((v), (idx))
#define lanes_permute_i(v, idx) __builtin_ia32_permvarsi512((v), (idx))
#elif LANES == 16 && defined(__AVX2__) && defined(__x86_64__)
// Each half compressed by a table-driven permute, the high half's lanes then moved up past the
// low half's n.
inline lanes_i lanes_compress(lanes_i v, ushort km) {
    uint klo = km & 255u, khi = (uint)km >> 8;
    int n = popcount(klo), m = popcount(khi);
    int8 lo = __builtin_ia32_permvarsi256(v.lo, lanes_compress8_index(klo));
    int8 hi = __builtin_ia32_permvarsi256(v.hi, lanes_compress8_index(khi));
    int8 i8 = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
    int8 jlo = i8 - (int8)(n), jhi = i8 + (int8)(8 - n);
    int8 hlo = __builtin_ia32_permvarsi256(hi, jlo & (int8)(7));
    int8 hhi = __builtin_ia32_permvarsi256(hi, jhi & (int8)(7));
    int8 rlo = select(select((int8)(0), hlo, jlo < (int8)(m)), lo, i8 < (int8)(n));
    int8 rhi = select((int8)(0), hhi, jhi < (int8)(m));
    return (lanes_i)(rlo, rhi);
}
inline lanes_f lanes_permute(lanes_f v, lanes_i idx) {
    int8 a = idx.lo & (int8)(7), b = idx.hi & (int8)(7);
    float8 lo = select(__builtin_ia32_permvarsf256(v.lo, a), __builtin_ia32_permvarsf256(v.hi, a),
                       (idx.lo & (int8)(8)) != (int8)(0));
    float8 hi = select(__builtin_ia32_permvarsf256(v.lo, b), __builtin_ia32_permvarsf256(v.hi, b),
                       (idx.hi & (int8)(8)) != (int8)(0));
    return (lanes_f)(lo, hi);
}
inline lanes_i lanes_permute_i(lanes_i v, lanes_i idx) {
    return as_lanes_i(lanes_permute(as_lanes_f(v), idx));
}
#elif LANES == 8 && defined(__AVX2__) && defined(__x86_64__)
inline lanes_i lanes_compress(lanes_i v, ushort km) {
    return select((int8)(0), __builtin_ia32_permvarsi256(v, lanes_compress8_index(km)),
                  LANE_IDS < (int8)(popcount((uint)km & 255u)));
}
#define lanes_permute(v, idx) __builtin_ia32_permvarsf256((v), (idx))
#define lanes_permute_i(v, idx) __builtin_ia32_permvarsi256((v), (idx))
#else
inline lanes_i lanes_compress(lanes_i v, ushort km) {
    int in[LANES], out[LANES];
    lanes_vstore(v, 0, in);
    int n = 0;
    for (int l = 0; l < LANES; ++l) {
        out[l] = 0;
        if ((km >> l) & 1) out[n++] = in[l];
    }
    return lanes_vload(0, out);
}
inline lanes_f lanes_permute(lanes_f v, lanes_i idx) {
    float in[LANES], out[LANES];
    int i[LANES];
    lanes_vstore(v, 0, in);
    lanes_vstore(idx, 0, i);
    for (int l = 0; l < LANES; ++l) out[l] = in[i[l] & (LANES - 1)];
    return lanes_vload(0, out);
}
inline lanes_i lanes_permute_i(lanes_i v, lanes_i idx) {
    return as_lanes_i(lanes_permute(as_lanes_f(v), idx));
}
#endif

// Rows into lanes. A lane's node (32 words) or triangle (12) is a row of neighbouring words,
// and a gather loads one element at a time: on AMD's Zen 5, 0.5 ns an element, 128 ns for the
// 32 gathers of a node visit of sixteen lanes against 15 ns for the same bytes as rows
// (2026-12-02). lanes_rows8 loads eight words of each lane's
// row, two lanes a vector, and transposes them by shuffles; lanes_rows4, four. With
// LANES_GATHERS the walk gathers instead (the two read the same words: same hits).
#if LANES == 16
#define LANES_UNPACKLO 0, 16, 1, 17, 4, 20, 5, 21, 8, 24, 9, 25, 12, 28, 13, 29
#define LANES_UNPACKHI 2, 18, 3, 19, 6, 22, 7, 23, 10, 26, 11, 27, 14, 30, 15, 31
#define LANES_PAIRSLO 0, 1, 16, 17, 4, 5, 20, 21, 8, 9, 24, 25, 12, 13, 28, 29
#define LANES_PAIRSHI 2, 3, 18, 19, 6, 7, 22, 23, 10, 11, 26, 27, 14, 15, 30, 31
#define LANES_QUADSLO 0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27
#define LANES_QUADSHI 4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31
// rows8's vector i: lane i's eight words in the low half, lane i + 8's in the high one; rows4's:
// the four words of lanes i, i + 4, i + 8 and i + 12.
#define LANES_ROW8(base, off, w, i) \
    (lanes_f)(vload8(0, base + off[i] + w), vload8(0, base + off[i + 8] + w))
#define LANES_ROW4(base, off, w, i)                                                    \
    (lanes_f)(vload4(0, base + off[i] + w), vload4(0, base + off[i + 4] + w),        \
              vload4(0, base + off[i + 8] + w), vload4(0, base + off[i + 12] + w))
#else
// Eight lanes: the same in 128-bit halves (a 4×4 transpose in each), rows8's vector i lane i's
// words, rows4's the words of lanes i and i + 4.
#define LANES_UNPACKLO 0, 8, 1, 9, 4, 12, 5, 13
#define LANES_UNPACKHI 2, 10, 3, 11, 6, 14, 7, 15
#define LANES_PAIRSLO 0, 1, 8, 9, 4, 5, 12, 13
#define LANES_PAIRSHI 2, 3, 10, 11, 6, 7, 14, 15
#define LANES_QUADSLO 0, 1, 2, 3, 8, 9, 10, 11
#define LANES_QUADSHI 4, 5, 6, 7, 12, 13, 14, 15
#define LANES_ROW8(base, off, w, i) vload8(0, base + off[i] + w)
#define LANES_ROW4(base, off, w, i) \
    (lanes_f)(vload4(0, base + off[i] + w), vload4(0, base + off[i + 4] + w))
#endif
#define LANES_SHUFFLE(A, B, P) __builtin_shufflevector(A, B, P)

// 4×4 transposes, one in each 128-bit quarter: word j of m[i]'s quarter q to word i of c[j]'s
// quarter q.
LANES_INLINE void lanes_transpose4(const lanes_f* m, lanes_f* c) {
    lanes_f t0 = LANES_SHUFFLE(m[0], m[1], LANES_UNPACKLO);
    lanes_f t1 = LANES_SHUFFLE(m[0], m[1], LANES_UNPACKHI);
    lanes_f t2 = LANES_SHUFFLE(m[2], m[3], LANES_UNPACKLO);
    lanes_f t3 = LANES_SHUFFLE(m[2], m[3], LANES_UNPACKHI);
    c[0] = LANES_SHUFFLE(t0, t2, LANES_PAIRSLO);
    c[1] = LANES_SHUFFLE(t0, t2, LANES_PAIRSHI);
    c[2] = LANES_SHUFFLE(t1, t3, LANES_PAIRSLO);
    c[3] = LANES_SHUFFLE(t1, t3, LANES_PAIRSHI);
}

// 8×8 transposes of words in each 256-bit half: word j of m[i]'s half h to word i of c[j]'s
// half h (with eight lanes, the transpose of the eight vectors).
LANES_INLINE void lanes_transpose8(const lanes_f* m, lanes_f* c) {
    lanes_f s[8];
    // s[j]: word j of rows 0-3 in quarter 0 (and 2), word j + 4 in quarter 1 (and 3); s[j + 4]
    // the same for rows 4-7. Then the quarters of each word together.
    lanes_transpose4(m, s);
    lanes_transpose4(m + 4, s + 4);
#pragma unroll
    for (int i = 0; i < 4; ++i) {
        c[i] = LANES_SHUFFLE(s[i], s[i + 4], LANES_QUADSLO);
        c[i + 4] = LANES_SHUFFLE(s[i], s[i + 4], LANES_QUADSHI);
    }
}

// Words [w, w + 8) of the row at word offset off[l] of base, for each lane l, into c[0..8):
// word w + i of lane l in lane l of c[i].
LANES_INLINE void lanes_rows8(global const float* base, const int* off, int w, lanes_f* c) {
    lanes_f m[8];
#pragma unroll
    for (int i = 0; i < 8; ++i) m[i] = LANES_ROW8(base, off, w, i);
    lanes_transpose8(m, c);
}

// The same for words [w, w + 4), into c[0..4).
LANES_INLINE void lanes_rows4(global const float* base, const int* off, int w, lanes_f* c) {
    lanes_f m[4];
#pragma unroll
    for (int i = 0; i < 4; ++i) m[i] = LANES_ROW4(base, off, w, i);
    lanes_transpose4(m, c);
}

// The lanes' rays and walks, one field a lane (offsets are in 4-byte words: a GpuWideNode is 32,
// min_x, min_y, min_z, max_x, max_y, max_z, child, count, 4 each; a GpuTriangle 12):
//   ox oy oz     origin                      ix iy iz   safe reciprocal direction (prepare_ray's)
//   px py pz     origin in the permuted axes sx sy sz   shear (prepare_ray's)
//   kx ky kz     the permutation, as word offsets in a vertex
//   tfar         the nearest hit's t so far  hv hw hdet its edge functions v, w and their sum
//   prim         its triangle (NO_HIT, -1, while none)
//   cur          the item visited, in lanes_pack form: a node, or a leaf (negative)
//   sp           stack entries               live has fin: lanes with a ray, with an item to
//                                            visit, done and not yet returned by lanes_walk
//   any          lanes whose ray is a shadow ray: done at its first hit before tfar
#define LANES_FLOAT_FIELDS(X) X(ox) X(oy) X(oz) X(ix) X(iy) X(iz) X(px) X(py) X(pz) \
    X(sx) X(sy) X(sz) X(tfar) X(hv) X(hw) X(hdet)
#define LANES_INT_FIELDS(X) X(kx) X(ky) X(kz) X(prim) X(cur) X(sp) X(live) X(has) X(fin) X(any)

// The fields as vectors, as lanes_walk works on them.
typedef struct {
#define LANES_VECTOR_F(f) lanes_f f;
#define LANES_VECTOR_I(f) lanes_i f;
    LANES_FLOAT_FIELDS(LANES_VECTOR_F)
    LANES_INT_FIELDS(LANES_VECTOR_I)
#undef LANES_VECTOR_F
#undef LANES_VECTOR_I
} Lanes;

// What the lanes keep: their fields, their stacks and rays. The fields are one block seen two
// ways: lane by lane (`M->ox[l]`), as scalar code writes a lane's ray, and as Lanes' vectors
// (`M->V.ox`), which lanes_walk reads and writes where they are. The compiler keeps a walk's
// fields in memory either way (26 vectors with the walk's temporaries are more than the 32
// registers); a private copy for the walk, loaded as it began and stored as it returned, cost
// 3-6 % of the 1 M-triangle scenes' time in the copies (AMD Zen 4, 2026-12-03).
typedef struct {
    union {
        Lanes V;
        struct {
#define LANES_ARRAY_F(f) float f[LANES];
#define LANES_ARRAY_I(f) int f[LANES];
            LANES_FLOAT_FIELDS(LANES_ARRAY_F)
            LANES_INT_FIELDS(LANES_ARRAY_I)
#undef LANES_ARRAY_F
#undef LANES_ARRAY_I
        };
    };
    // The stacks: entry k of lane l at word 2 (l LANES_STACK_STRIDE + k) (LANES_ENTRY), its entry
    // distance, then its item in lanes_pack form (as float bits).
    float stack[2 * LANES_STACK_STRIDE * LANES];
    float3 o[LANES], d[LANES];  // the rays, for the scalar test's rare cases
} LaneMemory;

LANES_INLINE void lanes_init(LaneMemory* M) {
    for (int l = 0; l < LANES; ++l) {
#define LANES_ZERO(f) M->f[l] = 0;
        LANES_FLOAT_FIELDS(LANES_ZERO)
        LANES_INT_FIELDS(LANES_ZERO)
#undef LANES_ZERO
        M->hdet[l] = 1.0f;
        M->prim[l] = -1;
    }
}

// Rays given to lanes, lane by lane (scalar stores, which lanes_set_rays and packet_set_rays
// then load by vector: one wait for the stores a batch of rays, where a vector a field put
// together by selects lived on the stack, three instructions a field a ray): origins,
// directions, each ray's end (tmax), whether it is a shadow ray (any: done at its first hit),
// and the lanes that took one (bit l of `taken`). Lanes that took none keep stale values, which
// are computed on and discarded.
typedef struct {
    float ox[LANES], oy[LANES], oz[LANES], dx[LANES], dy[LANES], dz[LANES], tmax[LANES];
    int any[LANES];
    uint taken;
} LanesRays;

LANES_INLINE void lanes_rays_init(LanesRays* R) {
    for (int l = 0; l < LANES; ++l) {
        R->ox[l] = R->oy[l] = R->oz[l] = R->dx[l] = R->dy[l] = R->dz[l] = R->tmax[l] = 0.0f;
        R->any[l] = 0;
    }
    R->taken = 0u;
}

// Lane `lane` of R takes the ray from o along d, to tmax (any_hit: a shadow ray).
LANES_INLINE void lanes_rays_put(LanesRays* R, int lane, float3 o, float3 d, float tmax,
                                 bool any_hit) {
    R->ox[lane] = o.x;
    R->oy[lane] = o.y;
    R->oz[lane] = o.z;
    R->dx[lane] = d.x;
    R->dy[lane] = d.y;
    R->dz[lane] = d.z;
    R->tmax[lane] = tmax;
    R->any[lane] = any_hit ? -1 : 0;
    R->taken |= 1u << lane;
}

// A component of each lane's vector (X, Y, Z) picked by the lane's axis K (0, 1, 2).
#define LANES_PICK(X, Y, Z, K) select(select(X, Y, (K) == (lanes_i)(1)), Z, (K) == (lanes_i)(2))

// traverse_wide.h's slab test of one box (its planes LX .. HZ, scalars) in every lane, from the
// lanes' origins ox, oy, oz and reciprocal directions ix, iy, iz: declares NEAR (the entry
// distance, at least 0) and FAR. With lo <= hi the near plane's distance is the lesser of the
// two, bit for bit (rounding is monotonic), so no plane is picked by the direction's sign.
#define LANES_BOX(LX, LY, LZ, HX, HY, HZ, NEAR, FAR)                                         \
    lanes_f NEAR, FAR;                                                                      \
    {                                                                                       \
        lanes_f x0_ = ((lanes_f)(LX) - ox) * ix, x1_ = ((lanes_f)(HX) - ox) * ix;           \
        lanes_f y0_ = ((lanes_f)(LY) - oy) * iy, y1_ = ((lanes_f)(HY) - oy) * iy;           \
        lanes_f z0_ = ((lanes_f)(LZ) - oz) * iz, z1_ = ((lanes_f)(HZ) - oz) * iz;           \
        NEAR = WIDE_MAX(WIDE_MAX(WIDE_MIN(x0_, x1_), WIDE_MIN(y0_, y1_)),                   \
                        WIDE_MAX(WIDE_MIN(z0_, z1_), (lanes_f)(0.0f)));                     \
        FAR = WIDE_MIN(WIDE_MIN(WIDE_MAX(x0_, x1_), WIDE_MAX(y0_, y1_)), WIDE_MAX(z0_, z1_)) * \
              1.00000024f;                                                                  \
    }

// prepare_ray lane by lane on R's rays, by selects (no branch on the dominant axis; one division
// an axis for all the lanes): declares ix iy iz (the safe reciprocal direction), kx ky kz (the
// permutation: z the dominant axis), px py pz (the origin in the permuted axes) and sx sy sz
// (the shear), prepare_ray's values bit for bit.
#define LANES_PREPARE_RAYS(OX, OY, OZ, DX, DY, DZ)                                            \
    lanes_f ix, iy, iz, px, py, pz, sx, sy, sz;                                               \
    lanes_i kx, ky, kz;                                                                       \
    {                                                                                         \
        const lanes_f tiny_ = (lanes_f)(1e-20f), one_ = (lanes_f)(1.0f);                      \
        lanes_f ax_ = fabs(DX), ay_ = fabs(DY), az_ = fabs(DZ);                               \
        ix = one_ / select(copysign(tiny_, DX), DX, ax_ > tiny_);                             \
        iy = one_ / select(copysign(tiny_, DY), DY, ay_ > tiny_);                             \
        iz = one_ / select(copysign(tiny_, DZ), DZ, az_ > tiny_);                             \
        const lanes_i two_ = (lanes_i)(2);                                                    \
        kz = select(select(two_, (lanes_i)(1), ay_ > az_), select(two_, (lanes_i)(0), ax_ > az_), \
                    ax_ > ay_);                                                               \
        kx = select(select((lanes_i)(1), two_, kz == (lanes_i)(1)), (lanes_i)(0), kz == two_);  \
        ky = select(select(two_, (lanes_i)(0), kz == (lanes_i)(1)), (lanes_i)(1), kz == two_);  \
        lanes_f rz_ = LANES_PICK(ix, iy, iz, kz);                                             \
        sx = LANES_PICK(DX, DY, DZ, kx) * rz_;                                                \
        sy = LANES_PICK(DX, DY, DZ, ky) * rz_;                                                \
        sz = rz_;                                                                             \
        px = LANES_PICK(OX, OY, OZ, kx);                                                      \
        py = LANES_PICK(OX, OY, OZ, ky);                                                      \
        pz = LANES_PICK(OX, OY, OZ, kz);                                                      \
    }

// R's rays as vectors: declares ox oy oz (origins), dx dy dz (directions), then
// LANES_PREPARE_RAYS's values.
#define LANES_LOAD_RAYS(R)                                                                    \
    lanes_f ox = lanes_vload(0, (R)->ox), oy = lanes_vload(0, (R)->oy);                       \
    lanes_f oz = lanes_vload(0, (R)->oz), dx = lanes_vload(0, (R)->dx);                       \
    lanes_f dy = lanes_vload(0, (R)->dy), dz = lanes_vload(0, (R)->dz);                       \
    LANES_PREPARE_RAYS(ox, oy, oz, dx, dy, dz)

// Lane `lane` will take the ray from o along d, to tmax (any_hit: a shadow ray, done at its
// first hit: any one, a hit says the segment is blocked); lanes_set_rays gives it the ray.
LANES_INLINE void lanes_take_ray(LaneMemory* M, LanesRays* R, int lane, float3 o, float3 d,
                                 float tmax, bool any_hit) {
    lanes_rays_put(R, lane, o, d, tmax, any_hit);
    M->o[lane] = o;
    M->d[lane] = d;
}

// The lanes that took rays in R take them, with no hit yet, written by vector (the walk reads them by
// vector: a vector load of words just stored one by one would wait for the stores, and the ray's
// set-up lane by lane cost 100 scalar instructions, with a branch on its dominant axis).
LANES_INLINE void lanes_set_rays(LaneMemory* M, const LanesRays* R) {
    Lanes* L = &M->V;
    const lanes_i m =
        ((lanes_i)((int)R->taken) >> LANE_IDS & (lanes_i)(1)) != (lanes_i)(0);
    LANES_LOAD_RAYS(R)
    L->ox = select(L->ox, ox, m);
    L->oy = select(L->oy, oy, m);
    L->oz = select(L->oz, oz, m);
    L->ix = select(L->ix, ix, m);
    L->iy = select(L->iy, iy, m);
    L->iz = select(L->iz, iz, m);
    L->px = select(L->px, px, m);
    L->py = select(L->py, py, m);
    L->pz = select(L->pz, pz, m);
    L->sx = select(L->sx, sx, m);
    L->sy = select(L->sy, sy, m);
    L->sz = select(L->sz, sz, m);
    L->kx = select(L->kx, kx, m);
    L->ky = select(L->ky, ky, m);
    L->kz = select(L->kz, kz, m);
    L->tfar = select(L->tfar, lanes_vload(0, R->tmax), m);
    // No hit: hv, hw and hdet are read only with a hit, which sets them.
    L->prim = select(L->prim, (lanes_i)(-1), m);
    L->sp = select(L->sp, (lanes_i)(0), m);
    L->any = select(L->any, lanes_vload(0, R->any), m);
    L->cur = select(L->cur, (lanes_i)(0), m);
    L->live |= m;
    L->has |= m;
}

// A lane's hit from its fields: distance, triangle (NO_HIT: none), edge functions v, w and
// their sum.
LANES_INLINE GpuHit lanes_hit_from(float t, int prim, float v, float w, float det) {
    GpuHit h;
    h.t = t;
    h.prim = (uint)prim;
    h.u = h.prim == NO_HIT ? 0.0f : v / det;
    h.v = h.prim == NO_HIT ? 0.0f : w / det;
    h.instance = 0u;
    return h;
}

// The hit of a lane whose walk is done.
LANES_INLINE GpuHit lanes_hit(const LaneMemory* M, int lane) {
    return lanes_hit_from(M->tfar[lane], M->prim[lane], M->hv[lane], M->hw[lane],
                          M->hdet[lane]);
}

// The lanes' watertight test's rare cases (an edge function of zero, a hit within the
// rounding-error bound): for each lane of `special`, the scalar test (intersect_leaf: double-
// precision edge functions, the error bound) decides triangle tri of that lane's ray o, d,
// with the lane's hit so far in *t, *v, *w, *det, *prim, which it updates.
LANES_INLINE void lanes_rare_cases(lanes_i special, lanes_i tri, const float3* o, const float3* d,
                                   global const GpuTriangle* tris, const SceneSurfaces* surf,
                                   bool any_hit, lanes_f* t, lanes_f* v, lanes_f* w,
                                   lanes_f* det, lanes_i* prim) {
    int sp_[LANES], tri_[LANES], prim_[LANES];
    float t_[LANES], v_[LANES], w_[LANES], det_[LANES];
    lanes_vstore(special, 0, sp_);
    lanes_vstore(tri, 0, tri_);
    lanes_vstore(*t, 0, t_);
    lanes_vstore(*v, 0, v_);
    lanes_vstore(*w, 0, w_);
    lanes_vstore(*det, 0, det_);
    lanes_vstore(*prim, 0, prim_);
    for (int l = 0; l < LANES; ++l) {
        if (!sp_[l]) continue;
        RayPrep r = prepare_ray(o[l], d[l]);
        GpuHit h = no_hit(t_[l]);
        intersect_leaf(&r, tris, surf, (uint)tri_[l], 1u, 0.0f, o[l], d[l], any_hit, &h);
        if (h.prim != NO_HIT) {
            t_[l] = h.t;
            v_[l] = h.u;
            w_[l] = h.v;
            det_[l] = 1.0f;
            prim_[l] = (int)h.prim;
        }
    }
    *t = lanes_vload(0, t_);
    *v = lanes_vload(0, v_);
    *w = lanes_vload(0, w_);
    *det = lanes_vload(0, det_);
    *prim = lanes_vload(0, prim_);
}

// After LANE_HITS_T (t, v, w, det, ok, special): triangle I's hits kept in the lanes of ok,
// nearer than their hits so far (tfar, hv, hw, hdet, prim), the scalar test deciding the
// lanes of special (whose rays are O[l], D[l]).
#define LANES_KEEP_HITS(I, O, D, ANY_HIT)                                                    \
    {                                                                                        \
        const lanes_i i_ = (lanes_i)(I);                                                     \
        ok &= ~special;                                                                      \
        tfar = select(tfar, t, ok);                                                          \
        hv = select(hv, v, ok);                                                              \
        hw = select(hw, w, ok);                                                              \
        hdet = select(hdet, det, ok);                                                        \
        prim = select(prim, i_, ok);                                                         \
        if (lanes_any(special)) {                                                            \
            lanes_rare_cases(special, i_, O, D, tris, surf, ANY_HIT, &tfar, &hv, &hw, &hdet, \
                             &prim);                                                         \
        }                                                                                    \
    }

// Lanes at a leaf are tested together once at least this many are (the others wait at it).
// Six of sixteen and three of eight measured fastest; two or four of eight were no faster on
// AMD's Zen 3 (2026-12-04).
#ifndef LANES_LEAF_MIN
#define LANES_LEAF_MIN (LANES == 16 ? 6 : 3)
#endif

// lanes_walk returns once this many lanes are done (or none is left walking): each return
// costs the shading loop's round over the lanes and the lanes' vectors to and from memory.
#ifndef LANES_DONE_MIN
#define LANES_DONE_MIN (LANES / 4)
#endif

// An item (the one a lane visits, or a stack entry) in one word: an interior child's index,
// or a leaf (child ~first, count k) as the sign bit, k in the next four bits and first below
// (the host enables lanes only for scenes of fewer than 2^27 triangles and leaves of at most
// 15: lanes_megakernel).
#define LANES_FIRST_MASK 0x07ffffff
LANES_INLINE lanes_i lanes_pack(lanes_i c, lanes_i k) {
    return select(c, (lanes_i)(0x80000000) | (k << (lanes_i)(27)) | ~c, k != (lanes_i)(0));
}

// Starts loading, for each lane of m, `bytes` bytes from element `first` (of `size` bytes) of
// the array at `base` into the caches, one prefetch a 64 bytes and no branch but the loop over
// the lanes (a lane reaching a leaf waits for others to reach theirs, a lane done for others
// to finish: the loads meanwhile cost nothing). The last byte's line is fetched too where an
// element may straddle one more line than the loop reaches; elements of whole lines (the
// nodes, 128 bytes, in buffers aligned to pages) need no such fetch, and after inlining the
// test folds away.
// With eight lanes every lane prefetches, those outside m element 0 (the root node, the first
// triangle: cached), with no branch but the mask's test: the loop over m's lanes took 6 % more
// time on the 1 M-triangle scenes on Zen 3; sixteen lanes keep the loop (not measured where
// they run).

// lanes_prefetch's loads of one element, at a.
LANES_INLINE void lanes_prefetch_element(ulong a, uint size, uint bytes) {
#pragma unroll
    for (uint o = 0u; o < bytes; o += 64u) __builtin_prefetch((const void*)(a + o));
    if (size % 64u != 0u || bytes % 64u != 0u) __builtin_prefetch((const void*)(a + bytes - 1u));
}

LANES_INLINE void lanes_prefetch(ulong base, lanes_i first, uint size, uint bytes, lanes_i m) {
    uint bits = lanes_kmask(m);
    if (bits == 0u) return;
#if LANES == 8
    // The lanes' byte offsets as one vector of 64-bit words (one shift or multiply for all
    // lanes, 10-25 % fewer instructions in the prefetches than offsets lane by lane).
    long at_[LANES];
    vstore8(convert_long8(select((lanes_i)(0), first, m)) * (long8)((long)size), 0, at_);
#pragma unroll
    for (int l = 0; l < LANES; ++l) lanes_prefetch_element(base + (ulong)at_[l], size, bytes);
#else
    int first_[LANES];
    lanes_vstore(first, 0, first_);
    while (bits != 0u) {
        uint l = (uint)__builtin_ctz(bits);
        bits &= bits - 1u;
        lanes_prefetch_element(base + (ulong)first_[l] * size, size, bytes);
    }
#endif
}

// The triangles prefetched of a leaf (a fixed number: a loop over each leaf's own count cost
// more in mispredicted branches than it saved; 2, 3 and 4 measured alike).
#ifndef LANES_PREFETCH_TRIS
#define LANES_PREFETCH_TRIS 4
#endif

// The node of NODES each lane of M goes to next (ITEM, if a node): its two cache lines are
// fetched as the lane takes it, a node step's leaves and pops before the step loads it, so the
// sixteen lanes' misses overlap that work (4-8 % of the 1 M-triangle scenes' time on Zen 4).
#define LANES_PREFETCH_NODE(NODES, ITEM, M)                                                 \
    lanes_prefetch((ulong)(NODES), (ITEM), sizeof(GpuWideNode), sizeof(GpuWideNode),       \
                   (M) & ((ITEM) >= (lanes_i)(0)));

// Triangle TRI of each lane of mask M (tw: the triangles as words), its vertices relative to
// the lane's origin in its permuted axes (KX, KY, KZ: 0, 1 or 2; PX, PY, PZ): declares aX ..
// cZ. Lanes outside M read triangle 0.
#ifdef LANES_GATHERS
#define LANES_TRIANGLE(TRI, M, KX, KY, KZ, PX, PY, PZ)                          \
    lanes_i b_ = (TRI) * (lanes_i)(12);                                          \
    lanes_f aX = LANES_GATHER_F(tw, b_ + (KX), M) - (PX);                     \
    lanes_f aY = LANES_GATHER_F(tw, b_ + (KY), M) - (PY);                     \
    lanes_f aZ = LANES_GATHER_F(tw, b_ + (KZ), M) - (PZ);                     \
    lanes_f bX = LANES_GATHER_F(tw, b_ + (lanes_i)(4) + (KX), M) - (PX);        \
    lanes_f bY = LANES_GATHER_F(tw, b_ + (lanes_i)(4) + (KY), M) - (PY);        \
    lanes_f bZ = LANES_GATHER_F(tw, b_ + (lanes_i)(4) + (KZ), M) - (PZ);        \
    lanes_f cX = LANES_GATHER_F(tw, b_ + (lanes_i)(8) + (KX), M) - (PX);        \
    lanes_f cY = LANES_GATHER_F(tw, b_ + (lanes_i)(8) + (KY), M) - (PY);        \
    lanes_f cZ = LANES_GATHER_F(tw, b_ + (lanes_i)(8) + (KZ), M) - (PZ);
#else
// As rows: each vertex's words in the lane's permuted axes by selects.
#define LANES_TRIANGLE(TRI, M, KX, KY, KZ, PX, PY, PZ)                          \
    int off_[LANES];                                                         \
    lanes_vstore(select((lanes_i)(0), (TRI) * (lanes_i)(12), M), 0, off_);           \
    lanes_f T[12];                                                           \
    lanes_rows8(tw, off_, 0, T);                                             \
    lanes_rows4(tw, off_, 8, T + 8);                                         \
    lanes_i kx1_ = (KX) == (lanes_i)(1), kx2_ = (KX) == (lanes_i)(2);              \
    lanes_i ky1_ = (KY) == (lanes_i)(1), ky2_ = (KY) == (lanes_i)(2);              \
    lanes_i kz1_ = (KZ) == (lanes_i)(1), kz2_ = (KZ) == (lanes_i)(2);              \
    lanes_f aX = LANES_AXIS(0, kx) - (PX);                                   \
    lanes_f aY = LANES_AXIS(0, ky) - (PY);                                   \
    lanes_f aZ = LANES_AXIS(0, kz) - (PZ);                                   \
    lanes_f bX = LANES_AXIS(4, kx) - (PX);                                   \
    lanes_f bY = LANES_AXIS(4, ky) - (PY);                                   \
    lanes_f bZ = LANES_AXIS(4, kz) - (PZ);                                   \
    lanes_f cX = LANES_AXIS(8, kx) - (PX);                                   \
    lanes_f cY = LANES_AXIS(8, ky) - (PY);                                   \
    lanes_f cZ = LANES_AXIS(8, kz) - (PZ);
#define LANES_AXIS(V, K) select(select(T[V], T[V + 1], K##1_), T[V + 2], K##2_)
#endif

// The most (lane, triangle) pairs a leaf step tests sixteen at a time (more: one triangle of
// every lane at a time).
#ifndef LANES_PAIRS_MAX
#define LANES_PAIRS_MAX 64
#endif

// Compare-exchange of two (distance, item) pairs in every lane, nearest first.
#define LANES_ORDER(A, B)                      \
    {                                          \
        lanes_i s = d##B < d##A;                 \
        lanes_f td = d##A;                     \
        d##A = select(d##A, d##B, s);          \
        d##B = select(d##B, td, s);            \
        lanes_i tc = c##A;                       \
        c##A = select(c##A, c##B, s);          \
        c##B = select(c##B, tc, s);            \
    }

// Walks the lanes' rays until LANES_DONE_MIN are done or none is left walking; returns the
// mask of those done (their `live` lanes cleared). No lane live: returns an empty mask.
LANES_INLINE lanes_i lanes_walk(LaneMemory* M, global const GpuWideNode* nodes,
                              global const GpuTriangle* tris, const SceneSurfaces* surf,
                              volatile global uint* overflow) {
    const lanes_f inf = (lanes_f)(INFINITY), zero = (lanes_f)(0.0f);
    const lanes_i izero = (lanes_i)(0), lane = LANE_IDS;
    global const float* nw = (global const float*)nodes;
    global const float* tw = (global const float*)tris;
    Lanes* L = &M->V;
    while (lanes_any(L->live)) {
        lanes_i arrived = izero;  // lanes that reached a leaf in this round
        // Interior nodes.
        lanes_i mi = L->has & (L->cur >= izero);
        if (lanes_any(mi)) {
            lanes_i base = L->cur * (lanes_i)(32);
// Child J's slab test in every lane of mi from its near and far planes (NX .. FZ) and its
// child and count words (C, K): declares d##J, the entry distance of a reached child (else
// infinity), and sets c##J to its item in lanes_pack form.
#define LANES_CHILD(J, NX, NY, NZ, FX, FY, FZ, C, K)                                         \
    lanes_f d##J;                                                                         \
    {                                                                                     \
        lanes_f x0 = (NX - L->ox) * L->ix, y0 = (NY - L->oy) * L->iy;                     \
        lanes_f nr = select(x0, y0, y0 > x0);                                             \
        lanes_f z0 = (NZ - L->oz) * L->iz;                                                \
        nr = select(nr, z0, z0 > nr);                                                     \
        nr = select(nr, zero, zero > nr);                                                 \
        lanes_f x1 = (FX - L->ox) * L->ix, y1 = (FY - L->oy) * L->iy;                     \
        lanes_f fr = select(x1, y1, y1 < x1);                                             \
        lanes_f z1 = (FZ - L->oz) * L->iz;                                                \
        fr = select(fr, z1, z1 < fr) * 1.00000024f;                                       \
        lanes_i cw = (C), kw = (K);                                                         \
        lanes_i reach = mi & ((cw > izero) | (kw != izero)) & (nr <= fr) & (nr < L->tfar);  \
        d##J = select(inf, nr, reach);                                                    \
        c##J = lanes_pack(cw, kw);                                                        \
    }
            lanes_i c0, c1, c2, c3;
#ifdef LANES_GATHERS
            // Children J and J + 1 at once: a row's words of two children are side by side, so
            // one 8-byte gather element brings both (half the gathered elements).
            ushort km = lanes_kmask(mi);
            lanes_i nx = select((lanes_i)(12), izero, L->ix >= zero);
            lanes_i ny = select((lanes_i)(16), (lanes_i)(4), L->iy >= zero);
            lanes_i nz = select((lanes_i)(20), (lanes_i)(8), L->iz >= zero);
            lanes_i fx = (lanes_i)(12) - nx, fy = (lanes_i)(20) - ny, fz = (lanes_i)(28) - nz;
#define LANES_CHILDREN(J, K)                                                                \
    lanes_f nx##J, nx##K, ny##J, ny##K, nz##J, nz##K, fx##J, fx##K, fy##J, fy##K, fz##J,    \
        fz##K, cw##J, cw##K, kw##J, kw##K;                                                  \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J) + nx, km, nx##J, nx##K);                        \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J) + ny, km, ny##J, ny##K);                        \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J) + nz, km, nz##J, nz##K);                        \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J) + fx, km, fx##J, fx##K);                        \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J) + fy, km, fy##J, fy##K);                        \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J) + fz, km, fz##J, fz##K);                        \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J + 24), km, cw##J, cw##K);                        \
    LANES_GATHER_PAIR(nw, base + (lanes_i)(J + 28), km, kw##J, kw##K);                        \
    LANES_CHILD(J, nx##J, ny##J, nz##J, fx##J, fy##J, fz##J, as_lanes_i(cw##J), as_lanes_i(kw##J)) \
    LANES_CHILD(K, nx##K, ny##K, nz##K, fx##K, fy##K, fz##K, as_lanes_i(cw##K), as_lanes_i(kw##K))
            LANES_CHILDREN(0, 1)
            LANES_CHILDREN(2, 3)
#else
            // The nodes as rows, one axis at a time (each child's near and far distances
            // folded in as in LANES_CHILD, x, y, z in turn), so that only one axis's planes and
            // the running distances are live: the 32 words of a node at once were more vectors
            // than registers.
            int off_[LANES];
            lanes_vstore(select(izero, base, mi), 0, off_);
            lanes_f d0, d1, d2, d3, f0, f1, f2, f3;
            {
                lanes_f lo[4], hi[4];
                lanes_i pos = L->ix >= zero;
                lanes_rows4(nw, off_, 0, lo);
                lanes_rows4(nw, off_, 12, hi);
#define LANES_SLAB_X(J)                                                \
    d##J = (select(hi[J], lo[J], pos) - L->ox) * L->ix;              \
    f##J = (select(lo[J], hi[J], pos) - L->ox) * L->ix;
                LANES_SLAB_X(0) LANES_SLAB_X(1) LANES_SLAB_X(2) LANES_SLAB_X(3)
#undef LANES_SLAB_X
            }
#define LANES_SLAB(J, O, I)                                                              \
    {                                                                                  \
        lanes_f n_ = (select(hi[J], lo[J], pos) - L->O) * L->I;                        \
        lanes_f f_ = (select(lo[J], hi[J], pos) - L->O) * L->I;                        \
        d##J = select(d##J, n_, n_ > d##J);                                            \
        f##J = select(f##J, f_, f_ < f##J);                                            \
    }
// The axis of origin O and reciprocal I, its planes at words WLO (minima) and WHI (maxima).
#define LANES_SLABS(WLO, WHI, O, I)                                                   \
    {                                                                               \
        lanes_f lo[4], hi[4];                                                       \
        lanes_i pos = L->I >= zero;                                                 \
        lanes_rows4(nw, off_, WLO, lo);                                             \
        lanes_rows4(nw, off_, WHI, hi);                                             \
        LANES_SLAB(0, O, I) LANES_SLAB(1, O, I) LANES_SLAB(2, O, I) LANES_SLAB(3, O, I) \
    }
            LANES_SLABS(4, 16, oy, iy)
            LANES_SLABS(8, 20, oz, iz)
#undef LANES_SLABS
#undef LANES_SLAB
            lanes_f W[8];
            lanes_rows8(nw, off_, 24, W);
#define LANES_CHILDREN(J)                                                                   \
    {                                                                                       \
        lanes_f nr = select(d##J, zero, zero > d##J), fr = f##J * 1.00000024f;              \
        lanes_i cw = as_lanes_i(W[J]), kw = as_lanes_i(W[4 + J]);                           \
        lanes_i reach = mi & ((cw > izero) | (kw != izero)) & (nr <= fr) & (nr < L->tfar);  \
        d##J = select(inf, nr, reach);                                                    \
        c##J = lanes_pack(cw, kw);                                                        \
    }
            LANES_CHILDREN(0)
            LANES_CHILDREN(1)
            LANES_CHILDREN(2)
            LANES_CHILDREN(3)
#endif
#undef LANES_CHILDREN
#undef LANES_CHILD
            LANES_ORDER(0, 1)
            LANES_ORDER(2, 3)
            LANES_ORDER(0, 2)
            LANES_ORDER(1, 3)
            LANES_ORDER(1, 2)
            // A lane about to overflow its stack ends its walk with the hit so far (as
            // traverse_wide_bvh does; the overflow is counted).
            lanes_i full = mi & (L->sp > (lanes_i)(LANES_STACK - 4));
            if (lanes_any(full)) {
                atomic_add(overflow, (uint)lanes_count(full));
                L->sp = select(L->sp, izero, full);
                mi &= ~full;
                L->has &= ~full;
            }
            // The reached children but the nearest pushed, farthest first; the nearest entered.
#if LANES == 8
            // Eight lanes: a lane's pushed entries are one 32-byte store at its stack pointer.
            // The reached children are a prefix of 1, 2, 3 (sorted; the others at infinity),
            // so the entries, farthest first, are selects: the top is child 1, below it 2, 3.
            {
                lanes_i p1 = mi & (d1 < inf), p2 = mi & (d2 < inf), p3 = mi & (d3 < inf);
                lanes_f e[8];
                e[0] = select(select(d1, d2, p2), d3, p3);
                e[1] = as_lanes_f(select(select(c1, c2, p2), c3, p3));
                e[2] = select(d1, d2, p3);
                e[3] = as_lanes_f(select(c1, c2, p3));
                e[4] = d1;
                e[5] = as_lanes_f(c1);
                e[6] = e[7] = zero;
                lanes_f rows[8];
                lanes_transpose8(e, rows);
                int at_[LANES];
                lanes_vstore(LANES_ENTRY(L->sp), 0, at_);
#pragma unroll
                for (int l = 0; l < LANES; ++l) vstore8(rows[l], 0, M->stack + at_[l]);
                L->sp -= p1 + p2 + p3;
            }
#else
#define LANES_PUSH(J)                                                              \
    {                                                                              \
        lanes_i p = mi & (d##J < inf);                                               \
        LANES_PUSH_PAIR(M->stack, LANES_ENTRY(L->sp), lanes_kmask(p), d##J,        \
                        as_lanes_f(c##J));                                         \
        L->sp -= p;                                                                \
    }
            LANES_PUSH(3)
            LANES_PUSH(2)
            LANES_PUSH(1)
#undef LANES_PUSH
#endif
            lanes_i enter = mi & (d0 < inf);
            arrived |= enter & (c0 < izero);
            L->cur = select(L->cur, c0, enter);
            LANES_PREFETCH_NODE(nodes, c0, enter)
            L->has &= ~(mi & ~enter);
        }
        // Leaves, once enough lanes are at one (or no lane is at a node).
        lanes_i ml = L->has & (L->cur < izero);
        if (lanes_any(ml) && (lanes_count(ml) >= LANES_LEAF_MIN || !lanes_any(L->has & ~ml))) {
            lanes_i first = L->cur & (lanes_i)(LANES_FIRST_MASK);
            lanes_i cnt = (L->cur >> (lanes_i)(27)) & (lanes_i)(15);
            int kmax = lanes_max(select(izero, cnt, ml));
            // The leaves' (lane, triangle) pairs in order, each lane's first triangle before its
            // second (pl, pt): sixteen pairs a test, not one triangle of every lane a test, of
            // which the lanes whose leaves are done (or that wait at a node) would take no part.
            int pl[LANES_PAIRS_MAX + LANES], pt[LANES_PAIRS_MAX + LANES];
            int pairs = 0;
            bool by_k = kmax > LANES_PAIRS_MAX / LANES;
            for (int k = 0; k < kmax && !by_k; ++k) {
                ushort km = lanes_kmask(ml & ((lanes_i)(k) < cnt));
                lanes_vstore(lanes_compress(lane, km), 0, pl + pairs);
                lanes_vstore(lanes_compress(first + (lanes_i)(k), km), 0, pt + pairs);
                pairs += popcount((uint)km);
            }
            // Each pair's verdict against its lane's hit before the leaves (the nearest of a
            // lane's hits is then kept, the first of equally near ones: the walk by triangle
            // order's). A pair that needs the scalar test sends the leaves to that walk.
            float rt[LANES_PAIRS_MAX], rv[LANES_PAIRS_MAX], rw[LANES_PAIRS_MAX];
            float rdet[LANES_PAIRS_MAX];
            uint hits[LANES_PAIRS_MAX / LANES], found = 0u;
            for (int p0 = 0; p0 < pairs && !by_k; p0 += LANES) {
                lanes_i idx = lanes_vload(0, pl + p0);
                lanes_i tri = lanes_vload(0, pt + p0);
                lanes_i m = (lane + (lanes_i)(p0)) < (lanes_i)(pairs);
                idx = select(izero, idx, m);
                lanes_i kx = lanes_permute_i(L->kx, idx), ky = lanes_permute_i(L->ky, idx);
                lanes_i kz = lanes_permute_i(L->kz, idx);
                lanes_f px = lanes_permute(L->px, idx), py = lanes_permute(L->py, idx);
                lanes_f pz = lanes_permute(L->pz, idx);
                lanes_f sx = lanes_permute(L->sx, idx), sy = lanes_permute(L->sy, idx);
                lanes_f sz = lanes_permute(L->sz, idx);
                LANES_TRIANGLE(tri, m, kx, ky, kz, px, py, pz)
                LANE_EDGES(lanes_f)
                LANE_HITS_T(lanes_f, lanes_i, m, zero, lanes_permute(L->tfar, idx))
                by_k = lanes_any(special);
                lanes_vstore(t, 0, rt + p0);
                lanes_vstore(v, 0, rv + p0);
                lanes_vstore(w, 0, rw + p0);
                lanes_vstore(det, 0, rdet + p0);
                hits[p0 / LANES] = lanes_kmask(ok);
                found |= hits[p0 / LANES];
            }
            // No pair hit: the lanes' hits stand as they are. Else each hit, in pair order,
            // replaces its lane's if nearer, by selects (no branch on the distances, and no
            // vector load of words just stored one by one, which waits for the stores).
            if (!by_k && found != 0u) {
                lanes_f tf = L->tfar, hv = L->hv, hw = L->hw, hdet = L->hdet;
                lanes_i prim = L->prim;
                for (int p0 = 0; p0 < pairs; p0 += LANES) {
                    for (uint h = hits[p0 / LANES]; h != 0u; h &= h - 1u) {
                        int i = p0 + (int)__builtin_ctz(h);
                        lanes_f t_ = (lanes_f)(rt[i]);
                        lanes_i nearer = (lane == (lanes_i)(pl[i])) & (t_ < tf);
                        tf = select(tf, t_, nearer);
                        hv = select(hv, (lanes_f)(rv[i]), nearer);
                        hw = select(hw, (lanes_f)(rw[i]), nearer);
                        hdet = select(hdet, (lanes_f)(rdet[i]), nearer);
                        prim = select(prim, (lanes_i)(pt[i]), nearer);
                    }
                }
                L->tfar = tf;
                L->hv = hv;
                L->hw = hw;
                L->hdet = hdet;
                L->prim = prim;
            }
            if (!by_k) kmax = 0;  // done: no walk by triangle order
            // The leaves one triangle of every lane at a time, in order, each lane's hit updated
            // as it goes; the scalar test's rare cases in turn.
            for (int k = 0; k < kmax; ++k) {
                lanes_i m = ml & ((lanes_i)(k) < cnt);
                lanes_i tri = first + (lanes_i)(k);
                LANES_TRIANGLE(tri, m, L->kx, L->ky, L->kz, L->px, L->py, L->pz)
                lanes_f sx = L->sx, sy = L->sy, sz = L->sz;
                LANE_EDGES(lanes_f)
                LANE_HITS_T(lanes_f, lanes_i, m, zero, L->tfar)
                ok &= ~special;
                L->tfar = select(L->tfar, t, ok);
                L->hv = select(L->hv, v, ok);
                L->hw = select(L->hw, w, ok);
                L->hdet = select(L->hdet, det, ok);
                L->prim = select(L->prim, tri, ok);
                if (lanes_any(special)) {
                    lanes_rare_cases(special, tri, M->o, M->d, tris, surf, false, &L->tfar,
                                     &L->hv, &L->hw, &L->hdet, &L->prim);
                }
            }
            // A shadow ray that hit something is done: its stack emptied.
            L->sp = select(L->sp, izero, ml & L->any & (L->prim >= izero));
            L->has &= ~ml;
        }
        // The lanes without an item pop one, passing over entries beyond their hit; a lane
        // with an empty stack is done.
        lanes_i done = izero;
        for (int round = 0; round < 3; ++round) {
            lanes_i pm = L->live & ~L->has & ~done;
            if (!lanes_any(pm)) break;
            lanes_i m = pm & (L->sp > izero);
            done |= pm & ~m;
            if (!lanes_any(m)) break;
            L->sp += m;
            lanes_i at = LANES_ENTRY(L->sp);
            lanes_f d, itemf;
            LANES_POP_PAIR(M->stack, at, lanes_kmask(m), d, itemf)
            lanes_i keep = m & (d < L->tfar);
            lanes_i item = as_lanes_i(itemf);
            L->cur = select(L->cur, item, keep);
            L->has |= keep;
            arrived |= keep & (item < izero);
            LANES_PREFETCH_NODE(nodes, item, keep)
        }
        // A leaf waits for other lanes to reach theirs: its triangles are fetched meanwhile.
        lanes_prefetch((ulong)tris, L->cur & (lanes_i)(LANES_FIRST_MASK), sizeof(GpuTriangle),
                       LANES_PREFETCH_TRIS * sizeof(GpuTriangle), arrived & L->has);
        done &= L->live;
        // What shading reads of the hit (the triangle was just read).
        lanes_prefetch((ulong)surf->shading, L->prim, sizeof(GpuTriShading), sizeof(GpuTriShading),
                       done & (L->prim >= izero));
        L->live &= ~done;
        L->fin |= done;
        if (lanes_count(L->fin) >= LANES_DONE_MIN || !lanes_any(L->live)) {
            lanes_i fin = L->fin;
            L->fin = izero;
            return fin;
        }
    }
    return (lanes_i)(0);
}

#ifdef LANES_SMALL
// A small scene (LANES_SMALL: at most SMALL_SCENE_MAX triangles) is tested whole rather than
// walked: the root's four child boxes against every live lane, then each reached child's
// triangles against the lanes that reach it, all of them, with no stack and no turns at nodes,
// leaves and pops. A triangle's words are the same in every lane (loaded once, no gather), and
// every lane is done in one call. A subtree's triangles are a range in the tree's order; a
// ray that leaves the scene from a surface (an open scene's sky) still skips the children it
// does not reach.

// The triangles under each of the root's children: [first[j], end[j]) (empty for an empty
// slot), found once a work item by a walk of the small tree. A range covers its subtree's
// leaves (were they not contiguous, it would cover triangles of other children too, which are
// then tested twice, with the same verdicts).
LANES_INLINE void lanes_small_ranges(global const GpuWideNode* nodes, uint count, uint* first,
                                     uint* end) {
    // Child i of node n: a leaf widens the range, an interior node is walked later.
#define LANES_SMALL_CHILD(n, i)                                                        \
    {                                                                                  \
        int c_ = ((global const int*)&nodes[n].child)[i];                              \
        uint k_ = ((global const uint*)&nodes[n].count)[i];                            \
        if (k_ != 0u) {                                                                \
            first[j] = min(first[j], (uint)~c_);                                       \
            end[j] = max(end[j], (uint)~c_ + k_);                                      \
        } else if (c_ > 0) {                                                           \
            stack[sp++] = c_;                                                          \
        }                                                                              \
    }
    for (int j = 0; j < 4; ++j) {
        first[j] = count;
        end[j] = 0u;
        int stack[LANES_STACK];
        int sp = 0;
        LANES_SMALL_CHILD(0, j)
        while (sp > 0) {
            if (sp + 4 > LANES_STACK) {
                // Deeper than a tree of so few triangles can be: all of them.
                first[j] = 0u;
                end[j] = count;
                break;
            }
            int n = stack[--sp];
            for (int i = 0; i < 4; ++i) LANES_SMALL_CHILD(n, i)
        }
        end[j] = min(end[j], count);
    }
#undef LANES_SMALL_CHILD
}

// Every live lane's ray against the triangles of the root's children it reaches (ranges:
// lanes_small_ranges's), each child's in order; the nearest hit is kept, the first of equally
// near ones (the verdicts are the leaf steps': LANE_EDGES, LANE_HITS_T, the scalar test's rare
// cases). Returns the lanes done: all that were live.
LANES_INLINE lanes_i lanes_walk_small(LaneMemory* M, global const GpuWideNode* nodes,
                                      global const GpuTriangle* tris, const uint* first,
                                      const uint* end, const SceneSurfaces* surf) {
    Lanes* L = &M->V;
    const lanes_i live = L->live;
    if (!lanes_any(live)) return (lanes_i)(0);
    const lanes_f zero = (lanes_f)(0.0f);
    global const float4* tv = (global const float4*)tris;
    const lanes_i kx = L->kx, ky = L->ky, kz = L->kz;
    const lanes_f ox = L->ox, oy = L->oy, oz = L->oz, ix = L->ix, iy = L->iy, iz = L->iz;
    const lanes_f px = L->px, py = L->py, pz = L->pz, sx = L->sx, sy = L->sy, sz = L->sz;
    lanes_f tfar = L->tfar, hv = L->hv, hw = L->hw, hdet = L->hdet;
    lanes_i prim = L->prim;
    global const float* r = (global const float*)nodes;  // the root: min_x .. max_z, 4 words each
    for (int j = 0; j < 4; ++j) {
        if (first[j] >= end[j]) continue;
        LANES_BOX(r[j], r[4 + j], r[8 + j], r[12 + j], r[16 + j], r[20 + j], near, far)
        const lanes_i m = live & (near <= far) & (near < tfar);
        if (!lanes_any(m)) continue;
        for (uint i = first[j]; i < end[j]; ++i) {
            float4 a = tv[3u * i], b = tv[3u * i + 1u], c = tv[3u * i + 2u];
            // Vertex V's axis K (the lane's permutation), relative to the lane's origin.
#define LANES_SMALL_AXIS(V, K, P) \
    (LANES_PICK((lanes_f)(V.x), (lanes_f)(V.y), (lanes_f)(V.z), K) - (P))
            lanes_f aX = LANES_SMALL_AXIS(a, kx, px), aY = LANES_SMALL_AXIS(a, ky, py);
            lanes_f aZ = LANES_SMALL_AXIS(a, kz, pz), bX = LANES_SMALL_AXIS(b, kx, px);
            lanes_f bY = LANES_SMALL_AXIS(b, ky, py), bZ = LANES_SMALL_AXIS(b, kz, pz);
            lanes_f cX = LANES_SMALL_AXIS(c, kx, px), cY = LANES_SMALL_AXIS(c, ky, py);
            lanes_f cZ = LANES_SMALL_AXIS(c, kz, pz);
#undef LANES_SMALL_AXIS
            LANE_EDGES(lanes_f)
            LANE_HITS_T(lanes_f, lanes_i, m, zero, tfar)
            LANES_KEEP_HITS((int)i, M->o, M->d, false)
        }
    }
    L->tfar = tfar;
    L->hv = hv;
    L->hw = hw;
    L->hdet = hdet;
    L->prim = prim;
    L->has &= ~live;
    L->live = (lanes_i)(0);
    L->fin = (lanes_i)(0);
    return live;
}
#endif

#endif  // MEGA_LANES

#endif  // CPU_TRAVERSE_LANES_H
