//! Structs shared between the host and the kernels.
//!
//! Each struct here is mirrored field for field in `kernels/shared/types.h`; the layout probe test
//! (`layout_probe_agrees_with_every_shared_rust_struct` in `tests/device.rs`) runs a kernel that reports
//! `sizeof` and field offsets on the device and compares them with [`layouts`]. A bare `float3`
//! never appears: it is 16 bytes in OpenCL, so three-component payloads travel as `float4` with
//! something useful in `.w`.
//!
//! The constants the kernels share (flags, kinds, modes, counter slots) are defined here once;
//! [`kernel_defines`] writes them as `#define`s in front of the kernel sources.

use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

/// A value the kernels see as a `#define`, written as an OpenCL C literal.
pub trait KernelConstant {
    /// The literal (`1u` for unsigned values, so the kernels' comparisons stay unsigned).
    fn literal(&self) -> String;
}

impl KernelConstant for u32 {
    fn literal(&self) -> String {
        format!("{self}u")
    }
}

impl KernelConstant for i32 {
    fn literal(&self) -> String {
        self.to_string()
    }
}

impl KernelConstant for usize {
    fn literal(&self) -> String {
        self.to_string()
    }
}

/// Defines constants shared with the kernels once: each becomes a Rust `pub const` and a line
/// of [`kernel_defines`], which `cl::program` puts in front of the kernel sources.
macro_rules! kernel_constants {
    ($($(#[$doc:meta])* $name:ident: $t:ty = $v:expr;)*) => {
        $($(#[$doc])* pub const $name: $t = $v;)*

        /// The `#define` of every constant shared with the kernels, one per line.
        pub fn kernel_defines() -> String {
            let mut s = String::new();
            $(s.push_str(&format!("#define {} {}\n", stringify!($name), $name.literal()));)*
            s
        }
    };
}

kernel_constants! {
    /// `DeviceTexture::flags`: the texels hold sRGB-encoded color (alpha stays linear).
    TEXTURE_SRGB: u32 = 1 << 8;
    /// `DeviceTexture::flags`: the mip level count sits in these bits.
    TEXTURE_LEVELS_MASK: u32 = 0xff;

    /// Sampler wrap modes in `DeviceTexRef::info.yz`: repeat.
    WRAP_REPEAT: i32 = 0;
    /// Clamp to the edge texel.
    WRAP_CLAMP: i32 = 1;
    /// Mirrored repeat.
    WRAP_MIRROR: i32 = 2;

    /// `DeviceTexRef::info.w` flag: nearest-texel lookups (sampler magFilter NEAREST).
    TEXREF_NEAREST: i32 = 1;
    /// `DeviceTexRef::info.w` flag: the finest level only (minFilter NEAREST or LINEAR, no mipmaps).
    TEXREF_NO_MIPS: i32 = 2;

    /// `DeviceInstance::flags`: the transform mirrors (negative determinant).
    INSTANCE_MIRRORED: u32 = 1;
    /// `DeviceInstance::flags`: a re-braided piece of one triangle of a small mesh (`root` and
    /// `wide_root` name it among the meshes' triangles), tested in world space without
    /// entering the instance (`bvh::instances`, `TwoLevel::braid`).
    INSTANCE_PIECE_TRIANGLE: u32 = 2;
    /// A binary TLAS leaf's count flag in the device's node array: the leaf is one piece (its
    /// slot in the instances), not triangles, so the two-level traversal tells the levels'
    /// leaves apart by the leaf itself (`TwoLevel::device_tlas`).
    TLAS_LEAF: u32 = 0x8000_0000;

    /// The megakernel's small-scene test (`SMALL_SCENE`, kernels/shared/traverse_wide.h) takes the
    /// triangles this many at a time, in vector lanes; its kernels are built for a whole number
    /// of such batches.
    SMALL_LANES: usize = 16;

    /// Material flags in `DeviceMaterial::emission.w`: both sides are front faces.
    MATERIAL_DOUBLE_SIDED: u32 = 1;
    /// `KHR_materials_unlit`: the surface shows its base color and ends the path.
    MATERIAL_UNLIT: u32 = 2;

    /// Alpha modes in `DeviceMaterial::alpha.y`: opaque.
    ALPHA_OPAQUE: u32 = 0;
    /// Cut out below the cutoff.
    ALPHA_MASK: u32 = 1;
    /// Stochastic transparency.
    ALPHA_BLEND: u32 = 2;

    /// Light kinds in `DeviceLight::position.w`: a point light.
    LIGHT_POINT: u32 = 0;
    /// A spot light: a point light with a cone.
    LIGHT_SPOT: u32 = 1;
    /// A directional light (sun).
    LIGHT_DIRECTIONAL: u32 = 2;
    /// An emissive triangle, sampled by area.
    LIGHT_TRIANGLE: u32 = 3;
    /// The environment map, sampled by its luminance table.
    LIGHT_ENVIRONMENT: u32 = 4;

    /// `DeviceFrame::strategy`: light and BSDF sampling combined by the power heuristic.
    STRATEGY_MIS: u32 = 0;
    /// BSDF sampling only.
    STRATEGY_BSDF: u32 = 1;
    /// Light sampling only.
    STRATEGY_LIGHTS: u32 = 2;

    /// `DevicePath::direction.w` flag: the last bounce was specular.
    PATH_SPECULAR: u32 = 1;
    /// `DevicePath::direction.w` flag: the camera ray escaped (with coverage counted).
    PATH_ESCAPED: u32 = 2;

    /// `DeviceFrame::background`: escaped camera rays see the environment.
    BACKGROUND_ENV: u32 = 0;
    /// Escaped camera rays add nothing and the film's `.w` counts the samples that hit.
    BACKGROUND_CUTOUT: u32 = 1;
    /// Escaped camera rays see the environment and the film's `.w` counts the samples that hit.
    BACKGROUND_COUNT: u32 = 2;
    /// `DevicePath::direction.w` flag: went straight through a thin wall since the last
    /// scattering vertex.
    PATH_THROUGH_WALL: u32 = 4;
    /// `DevicePath::direction.w`: the bits from here up hold the wavelength a path picked at its
    /// first dispersive surface (`KHR_materials_dispersion`), in 1/64 nm; 0: none picked yet.
    PATH_WAVELENGTH_SHIFT: u32 = 8;

    /// Slot of the counters buffer (u32): paths in this bounce's input queue.
    COUNT_IN: usize = 0;
    /// Paths queued for the next bounce.
    COUNT_OUT: usize = 1;
    /// Shadow rays queued for `connect`.
    COUNT_SHADOW: usize = 2;
    /// Samples dropped because they were NaN or infinite.
    COUNT_NONFINITE: usize = 3;
    /// Traversal stack overflows.
    COUNT_OVERFLOW: usize = 4;
    /// Pixels left active by the last convergence check (adaptive sampling).
    COUNT_ACTIVE: usize = 5;
    /// Length of the counters buffer.
    COUNTER_SLOTS: usize = 8;

    /// The film's fixed point (kernels/shared/film.h): a sum's integer is its radiance times
    /// 2^FILM_FRACTION_BITS.
    FILM_FRACTION_BITS: u32 = 24;

    /// Bits of an adaptive pixel's state (kernels/shared/adaptive.h): the samples it took.
    PIXEL_SAMPLES: u32 = 0x3fff_ffff;
    /// Its error was under the threshold at the last check.
    PIXEL_UNDER: u32 = 0x4000_0000;
    /// It and its eight neighbours were under the threshold: it takes no samples.
    PIXEL_CONVERGED: u32 = 0x8000_0000;

    /// `DeviceFrame::adaptive`: no adaptive sampling (its buffers untouched).
    ADAPTIVE_OFF: u32 = 0;
    /// Adaptive sampling, a pixel converged when its error is under the threshold (Cycles').
    ADAPTIVE_ERROR: u32 = 1;
    /// Adaptive sampling, the threshold weighed by the rays the pixel's samples traced
    /// (kernels/shared/adaptive.h's `pixel_threshold`).
    ADAPTIVE_COST: u32 = 2;

    /// The side of the square of pixels a work item of the megakernel with lanes
    /// (`MEGA_LANES`) renders: its sixteen lanes take them one after the other, so that a lane
    /// whose pixels sample quickly (the sky) takes more of them and none waits long for the
    /// others; a square rather than a row keeps the lanes' rays near each other.
    LANES_TILE: usize = 16;

    /// Slot of the statistics buffer (u64): extension rays traced.
    STAT_EXTENSION_RAYS: usize = 0;
    /// Shadow rays traced.
    STAT_SHADOW_RAYS: usize = 1;
    /// Length of the statistics buffer.
    STAT_SLOTS: usize = 4;
}

/// One BVH node holding the boxes of both children (Aila–Laine layout, 64 bytes).
///
/// A child index `>= 0` names an interior node; a negative one is a leaf `!first_triangle`
/// whose triangle count is in the matching `*_max.w` (as integer bits).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceBvhNode {
    /// Left child box minimum; `.w` = left child (i32 bits).
    pub left_min: [f32; 4],
    /// Left child box maximum; `.w` = left leaf triangle count (u32 bits, 0 for an interior child).
    pub left_max: [f32; 4],
    /// Right child box minimum; `.w` = right child (i32 bits).
    pub right_min: [f32; 4],
    /// Right child box maximum; `.w` = right leaf triangle count (u32 bits).
    pub right_max: [f32; 4],
}
const _: () = assert!(size_of::<DeviceBvhNode>() == 64);

/// A node of the 4-wide BVH (128 bytes): four child boxes by coordinate, one `float4` per box
/// plane, so the kernels test a ray against all four at once. A child is an interior node
/// (`child > 0`, `count == 0`), a leaf (`child = !first` triangle, `count > 0`), or an empty
/// slot (`child <= 0`, `count == 0`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceWideNode {
    /// Box minima, x coordinate of each child.
    pub min_x: [f32; 4],
    /// Box minima, y.
    pub min_y: [f32; 4],
    /// Box minima, z.
    pub min_z: [f32; 4],
    /// Box maxima, x.
    pub max_x: [f32; 4],
    /// Box maxima, y.
    pub max_y: [f32; 4],
    /// Box maxima, z.
    pub max_z: [f32; 4],
    /// Node index, or `!first` triangle of a leaf.
    pub child: [i32; 4],
    /// Leaf triangle count (0: interior or empty).
    pub count: [u32; 4],
}
const _: () = assert!(size_of::<DeviceWideNode>() == 128);

/// One placed mesh of a two-level scene (112 bytes): object from world as
/// `p_object = L (p_world - T)` for traversal, world from object as `p_world = M p_object + T`
/// for shading (the mesh's triangles and shading data stay in object space on the device),
/// bottom-level roots, and the instance's index and first light; see `kernels/shared/types.h` and
/// `bvh::instances`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceInstance {
    /// First row of L; `.w` = T.x, the world position of the object's origin.
    pub row0: [f32; 4],
    /// Second row of L; `.w` = T.y.
    pub row1: [f32; 4],
    /// Third row of L; `.w` = T.z.
    pub row2: [f32; 4],
    /// First row of M = L⁻¹ (world from object); `.w` = the light index of the instance's
    /// first emissive triangle (i32 bits; an emissive triangle's `v1.w` counts from it).
    pub world0: [f32; 4],
    /// Second row of M.
    pub world1: [f32; 4],
    /// Third row of M.
    pub world2: [f32; 4],
    /// Where the TLAS leaf (the piece) enters the bottom level in the binary node array: the
    /// BLAS's root or a subtree's; or with `INSTANCE_PIECE_TRIANGLE`, its triangle.
    pub root: u32,
    /// The same in the wide node array.
    pub wide_root: u32,
    /// The instance's index in the scene (host bookkeeping; hits name the slot).
    pub id: u32,
    /// `INSTANCE_MIRRORED`, `INSTANCE_PIECE_TRIANGLE`.
    pub flags: u32,
}
const _: () = assert!(size_of::<DeviceInstance>() == 112);

/// A triangle's vertices in world space, in BVH order (48 bytes); with two levels, in object
/// space, once per mesh (mesh after mesh, each in its BLAS's order).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceTriangle {
    /// Vertex 0; `.w` = material index (u32 bits).
    pub v0: [f32; 4],
    /// Vertex 1; `.w` = emissive light index (i32 bits, -1 when not emissive; two levels: the
    /// index among its mesh's emissive triangles, added to the instance's first light).
    pub v1: [f32; 4],
    /// Vertex 2; `.w` = object index (u32 bits; two levels: 0, the instance tells).
    pub v2: [f32; 4],
}
const _: () = assert!(size_of::<DeviceTriangle>() == 48);

