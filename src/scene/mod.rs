//! The scene on the host: objects with their geometry, materials, lights and cameras.
//!
//! Transforms are composed in f64; geometry is stored per object in object space and flattened
//! into world-space triangles (f32) whenever the scene changes.

mod accessor;
pub mod animation;
mod basisu;
mod bounds;
pub mod bvh_report;
mod compression;
mod env_presets;
mod environment;
pub mod framing;
mod gltf_import;
mod lenient;
mod lights;
pub mod limits;
mod pose;
mod repeats;
mod sources;
mod tangents;
mod textures;
mod validate;
mod variants;
pub mod views;

pub use bounds::{ABSURD_COORDINATE, RenderFrame, is_sane, robust_bounds, robust_bounds_of};
pub use env_presets::EnvPreset;
pub use environment::{EnvMap, EnvSampling, MAX_ENV_WIDTH};
pub use gltf_import::{AUTO_YFOV, load, load_from_bytes, load_with};
pub use lights::{LightPreset, Shadows, default_light_radius, default_light_rig, preset_lights};
pub use textures::{
    Image, MAX_TEXTURE_SIDE, MaterialTextures, MipLevel, TexTransform, TextureRef, Wrap,
    linear_to_srgb, mip_chain, srgb_to_linear,
};
pub use validate::SUPPORTED_EXTENSIONS;
pub use variants::VariantRange;

use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The bundled default scene (made by `scripts/cornell_box.py`).
pub const BUNDLED_SCENE: &[u8] = include_bytes!("../../assets/cornell-box.glb");

/// Loads `path`, or the bundled Cornell box when there is none.
pub fn load_or_bundled(path: Option<&Path>) -> Result<Scene, SceneError> {
    load_or_bundled_with(path, None)
}

/// [`load_or_bundled`] with the files a scene's URIs name read also from inside `asset_root`.
pub fn load_or_bundled_with(
    path: Option<&Path>,
    asset_root: Option<&Path>,
) -> Result<Scene, SceneError> {
    match path {
        Some(p) => load_with(p, asset_root),
        None => load_from_bytes(BUNDLED_SCENE, None, "bundled Cornell box").map_err(|message| {
            SceneError::Invalid {
                path: PathBuf::from("assets/cornell-box.glb"),
                message,
            }
        }),
    }
}

/// Errors a user's scene file can cause.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read or parsed as glTF.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the glTF element.
        message: String,
    },
}

/// A triangle mesh in object space.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex normals; empty when the file had none (flat shading).
    pub normals: Vec<Vec3>,
    /// `TEXCOORD_0`; empty when absent.
    pub uvs: Vec<Vec2>,
    /// Triangles as vertex indices.
    pub indices: Vec<[u32; 3]>,
    /// Material index of each triangle.
    pub materials: Vec<u32>,
    /// `TEXCOORD_1`; empty when absent.
    pub uvs1: Vec<Vec2>,
    /// Tangents at each triangle's corners (xyz, w = bitangent sign), from the file's
    /// `TANGENT` or generated (MikkTSpace) for normal-mapped primitives; empty when no
    /// primitive of the mesh is normal-mapped. Zero where unknown.
    pub tangents: Vec<[Vec4; 3]>,
    /// `COLOR_0` per vertex (linear RGBA; alpha 1 where the file gave RGB); empty when no
    /// primitive of the mesh has it, white for the vertices of those without.
    pub colors: Vec<Vec4>,
    /// The triangles whose material a `KHR_materials_variants` variant changes.
    pub variants: Vec<VariantRange>,
}

impl crate::bvh::IndexedMesh for Mesh {
    fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }
}

impl Mesh {
    /// A mesh of separate triangles (three vertices each, none shared), all of material 0.
    pub fn soup(tris: &[[Vec3; 3]]) -> Self {
        Mesh {
            positions: tris.iter().flatten().copied().collect(),
            indices: (0..tris.len() as u32)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect(),
            materials: vec![0; tris.len()],
            ..Mesh::default()
        }
    }
}

