// The SIMD layer of the CPU megakernel's lanes (MEGA_LANES), in Embree's manner: vectors of LANES
// floats (vfloat), ints (vint) or uints (vuint); a lane mask as a vint (every bit of a lane set or
// clear) or as bits (vmask, lane l's in bit l); and what the walks and the batched shading need
// beyond OpenCL's vector arithmetic: reductions, gathers, pushes and pops of word pairs,
// compresses, permutes, and rows of words transposed into lanes. Each operation has one form per
// instruction set: AVX-512 (sixteen lanes: SIMD_AVX512), AVX2 (sixteen lanes as two halves, or
// eight; also eight lanes on an AVX-512 CPU: SIMD_AVX2), and lane by lane elsewhere.
#ifndef CPU_SIMD_H
#define CPU_SIMD_H

#ifdef MEGA_LANES
// The lanes: sixteen, or eight where the CPU has AVX2 but not AVX-512 (-DLANES=16 or 8 chooses):
// sixteen lanes there are two 256-bit halves to every vector operation and half as many vectors
// in its sixteen registers, and eight took 7-8 % less time on AMD's Zen 3 (2026-12-04).
#ifndef LANES
#if defined(__AVX2__) && !defined(__AVX512F__) && defined(__x86_64__)
#define LANES 8
#else
#define LANES 16
#endif
#endif
#define LANES_INLINE inline __attribute__((always_inline))

#if LANES == 16 && defined(__AVX512F__) && defined(__x86_64__)
#define SIMD_AVX512
#elif defined(__AVX2__) && defined(__x86_64__)
#define SIMD_AVX2
#endif

// The vector types, by width.
#if LANES == 16
typedef float16 vfloat;
typedef int16 vint;
typedef uint16 vuint;
#define as_vfloat as_float16
#define as_vint as_int16
#define as_vuint as_uint16
#define convert_vfloat convert_float16
#define convert_vuint convert_uint16
#define vload_lanes vload16
#define vstore_lanes vstore16
#define LANE_IDS ((vint)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))
#elif LANES == 8
typedef float8 vfloat;
typedef int8 vint;
typedef uint8 vuint;
#define as_vfloat as_float8
#define as_vint as_int8
#define as_vuint as_uint8
#define convert_vfloat convert_float8
#define convert_vuint convert_uint8
#define vload_lanes vload8
#define vstore_lanes vstore8
#define LANE_IDS ((vint)(0, 1, 2, 3, 4, 5, 6, 7))
#else
#error "LANES is 8 or 16"
#endif
typedef ushort vmask;

