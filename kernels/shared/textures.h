// Textures: RGBA8 mip chains packed in one uint buffer (DeviceTexture describes each), looked up
// through a material's DeviceTexRef (sampler wrap modes, texture coordinate set, KHR_texture_transform).
// Lookups are bilinear within one mip level; the level comes from the ray cone's footprint
// (Akenine-Moller et al., Ray Tracing Gems ch. 20), rounded up or down at random in proportion
// to the fraction, which averages to trilinear filtering over the samples of a pixel.
#ifndef SHARED_TEXTURES_H
#define SHARED_TEXTURES_H

#include "shared/types.h"
#include "shared/rng.h"

// What traversal and shading read about surfaces besides the triangles themselves.
typedef struct {
    global const DeviceTriShading* shading;
    global const DeviceTriUvs* uvs;  // a placeholder without HAS_TEXTURES
    global const DeviceTriTangents* tangents;
    global const DeviceTriColors* colors;  // a placeholder without HAS_VERTEX_COLORS
    global const DeviceMaterial* materials;
    global const DeviceTexRef* refs;
    global const DeviceTexture* textures;
    global const uint* texels;
    // Two levels: the instances, whose transforms carry object-space hits to world space for
    // shading (unused with the flat BVH; kernels that only trace may leave it out).
    global const DeviceInstance* instances;
#ifdef SMALL_SCENE
    // The megakernel's copy of a small scene's triangles and normals (traverse_wide.h), in
    // local memory; 0 in other kernels, which leave it out.
    local const struct SmallScene* small;
#endif
} SceneSurfaces;

// Texture coordinates at a hit and the mip level of one texel per unit of UV area per set:
// a texture of w x h texels is read at level lod + 0.5 log2(w h |det transform|).
typedef struct {
    float2 uv0;
    float2 uv1;
    float lod0;
    float lod1;
    float xi;  // picks the finer or the coarser of the two nearest levels
} TexCoords;

#ifdef HAS_TEXTURES

