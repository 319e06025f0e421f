// Builds a 4-wide BVH over PENUMBRA_DUMP_TRACE's triangles with Embree's own builder
// (rtcBuildBVH, SAH), writes it in penumbra's GpuWideNode layout with the triangles in leaf
// order, and the rays and (remapped) device hits beside it: native_trace then walks Embree's
// tree with penumbra's traversal.  embree_bvh IN OUT [maxLeaf] [travCost] [isectCost] [high]
#include <embree3/rtcore.h>
#include "dump.h"
#include <math.h>
typedef struct Node { int leaf; unsigned n; struct Node* c[4]; struct RTCBounds b[4]; unsigned count; unsigned ids[16]; } Node;
static void* create_node(RTCThreadLocalAllocator a, unsigned int n, void* u) {
    Node* x = rtcThreadLocalAlloc(a, sizeof(Node), 16); memset(x, 0, sizeof *x); x->n = n; return x; }
static void set_children(void* p, void** c, unsigned int n, void* u) { Node* x = p; for (unsigned i = 0; i < n; ++i) x->c[i] = c[i]; x->n = n; }
static void set_bounds(void* p, const struct RTCBounds** b, unsigned int n, void* u) { Node* x = p; for (unsigned i = 0; i < n; ++i) x->b[i] = *b[i]; }
static void* create_leaf(RTCThreadLocalAllocator a, const struct RTCBuildPrimitive* prims, size_t n, void* u) {
    Node* x = rtcThreadLocalAlloc(a, sizeof(Node), 16); memset(x, 0, sizeof *x); x->leaf = 1; x->count = n;
    for (size_t i = 0; i < n; ++i) x->ids[i] = prims[i].primID; return x; }
static float* tris; static float* out_tris; static uint32_t* new_index; static size_t placed;
static WideNode* nodes; static size_t node_count, node_cap;
int main(int argc, char** argv) {
    const char* in = argv[1]; const char* out = argv[2];
    unsigned max_leaf = argc > 3 ? atoi(argv[3]) : 4;
    float trav = argc > 4 ? atof(argv[4]) : 1.0f, isect = argc > 5 ? atof(argv[5]) : 1.0f;
    int high = argc > 6 && !strcmp(argv[6], "high");
    size_t ts; tris = load(in, "tris.bin", &ts); size_t n = ts / 48;
    struct RTCBuildPrimitive* prims = malloc(sizeof(*prims) * n * 2);
    for (size_t i = 0; i < n; ++i) {
        float* t = &tris[i * 12]; struct RTCBuildPrimitive p;
        p.lower_x = fminf(fminf(t[0], t[4]), t[8]); p.upper_x = fmaxf(fmaxf(t[0], t[4]), t[8]);
        p.lower_y = fminf(fminf(t[1], t[5]), t[9]); p.upper_y = fmaxf(fmaxf(t[1], t[5]), t[9]);
        p.lower_z = fminf(fminf(t[2], t[6]), t[10]); p.upper_z = fmaxf(fmaxf(t[2], t[6]), t[10]);
        p.geomID = 0; p.primID = i; prims[i] = p;
    }
    RTCDevice dev = rtcNewDevice(NULL); RTCBVH bvh = rtcNewBVH(dev);
    struct RTCBuildArguments a = rtcDefaultBuildArguments();
    a.buildQuality = high ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;
    a.maxBranchingFactor = 4; a.maxDepth = 48; a.maxLeafSize = max_leaf; a.minLeafSize = 1;
    a.traversalCost = trav; a.intersectionCost = isect; a.bvh = bvh; a.sahBlockSize = getenv("BLOCK") ? atoi(getenv("BLOCK")) : 1;
    a.primitives = prims; a.primitiveCount = n; a.primitiveArrayCapacity = high ? 2 * n : n;
    a.createNode = create_node; a.setNodeChildren = set_children; a.setNodeBounds = set_bounds; a.createLeaf = create_leaf;
    Node* root = rtcBuildBVH(&a);
    if (root->leaf) { fprintf(stderr, "root is a leaf\n"); return 1; }
    // Flatten as src/bvh/wide.rs's assemble: a node's interior children take consecutive slots
    // when it is written; leaves' triangles follow in the order they are met.
    node_cap = n; nodes = calloc(node_cap, sizeof(WideNode)); out_tris = malloc(ts); new_index = malloc(n * 4);
    Node** work = malloc(sizeof(Node*) * n); size_t* wslot = malloc(sizeof(size_t) * n); size_t top = 0;
    node_count = 1; work[top] = root; wslot[top++] = 0;
    while (top) {
        Node* x = work[--top]; size_t at = wslot[top]; WideNode w; memset(&w, 0, sizeof w);
        for (unsigned i = 0; i < x->n; ++i) {
            w.min_x[i] = x->b[i].lower_x; w.min_y[i] = x->b[i].lower_y; w.min_z[i] = x->b[i].lower_z;
            w.max_x[i] = x->b[i].upper_x; w.max_y[i] = x->b[i].upper_y; w.max_z[i] = x->b[i].upper_z;
            Node* c = x->c[i];
            if (c->leaf) {
                w.child[i] = ~(int32_t)placed; w.count[i] = c->count;
                for (unsigned k = 0; k < c->count; ++k) { memcpy(&out_tris[placed * 12], &tris[c->ids[k] * 12], 48); new_index[c->ids[k]] = placed++; }
            } else {
                w.child[i] = node_count; work[top] = c; wslot[top++] = node_count++;
            }
        }
        nodes[at] = w;
    }
    if (placed != n) { fprintf(stderr, "placed %zu of %zu (spatial splits duplicate; not supported)\n", placed, n); return 1; }
    size_t leaves = 0; for (size_t i = 0; i < node_count; ++i) for (int k = 0; k < 4; ++k) leaves += nodes[i].count[k] > 0;
    fprintf(stderr, "Embree tree: %zu wide nodes, %zu leaves (%.2f triangles a leaf)\n", node_count, leaves, (double)n / leaves);
    save(out, "nodes.bin", nodes, node_count * sizeof(WideNode)); save(out, "tris.bin", out_tris, ts);
    save_sets(in, out, new_index);
    return 0;
}
