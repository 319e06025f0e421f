// Traversal alone, for `bench trace` and the device agreement tests.

kernel void trace_closest(global const GpuBvhNode* nodes, global const GpuTriangle* tris,
                          global const GpuTriShading* shading,
                          global const GpuTriTangents* tangents,
                          global const GpuMaterial* materials, global const GpuTexRef* tex_refs,
                          global const GpuTexture* textures, global const uint* texels,
                          global const GpuRay* rays, uint count, global GpuHit* hits,
                          volatile global uint* counters) {
    uint i = get_global_id(0);
    if (i >= count) return;
    SceneSurfaces surf = {shading, tangents, materials, tex_refs, textures, texels};
    GpuRay r = rays[i];
    hits[i] = traverse(nodes, tris, &surf, r.origin.xyz, r.direction.xyz, r.origin.w,
                       r.direction.w, false, &counters[COUNT_OVERFLOW]);
}

kernel void trace_any(global const GpuBvhNode* nodes, global const GpuTriangle* tris,
                      global const GpuTriShading* shading, global const GpuTriTangents* tangents,
                      global const GpuMaterial* materials, global const GpuTexRef* tex_refs,
                      global const GpuTexture* textures, global const uint* texels,
                      global const GpuRay* rays, uint count, global uint* occluded,
                      volatile global uint* counters) {
    uint i = get_global_id(0);
    if (i >= count) return;
    SceneSurfaces surf = {shading, tangents, materials, tex_refs, textures, texels};
    GpuRay r = rays[i];
    GpuHit h = traverse(nodes, tris, &surf, r.origin.xyz, r.direction.xyz, r.origin.w,
                        r.direction.w, true, &counters[COUNT_OVERFLOW]);
    occluded[i] = h.prim != NO_HIT ? 1u : 0u;
}