// sRGB-encoded byte to linear value.
constant float SRGB_TO_LINEAR[256] = {
    0.000000000e+00f, 3.035269835e-04f, 6.070539671e-04f, 9.105809506e-04f, 1.214107934e-03f, 1.517634918e-03f,
    1.821161901e-03f, 2.124688885e-03f, 2.428215868e-03f, 2.731742852e-03f, 3.035269835e-03f, 3.346535764e-03f,
    3.676507324e-03f, 4.024717018e-03f, 4.391442037e-03f, 4.776953481e-03f, 5.181516702e-03f, 5.605391624e-03f,
    6.048833023e-03f, 6.512090793e-03f, 6.995410187e-03f, 7.499032043e-03f, 8.023192985e-03f, 8.568125618e-03f,
    9.134058702e-03f, 9.721217320e-03f, 1.032982303e-02f, 1.096009401e-02f, 1.161224518e-02f, 1.228648836e-02f,
    1.298303234e-02f, 1.370208305e-02f, 1.444384360e-02f, 1.520851442e-02f, 1.599629337e-02f, 1.680737575e-02f,
    1.764195449e-02f, 1.850022013e-02f, 1.938236096e-02f, 2.028856306e-02f, 2.121901038e-02f, 2.217388479e-02f,
    2.315336618e-02f, 2.415763245e-02f, 2.518685963e-02f, 2.624122189e-02f, 2.732089164e-02f, 2.842603950e-02f,
    2.955683444e-02f, 3.071344373e-02f, 3.189603307e-02f, 3.310476657e-02f, 3.433980681e-02f, 3.560131488e-02f,
    3.688945040e-02f, 3.820437160e-02f, 3.954623528e-02f, 4.091519691e-02f, 4.231141062e-02f, 4.373502926e-02f,
    4.518620439e-02f, 4.666508634e-02f, 4.817182423e-02f, 4.970656598e-02f, 5.126945837e-02f, 5.286064702e-02f,
    5.448027644e-02f, 5.612849005e-02f, 5.780543019e-02f, 5.951123816e-02f, 6.124605423e-02f, 6.301001765e-02f,
    6.480326669e-02f, 6.662593864e-02f, 6.847816984e-02f, 7.036009570e-02f, 7.227185068e-02f, 7.421356838e-02f,
    7.618538148e-02f, 7.818742181e-02f, 8.021982031e-02f, 8.228270713e-02f, 8.437621154e-02f, 8.650046204e-02f,
    8.865558629e-02f, 9.084171118e-02f, 9.305896285e-02f, 9.530746663e-02f, 9.758734714e-02f, 9.989872825e-02f,
    1.022417331e-01f, 1.046164841e-01f, 1.070231030e-01f, 1.094617108e-01f, 1.119324278e-01f, 1.144353738e-01f,
    1.169706678e-01f, 1.195384280e-01f, 1.221387722e-01f, 1.247718176e-01f, 1.274376804e-01f, 1.301364767e-01f,
    1.328683216e-01f, 1.356333297e-01f, 1.384316150e-01f, 1.412632911e-01f, 1.441284709e-01f, 1.470272665e-01f,
    1.499597898e-01f, 1.529261520e-01f, 1.559264637e-01f, 1.589608351e-01f, 1.620293756e-01f, 1.651321945e-01f,
    1.682694002e-01f, 1.714411007e-01f, 1.746474037e-01f, 1.778884160e-01f, 1.811642442e-01f, 1.844749945e-01f,
    1.878207723e-01f, 1.912016827e-01f, 1.946178304e-01f, 1.980693196e-01f, 2.015562538e-01f, 2.050787364e-01f,
    2.086368701e-01f, 2.122307574e-01f, 2.158605001e-01f, 2.195261997e-01f, 2.232279573e-01f, 2.269658735e-01f,
    2.307400485e-01f, 2.345505822e-01f, 2.383975738e-01f, 2.422811225e-01f, 2.462013267e-01f, 2.501582847e-01f,
    2.541520943e-01f, 2.581828529e-01f, 2.622506575e-01f, 2.663556048e-01f, 2.704977910e-01f, 2.746773121e-01f,
    2.788942635e-01f, 2.831487404e-01f, 2.874408377e-01f, 2.917706498e-01f, 2.961382708e-01f, 3.005437944e-01f,
    3.049873141e-01f, 3.094689228e-01f, 3.139887134e-01f, 3.185467781e-01f, 3.231432091e-01f, 3.277780981e-01f,
    3.324515363e-01f, 3.371636150e-01f, 3.419144249e-01f, 3.467040564e-01f, 3.515325995e-01f, 3.564001441e-01f,
    3.613067798e-01f, 3.662525956e-01f, 3.712376805e-01f, 3.762621230e-01f, 3.813260114e-01f, 3.864294338e-01f,
    3.915724777e-01f, 3.967552307e-01f, 4.019777798e-01f, 4.072402119e-01f, 4.125426135e-01f, 4.178850708e-01f,
    4.232676700e-01f, 4.286904966e-01f, 4.341536362e-01f, 4.396571738e-01f, 4.452011945e-01f, 4.507857828e-01f,
    4.564110232e-01f, 4.620769997e-01f, 4.677837961e-01f, 4.735314961e-01f, 4.793201831e-01f, 4.851499401e-01f,
    4.910208498e-01f, 4.969329951e-01f, 5.028864580e-01f, 5.088813209e-01f, 5.149176654e-01f, 5.209955732e-01f,
    5.271151257e-01f, 5.332764040e-01f, 5.394794890e-01f, 5.457244614e-01f, 5.520114015e-01f, 5.583403896e-01f,
    5.647115057e-01f, 5.711248295e-01f, 5.775804404e-01f, 5.840784179e-01f, 5.906188409e-01f, 5.972017884e-01f,
    6.038273389e-01f, 6.104955708e-01f, 6.172065624e-01f, 6.239603917e-01f, 6.307571363e-01f, 6.375968740e-01f,
    6.444796820e-01f, 6.514056374e-01f, 6.583748173e-01f, 6.653872983e-01f, 6.724431570e-01f, 6.795424696e-01f,
    6.866853124e-01f, 6.938717613e-01f, 7.011018919e-01f, 7.083757799e-01f, 7.156935005e-01f, 7.230551289e-01f,
    7.304607401e-01f, 7.379104088e-01f, 7.454042095e-01f, 7.529422168e-01f, 7.605245047e-01f, 7.681511472e-01f,
    7.758222183e-01f, 7.835377915e-01f, 7.912979403e-01f, 7.991027380e-01f, 8.069522577e-01f, 8.148465722e-01f,
    8.227857544e-01f, 8.307698768e-01f, 8.387990117e-01f, 8.468732315e-01f, 8.549926081e-01f, 8.631572135e-01f,
    8.713671192e-01f, 8.796223969e-01f, 8.879231179e-01f, 8.962693534e-01f, 9.046611744e-01f, 9.130986518e-01f,
    9.215818563e-01f, 9.301108584e-01f, 9.386857285e-01f, 9.473065367e-01f, 9.559733532e-01f, 9.646862479e-01f,
    9.734452904e-01f, 9.822505503e-01f, 9.911020971e-01f, 1.000000000e+00f,
};

