// Structs shared with the host. Each mirrors one in src/cl/types.rs field for field; the layout
// probe test checks sizes and offsets. No bare float3: payloads ride in .w of a float4.
// The constants named in comments here (TEXTURE_*, WRAP_*, TEXREF_*, MATERIAL_*, ALPHA_*,
// LIGHT_*, STRATEGY_*, PATH_*, COUNT_*, STAT_*, PIXEL_*) are defined once in src/cl/types.rs, from which
// the host generates generated/constants.h (src/cl/source.rs).
#ifndef SHARED_TYPES_H
#define SHARED_TYPES_H

#include "generated/constants.h"

typedef struct {
    float4 left_min;   // .w = left child (int bits): node index, or ~first triangle for a leaf
    float4 left_max;   // .w = left leaf triangle count (uint bits), 0 for an interior child
    float4 right_min;  // .w = right child (int bits)
    float4 right_max;  // .w = right leaf triangle count (uint bits)
} DeviceBvhNode;

// A node of the 4-wide BVH: the children's boxes by coordinate (lane i = child i). A child is
// an interior node (child > 0, count 0), a leaf (child = ~first triangle, count > 0) or an
// empty slot (child <= 0, count 0).
typedef struct {
    float4 min_x, min_y, min_z;
    float4 max_x, max_y, max_z;
    int4 child;
    uint4 count;
} DeviceWideNode;

// One placed mesh of a two-level scene (src/bvh/instances.rs): object_from_world as
// p_object = L (p_world - T), the rows of L with T in .w (T: the world position of the object's
// origin), for traversal; world_from_object as p_world = M p_object + T, the rows of M, for
// shading (triangles and shading data stay in object space, once per mesh); its bottom-level
// roots in the binary and the wide node arrays; its index and its first light.
typedef struct {
    float4 row0;       // first row of L; .w = T.x
    float4 row1;       // .w = T.y
    float4 row2;       // .w = T.z
    float4 world0;     // first row of M; .w = light index of its first emissive triangle (int bits)
    float4 world1;
    float4 world2;
    uint root;         // bottom-level root in the binary nodes
    uint wide_root;    // bottom-level root in the wide nodes
    uint id;           // the instance's index in the scene (host bookkeeping)
    uint flags;        // INSTANCE_MIRRORED, INSTANCE_PIECE_TRIANGLE
} DeviceInstance;

// World space in BVH order; with TWO_LEVEL object space, once per mesh (then v1.w counts the
// mesh's emissive triangles from the instance's first light, and v2.w is 0).
typedef struct {
    float4 v0;  // .w = material index (uint bits)
    float4 v1;  // .w = emissive light index (int bits), -1 when not emissive
    float4 v2;  // .w = object index (uint bits)
} DeviceTriangle;

// Per-corner normals of a triangle (36 bytes; float3 would pad to 48): n[3c..3c+2] is corner
// c's. A flat-shaded triangle's are all 0, whose interpolation, of length 0, leaves the
// geometric normal (path.h), as a flag would.
typedef struct {
    float n[9];
} DeviceTriShading;

// TEXCOORD_0 and TEXCOORD_1 of a triangle's corners (48 bytes); on the device only when some
// material samples a texture (HAS_TEXTURES), else a one-element placeholder that is never read.
typedef struct {
    float4 uv01;  // TEXCOORD_0 of vertices 0 (.xy) and 1 (.zw)
    float4 uv2;   // TEXCOORD_0 of vertex 2 (.xy); TEXCOORD_1 of vertex 0 (.zw)
    float4 uv1_12;  // TEXCOORD_1 of vertices 1 (.xy) and 2 (.zw)
} DeviceTriUvs;

typedef struct {
    float4 t0;  // unit tangent at vertex 0; .w = bitangent sign
    float4 t1;
    float4 t2;
} DeviceTriTangents;

// COLOR_0 at a triangle's corners (linear RGBA); on the device only with HAS_VERTEX_COLORS,
// else a one-element placeholder that is never read.
typedef struct {
    float4 c0;
    float4 c1;
    float4 c2;
} DeviceTriColors;

typedef struct {
    uint offset;  // first texel of level 0; levels follow, level l is max(1, w >> l) x max(1, h >> l)
    uint width;   // of level 0
    uint height;
    uint flags;   // mip level count (TEXTURE_LEVELS_MASK bits) | TEXTURE_SRGB
} DeviceTexture;

