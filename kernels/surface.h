// What a hit's textures do to its material: base color, metallic-roughness, transmission and
// emission, and the shading normal from a tangent-space normal map.

#ifdef HAS_TEXTURES
// Multiplies the material's factors by its textures at the hit.
inline void apply_textures(SurfaceMaterial* m, global const GpuMaterial* mat,
                           const SceneSurfaces* s, const TexCoords* tc) {
    if (mat->textures.x >= 0) m->base_color *= texture_sample(s, mat->textures.x, tc).xyz;
    if (mat->textures.y >= 0) {
        float4 mr = texture_sample(s, mat->textures.y, tc);
        m->roughness *= mr.y;
        m->metallic *= mr.z;
    }
#ifdef HAS_TRANSMISSION
    if (mat->textures2.x >= 0) m->transmission *= texture_sample(s, mat->textures2.x, tc).x;
#endif
#ifdef HAS_CLEARCOAT
    if (mat->textures3.x >= 0) m->clearcoat *= texture_sample(s, mat->textures3.x, tc).x;
    if (mat->textures3.y >= 0) m->coat_roughness *= texture_sample(s, mat->textures3.y, tc).y;
#endif
#ifdef HAS_SHEEN
    if (mat->textures2.z >= 0) m->sheen_color *= texture_sample(s, mat->textures2.z, tc).xyz;
    if (mat->textures2.w >= 0) m->sheen_roughness *= texture_sample(s, mat->textures2.w, tc).w;
#endif
#ifdef HAS_DIFFUSE_TRANSMISSION
    if (mat->textures4.w >= 0) m->diffuse_transmission *= texture_sample(s, mat->textures4.w, tc).w;
    if (mat->textures5.x >= 0) {
        m->diffuse_transmission_color *= texture_sample(s, mat->textures5.x, tc).xyz;
    }
#endif
#ifdef HAS_IRIDESCENCE
    // R: the factor; G: the thickness between the minimum and the maximum (else the maximum).
    if (mat->textures4.y >= 0) m->iridescence *= texture_sample(s, mat->textures4.y, tc).x;
    if (mat->textures4.z >= 0) {
        m->iridescence_thickness =
            mix(mat->iridescence.z, mat->iridescence.w, texture_sample(s, mat->textures4.z, tc).y);
    }
#endif
#ifdef HAS_ANISOTROPY
    // RG: the direction in tangent space (then turned by the rotation), B: the strength.
    if (mat->textures4.x >= 0) {
        float3 a = texture_sample(s, mat->textures4.x, tc).xyz;
        float2 d = a.xy * 2.0f - 1.0f;
        float2 r = m->aniso_rotation;
        if (dot(d, d) > 1e-12f) m->aniso_rotation = (float2)(r.x * d.x - r.y * d.y, r.y * d.x + r.x * d.y);
        m->anisotropy *= a.z;
    }
#endif
}

// Emitted radiance at the hit: the factor times the emissive texture.
inline float3 textured_emission(global const GpuMaterial* mat, const SceneSurfaces* s,
                                const TexCoords* tc) {
    float3 e = mat->emission.xyz;
    if (mat->textures.w >= 0) e *= texture_sample(s, mat->textures.w, tc).xyz;
    return e;
}
#endif

#ifdef HAS_NORMAL_MAPS
// The shading normal from the normal map `tex` scaled by `scale` (the material's normal
// texture, or its clearcoat normal texture). ns and ng face the side the ray came from; `front`
// says whether that is the triangle's front, in which case the tangent frame is the file's,
// else every axis of it is reversed (glTF reverses back-face normals of double-sided
// materials). The result is bent to stay above the geometric surface.
inline float3 normal_map(const SceneSurfaces* s, int tex, float scale, const TexCoords* tc,
                         uint prim, float u, float v, float3 ns, float3 ng, bool front) {
    GpuTriTangents tt = s->tangents[prim];
    float w0 = 1.0f - u - v;
    float3 t = w0 * tt.t0.xyz + u * tt.t1.xyz + v * tt.t2.xyz;
    float3 n = front ? ns : -ns;
    t -= n * dot(n, t);
    float len = length(t);
    if (!(len > 1e-8f)) return ns;
    t /= len;
    float3 b = cross(n, t) * (tt.t0.w < 0.0f ? -1.0f : 1.0f);
    float3 c = texture_sample(s, tex, tc).xyz * 2.0f - 1.0f;
    float3 mapped = normalize(c.x * scale * t + c.y * scale * b + c.z * n);
    if (!all(isfinite(mapped))) return ns;
    if (!front) mapped = -mapped;
    float cos_g = dot(mapped, ng);
    if (cos_g < 0.01f) mapped = normalize(mapped + (0.01f - cos_g) * ng);
    return mapped;
}
#endif

#ifdef HAS_ANISOTROPY
// The anisotropy direction (world) at a hit: `dir` (cos, sin of its angle, or the texture's
// direction turned by the rotation) in the frame (T, B) of the interpolated tangent, made
// orthogonal to the shading normal ns, and B = w N × T as normal maps use it (the file's frame,
// reversed on back faces). Without a tangent (no texture coordinates) the frame is onb's.
inline float3 anisotropy_direction(const SceneSurfaces* s, uint prim, float u, float v, float3 ns,
                                   bool front, float2 dir) {
    float3 n = front ? ns : -ns;
    float3 t, b;
    onb(n, &t, &b);
#ifdef HAS_TANGENTS
    GpuTriTangents tt = s->tangents[prim];
    float3 tg = (1.0f - u - v) * tt.t0.xyz + u * tt.t1.xyz + v * tt.t2.xyz;
    tg -= n * dot(n, tg);
    float len = length(tg);
    if (len > 1e-8f) {
        t = tg / len;
        b = cross(n, t) * (tt.t0.w < 0.0f ? -1.0f : 1.0f);
    }
#endif
    return dir.x * t + dir.y * b;
}
#endif
