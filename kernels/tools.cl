// Traversal alone, for `bench trace` and the device agreement tests.

#include "shared/types.h"
#include "shared/textures.h"
#include "shared/traverse.h"
#include "shared/traverse_wide.h"

// Closest hits and occlusion of arbitrary rays through the binary BVH (traverse.h) and the
// 4-wide one (traverse_wide.h); one definition for both.
#define TRACE_KERNELS(SUFFIX, NODE, TRAVERSE)                                                   \
    kernel void trace_closest##SUFFIX(                                                           \
        global const NODE* nodes, global const DeviceTriangle* tris,                                \
        global const DeviceInstance* instances, global const DeviceTriangle* object_tris,              \
        global const DeviceTriShading* shading, global const DeviceTriUvs* uvs,                        \
        global const DeviceTriTangents* tangents, global const DeviceTriColors* colors,             \
        global const DeviceMaterial* materials, global const DeviceTexRef* tex_refs,                   \
        global const DeviceTexture* textures, global const uint* texels, global const DeviceRay* rays, \
        uint count, global DeviceHit* hits, volatile global uint* counters) {                       \
        uint i = get_global_id(0);                                                               \
        if (i >= count) return;                                                                  \
        SceneSurfaces surf = {shading,  uvs,    tangents, colors,  materials,                    \
                              tex_refs, textures, texels, instances};                            \
        DeviceRay r = rays[i];                                                                      \
        hits[i] = TRAVERSE(nodes, tris, instances, object_tris, &surf, r.origin.xyz,             \
                           r.direction.xyz, r.origin.w, r.direction.w, false,                    \
                           &counters[COUNT_OVERFLOW]);                                           \
    }                                                                                            \
    kernel void trace_any##SUFFIX(                                                               \
        global const NODE* nodes, global const DeviceTriangle* tris,                                \
        global const DeviceInstance* instances, global const DeviceTriangle* object_tris,              \
        global const DeviceTriShading* shading, global const DeviceTriUvs* uvs,                        \
        global const DeviceTriTangents* tangents, global const DeviceTriColors* colors,             \
        global const DeviceMaterial* materials, global const DeviceTexRef* tex_refs,                   \
        global const DeviceTexture* textures, global const uint* texels, global const DeviceRay* rays, \
        uint count, global uint* occluded, volatile global uint* counters) {                     \
        uint i = get_global_id(0);                                                               \
        if (i >= count) return;                                                                  \
        SceneSurfaces surf = {shading,  uvs,    tangents, colors,  materials,                    \
                              tex_refs, textures, texels, instances};                            \
        DeviceRay r = rays[i];                                                                      \
        DeviceHit h = TRAVERSE(nodes, tris, instances, object_tris, &surf, r.origin.xyz,            \
                            r.direction.xyz, r.origin.w, r.direction.w, true,                    \
                            &counters[COUNT_OVERFLOW]);                                          \
        occluded[i] = h.prim != NO_HIT ? 1u : 0u;                                                \
    }

TRACE_KERNELS(, DeviceBvhNode, trace_scene)
TRACE_KERNELS(_wide, DeviceWideNode, trace_scene_wide)