// x's lanes folded to eight (sixteen lanes: the halves combined); a vector's words in pairs, as
// 8-byte words (typed: not through an int pointer, which the compiler may take for another
// object); the even words of lo and hi (in order) in *a and the odd ones in *b, and the opposite,
// a and b interleaved into *lo (their first half of lanes) and *hi.
#if LANES == 16
LANES_INLINE int8 lanes_fold8_or(vint x) { return x.lo | x.hi; }
LANES_INLINE int8 lanes_fold8_add(vint x) { return x.lo + x.hi; }
LANES_INLINE int8 lanes_fold8_max(vint x) { return max(x.lo, x.hi); }
LANES_INLINE void lanes_vstore_pairs(vfloat v, long* p) { vstore8(as_long8(v), 0, p); }
LANES_INLINE void lanes_deinterleave(vfloat lo, vfloat hi, vfloat* a, vfloat* b) {
    *a = __builtin_shufflevector(lo, hi, 0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    *b = __builtin_shufflevector(lo, hi, 1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
}
LANES_INLINE void lanes_interleave(vfloat a, vfloat b, vfloat* lo, vfloat* hi) {
    *lo = __builtin_shufflevector(a, b, 0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
    *hi = __builtin_shufflevector(a, b, 8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15,
                                  31);
}
#else
LANES_INLINE int8 lanes_fold8_or(vint x) { return x; }
LANES_INLINE int8 lanes_fold8_add(vint x) { return x; }
LANES_INLINE int8 lanes_fold8_max(vint x) { return x; }
LANES_INLINE void lanes_vstore_pairs(vfloat v, long* p) { vstore4(as_long4(v), 0, p); }
LANES_INLINE void lanes_deinterleave(vfloat lo, vfloat hi, vfloat* a, vfloat* b) {
    *a = __builtin_shufflevector(lo, hi, 0, 2, 4, 6, 8, 10, 12, 14);
    *b = __builtin_shufflevector(lo, hi, 1, 3, 5, 7, 9, 11, 13, 15);
}
LANES_INLINE void lanes_interleave(vfloat a, vfloat b, vfloat* lo, vfloat* hi) {
    *lo = __builtin_shufflevector(a, b, 0, 8, 1, 9, 2, 10, 3, 11);
    *hi = __builtin_shufflevector(a, b, 4, 12, 5, 13, 6, 14, 7, 15);
}
#endif

// Whether any lane of a mask is set.
inline bool lanes_any(vint m) {
    int8 a = lanes_fold8_or(m);
    int4 b = a.lo | a.hi;
    int2 c = b.lo | b.hi;
    return (c.x | c.y) != 0;
}

// The number of set lanes of a mask.
inline int lanes_count(vint m) {
    vint b = m & (vint)(1);
    int8 a = lanes_fold8_add(b);
    int4 c = a.lo + a.hi;
    int2 d = c.lo + c.hi;
    return d.x + d.y;
}

// The greatest lane.
inline int lanes_max(vint x) {
    int8 a = lanes_fold8_max(x);
    int4 b = max(a.lo, a.hi);
    int2 c = max(b.lo, b.hi);
    return max(c.x, c.y);
}

// Gathers and scatters: base[idx] (base a word address) in each lane of a mask (others 0); with
// AVX-512 one instruction, with AVX2 two gathers or a loop over the mask's lanes, else lane by
// lane. lanes_gather_pair: two neighbouring words at word offset idx of each lane of mask km,
// the first in *a, the second in *b. lanes_push_pair: the opposite, a and b stored side by side
// at word offset idx of each lane of km, a lane's push onto its stack.
#if defined(SIMD_AVX512)
inline vmask lanes_kmask(vint m) {
    return __builtin_ia32_cmpd512_mask(m, (vint)(0), 4, (ushort)0xffff);  // m != 0
}
LANES_INLINE vfloat lanes_gather(ulong base, vint idx, vint m) {
    return as_vfloat(
        __builtin_ia32_gathersiv16sf((vfloat)(0.0f), (const void*)base, idx, lanes_kmask(m), 4));
}
// 8-byte gathers, eight lanes each: half the elements of two gathers.
LANES_INLINE void lanes_gather_pair(ulong base, vint idx, vmask km, vfloat* a, vfloat* b) {
    vfloat lo = as_vfloat(
        __builtin_ia32_gathersiv8di((long8)(0), (const void*)base, idx.lo, (uchar)(km), 4));
    vfloat hi = as_vfloat(
        __builtin_ia32_gathersiv8di((long8)(0), (const void*)base, idx.hi, (uchar)(km >> 8), 4));
    lanes_deinterleave(lo, hi, a, b);
}
LANES_INLINE void lanes_push_pair(float* base, vint idx, vmask km, vfloat a, vfloat b) {
    vfloat lo, hi;
    lanes_interleave(a, b, &lo, &hi);
    __builtin_ia32_scattersiv8di((void*)base, (uchar)(km), idx.lo, as_long8(lo), 4);
    __builtin_ia32_scattersiv8di((void*)base, (uchar)(km >> 8), idx.hi, as_long8(hi), 4);
}
#elif defined(SIMD_AVX2)
// Masks by movmskps, gathers by AVX2's eight-lane gathers (pairs of words by its four-lane 8-byte
// ones); AVX2 has no scatter.
inline vmask lanes_kmask(vint m) {
    vint t = m != (vint)(0);
#if LANES == 16
    return (vmask)(__builtin_ia32_movmskps256(as_float8(t.lo)) |
                   (__builtin_ia32_movmskps256(as_float8(t.hi)) << 8));
#else
    return (vmask)__builtin_ia32_movmskps256(as_float8(t));
#endif
}
LANES_INLINE float8 lanes_gather8(ulong base, int8 idx8, int8 m8) {
    return __builtin_ia32_gatherd_ps256((float8)(0.0f), (const void*)base, idx8,
                                        as_float8(m8 != (int8)(0)), 4);
}
// Four lanes' 8-byte words at word offsets idx4, for the lanes of the low four bits.
LANES_INLINE float8 lanes_gather4q(ulong base, int4 idx4, int bits) {
    return as_float8(__builtin_ia32_gatherd_q256(
        (long4)(0), (const void*)base, idx4,
        as_long4(((long4)(1, 2, 4, 8) & (long4)((long)(bits))) != (long4)(0)), 4));
}
#if LANES == 16
LANES_INLINE vfloat lanes_gather(ulong base, vint idx, vint m) {
    return (vfloat)(lanes_gather8(base, idx.lo, m.lo), lanes_gather8(base, idx.hi, m.hi));
}
LANES_INLINE void lanes_gather_pair(ulong base, vint idx, vmask km, vfloat* a, vfloat* b) {
    vfloat lo = (vfloat)(lanes_gather4q(base, idx.lo.lo, km),
                         lanes_gather4q(base, idx.lo.hi, km >> 4));
    vfloat hi = (vfloat)(lanes_gather4q(base, idx.hi.lo, km >> 8),
                         lanes_gather4q(base, idx.hi.hi, km >> 12));
    lanes_deinterleave(lo, hi, a, b);
}
#else
LANES_INLINE vfloat lanes_gather(ulong base, vint idx, vint m) {
    return lanes_gather8(base, idx, m);
}
LANES_INLINE void lanes_gather_pair(ulong base, vint idx, vmask km, vfloat* a, vfloat* b) {
    vfloat lo = lanes_gather4q(base, idx.lo, km);
    vfloat hi = lanes_gather4q(base, idx.hi, km >> 4);
    lanes_deinterleave(lo, hi, a, b);
}
#endif
// A push without a scatter: every lane stores, one 8-byte store after another, those outside km
// into their free entry (the one at their stack pointer, which no walk reads: their pushes and
// pops leave it above the top). A loop over km's lanes alone cost a branch a lane and a
// mispredicted exit a push; the stores in every lane took 4-5 % less time on the 1 M-triangle
// scenes (AMD Zen 3, 2026-12-04).
LANES_INLINE void lanes_push_pair(float* base, vint idx, vmask km, vfloat a, vfloat b) {
    vfloat lo, hi;
    lanes_interleave(a, b, &lo, &hi);
    long q[LANES];
    int i[LANES];
    lanes_vstore_pairs(lo, q);
    lanes_vstore_pairs(hi, q + LANES / 2);
    vstore_lanes(idx, 0, i);
#pragma unroll
    for (int l = 0; l < LANES; ++l) *(long*)(base + i[l]) = q[l];
}
#else
inline vmask lanes_kmask(vint m) {
    int k[LANES];
    vstore_lanes(m, 0, k);
    vmask bits = 0;
    for (int l = 0; l < LANES; ++l) bits |= k[l] ? (vmask)(1 << l) : (vmask)0;
    return bits;
}
inline vfloat lanes_gather_bits(const float* base, vint idx, vmask km) {
    int i[LANES];
    float out[LANES];
    vstore_lanes(idx, 0, i);
    for (int l = 0; l < LANES; ++l) out[l] = (km >> l) & 1 ? base[i[l]] : 0.0f;
    return vload_lanes(0, out);
}
inline void lanes_scatter(float* base, vint idx, vfloat v, vmask km) {
    int i[LANES];
    float x[LANES];
    vstore_lanes(idx, 0, i);
    vstore_lanes(v, 0, x);
    for (int l = 0; l < LANES; ++l)
        if ((km >> l) & 1) base[i[l]] = x[l];
}
LANES_INLINE vfloat lanes_gather(ulong base, vint idx, vint m) {
    return lanes_gather_bits((const float*)base, idx, lanes_kmask(m));
}
LANES_INLINE void lanes_gather_pair(ulong base, vint idx, vmask km, vfloat* a, vfloat* b) {
    *a = lanes_gather_bits((const float*)base, idx, km);
    *b = lanes_gather_bits((const float*)base, idx + 1, km);
}
LANES_INLINE void lanes_push_pair(float* base, vint idx, vmask km, vfloat a, vfloat b) {
    lanes_scatter(base, idx, a, km);
    lanes_scatter(base, idx + 1, b, km);
}
#endif

// A pop, the words at idx and idx + 1 of each lane into *a and *b (lanes outside km read their
// entry too, which no walk uses): with eight lanes by one 8-byte load a lane, which took 1-4 %
// less time than AVX2's two four-lane 8-byte gathers on Zen 3; else a gather.
LANES_INLINE void lanes_pop_pair(const float* base, vint idx, vmask km, vfloat* a, vfloat* b) {
#if LANES == 8
    int i[LANES];
    long q[LANES];
    vstore_lanes(idx, 0, i);
#pragma unroll
    for (int l = 0; l < LANES; ++l) q[l] = *(const long*)(base + i[l]);
    vfloat lo = as_float8(vload4(0, q)), hi = as_float8(vload4(1, q));
    lanes_deinterleave(lo, hi, a, b);
#else
    lanes_gather_pair((ulong)base, idx, km, a, b);
#endif
}

// The lanes of mask km of v, in order, in the first lanes (the others 0); and the lanes of v
// named by idx.
#if defined(SIMD_AVX512)
LANES_INLINE vint lanes_compress(vint v, vmask km) {
    return __builtin_ia32_compresssi512_mask(v, (vint)(0), km);
}
LANES_INLINE vfloat lanes_permute(vfloat v, vint idx) {
    return __builtin_ia32_permvarsf512(v, idx);
}
LANES_INLINE vint lanes_permute_i(vint v, vint idx) { return __builtin_ia32_permvarsi512(v, idx); }
#elif defined(SIMD_AVX2)
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
#if LANES == 16
// Each half compressed by a table-driven permute, the high half's lanes then moved up past the
// low half's n.
LANES_INLINE vint lanes_compress(vint v, vmask km) {
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
    return (vint)(rlo, rhi);
}
LANES_INLINE vfloat lanes_permute(vfloat v, vint idx) {
    int8 a = idx.lo & (int8)(7), b = idx.hi & (int8)(7);
    float8 lo = select(__builtin_ia32_permvarsf256(v.lo, a), __builtin_ia32_permvarsf256(v.hi, a),
                       (idx.lo & (int8)(8)) != (int8)(0));
    float8 hi = select(__builtin_ia32_permvarsf256(v.lo, b), __builtin_ia32_permvarsf256(v.hi, b),
                       (idx.hi & (int8)(8)) != (int8)(0));
    return (vfloat)(lo, hi);
}
LANES_INLINE vint lanes_permute_i(vint v, vint idx) {
    return as_vint(lanes_permute(as_vfloat(v), idx));
}
#else
LANES_INLINE vint lanes_compress(vint v, vmask km) {
    return select((int8)(0), __builtin_ia32_permvarsi256(v, lanes_compress8_index(km)),
                  LANE_IDS < (int8)(popcount((uint)km & 255u)));
}
LANES_INLINE vfloat lanes_permute(vfloat v, vint idx) {
    return __builtin_ia32_permvarsf256(v, idx);
}
LANES_INLINE vint lanes_permute_i(vint v, vint idx) { return __builtin_ia32_permvarsi256(v, idx); }
#endif
#else
LANES_INLINE vint lanes_compress(vint v, vmask km) {
    int in[LANES], out[LANES];
    vstore_lanes(v, 0, in);
    int n = 0;
    for (int l = 0; l < LANES; ++l) {
        out[l] = 0;
        if ((km >> l) & 1) out[n++] = in[l];
    }
    return vload_lanes(0, out);
}
LANES_INLINE vfloat lanes_permute(vfloat v, vint idx) {
    float in[LANES], out[LANES];
    int i[LANES];
    vstore_lanes(v, 0, in);
    vstore_lanes(idx, 0, i);
    for (int l = 0; l < LANES; ++l) out[l] = in[i[l] & (LANES - 1)];
    return vload_lanes(0, out);
}
LANES_INLINE vint lanes_permute_i(vint v, vint idx) {
    return as_vint(lanes_permute(as_vfloat(v), idx));
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
LANES_INLINE vfloat lanes_row8(global const float* base, const int* off, int w, int i) {
    return (vfloat)(vload8(0, base + off[i] + w), vload8(0, base + off[i + 8] + w));
}
LANES_INLINE vfloat lanes_row4(global const float* base, const int* off, int w, int i) {
    return (vfloat)(vload4(0, base + off[i] + w), vload4(0, base + off[i + 4] + w),
                    vload4(0, base + off[i + 8] + w), vload4(0, base + off[i + 12] + w));
}
#else
// Eight lanes: the same in 128-bit halves (a 4×4 transpose in each), rows8's vector i lane i's
// words, rows4's the words of lanes i and i + 4.
#define LANES_UNPACKLO 0, 8, 1, 9, 4, 12, 5, 13
#define LANES_UNPACKHI 2, 10, 3, 11, 6, 14, 7, 15
#define LANES_PAIRSLO 0, 1, 8, 9, 4, 5, 12, 13
#define LANES_PAIRSHI 2, 3, 10, 11, 6, 7, 14, 15
#define LANES_QUADSLO 0, 1, 2, 3, 8, 9, 10, 11
#define LANES_QUADSHI 4, 5, 6, 7, 12, 13, 14, 15
LANES_INLINE vfloat lanes_row8(global const float* base, const int* off, int w, int i) {
    return vload8(0, base + off[i] + w);
}
LANES_INLINE vfloat lanes_row4(global const float* base, const int* off, int w, int i) {
    return (vfloat)(vload4(0, base + off[i] + w), vload4(0, base + off[i + 4] + w));
}
#endif
#define LANES_SHUFFLE(A, B, P) __builtin_shufflevector(A, B, P)

// 4×4 transposes, one in each 128-bit quarter: word j of m[i]'s quarter q to word i of c[j]'s
// quarter q.
LANES_INLINE void lanes_transpose4(const vfloat* m, vfloat* c) {
    vfloat t0 = LANES_SHUFFLE(m[0], m[1], LANES_UNPACKLO);
    vfloat t1 = LANES_SHUFFLE(m[0], m[1], LANES_UNPACKHI);
    vfloat t2 = LANES_SHUFFLE(m[2], m[3], LANES_UNPACKLO);
    vfloat t3 = LANES_SHUFFLE(m[2], m[3], LANES_UNPACKHI);
    c[0] = LANES_SHUFFLE(t0, t2, LANES_PAIRSLO);
    c[1] = LANES_SHUFFLE(t0, t2, LANES_PAIRSHI);
    c[2] = LANES_SHUFFLE(t1, t3, LANES_PAIRSLO);
    c[3] = LANES_SHUFFLE(t1, t3, LANES_PAIRSHI);
}

// 8×8 transposes of words in each 256-bit half: word j of m[i]'s half h to word i of c[j]'s
// half h (with eight lanes, the transpose of the eight vectors).
LANES_INLINE void lanes_transpose8(const vfloat* m, vfloat* c) {
    vfloat s[8];
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
LANES_INLINE void lanes_rows8(global const float* base, const int* off, int w, vfloat* c) {
    vfloat m[8];
#pragma unroll
    for (int i = 0; i < 8; ++i) m[i] = lanes_row8(base, off, w, i);
    lanes_transpose8(m, c);
}

// The same for words [w, w + 4), into c[0..4).
LANES_INLINE void lanes_rows4(global const float* base, const int* off, int w, vfloat* c) {
    vfloat m[4];
#pragma unroll
    for (int i = 0; i < 4; ++i) m[i] = lanes_row4(base, off, w, i);
    lanes_transpose4(m, c);
}

#endif  // MEGA_LANES

#endif  // CPU_SIMD_H