/// One placed mesh: a glTF node's mesh with its world transform.
#[derive(Clone, Debug)]
pub struct Object {
    /// Node or mesh name.
    pub name: String,
    /// World from object transform.
    pub world_from_object: DMat4,
    /// Hidden objects are left out of the BVH.
    pub visible: bool,
    /// The geometry, shared by every object that places the same glTF mesh (the importer
    /// reads each mesh once; a skinned or morphed node gets its own posed copy).
    pub mesh: Arc<Mesh>,
}

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha ignored.
    #[default]
    Opaque,
    /// Cut out below the cutoff.
    Mask(f32),
    /// Blended (stochastic transparency).
    Blend,
}

/// A glTF metallic-roughness material.
#[derive(Clone, Debug)]
pub struct Material {
    /// Material name.
    pub name: String,
    /// Linear RGBA base color factor.
    pub base_color: [f32; 4],
    /// Metallic factor.
    pub metallic: f32,
    /// Perceptual roughness factor.
    pub roughness: f32,
    /// Emitted radiance: emissiveFactor × `KHR_materials_emissive_strength`.
    pub emission: [f32; 3],
    /// Emits and scatters from both faces.
    pub double_sided: bool,
    /// Index of refraction (`KHR_materials_ior`), 1.5 by default.
    pub ior: f32,
    /// `KHR_materials_specular` specularFactor (0 makes a dielectric purely Lambertian).
    pub specular_factor: f32,
    /// `KHR_materials_specular` specularColorFactor.
    pub specular_color: [f32; 3],
    /// `KHR_materials_transmission` factor.
    pub transmission: f32,
    /// `KHR_materials_volume` thicknessFactor (0: thin-walled).
    pub thickness: f32,
    /// `KHR_materials_volume` attenuationColor.
    pub attenuation_color: [f32; 3],
    /// `KHR_materials_volume` attenuationDistance (infinite: no absorption).
    pub attenuation_distance: f32,
    /// Alpha mode.
    pub alpha: AlphaMode,
    /// Texture slots.
    pub textures: MaterialTextures,
    /// Normal texture scale (x and y of the tangent-space normal).
    pub normal_scale: f32,
    /// `KHR_materials_unlit`: shows its base color and scatters nothing.
    pub unlit: bool,
    /// `KHR_materials_clearcoat` clearcoatFactor (0: no coat).
    pub clearcoat: f32,
    /// `KHR_materials_clearcoat` clearcoatRoughnessFactor.
    pub clearcoat_roughness: f32,
    /// Scale of the clearcoat normal texture.
    pub clearcoat_normal_scale: f32,
    /// `KHR_materials_sheen` sheenColorFactor (linear; 0: no sheen).
    pub sheen_color: [f32; 3],
    /// `KHR_materials_sheen` sheenRoughnessFactor.
    pub sheen_roughness: f32,
    /// `KHR_materials_anisotropy` anisotropyStrength (0: isotropic).
    pub anisotropy: f32,
    /// `KHR_materials_anisotropy` anisotropyRotation (radians, counter-clockwise from the
    /// tangent).
    pub anisotropy_rotation: f32,
    /// `KHR_materials_iridescence` iridescenceFactor (0: no thin film).
    pub iridescence: f32,
    /// `KHR_materials_iridescence` iridescenceIor (of the film).
    pub iridescence_ior: f32,
    /// `KHR_materials_iridescence` iridescenceThicknessMinimum and Maximum (nanometres).
    pub iridescence_thickness: [f32; 2],
    /// `KHR_materials_diffuse_transmission` diffuseTransmissionFactor (0: none).
    pub diffuse_transmission: f32,
    /// `KHR_materials_diffuse_transmission` diffuseTransmissionColorFactor (linear).
    pub diffuse_transmission_color: [f32; 3],
    /// `KHR_materials_dispersion` dispersion (20 / Abbe number; 0: none).
    pub dispersion: f32,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: [0.8, 0.8, 0.8, 1.0],
            metallic: 0.0,
            roughness: 1.0,
            emission: [0.0; 3],
            double_sided: false,
            ior: 1.5,
            specular_factor: 1.0,
            specular_color: [1.0; 3],
            transmission: 0.0,
            thickness: 0.0,
            attenuation_color: [1.0; 3],
            attenuation_distance: f32::INFINITY,
            alpha: AlphaMode::Opaque,
            textures: MaterialTextures::default(),
            normal_scale: 1.0,
            unlit: false,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            clearcoat_normal_scale: 1.0,
            sheen_color: [0.0; 3],
            sheen_roughness: 0.0,
            anisotropy: 0.0,
            anisotropy_rotation: 0.0,
            iridescence: 0.0,
            iridescence_ior: 1.3,
            iridescence_thickness: [100.0, 400.0],
            diffuse_transmission: 0.0,
            diffuse_transmission_color: [1.0; 3],
            dispersion: 0.0,
        }
    }
}

