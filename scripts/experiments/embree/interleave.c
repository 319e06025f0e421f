// Relayouts a PENUMBRA_DUMP_TRACE dump so that nodes and triangles share one buffer, in the
// order a depth-first walk meets them (Embree's allocator order): each wide node at a 128-byte
// boundary, then the triangles of its leaves at 48-byte steps. Node index = offset / 128,
// triangle index = offset / 48. Writes the buffer as nodes.bin with an empty tris.bin (for
// native_trace: both pointers on it) and the rays with remapped hits.
#include "dump.h"
static size_t up(size_t x, size_t a) { return (x + a - 1) / a * a; }
int main(int argc, char** argv) {
    const char* in = argv[1]; const char* out = argv[2];
    size_t ns, ts; WideNode* nodes = load(in, "nodes.bin", &ns); char* tris = load(in, "tris.bin", &ts);
    size_t nn = ns / sizeof(WideNode), nt = ts / 48;
    size_t cap = ns * 2 + ts * 2 + (1 << 20); char* buf = calloc(cap, 1);
    uint32_t* new_node = malloc(nn * 4); uint32_t* new_tri = malloc(nt * 4);
    size_t at = 0;
    // Depth-first order: pop a node, place it, place its leaves' triangles, push its interior
    // children (last slot first, so that slot 0 comes next).
    uint32_t* stack = malloc(nn * 4); size_t sp = 0; stack[sp++] = 0;
    uint32_t* order = malloc(nn * 4); size_t placed = 0;
    while (sp) {
        uint32_t i = stack[--sp]; order[placed++] = i;
        at = up(at, 128); new_node[i] = at / 128; at += 128;
        for (int c = 0; c < 4; ++c) {
            if (nodes[i].count[c] > 0) {
                uint32_t first = ~nodes[i].child[c];
                at = up(at, 48);
                for (uint32_t k = 0; k < nodes[i].count[c]; ++k) { new_tri[first + k] = at / 48; at += 48; }
            }
        }
        for (int c = 3; c >= 0; --c) if (nodes[i].count[c] == 0 && nodes[i].child[c] > 0) stack[sp++] = nodes[i].child[c];
    }
    if (placed != nn) { fprintf(stderr, "reached %zu of %zu nodes\n", placed, nn); }
    for (size_t i = 0; i < nn; ++i) {
        WideNode w = nodes[i];
        for (int c = 0; c < 4; ++c) {
            if (w.count[c] > 0) { uint32_t first = ~w.child[c]; w.child[c] = ~(int32_t)new_tri[first];
                for (uint32_t k = 0; k < w.count[c]; ++k) memcpy(buf + (size_t)new_tri[first + k] * 48, tris + (size_t)(first + k) * 48, 48); }
            else if (w.child[c] > 0) w.child[c] = new_node[w.child[c]];
        }
        memcpy(buf + (size_t)new_node[i] * 128, &w, 128);
    }
    if (new_node[0] != 0) { fprintf(stderr, "root not at 0\n"); return 1; }
    fprintf(stderr, "interleaved: %zu bytes (nodes %zu + triangles %zu)\n", at, ns, ts);
    save(out, "nodes.bin", buf, up(at, 128)); save(out, "tris.bin", "", 0);
    save_sets(in, out, new_tri);
    return 0;
}