/// Per-corner normals of a triangle, in BVH order (36 bytes): `n[c]` is corner c's. A
/// flat-shaded triangle's are all zero, which the kernels' interpolation turns into its
/// geometric normal (a zero-length normal leaves it).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceTriShading {
    /// The corners' normals.
    pub n: [[f32; 3]; 3],
}
const _: () = assert!(size_of::<DeviceTriShading>() == 36);

/// Texture coordinates of a triangle's corners, in BVH order (48 bytes); on the device only
/// when some material samples a texture (else a one-element placeholder the kernels never read).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceTriUvs {
    /// `TEXCOORD_0` of vertices 0 and 1 (`.xy`, `.zw`).
    pub uv01: [f32; 4],
    /// `TEXCOORD_0` of vertex 2 (`.xy`); `TEXCOORD_1` of vertex 0 (`.zw`).
    pub uv2: [f32; 4],
    /// `TEXCOORD_1` of vertices 1 and 2 (`.xy`, `.zw`).
    pub uv1_12: [f32; 4],
}
const _: () = assert!(size_of::<DeviceTriUvs>() == 48);

/// Per-vertex tangents of a triangle, in BVH order (48 bytes); uploaded only when the scene
/// has normal maps.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceTriTangents {
    /// Unit tangent at vertex 0; `.w` = bitangent sign (±1).
    pub t0: [f32; 4],
    /// Tangent at vertex 1; `.w` = bitangent sign.
    pub t1: [f32; 4],
    /// Tangent at vertex 2; `.w` = bitangent sign.
    pub t2: [f32; 4],
}
const _: () = assert!(size_of::<DeviceTriTangents>() == 48);