impl Material {
    /// Whether the material scatters as a pure Lambertian (base color / pi): an opaque
    /// dielectric without a specular layer, coat, sheen or diffuse transmission. Textures cannot
    /// change that (the metallic and specular textures scale factors that are 0 here). Unlit
    /// materials do not scatter at all and do not count against it.
    pub fn is_lambertian(&self) -> bool {
        self.unlit
            || (self.metallic == 0.0
                && self.specular_factor == 0.0
                && self.transmission == 0.0
                && self.clearcoat == 0.0
                && self.diffuse_transmission == 0.0
                && self.sheen_color.iter().all(|&c| c == 0.0))
    }

    /// Whether light refracting through the material splits by wavelength: a dispersive
    /// transmitting volume (`KHR_materials_dispersion` has no effect on thin walls).
    pub fn is_dispersive(&self) -> bool {
        self.dispersion > 0.0 && self.transmission > 0.0 && self.thickness > 0.0
    }

    /// Whether the material emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.iter().any(|&e| e > 0.0)
    }
}

/// The kind of a punctual light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Emits equally in all directions.
    Point,
    /// A point light limited to a cone (glTF angles in radians).
    Spot {
        /// Inner cone angle.
        inner: f32,
        /// Outer cone angle.
        outer: f32,
    },
    /// Parallel light from infinitely far away.
    Directional,
}

/// A punctual light (`KHR_lights_punctual` or added by the user).
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Name shown in the overlay.
    pub name: String,
    /// Kind.
    pub kind: LightKind,
    /// World position (point and spot).
    pub position: DVec3,
    /// Unit direction the light travels (spot and directional).
    pub direction: DVec3,
    /// Linear color.
    pub color: [f32; 3],
    /// Radiant intensity (W/sr, point and spot) or irradiance (directional), used 1:1.
    pub intensity: f32,
    /// The light radius (`--light-radius`, "light radius" in the overlay): in world units, an
    /// angular radius in radians for directional lights; 0 gives hard shadows.
    pub light_radius: f32,
}

/// A perspective camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Name shown to users.
    pub name: String,
    /// Eye position.
    pub eye: DVec3,
    /// Unit view direction.
    pub forward: DVec3,
    /// Unit up vector.
    pub up: DVec3,
    /// Vertical field of view in radians.
    pub yfov: f64,
}

impl Camera {
    /// A camera at `eye` looking at `target`, with +Y up.
    pub fn look_at(name: &str, eye: DVec3, target: DVec3, yfov: f64) -> Self {
        let forward = (target - eye).normalize();
        let side = forward.cross(DVec3::Y);
        let side = if side.length_squared() < 1e-12 {
            DVec3::X
        } else {
            side.normalize()
        };
        Self {
            name: name.into(),
            eye,
            forward,
            up: side.cross(forward).normalize(),
            yfov,
        }
    }

    /// The automatic camera: looks at the box from its front (+Z), slightly above, so that the
    /// whole box fits the vertical field of view.
    pub fn framing(bounds: &Bounds, yfov: f64) -> Self {
        let center = bounds.center();
        let radius = (bounds.diagonal() * 0.5).max(1e-6);
        let distance = radius / (yfov * 0.5).sin();
        let dir = DVec3::new(0.35, 0.3, 1.0).normalize();
        Self::look_at("auto", center + dir * distance, center, yfov)
    }
}

/// An axis-aligned box in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Minimum corner.
    pub min: DVec3,
    /// Maximum corner.
    pub max: DVec3,
}

impl Default for Bounds {
    fn default() -> Self {
        Self {
            min: DVec3::splat(f64::INFINITY),
            max: DVec3::splat(f64::NEG_INFINITY),
        }
    }
}

