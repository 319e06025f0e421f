// Kernels for tests and benchmarks: traversal alone, and the layout probe.

kernel void trace_closest(global const GpuBvhNode* nodes, global const GpuTriangle* tris,
                          global const GpuRay* rays, uint count, global GpuHit* hits,
                          volatile global uint* counters) {
    uint i = get_global_id(0);
    if (i >= count) return;
    GpuRay r = rays[i];
    hits[i] = traverse(nodes, tris, r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w,
                       false, &counters[COUNT_OVERFLOW]);
}

kernel void trace_any(global const GpuBvhNode* nodes, global const GpuTriangle* tris,
                      global const GpuRay* rays, uint count, global uint* occluded,
                      volatile global uint* counters) {
    uint i = get_global_id(0);
    if (i >= count) return;
    GpuRay r = rays[i];
    GpuHit h = traverse(nodes, tris, r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w,
                        true, &counters[COUNT_OVERFLOW]);
    occluded[i] = h.prim != NO_HIT ? 1u : 0u;
}

// Writes, per shared struct, its size then each field's offset, in the order of
// src/cl/types.rs::layouts().
#define PROBE_SIZE(T) out[n++] = (uint)sizeof(T)
#define PROBE_FIELD(T, f) out[n++] = (uint)((size_t)&((T*)0)->f)
kernel void probe_layout(global uint* out) {
    if (get_global_id(0) != 0) return;
    uint n = 0;
    PROBE_SIZE(GpuBvhNode);
    PROBE_FIELD(GpuBvhNode, left_min); PROBE_FIELD(GpuBvhNode, left_max);
    PROBE_FIELD(GpuBvhNode, right_min); PROBE_FIELD(GpuBvhNode, right_max);
    PROBE_SIZE(GpuTriangle);
    PROBE_FIELD(GpuTriangle, v0); PROBE_FIELD(GpuTriangle, v1); PROBE_FIELD(GpuTriangle, v2);
    PROBE_SIZE(GpuTriShading);
    PROBE_FIELD(GpuTriShading, n0); PROBE_FIELD(GpuTriShading, n1);
    PROBE_FIELD(GpuTriShading, n2); PROBE_FIELD(GpuTriShading, uv01);
    PROBE_FIELD(GpuTriShading, uv2);
    PROBE_SIZE(GpuMaterial);
    PROBE_FIELD(GpuMaterial, base_color); PROBE_FIELD(GpuMaterial, emission);
    PROBE_FIELD(GpuMaterial, params); PROBE_FIELD(GpuMaterial, specular);
    PROBE_FIELD(GpuMaterial, volume); PROBE_FIELD(GpuMaterial, alpha);
    PROBE_FIELD(GpuMaterial, textures); PROBE_FIELD(GpuMaterial, textures2);
    PROBE_SIZE(GpuLight);
    PROBE_FIELD(GpuLight, position); PROBE_FIELD(GpuLight, intensity);
    PROBE_FIELD(GpuLight, spot); PROBE_FIELD(GpuLight, extra);
    PROBE_SIZE(GpuCamera);
    PROBE_FIELD(GpuCamera, origin); PROBE_FIELD(GpuCamera, forward);
    PROBE_FIELD(GpuCamera, right); PROBE_FIELD(GpuCamera, up);
    PROBE_SIZE(GpuFrame);
    PROBE_FIELD(GpuFrame, width); PROBE_FIELD(GpuFrame, height);
    PROBE_FIELD(GpuFrame, samples_in_wave); PROBE_FIELD(GpuFrame, first_sample);
    PROBE_FIELD(GpuFrame, seed); PROBE_FIELD(GpuFrame, max_bounces);
    PROBE_FIELD(GpuFrame, rr_depth); PROBE_FIELD(GpuFrame, strategy);
    PROBE_FIELD(GpuFrame, sky); PROBE_FIELD(GpuFrame, light_count);
    PROBE_FIELD(GpuFrame, light_weight_total); PROBE_FIELD(GpuFrame, bounce);
    PROBE_FIELD(GpuFrame, pad);
    PROBE_SIZE(GpuPath);
    PROBE_FIELD(GpuPath, origin); PROBE_FIELD(GpuPath, direction);
    PROBE_FIELD(GpuPath, throughput); PROBE_FIELD(GpuPath, radiance);
    PROBE_SIZE(GpuHit);
    PROBE_FIELD(GpuHit, t); PROBE_FIELD(GpuHit, u); PROBE_FIELD(GpuHit, v); PROBE_FIELD(GpuHit, prim);
    PROBE_SIZE(GpuShadowRay);
    PROBE_FIELD(GpuShadowRay, origin); PROBE_FIELD(GpuShadowRay, direction);
    PROBE_FIELD(GpuShadowRay, contribution);
    PROBE_SIZE(GpuRay);
    PROBE_FIELD(GpuRay, origin); PROBE_FIELD(GpuRay, direction);
    out[n] = 0xffffffffu;
}
