// Embree 3 (Debian 12's libembree-dev) on rays dumped by PENUMBRA_DUMP_TRACE: one thread,
// rtcIntersect1 per ray over the primary and diffuse sets (the dump has no shadow rays),
// thread CPU time; hits compared with the device's.
#include <embree3/rtcore.h>
#include <math.h>
#include "dump.h"
#include <time.h>
#include <xmmintrin.h>
#include <pmmintrin.h>
static double cpu_s(void) { struct timespec t; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }
int main(int argc, char** argv) {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON); _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    const char* dir = argv[1];
    const char* quality = argc > 2 ? argv[2] : "medium";
    size_t ts; float* tris = load(dir, "tris.bin", &ts);
    size_t n = ts / 48;
    char cfg[256]; snprintf(cfg, sizeof cfg, "threads=1,%s", argc > 3 ? argv[3] : ""); RTCDevice dev = rtcNewDevice(cfg); fprintf(stderr, "config %s\n", cfg);
    RTCScene scene = rtcNewScene(dev);
    if (!strcmp(quality, "high")) rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    if (!strcmp(quality, "robust")) rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    if (!strcmp(quality, "low")) rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float* v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, 3 * n);
    uint32_t* idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, n);
    for (size_t i = 0; i < n; ++i) for (int k = 0; k < 3; ++k) { memcpy(&v[(3 * i + k) * 3], &tris[i * 12 + k * 4], 12); idx[3 * i + k] = 3 * i + k; }
    rtcCommitGeometry(g); rtcAttachGeometry(scene, g); rtcReleaseGeometry(g);
    double b0 = cpu_s(); rtcCommitScene(scene); fprintf(stderr, "%zu triangles, build %.2f s (%s)\n", n, cpu_s() - b0, quality);
    const char* sets[] = {"primary", "diffuse", "shadow"};
    struct RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
    for (int s = 0; s < 2; ++s) {
        char name[64]; size_t rs, hs;
        snprintf(name, sizeof name, "%s_rays.bin", sets[s]); Ray* rays = load(dir, name, &rs);
        snprintf(name, sizeof name, "%s_hits.bin", sets[s]); Hit* want = load(dir, name, &hs);
        size_t m = rs / sizeof(Ray); double best = 1e9; size_t hits = 0, bad = 0;
        for (int pass = 0; pass < 4; ++pass) {
            hits = bad = 0; double c0 = cpu_s();
            for (size_t i = 0; i < m; ++i) {
                Ray* r = &rays[i];
                if (s == 2) {
                    struct RTCRay ray = {r->o[0], r->o[1], r->o[2], r->o[3], r->d[0], r->d[1], r->d[2], 0.0f, r->d[3], -1u, 0, 0};
                    rtcOccluded1(scene, &ctx, &ray);
                    int hit = ray.tfar < 0.0f; hits += hit;
                    if (pass == 0 && hit != (want[i].prim != 0xffffffffu)) ++bad;
                } else {
                    struct RTCRayHit rh; memset(&rh, 0, sizeof rh);
                    rh.ray.org_x = r->o[0]; rh.ray.org_y = r->o[1]; rh.ray.org_z = r->o[2]; rh.ray.tnear = r->o[3];
                    rh.ray.dir_x = r->d[0]; rh.ray.dir_y = r->d[1]; rh.ray.dir_z = r->d[2]; rh.ray.tfar = r->d[3];
                    rh.ray.mask = -1u; rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &ctx, &rh);
                    if (getenv("TWICE")) { float tf = r->d[3]; rh.ray.tfar = tf; rh.hit.geomID = RTC_INVALID_GEOMETRY_ID; rtcIntersect1(scene, &ctx, &rh); }
                    int hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID; hits += hit;
                    if (pass == 0) { int wh = want[i].prim != 0xffffffffu; if (hit != wh || (hit && fabsf(rh.ray.tfar - want[i].t) > 1e-4f * fmaxf(1.0f, want[i].t))) ++bad; }
                }
            }
            double c = cpu_s() - c0; if (c < best) best = c;
        }
        printf("%-8s %zu rays, %zu hits, %zu differ from the device's; best of 4: %.3f CPU s, %.0f ns a ray, %.2f M rays per CPU s\n", sets[s], m, hits, bad, best, best / m * 1e9, m / best / 1e6);
    }
    return 0;
}