/// `COLOR_0` at a triangle's corners, linear RGBA, in BVH order (48 bytes); uploaded only
/// when some mesh has vertex colours (`HAS_VERTEX_COLORS`), white where a mesh has none.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceTriColors {
    /// Colour at vertex 0 (RGBA).
    pub c0: [f32; 4],
    /// Colour at vertex 1.
    pub c1: [f32; 4],
    /// Colour at vertex 2.
    pub c2: [f32; 4],
}
const _: () = assert!(size_of::<DeviceTriColors>() == 48);

/// One texture in the packed texel buffer (16 bytes). Its mip levels follow each other from
/// `offset`, level `l` being `max(1, width >> l)` × `max(1, height >> l)` RGBA8 texels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceTexture {
    /// Index of the first texel of level 0 in the texel buffer.
    pub offset: u32,
    /// Width of level 0.
    pub width: u32,
    /// Height of level 0.
    pub height: u32,
    /// Mip level count (`TEXTURE_LEVELS_MASK` bits) and `TEXTURE_SRGB`.
    pub flags: u32,
}
const _: () = assert!(size_of::<DeviceTexture>() == 16);

/// A material's use of a texture: which one, the sampler and the `KHR_texture_transform`
/// (48 bytes). The lookup coordinate is `(dot(m0.xyz, (u, v, 1)), dot(m1.xyz, (u, v, 1)))`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceTexRef {
    /// First row of the UV transform; `.w` = texture coordinate set (u32 bits, 0 or 1).
    pub m0: [f32; 4],
    /// Second row of the UV transform; `.w` = ½·log2 |det| of the transform (mip bias).
    pub m1: [f32; 4],
    /// `.x` texture index, `.y` wrap S, `.z` wrap T (`WRAP_*`), `.w` filter flags (`TEXREF_*`).
    pub info: [i32; 4],
}
const _: () = assert!(size_of::<DeviceTexRef>() == 48);