impl Bounds {
    /// Grows the box to hold `p`.
    pub fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    /// Whether the box holds nothing.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
    /// The center.
    pub fn center(&self) -> DVec3 {
        if self.is_empty() {
            DVec3::ZERO
        } else {
            (self.min + self.max) * 0.5
        }
    }
    /// The length of the diagonal (1 for an empty box).
    pub fn diagonal(&self) -> f64 {
        if self.is_empty() {
            1.0
        } else {
            (self.max - self.min).length()
        }
    }
}

/// A flattened world-space triangle with what shading needs.
#[derive(Clone, Copy, Debug, Default)]
pub struct WorldTriangle {
    /// Vertices.
    pub v: [Vec3; 3],
    /// Vertex normals (the geometric normal when the mesh had none).
    pub n: [Vec3; 3],
    /// Whether `n` came from the file.
    pub smooth: bool,
    /// `TEXCOORD_0` per vertex.
    pub uv: [Vec2; 3],
    /// `TEXCOORD_1` per vertex.
    pub uv1: [Vec2; 3],
    /// World-space tangents per vertex (w = bitangent sign), when the mesh has them.
    pub tangents: Option<[Vec4; 3]>,
    /// `COLOR_0` per vertex (linear RGBA), when the mesh has it.
    pub colors: Option<[Vec4; 3]>,
    /// Material index.
    pub material: u32,
    /// Object index.
    pub object: u32,
}

/// A loaded scene.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Where it came from (a file path or "bundled Cornell box").
    pub source: String,
    /// Placed meshes.
    pub objects: Vec<Object>,
    /// Materials, indexed by `Mesh::materials`.
    pub materials: Vec<Material>,
    /// Punctual lights.
    pub lights: Vec<Light>,
    /// The file's cameras (the automatic one when the file has none).
    pub cameras: Vec<Camera>,
    /// True when the file had no light and the default rig was added.
    pub default_rig: bool,
    /// Warnings raised while loading (unsupported optional extensions, skipped primitives).
    pub warnings: Vec<String>,
    /// Decoded images used by the materials (only those).
    pub images: Vec<Arc<Image>>,
    /// `KHR_materials_variants` variant names (empty: none).
    pub variants: Vec<String>,
    /// The selected variant (`None`: the default materials).
    pub variant: Option<usize>,
    /// Texture uses, indexed by `MaterialTextures`.
    pub texture_refs: Vec<TextureRef>,
    /// The last [`Scene::bounds`] with the placement it was found for.
    pub bounds_cache: BoundsCache,
    /// Quick BLASes that the first-view probe built, left for the renderer's first load.
    pub quick_blases: QuickBlases,
    /// The file's clips and what poses the scene at any time of them (empty when the file has
    /// no animations).
    pub animation: Arc<animation::Animation>,
}

/// Quick BLASes ([`crate::bvh::quick_blas`]) of some of a scene's meshes, each with the mesh
/// it was built from: the first-view probe ([`framing::Probe`]) traces them and leaves them
/// here, and the renderer's first load takes them ([`Scene::take_quick_blases`]) instead of
/// building them again. A clone of the scene starts without them.
#[derive(Debug, Default)]
pub struct QuickBlases(std::sync::Mutex<Vec<(Arc<Mesh>, crate::bvh::Blas)>>);

impl Clone for QuickBlases {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl QuickBlases {
    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(Arc<Mesh>, crate::bvh::Blas)>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// [`Scene::bounds`] remembered with a fingerprint of what it depends on (each object's mesh,
/// its size, transform and visibility): opening a large scene asks for the bounds several
/// times (the first view, the render space, the viewer's camera), and each is a pass over
/// every placed triangle (about 3 s for 64 M triangles on 2 cores).
#[derive(Debug, Default)]
pub struct BoundsCache(std::sync::Mutex<Option<(u64, Bounds)>>);

impl Clone for BoundsCache {
    fn clone(&self) -> Self {
        Self(std::sync::Mutex::new(*self.lock()))
    }
}

impl BoundsCache {
    fn lock(&self) -> std::sync::MutexGuard<'_, Option<(u64, Bounds)>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Scene {
    /// Leaves quick BLASes of this scene's meshes for the renderer ([`QuickBlases`]).
    pub fn keep_quick_blases(&self, blases: Vec<(Arc<Mesh>, crate::bvh::Blas)>) {
        *self.quick_blases.lock() = blases;
    }

