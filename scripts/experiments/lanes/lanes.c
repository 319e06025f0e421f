// Rays in AVX-512 lanes: sixteen independent rays walk penumbra's 4-wide BVH together, one lane
// a ray, each at its own node, with gathers for the node and triangle data, and a lane whose ray
// is done takes the next ray at once (a ray stream). The question it answers: do sixteen
// independent walks in flight hide the memory latency that one walk at a time waits on?
// Over the rays and tree that `PENUMBRA_DUMP_TRACE=DIR penumbra bench trace --wide --bvh flat`
// dumps (nodes.bin, tris.bin, {primary,diffuse}_{rays,hits}.bin), one thread, thread CPU time.
// The triangle test is Moller-Trumbore, not the kernels' watertight one: hits on edges may
// differ, so a few mismatches against the device's hits are expected.
// Build: gcc -O3 -march=native lanes.c -lm -o /tmp/lanes; run: /tmp/lanes DIR [passes]
#include <immintrin.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct { float t, u, v; uint32_t prim, instance; } Hit;
#define L 16
#define DEPTH 192

static void* load(const char* dir, const char* name, size_t* size) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE* f = fopen(path, "rb");
    if (!f) { perror(path); exit(1); }
    fseek(f, 0, SEEK_END);
    *size = ftell(f);
    fseek(f, 0, SEEK_SET);
    size_t cap = (*size + (1 << 21) - 1) & ~(size_t)((1 << 21) - 1);
    void* p = aligned_alloc(1 << 21, cap ? cap : 1 << 21);
#ifdef __linux__
    extern int madvise(void*, size_t, int);
    madvise(p, cap, 14 /* MADV_HUGEPAGE */);
#endif
    if (fread(p, 1, *size, f) != *size) { perror(path); exit(1); }
    fclose(f);
    return p;
}

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