inline float4 unpack_texel(uint t, bool srgb) {
    uint r = t & 0xffu;
    uint g = (t >> 8) & 0xffu;
    uint b = (t >> 16) & 0xffu;
    float a = (float)(t >> 24) * (1.0f / 255.0f);
    if (srgb) return (float4)(SRGB_TO_LINEAR[r], SRGB_TO_LINEAR[g], SRGB_TO_LINEAR[b], a);
    return (float4)((float)r, (float)g, (float)b, (float)(t >> 24)) * (1.0f / 255.0f);
}

// Texel index i folded into [0, n) by a wrap mode.
inline int wrap_texel(int i, int n, int mode) {
    if (mode == WRAP_CLAMP) return clamp(i, 0, n - 1);
    if (mode == WRAP_MIRROR) {
        int period = 2 * n;
        int m = i % period;
        if (m < 0) m += period;
        return m < n ? m : period - 1 - m;
    }
    int m = i % n;
    return m < 0 ? m + n : m;
}

// Bilinear (or with `nearest`, nearest-texel) lookup of level `level` at texture coordinate st
// (texel centres at half-integers).
inline float4 texture_level(const SceneSurfaces* s, DeviceTexture t, int wrap_s, int wrap_t,
                            float2 st, uint level, bool nearest) {
    uint offset = t.offset;
    uint w = t.width;
    uint h = t.height;
    for (uint l = 0; l < level; ++l) {
        offset += w * h;
        w = max(1u, w >> 1);
        h = max(1u, h >> 1);
    }
    // Keep far-away coordinates inside int range; wrapping makes the shift invisible for
    // repeat and mirror, and clamp does not care.
    float2 p = clamp(st, -65536.0f, 65536.0f) * (float2)((float)w, (float)h) - 0.5f;
    float2 f = floor(p);
    float2 a = p - f;
    int x0 = (int)f.x;
    int y0 = (int)f.y;
    int xa = wrap_texel(x0, (int)w, wrap_s);
    int xb = wrap_texel(x0 + 1, (int)w, wrap_s);
    int ya = wrap_texel(y0, (int)h, wrap_t);
    int yb = wrap_texel(y0 + 1, (int)h, wrap_t);
    bool srgb = (t.flags & TEXTURE_SRGB) != 0u;
    global const uint* texels = s->texels + offset;
    if (nearest) {
        // The texel whose square holds st: the nearer of the bilinear pair on each axis.
        int x = a.x < 0.5f ? xa : xb;
        int y = a.y < 0.5f ? ya : yb;
        return unpack_texel(texels[y * (int)w + x], srgb);
    }
    float4 c00 = unpack_texel(texels[ya * (int)w + xa], srgb);
    float4 c10 = unpack_texel(texels[ya * (int)w + xb], srgb);
    float4 c01 = unpack_texel(texels[yb * (int)w + xa], srgb);
    float4 c11 = unpack_texel(texels[yb * (int)w + xb], srgb);
    return mix(mix(c00, c10, a.x), mix(c01, c11, a.x), a.y);
}

// Looks up texture reference `ref` at a hit.
inline float4 texture_sample(const SceneSurfaces* s, int ref, const TexCoords* tc) {
    DeviceTexRef r = s->refs[ref];
    bool second = as_uint(r.m0.w) == 1u;
    float3 uv = (float3)(second ? tc->uv1 : tc->uv0, 1.0f);
    float2 st = (float2)(dot(r.m0.xyz, uv), dot(r.m1.xyz, uv));
    DeviceTexture t = s->textures[r.info.x];
    uint levels = t.flags & TEXTURE_LEVELS_MASK;
    float lod = (second ? tc->lod1 : tc->lod0) + r.m1.w +
                0.5f * log2((float)t.width * (float)t.height);
    lod = clamp(lod, 0.0f, (float)(levels - 1u));
    uint level = (uint)lod;
    if (tc->xi < lod - (float)level) level = min(level + 1u, levels - 1u);
    if ((r.info.w & TEXREF_NO_MIPS) != 0) level = 0u;
    return texture_level(s, t, r.info.y, r.info.z, st, level, (r.info.w & TEXREF_NEAREST) != 0);
}