typedef struct {
    float4 m0;  // first row of the UV transform; .w = texture coordinate set (uint bits)
    float4 m1;  // second row; .w = 0.5 * log2 |det| (mip bias)
    int4 info;  // .x texture index, .y wrap S, .z wrap T (WRAP_*), .w flags (TEXREF_*)
} DeviceTexRef;

typedef struct {
    float4 scale;     // .x intensity, .y pdf normalization W*H / (sum f * 2 pi^2), .z NEE pick probability
    float4 rotation;  // .x cos, .y sin of the rotation about +Y
    uint width;
    uint height;
    uint light;       // index in the light list
    uint pad;
} DeviceEnvironment;

typedef struct {
    float4 base_color;  // linear base color; .w = alpha
    float4 emission;    // emitted radiance; .w = flags (uint bits, MATERIAL_*)
    float4 params;      // .x metallic, .y roughness, .z ior, .w specularFactor
    float4 specular;    // specularColorFactor; .w = transmission
    float4 volume;      // attenuationColor; .w = attenuationDistance (INFINITY: none)
    float4 alpha;       // .x alphaCutoff, .y mode (uint bits, ALPHA_*), .z thickness, .w normal scale
    int4 textures;      // texture refs: base color, metallic-roughness, normal, emissive; -1 none
    int4 textures2;     // texture refs: .x transmission, .y thickness; -1 none
    float4 coat;        // clearcoat: .x factor, .y roughness, .z normal texture scale
    int4 textures3;     // texture refs: .x clearcoat, .y clearcoat roughness, .z clearcoat normal
    float4 sheen;       // sheen: .xyz color, .w roughness
    float4 aniso;       // anisotropy: .x strength, .y cos, .z sin of the rotation; .w dispersion
    float4 iridescence; // iridescence: .x factor, .y ior, .z thickness minimum, .w maximum (nm)
    float4 diffuse_transmission;  // .xyz color, .w factor
    int4 textures4;     // texture refs: .x anisotropy, .y iridescence (R), .z iridescence
                        // thickness (G), .w diffuse transmission (A); -1 none
    int4 textures5;     // texture refs: .x diffuse transmission color; -1 none
} DeviceMaterial;

typedef struct {
    float4 position;   // position, or travel direction (directional); .w = kind (uint bits)
    float4 intensity;  // intensity (point/spot) or irradiance (directional); .w = light radius
    float4 spot;       // spot axis; .w = cos outer angle. Triangle: .x = index bits, .y = area,
                       // .z = instance slot (uint bits, two levels)
    float4 extra;      // .x = cos inner angle, .y = selection probability
} DeviceLight;

typedef struct {
    float4 origin;   // eye; .w = lens radius
    float4 forward;  // unit view direction; .w = focus distance
    float4 right;    // right * tan(fov/2) * aspect
    float4 up;       // up * tan(fov/2)
} DeviceCamera;

typedef struct {
    uint width;
    uint height;
    uint samples_in_wave;
    uint first_sample;
    uint seed;
    uint max_bounces;
    uint rr_depth;
    uint strategy;  // STRATEGY_*
    float4 sky;     // uniform environment radiance
    uint light_count;
    uint bounce;
    uint background;  // BACKGROUND_*: what an escaped camera ray adds
    uint triangles;   // the scene's, for SMALL_SCENE (traverse_wide.h); 0 elsewhere
    uint adaptive;    // 1: adaptive sampling (adaptive.h); 0: its buffers untouched
    uint pad[3];
} DeviceFrame;

typedef struct {
    float4 origin;      // .w = pdf of the BSDF sample that made this ray (0: camera ray)
    float4 direction;   // .w = flags (uint bits): PATH_SPECULAR, PATH_ESCAPED, PATH_THROUGH_WALL
    float4 throughput;  // .w = slot (uint bits): pixel + sample_in_wave * pixels
    float4 radiance;    // .w = random state (uint bits)
} DevicePath;

typedef struct {
    float t;
    float u;      // weight of vertex 1
    float v;      // weight of vertex 2
    uint prim;    // triangle in BVH order (two levels: object-space triangle), 0xffffffff on a miss
    uint instance;  // the instance hit: its slot in the instance buffer (two levels; 0 when flat)
} DeviceHit;

typedef struct {
    float4 origin;        // .w = maximum distance
    float4 direction;     // .w = path slot (uint bits)
    float4 contribution;  // radiance added to the path when the light is visible
} DeviceShadowRay;

typedef struct {
    float4 origin;     // .w = tmin
    float4 direction;  // .w = tmax
} DeviceRay;

#endif  // SHARED_TYPES_H