/// The environment map's constants (48 bytes). Texels are RGB f32 triples, row 0 at the top
/// (+Y); the map's centre column looks along −Z before rotation.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceEnvironment {
    /// `.x` radiance scale (intensity), `.y` pdf normalization W·H / (Σf · 2π²), `.z`
    /// probability that next-event estimation picks the environment, `.w` unused.
    pub scale: [f32; 4],
    /// `.x` cos and `.y` sin of the rotation about +Y; `.zw` unused.
    pub rotation: [f32; 4],
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Index of the environment in the light list.
    pub light: u32,
    /// Padding.
    pub pad: u32,
}
const _: () = assert!(size_of::<DeviceEnvironment>() == 48);

/// A glTF material as the kernels see it (256 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceMaterial {
    /// Linear base color; `.w` = alpha.
    pub base_color: [f32; 4],
    /// Emitted radiance (emissiveFactor × strength); `.w` = flags (u32 bits, `MATERIAL_*`).
    pub emission: [f32; 4],
    /// `.x` metallic, `.y` roughness, `.z` ior, `.w` specularFactor.
    pub params: [f32; 4],
    /// specularColorFactor; `.w` = transmission factor.
    pub specular: [f32; 4],
    /// `KHR_materials_volume` attenuationColor; `.w` = attenuationDistance (INFINITY: none).
    pub volume: [f32; 4],
    /// `.x` alphaCutoff, `.y` alpha mode (u32 bits, `ALPHA_*`), `.z` thicknessFactor,
    /// `.w` normal texture scale.
    pub alpha: [f32; 4],
    /// Texture references (base color, metallic-roughness, normal, emissive); -1 when absent.
    pub textures: [i32; 4],
    /// More texture references (`.x` transmission, `.y` thickness, `.z` sheen color, `.w` sheen
    /// roughness (A)); -1 when absent.
    pub textures2: [i32; 4],
    /// `KHR_materials_clearcoat`: `.x` clearcoatFactor, `.y` clearcoatRoughnessFactor, `.z`
    /// clearcoat normal texture scale; `.w` spare.
    pub coat: [f32; 4],
    /// Texture references of the extensions: `.x` clearcoat (R), `.y` clearcoat roughness (G),
    /// `.z` clearcoat normal; `.w` spare; -1 when absent.
    pub textures3: [i32; 4],
    /// `KHR_materials_sheen`: `.xyz` sheenColorFactor, `.w` sheenRoughnessFactor.
    pub sheen: [f32; 4],
    /// `KHR_materials_anisotropy`: `.x` anisotropyStrength, `.y` cos and `.z` sin of
    /// anisotropyRotation; `.w` `KHR_materials_dispersion` dispersion.
    pub aniso: [f32; 4],
    /// `KHR_materials_iridescence`: `.x` iridescenceFactor, `.y` iridescenceIor, `.z`
    /// iridescenceThicknessMinimum, `.w` iridescenceThicknessMaximum (nanometres).
    pub iridescence: [f32; 4],
    /// `KHR_materials_diffuse_transmission`: `.xyz` diffuseTransmissionColorFactor, `.w`
    /// diffuseTransmissionFactor.
    pub diffuse_transmission: [f32; 4],
    /// Texture references: `.x` anisotropy (RG direction, B strength), `.y` iridescence (R),
    /// `.z` iridescence thickness (G), `.w` diffuse transmission (A); -1 when absent.
    pub textures4: [i32; 4],
    /// Texture references: `.x` diffuse transmission color (sRGB RGB); `.yzw` spare; -1 when
    /// absent.
    pub textures5: [i32; 4],
}
const _: () = assert!(size_of::<DeviceMaterial>() == 256);

