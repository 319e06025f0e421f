// Times trace_range (entry.cl, built by build.sh) on rays dumped by
// PENUMBRA_DUMP_TRACE=DIR penumbra bench trace --wide --bvh flat ..., single-threaded, and
// checks the hits against the device's.
#include <immintrin.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct { float t, u, v; uint32_t prim, instance; } Hit;
void trace_range(const void* nodes, const void* tris, const void* rays, uint32_t first,
                 uint32_t end, Hit* hits, volatile uint32_t* counters, uint32_t passes);

// OpenCL's atomic_inc on a global pointer, as clang mangles it for this target.
uint32_t _Z10atomic_incPU8CLglobalVj(volatile uint32_t* p) { return __atomic_fetch_add(p, 1, 0); }

// Quantised 64-byte nodes (NATIVE_QUANT=1, a build with -DQUANT and a kernel copy that has
// traverse_quant): each child box in 8 bits a plane relative to the node's own box, rounded
// outwards so that the decoded box (fmaf(q, scale, origin), as the kernel computes it) holds the
// exact one.
typedef struct {
    float min_x[4], min_y[4], min_z[4], max_x[4], max_y[4], max_z[4];
    int32_t child[4];
    uint32_t count[4];
} WideNode;
typedef struct {
    float o[3], s[3];
    uint8_t q[6][4];  // lo x, hi x, lo y, hi y, lo z, hi z
    int32_t child[4];
} QNode;
// NATIVE_QUANT needs a kernel copy with the quantised walk (see docs/benchmarks.md, "Sixth
// session"); it is not in kernels/.
void trace_range_q(const void* nodes, const void* tris, const void* rays, uint32_t first,
                   uint32_t end, Hit* hits, volatile uint32_t* counters, uint32_t passes)
    __attribute__((weak));

static QNode* quantise(const WideNode* w, size_t count) {
    QNode* q = aligned_alloc(1 << 21, (count * sizeof(QNode) + (1 << 21) - 1) & ~(size_t)((1 << 21) - 1));
    for (size_t i = 0; i < count; ++i) {
        const WideNode* n = &w[i];
        QNode* out = &q[i];
        memset(out, 0, sizeof *out);
        const float* lo[3] = {n->min_x, n->min_y, n->min_z};
        const float* hi[3] = {n->max_x, n->max_y, n->max_z};
        int used[4];
        for (int c = 0; c < 4; ++c) {
            used[c] = n->count[c] > 0 || n->child[c] > 0;
            if (n->count[c] > 0) {
                if (n->count[c] > 15 || (uint32_t)~n->child[c] >= (1u << 27)) abort();
                out->child[c] = (int32_t)(0x80000000u | n->count[c] << 27 | (uint32_t)~n->child[c]);
            } else if (n->child[c] > 0) {
                out->child[c] = n->child[c];
            }
        }
        for (int a = 0; a < 3; ++a) {
            float l = INFINITY, h = -INFINITY;
            for (int c = 0; c < 4; ++c)
                if (used[c]) l = fminf(l, lo[a][c]), h = fmaxf(h, hi[a][c]);
            if (!(l <= h)) l = h = 0.0f;
            float s = (h - l) / 255.0f;
            if (s <= 1e-20f) s = 1e-20f;
            while (fmaf(255.0f, s, l) < h) s = nextafterf(s, INFINITY);
            out->o[a] = l, out->s[a] = s;
            for (int c = 0; c < 4; ++c) {
                if (!used[c]) continue;
                float ql = floorf((lo[a][c] - l) / s), qh = ceilf((hi[a][c] - l) / s);
                ql = fmaxf(0.0f, fminf(255.0f, ql)), qh = fmaxf(0.0f, fminf(255.0f, qh));
                while (ql > 0.0f && fmaf(ql, s, l) > lo[a][c]) ql -= 1.0f;
                while (qh < 255.0f && fmaf(qh, s, l) < hi[a][c]) qh += 1.0f;
                if (fmaf(ql, s, l) > lo[a][c] || fmaf(qh, s, l) < hi[a][c]) abort();
                out->q[2 * a][c] = (uint8_t)ql, out->q[2 * a + 1][c] = (uint8_t)qh;
            }
        }
    }
    return q;
}

// NATIVE_MERGE=N: an interior child whose subtree holds at most N triangles (one contiguous
// range) becomes one leaf (bottom-up, in place; the merged nodes stay in the array unused).
static void merge_leaves(WideNode* w, size_t count, uint32_t limit) {
    size_t merged = 0;
    for (size_t i = count; i-- > 0;) {
        WideNode* n = &w[i];
        for (int c = 0; c < 4; ++c) {
            if (n->count[c] > 0 || n->child[c] <= 0) continue;
            const WideNode* k = &w[n->child[c]];
            uint32_t first = UINT32_MAX, total = 0, end = 0;
            int ok = 1;
            for (int j = 0; j < 4 && ok; ++j) {
                if (k->count[j] > 0) {
                    uint32_t f = (uint32_t)~k->child[j];
                    if (first == UINT32_MAX) first = f, end = f;
                    ok = f == end;  // the leaves' ranges follow each other in slot order
                    end = f + k->count[j];
                    total += k->count[j];
                } else if (k->child[j] > 0) {
                    ok = 0;
                }
            }
            if (ok && total > 0 && total <= limit) {
                n->child[c] = ~(int32_t)first;
                n->count[c] = total;
                ++merged;
            }
        }
    }
    // Drop the nodes no longer reached, keeping the others' order.
    uint8_t* live = calloc(count, 1);
    uint32_t* index = calloc(count, 4);
    live[0] = 1;
    size_t kept = 0;
    for (size_t i = 0; i < count; ++i) {
        if (!live[i]) continue;
        index[i] = kept++;
        for (int c = 0; c < 4; ++c)
            if (w[i].count[c] == 0 && w[i].child[c] > 0) live[w[i].child[c]] = 1;
    }
    for (size_t i = 0; i < count; ++i) {
        if (!live[i]) continue;
        WideNode n = w[i];
        for (int c = 0; c < 4; ++c)
            if (n.count[c] == 0 && n.child[c] > 0) n.child[c] = index[n.child[c]];
        w[index[i]] = n;
    }
    fprintf(stderr, "merged %zu subtrees into leaves of at most %u triangles; %zu of %zu nodes\n",
            merged, limit, kept, count);
}

