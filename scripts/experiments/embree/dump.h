// Reading and writing the raw arrays of a PENUMBRA_DUMP_TRACE dump (src/bench/trace.rs).
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
typedef struct { float t, u, v; uint32_t prim, instance; } Hit;
typedef struct { float o[4], d[4]; } Ray;
typedef struct { float min_x[4], min_y[4], min_z[4], max_x[4], max_y[4], max_z[4]; int32_t child[4]; uint32_t count[4]; } WideNode;
static void* load(const char* dir, const char* name, size_t* size) {
    char path[1024]; snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE* f = fopen(path, "rb"); if (!f) { perror(path); exit(1); }
    fseek(f, 0, SEEK_END); *size = ftell(f); fseek(f, 0, SEEK_SET);
    void* p = malloc(*size ? *size : 1); if (fread(p, 1, *size, f) != *size) exit(1); fclose(f); return p;
}
static void save(const char* dir, const char* name, const void* p, size_t size) {
    char path[1024]; snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE* f = fopen(path, "wb"); if (!f) { perror(path); exit(1); } fwrite(p, 1, size, f); fclose(f);
}
// Copies the dump's primary and diffuse rays from `in` to `out`, with their hits' triangle
// indices renumbered through new_index (triangles moved by a relayout).
static void save_sets(const char* in, const char* out, const uint32_t* new_index) {
    const char* sets[] = {"primary", "diffuse"};
    for (int s = 0; s < 2; ++s) {
        char name[64]; size_t rs, hs;
        snprintf(name, sizeof name, "%s_rays.bin", sets[s]); void* rays = load(in, name, &rs); save(out, name, rays, rs);
        snprintf(name, sizeof name, "%s_hits.bin", sets[s]); Hit* h = load(in, name, &hs);
        for (size_t i = 0; i < hs / sizeof(Hit); ++i) if (h[i].prim != 0xffffffffu) h[i].prim = new_index[h[i].prim];
        save(out, name, h, hs);
    }
}