/// One light for next-event estimation (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceLight {
    /// Position (point/spot), or the direction light travels (directional); `.w` = kind (u32 bits).
    pub position: [f32; 4],
    /// Radiant intensity (point/spot) or irradiance (directional) per channel; `.w` = the light
    /// radius, `Light::light_radius` (world units; an angular radius in radians for a
    /// directional light).
    pub intensity: [f32; 4],
    /// Spot axis (direction light travels); `.w` = cos of the outer cone angle.
    /// For a triangle light: `.x` = triangle index (u32 bits), `.y` = area, `.z` = the
    /// instance's slot in the instance buffer (u32 bits; two levels).
    pub spot: [f32; 4],
    /// `.x` = cos of the inner cone angle; `.y` = selection probability; `.zw` unused.
    pub extra: [f32; 4],
}
const _: () = assert!(size_of::<DeviceLight>() == 64);

/// A pinhole camera (64 bytes). Rays leave `origin` towards
/// `forward + (2u - 1)·right + (1 - 2v)·up` for film coordinates (u, v) in [0, 1]².
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceCamera {
    /// Eye position; `.w` = lens radius (0 for a pinhole).
    pub origin: [f32; 4],
    /// Unit view direction; `.w` = focus distance.
    pub forward: [f32; 4],
    /// Camera right scaled by tan(fov/2)·aspect; `.w` unused.
    pub right: [f32; 4],
    /// Camera up scaled by tan(fov/2); `.w` unused.
    pub up: [f32; 4],
}
const _: () = assert!(size_of::<DeviceCamera>() == 64);