    /// Takes the quick BLASes left by the first-view probe (none the second time).
    pub fn take_quick_blases(&self) -> Vec<(Arc<Mesh>, crate::bvh::Blas)> {
        std::mem::take(&mut *self.quick_blases.lock())
    }

    /// Which materials some triangle uses, by index: in its own material or in a
    /// `KHR_materials_variants` variant (hidden objects count: they can be shown again).
    pub fn used_materials(&self) -> Vec<bool> {
        let mut used = vec![false; self.materials.len()];
        let mut mark = |i: u32| {
            if let Some(u) = used.get_mut(i as usize) {
                *u = true;
            }
        };
        for o in &self.objects {
            o.mesh.materials.iter().for_each(|&m| mark(m));
            for v in &o.mesh.variants {
                mark(v.default);
                v.materials.iter().for_each(|&(_, m)| mark(m));
            }
        }
        used
    }

    /// World-space triangles of the visible objects, in object order (absurd ones dropped).
    pub fn world_triangles(&self) -> Vec<WorldTriangle> {
        self.flatten(&RenderFrame::default()).triangles
    }

    /// The visible objects' triangles in the render space of `frame`, in object order: moved
    /// and scaled in f64 before they become f32. Triangles with a non-finite or absurd vertex
    /// (see [`is_sane`]) are dropped and counted. Written straight into the one list, each
    /// object's in parallel: no per-object lists to copy over.
    pub fn flatten(&self, frame: &RenderFrame) -> Flattened {
        let (triangles, dropped) = self.gather(frame, true, |p, ti| p.world_triangle(ti));
        Flattened { dropped, triangles }
    }

    /// [`Scene::flatten`] one visible object at a time: `each` gets every object's kept
    /// triangles in order (made in parallel), so that a caller converting them holds one
    /// object's [`WorldTriangle`]s at a time, not the scene's. Returns the number dropped.
    pub fn flatten_each(
        &self,
        frame: &RenderFrame,
        mut each: impl FnMut(Vec<WorldTriangle>),
    ) -> usize {
        let mut dropped = 0;
        for (oi, o) in self.objects.iter().enumerate().filter(|(_, o)| o.visible) {
            let p = Placed::new(oi as u32, o, frame, true);
            let mut triangles = Vec::new();
            p.extend_kept(&|p, ti| p.world_triangle(ti), &mut triangles);
            each(triangles);
            dropped += p.dropped;
        }
        dropped
    }

    /// The visible objects with triangles, each with its vertices in the space of `frame`
    /// (transformed once) and the triangles that [`Scene::flatten`] keeps: what the host probes
    /// of the first view trace, without a copy of every world triangle (36 bytes a triangle
    /// against about 6 for the vertices of a closed mesh).
    pub fn world_objects(&self, frame: &RenderFrame) -> Vec<WorldObject> {
        use rayon::prelude::*;
        self.objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.visible && !o.mesh.indices.is_empty())
            .map(|(oi, o)| {
                let p = Placed::new(oi as u32, o, frame, false);
                let kept = (p.dropped > 0).then(|| {
                    (0..o.mesh.indices.len() as u32)
                        .into_par_iter()
                        .filter(|&ti| p.kept(ti as usize))
                        .collect()
                });
                WorldObject {
                    mesh: o.mesh.clone(),
                    world: p.world,
                    kept,
                    flip: p.flip,
                }
            })
            .collect()
    }

    /// `make(object, triangle)` of every kept triangle of the visible objects, in order, and
    /// the number dropped. Objects go one after the other, each one's vertices transformed and
    /// its triangles made in parallel, into one list of the right capacity.
    fn gather<T: Send>(
        &self,
        frame: &RenderFrame,
        normals: bool,
        make: impl Fn(&Placed, usize) -> T + Sync,
    ) -> (Vec<T>, usize) {
        let visible = || self.objects.iter().enumerate().filter(|(_, o)| o.visible);
        let mut out = Vec::with_capacity(visible().map(|(_, o)| o.mesh.indices.len()).sum());
        let mut dropped = 0;
        for (oi, o) in visible() {
            let p = Placed::new(oi as u32, o, frame, normals);
            p.extend_kept(&make, &mut out);
            dropped += p.dropped;
        }
        (out, dropped)
    }