#define G(idx, base) _mm512_mask_i32gather_ps(zero, m, (idx), (base), 4)
#define GI(idx, base) _mm512_mask_i32gather_epi32(izero, m, (idx), (base), 4)
#define CSWAP(a, b)                                                            \
    {                                                                          \
        __mmask16 s = _mm512_cmp_ps_mask(d##b, d##a, _CMP_LT_OQ);              \
        __m512 td = d##a;                                                      \
        d##a = _mm512_mask_blend_ps(s, d##a, d##b);                            \
        d##b = _mm512_mask_blend_ps(s, d##b, td);                              \
        __m512i tc = c##a;                                                     \
        c##a = _mm512_mask_blend_epi32(s, c##a, c##b);                         \
        c##b = _mm512_mask_blend_epi32(s, c##b, tc);                           \
    }

static uint64_t iterations, lane_steps;

// Node layout (GpuWideNode, 32 words): min_x[4] min_y[4] min_z[4] max_x[4] max_y[4] max_z[4]
// child[4] count[4]; child > 0 interior, ~first with count > 0 a leaf. Triangles: 12 words,
// v0 v1 v2 as float4.
static void trace_lanes(const float* nodes, const float* tris, const float* rays, uint32_t n,
                        Hit* hits) {
    const __m512 zero = _mm512_setzero_ps(), inf = _mm512_set1_ps(INFINITY);
    const __m512i izero = _mm512_setzero_si512(), one = _mm512_set1_epi32(1);
    const __m512i lane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
    static float stack_d[DEPTH * L];
    static int stack_c[DEPTH * L], stack_k[DEPTH * L];
    __m512 dx = zero, dy = zero, dz = zero;
    __m512 ox = zero, oy = zero, oz = zero, ix = zero, iy = zero, iz = zero, tmin = zero,
           tfar = zero, hu = zero, hv = zero;
    __m512i nx = izero, ny = izero, nz = izero, fx = izero, fy = izero, fz = izero;
    __m512i cur = izero, cnt = izero, sp = izero, prim = izero, rid = izero;
    __mmask16 active = 0, has = 0;
    uint32_t next = 0;
    for (;;) {
        // Refill the lanes without a ray.
        __mmask16 free = ~active;
        if (free && next < n) {
            __m512i ids = _mm512_maskz_expand_epi32(free, _mm512_add_epi32(_mm512_set1_epi32(next), lane));
            __mmask16 m = free & _mm512_cmp_epi32_mask(ids, _mm512_set1_epi32(n), _MM_CMPINT_LT);
            next += __builtin_popcount(m);
            rid = _mm512_mask_mov_epi32(rid, m, ids);
            __m512i b = _mm512_slli_epi32(ids, 3);
            ox = _mm512_mask_i32gather_ps(ox, m, b, rays, 4);
            oy = _mm512_mask_i32gather_ps(oy, m, _mm512_add_epi32(b, one), rays, 4);
            oz = _mm512_mask_i32gather_ps(oz, m, _mm512_add_epi32(b, _mm512_set1_epi32(2)), rays, 4);
            tmin = _mm512_mask_i32gather_ps(tmin, m, _mm512_add_epi32(b, _mm512_set1_epi32(3)), rays, 4);
            dx = _mm512_mask_i32gather_ps(dx, m, _mm512_add_epi32(b, _mm512_set1_epi32(4)), rays, 4);
            dy = _mm512_mask_i32gather_ps(dy, m, _mm512_add_epi32(b, _mm512_set1_epi32(5)), rays, 4);
            dz = _mm512_mask_i32gather_ps(dz, m, _mm512_add_epi32(b, _mm512_set1_epi32(6)), rays, 4);
            tfar = _mm512_mask_i32gather_ps(tfar, m, _mm512_add_epi32(b, _mm512_set1_epi32(7)), rays, 4);
            // Safe reciprocals (as RayPrep: tiny components replaced by a signed tiny value).
            __m512 tiny = _mm512_set1_ps(1e-20f);
#define SAFE(dd) _mm512_mask_blend_ps(_mm512_cmp_ps_mask(_mm512_abs_ps(dd), tiny, _CMP_LT_OQ), dd, \
                                     _mm512_or_ps(tiny, _mm512_and_ps(dd, _mm512_set1_ps(-0.0f))))
            ix = _mm512_mask_div_ps(ix, m, _mm512_set1_ps(1.0f), SAFE(dx));
            iy = _mm512_mask_div_ps(iy, m, _mm512_set1_ps(1.0f), SAFE(dy));
            iz = _mm512_mask_div_ps(iz, m, _mm512_set1_ps(1.0f), SAFE(dz));
            __mmask16 px = _mm512_cmp_ps_mask(ix, zero, _CMP_GE_OQ);
            __mmask16 py = _mm512_cmp_ps_mask(iy, zero, _CMP_GE_OQ);
            __mmask16 pz = _mm512_cmp_ps_mask(iz, zero, _CMP_GE_OQ);
            nx = _mm512_mask_blend_epi32(px, _mm512_set1_epi32(12), izero);
            ny = _mm512_mask_blend_epi32(py, _mm512_set1_epi32(16), _mm512_set1_epi32(4));
            nz = _mm512_mask_blend_epi32(pz, _mm512_set1_epi32(20), _mm512_set1_epi32(8));
            fx = _mm512_sub_epi32(_mm512_set1_epi32(12), nx);
            fy = _mm512_sub_epi32(_mm512_set1_epi32(20), ny);
            fz = _mm512_sub_epi32(_mm512_set1_epi32(28), nz);
            cur = _mm512_mask_mov_epi32(cur, m, izero);
            sp = _mm512_mask_mov_epi32(sp, m, izero);
            prim = _mm512_mask_mov_epi32(prim, m, _mm512_set1_epi32(-1));
            active |= m;
            has |= m;
        }
        if (!active) break;
        ++iterations;
        // Interior nodes.
        __mmask16 mi = has & _mm512_cmp_epi32_mask(cur, izero, _MM_CMPINT_GE);
        if (mi) {
            __mmask16 m = mi;
            __m512i base = _mm512_slli_epi32(cur, 5);
            __m512 d0, d1, d2, d3;
            __m512i c0, c1, c2, c3;
#define CHILD(j)                                                                                  \
    {                                                                                             \
        __m512i bj = _mm512_add_epi32(base, _mm512_set1_epi32(j));                                \
        __m512 x0 = _mm512_mul_ps(_mm512_sub_ps(G(_mm512_add_epi32(bj, nx), nodes), ox), ix);     \
        __m512 x1 = _mm512_mul_ps(_mm512_sub_ps(G(_mm512_add_epi32(bj, fx), nodes), ox), ix);     \
        __m512 y0 = _mm512_mul_ps(_mm512_sub_ps(G(_mm512_add_epi32(bj, ny), nodes), oy), iy);     \
        __m512 y1 = _mm512_mul_ps(_mm512_sub_ps(G(_mm512_add_epi32(bj, fy), nodes), oy), iy);     \
        __m512 z0 = _mm512_mul_ps(_mm512_sub_ps(G(_mm512_add_epi32(bj, nz), nodes), oz), iz);     \
        __m512 z1 = _mm512_mul_ps(_mm512_sub_ps(G(_mm512_add_epi32(bj, fz), nodes), oz), iz);     \
        __m512 nr = _mm512_max_ps(_mm512_max_ps(_mm512_max_ps(x0, y0), z0), tmin);                \
        __m512 fr = _mm512_mul_ps(_mm512_min_ps(_mm512_min_ps(x1, y1), z1), _mm512_set1_ps(1.00000024f)); \
        c##j = GI(_mm512_add_epi32(bj, _mm512_set1_epi32(24)), nodes);                           \
        __mmask16 v = _mm512_cmp_epi32_mask(c##j, izero, _MM_CMPINT_NE);                         \
        __mmask16 r = m & v & _mm512_cmp_ps_mask(nr, fr, _CMP_LE_OQ) &                            \
                      _mm512_cmp_ps_mask(nr, tfar, _CMP_LT_OQ);                                   \
        d##j = _mm512_mask_blend_ps(r, inf, nr);                                                  \
    }
            CHILD(0) CHILD(1) CHILD(2) CHILD(3)
            CSWAP(0, 1) CSWAP(2, 3) CSWAP(0, 2) CSWAP(1, 3) CSWAP(1, 2)
            // Push the reached ones but the nearest, farthest first; enter the nearest.
#define PUSH(j)                                                                             \
    {                                                                                       \
        __mmask16 p = mi & _mm512_cmp_ps_mask(d##j, inf, _CMP_LT_OQ);                       \
        __m512i at = _mm512_add_epi32(_mm512_slli_epi32(sp, 4), lane);                      \
        _mm512_mask_i32scatter_ps(stack_d, p, at, d##j, 4);                                 \
        _mm512_mask_i32scatter_epi32(stack_c, p, at, c##j, 4);                              \
        sp = _mm512_mask_add_epi32(sp, p, sp, one);                                         \
    }
            PUSH(3) PUSH(2) PUSH(1)
            __mmask16 e = mi & _mm512_cmp_ps_mask(d0, inf, _CMP_LT_OQ);
            cur = _mm512_mask_mov_epi32(cur, e, c0);
            has &= ~(mi & ~e);
        }
        // Leaves.
        __mmask16 ml = has & ~mi;
        static int leaf_min = -1;
        if (leaf_min < 0) leaf_min = getenv("LEAF_MIN") ? atoi(getenv("LEAF_MIN")) : 1;
        if (ml && (__builtin_popcount(ml) >= leaf_min || !(has & ~ml) )) {
            __m512i first = _mm512_and_si512(cur, _mm512_set1_epi32((1 << 27) - 1));
            cnt = _mm512_and_si512(_mm512_srli_epi32(cur, 27), _mm512_set1_epi32(15));
            int kmax = _mm512_mask_reduce_max_epi32(ml, cnt);
            for (int k = 0; k < kmax; ++k) {
                __mmask16 m = ml & _mm512_cmp_epi32_mask(_mm512_set1_epi32(k), cnt, _MM_CMPINT_LT);
                __m512i tri = _mm512_add_epi32(first, _mm512_set1_epi32(k));
                __m512i b = _mm512_mullo_epi32(tri, _mm512_set1_epi32(12));
#define TV(o) G(_mm512_add_epi32(b, _mm512_set1_epi32(o)), tris)
                __m512 ax = TV(0), ay = TV(1), az = TV(2);
                __m512 e1x = _mm512_sub_ps(TV(4), ax), e1y = _mm512_sub_ps(TV(5), ay), e1z = _mm512_sub_ps(TV(6), az);
                __m512 e2x = _mm512_sub_ps(TV(8), ax), e2y = _mm512_sub_ps(TV(9), ay), e2z = _mm512_sub_ps(TV(10), az);
                __m512 px = _mm512_fmsub_ps(dy, e2z, _mm512_mul_ps(dz, e2y));
                __m512 py = _mm512_fmsub_ps(dz, e2x, _mm512_mul_ps(dx, e2z));
                __m512 pz = _mm512_fmsub_ps(dx, e2y, _mm512_mul_ps(dy, e2x));
                __m512 det = _mm512_fmadd_ps(e1x, px, _mm512_fmadd_ps(e1y, py, _mm512_mul_ps(e1z, pz)));
                __m512 inv = _mm512_div_ps(_mm512_set1_ps(1.0f), det);
                __m512 sx = _mm512_sub_ps(ox, ax), sy = _mm512_sub_ps(oy, ay), sz = _mm512_sub_ps(oz, az);
                __m512 u = _mm512_mul_ps(_mm512_fmadd_ps(sx, px, _mm512_fmadd_ps(sy, py, _mm512_mul_ps(sz, pz))), inv);
                __m512 qx = _mm512_fmsub_ps(sy, e1z, _mm512_mul_ps(sz, e1y));
                __m512 qy = _mm512_fmsub_ps(sz, e1x, _mm512_mul_ps(sx, e1z));
                __m512 qz = _mm512_fmsub_ps(sx, e1y, _mm512_mul_ps(sy, e1x));
                __m512 v = _mm512_mul_ps(_mm512_fmadd_ps(dx, qx, _mm512_fmadd_ps(dy, qy, _mm512_mul_ps(dz, qz))), inv);
                __m512 t = _mm512_mul_ps(_mm512_fmadd_ps(e2x, qx, _mm512_fmadd_ps(e2y, qy, _mm512_mul_ps(e2z, qz))), inv);
                __mmask16 ok = m & _mm512_cmp_ps_mask(det, zero, _CMP_NEQ_OQ) &
                               _mm512_cmp_ps_mask(u, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(v, zero, _CMP_GE_OQ) &
                               _mm512_cmp_ps_mask(_mm512_add_ps(u, v), _mm512_set1_ps(1.0f), _CMP_LE_OQ) &
                               _mm512_cmp_ps_mask(t, tmin, _CMP_GT_OQ) & _mm512_cmp_ps_mask(t, tfar, _CMP_LT_OQ);
                tfar = _mm512_mask_mov_ps(tfar, ok, t);
                hu = _mm512_mask_mov_ps(hu, ok, u);
                hv = _mm512_mask_mov_ps(hv, ok, v);
                prim = _mm512_mask_mov_epi32(prim, ok, tri);
            }
            has &= ~ml;
            lane_steps += __builtin_popcount(ml);
        } else ml = 0;
        lane_steps += __builtin_popcount(mi);
        // Pop for the lanes without an item: entries that start beyond the hit are dropped.
        for (int round = 0; round < 3; ++round) {
            __mmask16 pm = active & ~has;
            if (!pm) break;
            __mmask16 m = pm & _mm512_cmp_epi32_mask(sp, izero, _MM_CMPINT_GT);
            __mmask16 done = pm & ~m;
            if (done) {
                __m512i h = _mm512_mullo_epi32(rid, _mm512_set1_epi32(5));
                _mm512_mask_i32scatter_ps((float*)hits, done, h, tfar, 4);
                _mm512_mask_i32scatter_ps((float*)hits, done, _mm512_add_epi32(h, one), hu, 4);
                _mm512_mask_i32scatter_ps((float*)hits, done, _mm512_add_epi32(h, _mm512_set1_epi32(2)), hv, 4);
                _mm512_mask_i32scatter_epi32((int*)hits, done, _mm512_add_epi32(h, _mm512_set1_epi32(3)), prim, 4);
                active &= ~done;
            }
            if (!m) break;
            sp = _mm512_mask_sub_epi32(sp, m, sp, one);
            __m512i at = _mm512_add_epi32(_mm512_slli_epi32(sp, 4), lane);
            __m512 d = _mm512_mask_i32gather_ps(zero, m, at, stack_d, 4);
            __mmask16 keep = m & _mm512_cmp_ps_mask(d, tfar, _CMP_LT_OQ);
            cur = _mm512_mask_i32gather_epi32(cur, keep, at, stack_c, 4);
            has |= keep;
        }
    }
}

int main(int argc, char** argv) {
    const char* dir = argc > 1 ? argv[1] : "/tmp/emb/bunnies";
    int runs = argc > 2 ? atoi(argv[2]) : 3;
    _mm_setcsr(_mm_getcsr() | 0x8040);  // FTZ | DAZ
    size_t ns, ts;
    const float* nodes = load(dir, "nodes.bin", &ns);
    const float* tris = load(dir, "tris.bin", &ts);
    if (ts == 0) tris = nodes;
    {   // pack the leaves' counts into their child words
        int32_t* w = (int32_t*)nodes;
        for (size_t i = 0; i < ns / 128; ++i)
            for (int c = 0; c < 4; ++c) {
                int32_t ch = w[i * 32 + 24 + c];
                uint32_t ct = (uint32_t)w[i * 32 + 28 + c];
                if (ct > 0) {
                    if (ct > 15 || (uint32_t)~ch >= (1u << 27)) { fprintf(stderr, "leaf too big\n"); exit(1); }
                    w[i * 32 + 24 + c] = (int32_t)(0x80000000u | ct << 27 | (uint32_t)~ch);
                } else if (ch <= 0) w[i * 32 + 24 + c] = 0;
            }
    }
    const char* sets[] = {"primary", "diffuse"};
    for (int s = 0; s < 2; ++s) {
        char name[64];
        size_t rs, hs;
        snprintf(name, sizeof name, "%s_rays.bin", sets[s]);
        const float* rays = load(dir, name, &rs);
        snprintf(name, sizeof name, "%s_hits.bin", sets[s]);
        const Hit* want = load(dir, name, &hs);
        uint32_t n = rs / 32;
        Hit* got = calloc(n, sizeof(Hit));
        double best = 1e30;
        iterations = lane_steps = 0;
        for (int r = 0; r < runs; ++r) {
            for (uint32_t i = 0; i < n; ++i) got[i].prim = 0xfffffffe;
            double t0 = now();
            trace_lanes(nodes, tris, rays, n, got);
            double t = now() - t0;
            if (t < best) best = t;
        }
        size_t bad = 0, badt = 0;
        for (uint32_t i = 0; i < n; ++i) {
            if (got[i].prim != want[i].prim) ++bad;
            else if (want[i].prim != 0xffffffffu && fabsf(got[i].t - want[i].t) > 1e-4f * want[i].t) ++badt;
        }
        printf("%-8s %8u rays  %.0f ns a ray (best of %d, one thread)  prim mismatches %zu, t %zu;"
               "  lane use %.0f %%, %.1f steps a ray\n",
               sets[s], n, best / n * 1e9, runs, bad, badt,
               100.0 * lane_steps / (iterations * 16.0), (double)lane_steps / runs / n);
    }
    return 0;
}