/// Per-frame constants of the path tracer (80 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceFrame {
    /// Film width in pixels.
    pub width: u32,
    /// Film height in pixels.
    pub height: u32,
    /// Paths per pixel in this wave.
    pub samples_in_wave: u32,
    /// Index of the first sample of this wave (for the random sequence).
    pub first_sample: u32,
    /// User seed.
    pub seed: u32,
    /// Maximum bounces after the first hit.
    pub max_bounces: u32,
    /// Bounce from which Russian roulette applies (u32::MAX: never).
    pub rr_depth: u32,
    /// Sampling strategy (`STRATEGY_*`).
    pub strategy: u32,
    /// Uniform environment radiance; `.w` unused.
    pub sky: [f32; 4],
    /// Number of lights in the light list.
    pub light_count: u32,
    /// Current bounce (set per launch by the host).
    pub bounce: u32,
    /// What an escaped camera ray adds (`BACKGROUND_*`).
    pub background: u32,
    /// The scene's triangles, for the megakernel's small-scene test (`SMALL_SCENE`), which is
    /// built for up to `SMALL_SCENE_MAX` of them so that hiding or showing an object in such a
    /// scene does not build the kernels again; 0 elsewhere.
    pub triangles: u32,
    /// `ADAPTIVE_ERROR` or `ADAPTIVE_COST`: adaptive sampling (kernels/shared/adaptive.h) by
    /// that rule: converged pixels are skipped and the half buffer, sample and ray counts kept;
    /// `ADAPTIVE_OFF`: none of them is read or written.
    pub adaptive: u32,
    /// Pads the struct to the device's 16-byte alignment.
    pub pad: [u32; 3],
}
const _: () = assert!(size_of::<DeviceFrame>() == 80);

/// The state of one path between stages (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DevicePath {
    /// Ray origin; `.w` = pdf of the BSDF sample that made this ray (0 after a camera ray).
    pub origin: [f32; 4],
    /// Unit ray direction; `.w` = 1 when the last bounce was specular (u32 bits as flags).
    pub direction: [f32; 4],
    /// Path throughput; `.w` = slot (u32 bits): pixel + sample_in_wave × pixels.
    pub throughput: [f32; 4],
    /// Radiance gathered so far; `.w` = random state (u32 bits).
    pub radiance: [f32; 4],
}
const _: () = assert!(size_of::<DevicePath>() == 64);