    /// Object `i` placed in the render space of `frame` (its vertices and normals
    /// transformed once), from which its triangles are read as [`Scene::flatten`] makes them.
    pub fn place(&self, i: usize, frame: &RenderFrame) -> Placed<'_> {
        Placed::new(i as u32, &self.objects[i], frame, true)
    }

    /// Object `i`'s triangles in the render space of `frame`, in its mesh's order, as
    /// [`Scene::flatten`] gives them (whether or not the object is visible).
    pub fn flatten_object(&self, i: usize, frame: &RenderFrame) -> Flattened {
        let p = Placed::new(i as u32, &self.objects[i], frame, true);
        let triangles = (0..self.objects[i].mesh.indices.len())
            .filter(|&ti| p.kept(ti))
            .map(|ti| p.world_triangle(ti))
            .collect();
        Flattened {
            triangles,
            dropped: p.dropped,
        }
    }

    /// Robust world-space bounds of the visible geometry (see [`robust_bounds`]): what
    /// framing, the default light radius and the render frame use.
    pub fn bounds(&self) -> Bounds {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for o in &self.objects {
            o.visible.hash(&mut h);
            Arc::as_ptr(&o.mesh).hash(&mut h);
            o.mesh.positions.as_ptr().hash(&mut h);
            (o.mesh.positions.len(), o.mesh.indices.len()).hash(&mut h);
            o.world_from_object
                .to_cols_array()
                .map(f64::to_bits)
                .hash(&mut h);
        }
        let key = h.finish();
        if let Some((k, b)) = *self.bounds_cache.lock()
            && k == key
        {
            return b;
        }
        use rayon::prelude::*;
        let visible: Vec<&Object> = self.objects.iter().filter(|o| o.visible).collect();
        // Each pass over an object transforms its vertices once, not each triangle's corners
        // (the same values: about a sixth of the transforms on a closed mesh); up to
        // BOUNDS_KEPT_VERTICES vertices in all, once for the three passes (a posed frame of
        // a 1 M-triangle animation finds its bounds anew).
        let total: usize = visible.iter().map(|o| o.mesh.positions.len()).sum();
        let kept: Option<Vec<Vec<DVec3>>> = (total <= BOUNDS_KEPT_VERTICES)
            .then(|| visible.par_iter().map(|o| world_points(o)).collect());
        let b = robust_bounds_of(visible.len(), &|k| {
            let world = match &kept {
                Some(worlds) => std::borrow::Cow::Borrowed(&worlds[k][..]),
                None => std::borrow::Cow::Owned(world_points(visible[k])),
            };
            visible[k]
                .mesh
                .indices
                .iter()
                .map(move |t| t.map(|i| world[i as usize]))
        });
        *self.bounds_cache.lock() = Some((key, b));
        b
    }

    /// Triangles of the visible objects with a non-finite or absurd world vertex (those that
    /// [`Scene::flatten`] drops), counted without flattening.
    pub fn absurd_triangles(&self) -> usize {
        use rayon::prelude::*;
        self.objects
            .par_iter()
            .filter(|o| o.visible)
            .map(|o| {
                let m = o.world_from_object;
                let sane: Vec<bool> = o
                    .mesh
                    .positions
                    .iter()
                    .map(|p| is_sane(m.transform_point3(p.as_dvec3())))
                    .collect();
                o.mesh
                    .indices
                    .iter()
                    .filter(|t| !t.iter().all(|&i| sane[i as usize]))
                    .count()
            })
            .sum()
    }

    /// Number of triangles over all visible objects.
    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .filter(|o| o.visible)
            .map(|o| o.mesh.indices.len())
            .sum()
    }
}

/// The distinct meshes among `objects` (the index of the first object using each) and each
/// object's mesh. The importer reads each glTF mesh once and the nodes placing it share it
/// (`Object::mesh` is an `Arc`), so meshes are told apart by identity.
pub fn distinct_meshes(objects: &[&Object]) -> (Vec<usize>, Vec<u32>) {
    let mut index = std::collections::HashMap::<*const Mesh, u32>::new();
    let mut first = vec![];
    let mesh_of = objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            *index.entry(Arc::as_ptr(&o.mesh)).or_insert_with(|| {
                first.push(i);
                first.len() as u32 - 1
            })
        })
        .collect();
    (first, mesh_of)
}

