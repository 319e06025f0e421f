// Scattering at a surface. Contract: bsdf_eval returns f(wo, wi) * |cos(n, wi)| and its pdf
// (solid angle); bsdf_sample returns that value divided by the pdf, or 0 when no direction is made.

typedef struct {
    float3 base_color;
    float metallic;
    float roughness;
    float ior;
    float specular_factor;
    float3 specular_color;
} SurfaceMaterial;

inline SurfaceMaterial surface_material(global const GpuMaterial* m) {
    SurfaceMaterial s;
    s.base_color = m->base_color.xyz;
    s.metallic = m->params.x;
    s.roughness = m->params.y;
    s.ior = m->params.z;
    s.specular_factor = m->params.w;
    s.specular_color = m->specular.xyz;
    return s;
}

// Lambertian diffuse from the base color.
inline float3 bsdf_eval(const SurfaceMaterial* m, float3 n, float3 wo, float3 wi, float* pdf) {
    float cos_i = dot(n, wi);
    if (cos_i <= 0.0f || dot(n, wo) <= 0.0f) {
        *pdf = 0.0f;
        return (float3)(0.0f);
    }
    *pdf = cos_i * INV_PI_F;
    return m->base_color * (cos_i * INV_PI_F);
}

inline float3 bsdf_sample(const SurfaceMaterial* m, float3 n, float3 wo, float u1, float u2,
                          float3* wi, float* pdf, bool* specular) {
    float3 v_local = sample_cosine(u1, u2);
    *wi = to_world(v_local, n);
    *pdf = v_local.z * INV_PI_F;
    *specular = false;
    if (*pdf <= 0.0f || dot(n, wo) <= 0.0f) return (float3)(0.0f);
    return m->base_color;
}