/// The closest hit of an extension ray (20 bytes). `prim` is `u32::MAX` on a miss.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceHit {
    /// Hit distance along the ray.
    pub t: f32,
    /// Barycentric coordinate of vertex 1.
    pub u: f32,
    /// Barycentric coordinate of vertex 2.
    pub v: f32,
    /// Triangle index in BVH order (two levels: the object-space triangle, mesh after mesh,
    /// each in its BLAS's order), or `u32::MAX` for a miss.
    pub prim: u32,
    /// The instance hit: its slot in the instance buffer, which is in TLAS order (two levels; 0
    /// with the flat BVH).
    pub instance: u32,
}
const _: () = assert!(size_of::<DeviceHit>() == 20);

/// A shadow ray with the radiance it carries if unoccluded (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceShadowRay {
    /// Ray origin; `.w` = maximum distance.
    pub origin: [f32; 4],
    /// Unit direction; `.w` = path slot (u32 bits).
    pub direction: [f32; 4],
    /// Radiance to add to the path if the light is visible; `.w` unused.
    pub contribution: [f32; 4],
}
const _: () = assert!(size_of::<DeviceShadowRay>() == 48);

/// A ray for the traversal benchmark and the device agreement tests (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct DeviceRay {
    /// Origin; `.w` = tmin.
    pub origin: [f32; 4],
    /// Direction (need not be unit); `.w` = tmax.
    pub direction: [f32; 4],
}
const _: () = assert!(size_of::<DeviceRay>() == 32);

/// A struct's name, size and (field, offset) list.
pub type StructLayout = (&'static str, usize, Vec<(&'static str, usize)>);

/// Every shared struct with its size and field offsets, for the layout probe test.
pub fn layouts() -> Vec<StructLayout> {
    macro_rules! layout {
        ($t:ty, $($f:ident),*) => {
            (stringify!($t), size_of::<$t>(), vec![$((stringify!($f), offset_of!($t, $f))),*])
        };
    }
    vec![
        layout!(DeviceBvhNode, left_min, left_max, right_min, right_max),
        layout!(DeviceTriangle, v0, v1, v2),
        layout!(
            DeviceInstance,
            row0,
            row1,
            row2,
            world0,
            world1,
            world2,
            root,
            wide_root,
            id,
            flags
        ),
        layout!(DeviceTriShading, n),
        layout!(DeviceTriUvs, uv01, uv2, uv1_12),
        layout!(DeviceTriTangents, t0, t1, t2),
        layout!(DeviceTriColors, c0, c1, c2),
        layout!(DeviceTexture, offset, width, height, flags),
        layout!(DeviceTexRef, m0, m1, info),
        layout!(
            DeviceEnvironment,
            scale,
            rotation,
            width,
            height,
            light,
            pad
        ),
        layout!(
            DeviceMaterial,
            base_color,
            emission,
            params,
            specular,
            volume,
            alpha,
            textures,
            textures2,
            coat,
            textures3,
            sheen,
            aniso,
            iridescence,
            diffuse_transmission,
            textures4,
            textures5
        ),
        layout!(DeviceLight, position, intensity, spot, extra),
        layout!(DeviceCamera, origin, forward, right, up),
        layout!(
            DeviceFrame,
            width,
            height,
            samples_in_wave,
            first_sample,
            seed,
            max_bounces,
            rr_depth,
            strategy,
            sky,
            light_count,
            bounce,
            background,
            triangles,
            adaptive
        ),
        layout!(DevicePath, origin, direction, throughput, radiance),
        layout!(DeviceHit, t, u, v, prim, instance),
        layout!(DeviceShadowRay, origin, direction, contribution),
        layout!(DeviceRay, origin, direction),
        layout!(
            DeviceWideNode,
            min_x,
            min_y,
            min_z,
            max_x,
            max_y,
            max_z,
            child,
            count
        ),
    ]
}