/// Triangles in render space, and how many were dropped.
#[derive(Clone, Debug, Default)]
pub struct Flattened {
    /// The triangles kept.
    pub triangles: Vec<WorldTriangle>,
    /// Triangles with a non-finite or absurd vertex, left out.
    pub dropped: usize,
}

/// A placed mesh's vertices in render space, from which its triangles are read as
/// [`Scene::flatten`] makes them ([`Scene::world_objects`]).
#[derive(Clone, Debug)]
pub struct WorldObject {
    /// The object's mesh.
    pub mesh: Arc<Mesh>,
    /// Its vertices in render space.
    pub world: Vec<Vec3>,
    /// The mesh triangles kept, in order, where some have an absurd vertex (else all are).
    pub kept: Option<Vec<u32>>,
    /// A mirroring transform: two corners are swapped to keep front faces in front.
    pub flip: bool,
}

impl WorldObject {
    /// Triangles kept.
    pub fn len(&self) -> usize {
        self.kept.as_ref().map_or(self.mesh.indices.len(), Vec::len)
    }

    /// Whether no triangle is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The mesh triangle of kept triangle `k`.
    #[inline]
    pub fn triangle(&self, k: usize) -> usize {
        self.kept.as_ref().map_or(k, |kept| kept[k] as usize)
    }

    /// The render-space corners of mesh triangle `ti` (as `Placed::vertices`).
    #[inline]
    pub fn vertices(&self, ti: usize) -> [Vec3; 3] {
        let [a, b, c] = self.mesh.indices[ti];
        let w = &self.world;
        let (a, b, c) = (w[a as usize], w[b as usize], w[c as usize]);
        if self.flip { [a, c, b] } else { [a, b, c] }
    }
}

/// The most vertices whose world positions [`Scene::bounds`] keeps for its three passes
/// (24 bytes each: 96 MB).
const BOUNDS_KEPT_VERTICES: usize = 1 << 22;

/// Object `o`'s vertices in world space (f64), each transformed once.
pub(crate) fn world_points(o: &Object) -> Vec<DVec3> {
    let m = o.world_from_object;
    o.mesh
        .positions
        .iter()
        .map(|p| m.transform_point3(p.as_dvec3()))
        .collect()
}

/// An object's vertices (and normals, when asked for) in render space, from which its
/// flattened triangles are made one by one ([`Scene::place`]).
pub struct Placed<'a> {
    object: u32,
    o: &'a Object,
    /// Render-space vertices.
    world: Vec<Vec3>,
    /// Whether each world vertex is sane (see [`is_sane`]).
    sane: Vec<bool>,
    /// World-space unit normals (empty when not asked for or the mesh has none).
    normals: Vec<Vec3>,
    /// Triangles with an absurd vertex.
    dropped: usize,
    /// A mirroring transform: the winding is flipped.
    flip: bool,
}

impl<'a> Placed<'a> {
    fn new(object: u32, o: &'a Object, frame: &RenderFrame, normals: bool) -> Self {
        use rayon::prelude::*;
        let m = o.world_from_object;
        let (world, sane): (Vec<Vec3>, Vec<bool>) = o
            .mesh
            .positions
            .par_iter()
            .map(|p| {
                let w = m.transform_point3(p.as_dvec3());
                (frame.point(w), is_sane(w))
            })
            .unzip();
        let normal_matrix = m.inverse().transpose();
        let normals = if normals {
            o.mesh
                .normals
                .par_iter()
                .map(|n| {
                    normal_matrix
                        .transform_vector3(n.as_dvec3())
                        .normalize_or_zero()
                        .as_vec3()
                })
                .collect()
        } else {
            Vec::new()
        };
        let dropped = o
            .mesh
            .indices
            .par_iter()
            .filter(|t| !t.iter().all(|&i| sane[i as usize]))
            .count();
        Placed {
            object,
            o,
            world,
            sane,
            normals,
            dropped,
            flip: m.determinant() < 0.0,
        }
    }

    fn kept(&self, ti: usize) -> bool {
        self.o.mesh.indices[ti]
            .iter()
            .all(|&i| self.sane[i as usize])
    }