#endif

// Interpolated texture coordinates at barycentrics (u, v) with the finest level everywhere
// (alpha tests and light sampling, where footprints are unknown).
inline TexCoords texcoords_at(DeviceTriUvs sh, float u, float v) {
    float w0 = 1.0f - u - v;
    TexCoords tc;
    tc.uv0 = w0 * sh.uv01.xy + u * sh.uv01.zw + v * sh.uv2.xy;
    tc.uv1 = w0 * sh.uv2.zw + u * sh.uv1_12.xy + v * sh.uv1_12.zw;
    tc.lod0 = -INFINITY;
    tc.lod1 = -INFINITY;
    tc.xi = 0.0f;
    return tc;
}

// The ray-cone level of detail at a hit: a cone of `width` meets the triangle (edges e1, e2)
// at cosine `cos_i`; each set's level adds half the log of its texture-to-world area ratio.
inline void texcoords_footprint(TexCoords* tc, DeviceTriUvs sh, float3 e1, float3 e2,
                                float width, float cos_i) {
    float world = fmax(length(cross(e1, e2)), 1e-30f);
    float2 a0 = sh.uv01.zw - sh.uv01.xy;
    float2 b0 = sh.uv2.xy - sh.uv01.xy;
    float2 a1 = sh.uv1_12.xy - sh.uv2.zw;
    float2 b1 = sh.uv1_12.zw - sh.uv2.zw;
    float uv_area0 = fabs(a0.x * b0.y - a0.y * b0.x);
    float uv_area1 = fabs(a1.x * b1.y - a1.y * b1.x);
    float base = log2(width / fmax(cos_i, 1e-3f));
    tc->lod0 = base + 0.5f * log2(uv_area0 / world);
    tc->lod1 = base + 0.5f * log2(uv_area1 / world);
}

#ifdef HAS_VERTEX_COLORS
// COLOR_0 of triangle `prim` at barycentrics (u, v) (u: weight of vertex 1): what the glTF spec
// multiplies into the base color and its alpha.
inline float4 vertex_color(const SceneSurfaces* s, uint prim, float u, float v) {
    DeviceTriColors c = s->colors[prim];
    return (1.0f - u - v) * c.c0 + u * c.c1 + v * c.c2;
}
#endif

#ifdef HAS_ALPHA
// Whether a ray passes through triangle `prim` at barycentrics (u, v): MASK below the cutoff
// always; BLEND with probability 1 - alpha, decided by a hash of the ray and the triangle so
// that extension and shadow rays alike see a consistent stochastic surface.
inline bool alpha_passes(const SceneSurfaces* s, uint prim, uint material, float u, float v,
                         float3 o, float3 d) {
    global const DeviceMaterial* m = &s->materials[material];
    uint mode = as_uint(m->alpha.y);
    if (mode == ALPHA_OPAQUE) return false;
    float alpha = m->base_color.w;
#ifdef HAS_TEXTURES
    if (m->textures.x >= 0) {
        TexCoords tc = texcoords_at(s->uvs[prim], u, v);
        alpha *= texture_sample(s, m->textures.x, &tc).w;
    }
#endif
#ifdef HAS_VERTEX_COLORS
    alpha *= vertex_color(s, prim, u, v).w;
#endif
    if (mode == ALPHA_MASK) return alpha < m->alpha.x;
    uint h = hash_u32(prim ^ hash_u32(as_uint(o.x) ^ hash_u32(as_uint(o.y) ^
             hash_u32(as_uint(o.z) ^ hash_u32(as_uint(d.x) ^ hash_u32(as_uint(d.y) ^
             hash_u32(as_uint(d.z))))))));
    return (float)(h >> 8) * (1.0f / 16777216.0f) >= alpha;
}
#endif

#endif  // SHARED_TEXTURES_H