// Counters for NATIVE_COUNT=1 builds.
static uint64_t nodes_visited, tris_tested;
void count_node(void) { ++nodes_visited; }
void count_tri(void) { ++tris_tested; }

static void* load(const char* dir, const char* name, size_t* size) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE* f = fopen(path, "rb");
    if (!f) { perror(path); exit(1); }
    fseek(f, 0, SEEK_END);
    *size = ftell(f);
    fseek(f, 0, SEEK_SET);
    void* p = aligned_alloc(1 << 21, (*size + (1 << 21) - 1) & ~(size_t)((1 << 21) - 1));
#ifdef __linux__
    extern int madvise(void*, size_t, int);
    madvise(p, (*size + (1 << 21) - 1) & ~(size_t)((1 << 21) - 1), 14 /* MADV_HUGEPAGE */);
#endif
    if (fread(p, 1, *size, f) != *size) { perror(path); exit(1); }
    fclose(f);
    return p;
}

static double now(clockid_t c) {
    struct timespec t;
    clock_gettime(c, &t);
    return t.tv_sec + t.tv_nsec * 1e-9;
}

int main(int argc, char** argv) {
    const char* dir = argc > 1 ? argv[1] : "/tmp/n13dump";
    int runs = argc > 2 ? atoi(argv[2]) : 3;
    if (!getenv("NATIVE_KEEP_DENORMALS")) _mm_setcsr(_mm_getcsr() | 0x8040);  // FTZ | DAZ
    size_t ns, ts;
    void* nodes = load(dir, "nodes.bin", &ns);
    void* tris = load(dir, "tris.bin", &ts);
    // An empty tris.bin: the triangles share the nodes' buffer (embree/interleave.c).
    if (ts == 0) tris = nodes;
    void (*trace)(const void*, const void*, const void*, uint32_t, uint32_t, Hit*,
                  volatile uint32_t*, uint32_t) = trace_range;
    uint32_t passes = getenv("NATIVE_TWICE") ? 2 : 1;
    if (getenv("NATIVE_MERGE")) merge_leaves(nodes, ns / sizeof(WideNode), atoi(getenv("NATIVE_MERGE")));
    if (getenv("NATIVE_QUANT")) {
        nodes = quantise(nodes, ns / sizeof(WideNode));
        trace = trace_range_q;
        fprintf(stderr, "quantised nodes: %zu bytes\n", ns / sizeof(WideNode) * sizeof(QNode));
    }
    const char* sets[] = {"primary", "diffuse"};
    for (int s = 0; s < 2; ++s) {
        char name[64];
        size_t rs, hs;
        snprintf(name, sizeof name, "%s_rays.bin", sets[s]);
        void* rays = load(dir, name, &rs);
        snprintf(name, sizeof name, "%s_hits.bin", sets[s]);
        Hit* want = load(dir, name, &hs);
        uint32_t n = rs / 32;
        if (getenv("NATIVE_SHUFFLE")) {  // a random order, and the expected hits with it
            uint64_t x = 88172645463325252ull;
            uint32_t (*rr)[8] = rays;
            for (uint32_t i = n - 1; i > 0; --i) {
                x ^= x << 13, x ^= x >> 7, x ^= x << 17;
                uint32_t j = x % (i + 1);
                uint32_t t[8];
                memcpy(t, rr[i], 32), memcpy(rr[i], rr[j], 32), memcpy(rr[j], t, 32);
                Hit h = want[i];
                want[i] = want[j], want[j] = h;
            }
        }
        Hit* got = calloc(n, sizeof(Hit));
        uint32_t counters[16] = {0};
        double best = 1e30;
        nodes_visited = tris_tested = 0;
        for (int r = 0; r < runs; ++r) {
            double t0 = now(CLOCK_THREAD_CPUTIME_ID);
            trace(nodes, tris, rays, 0, n, got, counters, passes);
            double t = now(CLOCK_THREAD_CPUTIME_ID) - t0;
            if (t < best) best = t;
        }
        size_t bad = 0;
        for (uint32_t i = 0; i < n; ++i)
            if (got[i].prim != want[i].prim || got[i].t != want[i].t) ++bad;
        printf("%-8s %8u rays  %.3f CPU s (best of %d, one thread)  %.2f M rays per CPU s  "
               "%.0f ns a ray  mismatches %zu\n",
               sets[s], n, best, runs, n / best / 1e6, best / n * 1e9, bad);
        if (nodes_visited)
            printf("         %.2f wide nodes and %.2f triangles a ray\n",
                   (double)nodes_visited / runs / n, (double)tris_tested / runs / n);
    }
    return 0;
}