    /// Appends `make(self, triangle)` of each kept triangle, in order, made in parallel (an
    /// exact-size extend when nothing is dropped).
    fn extend_kept<T: Send>(&self, make: &(impl Fn(&Self, usize) -> T + Sync), out: &mut Vec<T>) {
        use rayon::prelude::*;
        let all = 0..self.o.mesh.indices.len();
        if self.dropped == 0 {
            out.par_extend(all.into_par_iter().map(|ti| make(self, ti)));
        } else {
            let kept = all.into_par_iter().filter(|&ti| self.kept(ti));
            out.par_extend(kept.map(|ti| make(self, ti)));
        }
    }

    /// Triangle `ti`'s corners, two swapped under a mirroring transform to keep front faces
    /// in front.
    #[inline]
    pub fn corners(&self, ti: usize) -> [u32; 3] {
        let [a, b, c] = self.o.mesh.indices[ti];
        if self.flip { [a, c, b] } else { [a, b, c] }
    }

    /// Triangles with a non-finite or absurd vertex, which [`Scene::flatten`] drops.
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// Mesh triangle `ti`'s render-space corners and corner normals (the geometric normal
    /// where the mesh has none or a vertex's is zero), and whether the normals came from the
    /// file: the geometry of its [`WorldTriangle`], made without the rest.
    #[inline]
    pub fn shape(&self, ti: usize) -> ([Vec3; 3], [Vec3; 3], bool) {
        self.shape_at(self.corners(ti))
    }

    /// [`Placed::shape`] of the triangle with corners `idx` (as [`Placed::corners`] gives
    /// them).
    #[inline]
    pub fn shape_at(&self, idx: [u32; 3]) -> ([Vec3; 3], [Vec3; 3], bool) {
        let v = idx.map(|i| self.world[i as usize]);
        let geometric = || (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        let smooth = !self.normals.is_empty();
        let n = if smooth {
            let n = idx.map(|i| self.normals[i as usize]);
            // The geometric normal only where a corner has none (most triangles need none).
            if n.contains(&Vec3::ZERO) {
                let g = geometric();
                n.map(|n| if n == Vec3::ZERO { g } else { n })
            } else {
                n
            }
        } else {
            [geometric(); 3]
        };
        (v, n, smooth)
    }

    /// Mesh triangle `ti`'s world-space tangents (w = bitangent sign), when the mesh has them.
    pub fn tangents(&self, ti: usize) -> Option<[Vec4; 3]> {
        let m = self.o.world_from_object;
        let flip = self.flip;
        self.o.mesh.tangents.get(ti).map(|t| {
            let corners = if flip { [t[0], t[2], t[1]] } else { *t };
            corners.map(|t| {
                let d = m
                    .transform_vector3(t.truncate().as_dvec3())
                    .normalize_or_zero()
                    .as_vec3();
                // A mirroring transform flips the bitangent too.
                d.extend(if flip { -t.w } else { t.w })
            })
        })
    }

    /// Whether the object's transform mirrors (two corners of each triangle swapped).
    pub fn mirrors(&self) -> bool {
        self.flip
    }

    /// Mesh triangle `ti`'s material.
    #[inline]
    pub fn material(&self, ti: usize) -> u32 {
        self.o.mesh.materials[ti]
    }

    fn world_triangle(&self, ti: usize) -> WorldTriangle {
        let o = self.o;
        let idx = self.corners(ti);
        let (v, n, smooth) = self.shape(ti);
        let uv = if o.mesh.uvs.is_empty() {
            [Vec2::ZERO; 3]
        } else {
            idx.map(|i| o.mesh.uvs[i as usize])
        };
        let uv1 = if o.mesh.uvs1.is_empty() {
            [Vec2::ZERO; 3]
        } else {
            idx.map(|i| o.mesh.uvs1[i as usize])
        };
        let colors = (!o.mesh.colors.is_empty()).then(|| idx.map(|i| o.mesh.colors[i as usize]));
        WorldTriangle {
            v,
            n,
            smooth,
            uv,
            uv1,
            tangents: self.tangents(ti),
            colors,
            material: o.mesh.materials[ti],
            object: self.object,
        }
    }
}
