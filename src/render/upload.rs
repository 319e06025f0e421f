//! Turning the host scene into the device's structs: triangles and shading data in BVH order
//! (flat: world space, one per placed triangle; two levels: object space, one per mesh
//! triangle), materials and the camera. The light list is built in `lights`, the textures in
//! `textures`.

use crate::bvh::{Bvh, PIECE_TRIANGLE, Ray, TwoLevel};
use crate::cl::types::*;
use crate::scene::{
    AlphaMode, Camera, Material, Mesh, RenderFrame, Scene, WorldTriangle, robust_bounds_of,
};
use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;

/// The acceleration structure of the scene on the device, with its host reference.
#[derive(Clone, Debug)]
pub enum Accel {
    /// One BVH over the world-space triangles.
    Flat(Bvh),
    /// A BLAS per distinct mesh and a TLAS over the instances (render space).
    TwoLevel(TwoLevel),
}

impl Accel {
    /// "flat" or "two-level".
    pub fn name(&self) -> &'static str {
        match self {
            Accel::Flat(_) => "flat",
            Accel::TwoLevel(_) => "two-level",
        }
    }

    /// Nodes over both levels.
    pub fn node_count(&self) -> usize {
        match self {
            Accel::Flat(b) => b.nodes.len(),
            Accel::TwoLevel(t) => {
                t.tlas.nodes.len() + t.blases.iter().map(|b| b.bvh.nodes.len()).sum::<usize>()
            }
        }
    }

    /// The SAH cost of the flat BVH, or of the TLAS.
    pub fn sah_cost(&self) -> f32 {
        match self {
            Accel::Flat(b) => b.sah_cost,
            Accel::TwoLevel(t) => t.tlas.sah_cost,
        }
    }

    /// The deepest leaf: of the flat BVH, or the TLAS's depth plus the deepest BLAS's.
    pub fn depth(&self) -> u32 {
        match self {
            Accel::Flat(b) => b.depth,
            Accel::TwoLevel(t) => {
                t.tlas.depth + 1 + t.blases.iter().map(|b| b.bvh.depth).max().unwrap_or(0)
            }
        }
    }

    /// Distinct meshes and instances (1 and 0 for the flat BVH).
    pub fn instancing(&self) -> (usize, usize) {
        match self {
            Accel::Flat(_) => (1, 0),
            Accel::TwoLevel(t) => (t.blases.len(), t.instances.len()),
        }
    }
}

/// Where a two-level scene's parts sit on the device, to update instances in place.
#[derive(Clone, Debug, Default)]
pub struct InstanceLayout {
    /// The object each instance places (index in `Scene::objects`).
    pub objects: Vec<u32>,
    /// Each BLAS's root in the binary node array.
    pub roots: Vec<u32>,
    /// Each BLAS's root in the wide node array (empty while the device has no wide nodes).
    pub wide_roots: Vec<u32>,
    /// Per BLAS, each binary node's wide node (relative to its root; `u32::MAX` for one inside
    /// a wide node): where a re-braided piece enters the wide BLAS (empty while the device has
    /// no wide nodes).
    pub wide_of: Vec<Vec<u32>>,
    /// Each instance's first light (the light index of its first emissive triangle).
    pub light_bases: Vec<i32>,
    /// Each small instance's first world-space triangle copy in the device triangles (see
    /// [`piece_copies`]; `u32::MAX` for an instance that is not small).
    pub copy_bases: Vec<u32>,
    /// Per BLAS, a small mesh's object-space device triangles (empty for the others): what a
    /// moved small instance's copies are made from once the triangles live on the device only.
    pub small_meshes: Vec<Vec<GpuTriangle>>,
}

impl InstanceLayout {
    /// The world-space copies of every small instance's triangles (hidden ones too, so that
    /// showing one writes in place), to follow the meshes' `first` object-space triangles in
    /// the device triangles; keeps where each instance's copies start.
    pub fn piece_copies(&mut self, two: &TwoLevel, first: usize) -> Vec<GpuTriangle> {
        let mut copies = vec![];
        self.copy_bases = (0..two.instances.len())
            .map(|i| {
                let mesh = &self.small_meshes[two.instances[i].blas as usize];
                if mesh.is_empty() {
                    return u32::MAX;
                }
                let base = (first + copies.len()) as u32;
                copies.extend(piece_copies(two, mesh, i));
                base
            })
            .collect();
        copies
    }

    /// The device instances of `two` in TLAS order, one per TLAS slot (a re-braided piece of
    /// an instance: the instance's transforms and the BLAS node it enters at), padded to
    /// [`TwoLevel::max_pieces`] so that the buffer holds any later TLAS's.
    pub fn gpu_instances(&self, two: &TwoLevel) -> Vec<GpuInstance> {
        let mut out: Vec<GpuInstance> = two
            .tlas
            .tri_indices
            .iter()
            .zip(&two.pieces)
            .map(|(&i, &node)| {
                let inst = &two.instances[i as usize];
                let b = inst.blas as usize;
                // A piece of one triangle names it (among the meshes' triangles) in both.
                let triangle = node & PIECE_TRIANGLE != 0;
                let (root, wide_root) = if triangle {
                    let k = node & !PIECE_TRIANGLE;
                    (self.copy_bases[i as usize] + k, two.firsts[b] + k)
                } else {
                    // Without the wide nodes on the device (`NodeForms`), no wide root.
                    let wide = |m: &Vec<u32>| self.wide_roots[b] + m[node as usize];
                    (self.roots[b] + node, self.wide_of.get(b).map_or(0, wide))
                };
                let mut world = inst.world_rows();
                world[0][3] = f32::from_bits(self.light_bases[i as usize] as u32);
                GpuInstance {
                    row0: inst.rows[0],
                    row1: inst.rows[1],
                    row2: inst.rows[2],
                    world0: world[0],
                    world1: world[1],
                    world2: world[2],
                    root,
                    wide_root,
                    id: i,
                    flags: if inst.mirrored { INSTANCE_MIRRORED } else { 0 }
                        | if triangle { INSTANCE_PIECE_TRIANGLE } else { 0 },
                }
            })
            .collect();
        out.resize(two.max_pieces.max(1), GpuInstance::default());
        out
    }
}

/// A small instance's triangles in world space, where the two-level traversal tests them as
/// pieces of the TLAS without entering the instance (`TwoLevel::braid`): the vertices as
/// [`crate::bvh::Instance::device_triangle`] carries them (the host reference tests the same
/// values), the payloads of `mesh`, the instance's mesh's object-space device triangles.
pub fn piece_copies(two: &TwoLevel, mesh: &[GpuTriangle], i: usize) -> Vec<GpuTriangle> {
    let inst = &two.instances[i];
    let v = |p: Vec3, payload: f32| [p.x, p.y, p.z, payload];
    two.blases[inst.blas as usize]
        .triangles()
        .zip(mesh)
        .map(|(t, o)| {
            let w = inst.device_triangle(&t);
            GpuTriangle {
                v0: v(w[0], o.v0[3]),
                v1: v(w[1], o.v1[3]),
                v2: v(w[2], o.v2[3]),
            }
        })
        .collect()
}

/// An emissive triangle of the light table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emitter {
    /// Its index in the device triangles (flat: BVH order; two levels: the mesh triangle).
    pub prim: u32,
    /// Its instance's index (two levels; 0 when flat).
    pub instance: u32,
    /// World (render space) area.
    pub area: f32,
    /// Emitted power, for light selection.
    pub power: f32,
    /// Centroid in render space.
    pub centroid: Vec3,
    /// Its material (index in the scene's materials).
    pub material: u32,
}

/// The scene as uploaded, kept on the host for picking and for tests.
pub struct HostScene {
    /// The acceleration structure.
    pub accel: Accel,
    /// Two levels: where the instances' parts sit on the device (empty when flat).
    pub layout: InstanceLayout,
    /// Triangles as the device has them: the flat BVH's world triangles in BVH order; moved
    /// to the device by `Renderer::load_scene` (empty after). Two levels: only the small
    /// instances' world-space copies that follow the meshes' object-space triangles on the
    /// device (mesh after mesh in BLAS order, written straight into the device buffer by
    /// [`HostScene::fill_meshes`]).
    pub triangles: Vec<GpuTriangle>,
    /// Flat: each triangle's object (index in `Scene::objects`) in BVH order, for picking
    /// (4 bytes a triangle where `triangles` holds 48); empty with two levels.
    pub objects: Vec<u32>,
    /// Flat: world vertices in BVH order (for the host traversal); empty with two levels,
    /// whose BLASes hold their triangles.
    pub vertices: Vec<[Vec3; 3]>,
    /// Corner normals, indexed as `triangles`; moved to the device by `Renderer::load_scene`
    /// (empty after; two levels: always, [`HostScene::fill_meshes`]).
    pub shading: Vec<GpuTriShading>,
    /// Texture coordinates, indexed as `triangles`; empty when no material samples a texture
    /// ([`samples_textures`]), with two levels, and after `Renderer::load_scene` moved them.
    pub uvs: Vec<GpuTriUvs>,
    /// Tangents, indexed as `triangles`; empty when no triangle is normal-mapped, with two
    /// levels, and after `Renderer::load_scene` moved them to the device.
    pub tangents: Vec<GpuTriTangents>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emissive triangles, in light-table order.
    pub emissive: Vec<Emitter>,
    /// The map from world space to the render space the triangles are in.
    pub space: RenderFrame,
    /// The middle and the diagonal of the robust bounds of the triangles.
    middle: (Vec3, f32),
}

pub(super) fn f4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

pub(super) fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// The device form of a material.
pub fn gpu_material(m: &Material) -> GpuMaterial {
    let flags = if m.double_sided {
        MATERIAL_DOUBLE_SIDED
    } else {
        0
    } | if m.unlit { MATERIAL_UNLIT } else { 0 };
    GpuMaterial {
        base_color: m.base_color,
        emission: [
            m.emission[0],
            m.emission[1],
            m.emission[2],
            f32::from_bits(flags),
        ],
        params: [m.metallic, m.roughness, m.ior, m.specular_factor],
        specular: [
            m.specular_color[0],
            m.specular_color[1],
            m.specular_color[2],
            m.transmission,
        ],
        volume: [
            m.attenuation_color[0],
            m.attenuation_color[1],
            m.attenuation_color[2],
            m.attenuation_distance,
        ],
        alpha: [
            match m.alpha {
                AlphaMode::Mask(c) => c,
                _ => 0.5,
            },
            f32::from_bits(match m.alpha {
                AlphaMode::Opaque => ALPHA_OPAQUE,
                AlphaMode::Mask(_) => ALPHA_MASK,
                AlphaMode::Blend => ALPHA_BLEND,
            }),
            m.thickness,
            m.normal_scale,
        ],
        textures: [
            slot(m.textures.base_color),
            slot(m.textures.metallic_roughness),
            slot(m.textures.normal),
            slot(m.textures.emissive),
        ],
        textures2: [
            slot(m.textures.transmission),
            -1,
            slot(m.textures.sheen_color),
            slot(m.textures.sheen_roughness),
        ],
        coat: [
            m.clearcoat,
            m.clearcoat_roughness,
            m.clearcoat_normal_scale,
            0.0,
        ],
        textures3: [
            slot(m.textures.clearcoat),
            slot(m.textures.clearcoat_roughness),
            slot(m.textures.clearcoat_normal),
            -1,
        ],
        sheen: [
            m.sheen_color[0],
            m.sheen_color[1],
            m.sheen_color[2],
            m.sheen_roughness,
        ],
        aniso: [
            m.anisotropy,
            m.anisotropy_rotation.cos(),
            m.anisotropy_rotation.sin(),
            m.dispersion,
        ],
        iridescence: [
            m.iridescence,
            m.iridescence_ior,
            m.iridescence_thickness[0],
            m.iridescence_thickness[1],
        ],
        diffuse_transmission: [
            m.diffuse_transmission_color[0],
            m.diffuse_transmission_color[1],
            m.diffuse_transmission_color[2],
            m.diffuse_transmission,
        ],
        textures4: [
            slot(m.textures.anisotropy),
            slot(m.textures.iridescence),
            slot(m.textures.iridescence_thickness),
            slot(m.textures.diffuse_transmission),
        ],
        textures5: [slot(m.textures.diffuse_transmission_color), -1, -1, -1],
    }
}

fn slot(r: Option<u32>) -> i32 {
    r.map_or(-1, |r| r as i32)
}

/// Whether some material samples a texture: only then do the kernels read texture coordinates
/// (`HAS_TEXTURES` comes from the materials in use, a subset), and only then are they uploaded.
pub fn samples_textures(materials: &[Material]) -> bool {
    materials.iter().any(|m| m.textures.any())
}

impl HostScene {
    /// The flat form of `world` (render space, in object order): converted to the device
    /// structs and dropped before the BVH is built, then the structs are put in BVH order one
    /// array at a time, so that the large intermediate triangles and two orders of the same
    /// data are never held together.
    pub fn flat(world: Vec<WorldTriangle>, materials: &[Material]) -> Self {
        let normal_mapped = world.iter().any(|t| t.tangents.is_some());
        let mut structs = FlatStructs::new(world.len(), normal_mapped, samples_textures(materials));
        structs.add(world);
        let middle = middle_of(1, &|_| {
            structs.vertices.iter().map(|v| v.map(Vec3::as_dvec3))
        });
        Self::flat_from(structs, materials, middle)
    }

    /// [`HostScene::flat`] of `scene`'s visible objects in render space `space`, converted to
    /// the device structs one object at a time (never the whole scene's [`WorldTriangle`]s
    /// at once), and the number of triangles dropped ([`Scene::flatten`]).
    pub fn flatten(scene: &Scene, space: &RenderFrame, materials: &[Material]) -> (Self, usize) {
        let visible = || scene.objects.iter().filter(|o| o.visible);
        // Tangents are kept when some kept triangle has them (as `flat` decides).
        let maybe_mapped = visible().any(|o| !o.mesh.tangents.is_empty());
        let textured = samples_textures(materials);
        let mut structs = FlatStructs::new(scene.triangle_count(), maybe_mapped, textured);
        let dropped = scene.flatten_each(space, |world| structs.add(world));
        if !structs.mapped {
            structs.tangents = Vec::new();
        }
        (
            Self::flat_from(structs, materials, render_middle(scene, space)),
            dropped,
        )
    }

    fn flat_from(structs: FlatStructs, materials: &[Material], middle: (Vec3, f32)) -> Self {
        let FlatStructs {
            triangles,
            shading,
            uvs,
            tangents,
            vertices,
            ..
        } = structs;
        let normal_mapped = !tangents.is_empty();
        let bvh = crate::bvh::build(&vertices);
        fn gather<T: Copy + Send + Sync>(v: Vec<T>, order: &[u32]) -> Vec<T> {
            order.par_iter().map(|&i| v[i as usize]).collect()
        }
        let vertices = gather(vertices, &bvh.tri_indices);
        let mut triangles = gather(triangles, &bvh.tri_indices);
        let shading = gather(shading, &bvh.tri_indices);
        let uvs = if uvs.is_empty() {
            uvs
        } else {
            gather(uvs, &bvh.tri_indices)
        };
        let tangents = if normal_mapped {
            gather(tangents, &bvh.tri_indices)
        } else {
            tangents
        };
        let mut emissive = Vec::new();
        for (order, (tri, v)) in triangles.iter_mut().zip(&vertices).enumerate() {
            let m = &materials[tri.v0[3].to_bits() as usize];
            let area = triangle_area(v);
            if m.is_emissive() && area > 0.0 {
                let sides = if m.double_sided { 2.0 } else { 1.0 };
                let power = luminance(m.emission) * area * std::f32::consts::PI * sides;
                tri.v1[3] = f32::from_bits(emissive.len() as u32);
                emissive.push(Emitter {
                    prim: order as u32,
                    instance: 0,
                    area,
                    power,
                    centroid: v.iter().sum::<Vec3>() / 3.0,
                    material: tri.v0[3].to_bits(),
                });
            }
        }
        let objects = triangles.par_iter().map(|t| t.v2[3].to_bits()).collect();
        Self {
            vertices,
            objects,
            uvs,
            ..Self::assemble(
                Accel::Flat(bvh),
                InstanceLayout::default(),
                (triangles, shading, tangents),
                materials,
                emissive,
                middle,
            )
        }
    }

    /// The scene of `accel` with its device structs, in render space yet to be set.
    fn assemble(
        accel: Accel,
        layout: InstanceLayout,
        (triangles, shading, tangents): (Vec<GpuTriangle>, Vec<GpuTriShading>, Vec<GpuTriTangents>),
        materials: &[Material],
        emissive: Vec<Emitter>,
        middle: (Vec3, f32),
    ) -> Self {
        Self {
            accel,
            layout,
            triangles,
            objects: vec![],
            vertices: vec![],
            shading,
            uvs: vec![],
            tangents,
            materials: materials.iter().map(gpu_material).collect(),
            emissive,
            space: RenderFrame::default(),
            middle,
        }
    }

    /// Fills the device structs of a two-level scene: every mesh's triangles and shading data
    /// once, in object space and BLAS order (`meshes[b]` is BLAS b's mesh), and the light
    /// table's emissive triangles instance by instance (each instance's first light is kept in
    /// `layout.light_bases`). `two`'s instances are in render space; `middle` is the
    /// scene's robust middle and diagonal there ([`render_middle`]).
    pub fn two_level(
        two: TwoLevel,
        meshes: &[&Mesh],
        materials: &[Material],
        middle: (Vec3, f32),
    ) -> Self {
        // Each mesh's emissive triangles (index among the meshes' triangles, material); the
        // device structs themselves are written at the upload (`HostScene::fill_meshes`).
        let mesh_emitters: Vec<Vec<(u32, u32)>> = meshes
            .par_iter()
            .zip(&two.blases)
            .enumerate()
            .map(|(b, (m, blas))| {
                emissive_triangles(m, &blas.bvh.tri_indices, materials)
                    .into_iter()
                    .map(|(k, material)| (two.firsts[b] + k, material))
                    .collect()
            })
            .collect();
        // A small mesh's object-space device triangles, for its instances' world-space copies.
        let small_meshes = meshes
            .iter()
            .zip(&two.blases)
            .map(|(m, blas)| {
                if !two.is_small(blas) {
                    return Vec::new();
                }
                let n = blas.bvh.tri_indices.len();
                let mut tris = vec![GpuTriangle::default(); n];
                let mut shading = vec![GpuTriShading::default(); n];
                let out = (
                    (&mut tris[..], &mut shading[..]),
                    (&mut [][..], &mut [][..]),
                );
                object_triangles(m, &blas.bvh.tri_indices, materials, out);
                tris
            })
            .collect();
        let mut emissive = vec![];
        let mut light_bases = vec![];
        for (i, inst) in two.instances.iter().enumerate() {
            light_bases.push(emissive.len() as i32);
            for &(prim, material) in &mesh_emitters[inst.blas as usize] {
                let v = two.hit_triangle(prim, i as u32);
                let m = &materials[material as usize];
                emissive.push(emitter(prim, i as u32, &v, material, m));
            }
        }
        Self::assemble(
            Accel::TwoLevel(two),
            InstanceLayout {
                light_bases,
                small_meshes,
                ..InstanceLayout::default()
            },
            (vec![], vec![], vec![]),
            materials,
            emissive,
            middle,
        )
    }

    /// Two levels: writes every mesh's device structs, once, in object space and BLAS order
    /// (`meshes[b]` is BLAS b's mesh) to the front of `triangles` and `shading` (and of `uvs`
    /// and `tangents` when not empty), each mesh its own range, in parallel. The renderer writes
    /// them straight into the device buffers ([`crate::cl::Buffer::fill_mapped`]): on a CPU
    /// device no host copy of these arrays (144 bytes a triangle) is made beside them.
    pub fn fill_meshes(
        two: &TwoLevel,
        meshes: &[&Mesh],
        materials: &[Material],
        (triangles, shading, uvs, tangents): (
            &mut [GpuTriangle],
            &mut [GpuTriShading],
            &mut [GpuTriUvs],
            &mut [GpuTriTangents],
        ),
    ) {
        let sizes: Vec<usize> = two.blases.iter().map(|b| b.bvh.tri_indices.len()).collect();
        let sizes_if = |full: bool| {
            if full {
                sizes.clone()
            } else {
                vec![0; sizes.len()]
            }
        };
        let (uv_sizes, tangent_sizes) = (sizes_if(!uvs.is_empty()), sizes_if(!tangents.is_empty()));
        let parts = split_by(triangles, &sizes)
            .into_iter()
            .zip(split_by(shading, &sizes))
            .zip(
                split_by(uvs, &uv_sizes)
                    .into_iter()
                    .zip(split_by(tangents, &tangent_sizes)),
            );
        meshes
            .par_iter()
            .zip(&two.blases)
            .zip(parts.collect::<Vec<_>>())
            .for_each(|((m, blas), out)| {
                object_triangles(m, &blas.bvh.tri_indices, materials, out);
            });
    }

    /// Triangles over all placed meshes.
    pub fn triangle_count(&self) -> usize {
        match &self.accel {
            Accel::Flat(_) => self.vertices.len(),
            Accel::TwoLevel(t) => t.triangle_count(),
        }
    }

    /// Scales each emissive triangle's selection power by its material's factor in
    /// `per_material` (see [`emissive_texture_means`]).
    pub fn scale_emitter_power(&mut self, per_material: &[f32]) {
        for e in &mut self.emissive {
            e.power *= per_material
                .get(e.material as usize)
                .copied()
                .unwrap_or(1.0);
        }
    }

    /// The middle and the diagonal of the scene's robust box (a lone far-away object does not
    /// count, see [`robust_bounds`]), in render space.
    pub fn bounds(&self) -> (Vec3, f32) {
        self.middle
    }

    /// Two levels: recomputes the emissive triangles of instance `i` after it moved (area,
    /// power and centroid).
    pub fn replace_emitters(&mut self, i: u32) {
        let Accel::TwoLevel(two) = &self.accel else {
            return;
        };
        for e in self.emissive.iter_mut().filter(|e| e.instance == i) {
            let v = two.hit_triangle(e.prim, i);
            let area = triangle_area(&v);
            e.power = if e.area > 0.0 {
                e.power * area / e.area
            } else {
                0.0
            };
            e.area = area;
            e.centroid = v.iter().sum::<Vec3>() / 3.0;
        }
    }

    /// The closest hit along `ray` (render space), as the device reports it.
    pub fn intersect(&self, ray: &Ray) -> Option<GpuHit> {
        match &self.accel {
            Accel::Flat(b) => b.intersect(ray, &self.vertices).map(|h| GpuHit {
                t: h.t,
                u: h.u,
                v: h.v,
                prim: h.prim,
                instance: 0,
            }),
            Accel::TwoLevel(t) => t.device_hit(ray),
        }
    }

    /// Whether anything blocks `ray` within its interval.
    pub fn occluded(&self, ray: &Ray) -> bool {
        match &self.accel {
            Accel::Flat(b) => b.occluded(ray, &self.vertices),
            Accel::TwoLevel(t) => t.occluded(ray),
        }
    }

    /// The object (index in `Scene::objects`) a device hit is on.
    pub fn object_of(&self, hit: &GpuHit) -> u32 {
        match &self.accel {
            Accel::Flat(_) => self.objects[hit.prim as usize],
            Accel::TwoLevel(t) => {
                self.layout.objects[t.tlas.tri_indices[hit.instance as usize] as usize]
            }
        }
    }

    /// The world (render space) vertices of a device hit's triangle.
    pub fn hit_triangle(&self, hit: &GpuHit) -> [Vec3; 3] {
        match &self.accel {
            Accel::Flat(_) => self.vertices[hit.prim as usize],
            Accel::TwoLevel(t) => {
                t.hit_triangle(hit.prim, t.tlas.tri_indices[hit.instance as usize])
            }
        }
    }
}

fn triangle_area(v: &[Vec3; 3]) -> f32 {
    0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
}

/// The light-table entry of an emissive triangle with world vertices `v`.
fn emitter(prim: u32, instance: u32, v: &[Vec3; 3], material: u32, m: &Material) -> Emitter {
    let area = triangle_area(v);
    let sides = if m.double_sided { 2.0 } else { 1.0 };
    Emitter {
        prim,
        instance,
        area,
        power: luminance(m.emission) * area * std::f32::consts::PI * sides,
        centroid: v.iter().sum::<Vec3>() / 3.0,
        material,
    }
}

/// The middle and the diagonal of the visible objects' robust bounds in render space `space`:
/// those of [`Scene::bounds`] (world space, computed once and cached) carried over, not
/// computed again over every placed triangle (1.8 s of a 64 M-triangle scene's opening). The
/// robust box does not depend on the frame (a translation and a power-of-two scale) but for
/// rounding.
pub fn render_middle(scene: &Scene, space: &RenderFrame) -> (Vec3, f32) {
    let b = scene.bounds();
    if b.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (space.point(b.center()), space.length(b.diagonal()))
    }
}

/// The middle and the diagonal of the robust bounds of the parts' triangles (see
/// [`robust_bounds_of`]).
fn middle_of<I: Iterator<Item = [DVec3; 3]>>(
    parts: usize,
    part: &(dyn Fn(usize) -> I + Sync),
) -> (Vec3, f32) {
    let b = robust_bounds_of(parts, part);
    if b.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (b.center().as_vec3(), b.diagonal() as f32)
    }
}

/// `v` cut into consecutive parts of `sizes` elements (empty parts once `v` runs out: the
/// tangents of a scene without normal maps, the texture coordinates of one without textures).
fn split_by<'a, T>(mut v: &'a mut [T], sizes: &[usize]) -> Vec<&'a mut [T]> {
    sizes
        .iter()
        .map(|&n| {
            let n = n.min(v.len());
            let (part, rest) = std::mem::take(&mut v).split_at_mut(n);
            v = rest;
            part
        })
        .collect()
}

/// One mesh's device structs for [`object_triangles`] to fill: triangles, corner normals,
/// texture coordinates (empty when no material samples a texture) and tangents (empty when no
/// mesh is normal-mapped).
type MeshStructs<'a> = (
    (&'a mut [GpuTriangle], &'a mut [GpuTriShading]),
    (&'a mut [GpuTriUvs], &'a mut [GpuTriTangents]),
);

/// Whether triangle `ti` of `m` (vertices `v`) is a light: an emissive material and a
/// nonzero object-space area.
fn emits(m: &Mesh, ti: u32, v: &[Vec3; 3], materials: &[Material]) -> bool {
    materials[m.materials[ti as usize] as usize].is_emissive() && triangle_area(v) > 0.0
}

/// One mesh's emissive triangles in the order `order` (index in that order, material), as
/// [`object_triangles`] finds them.
fn emissive_triangles(m: &Mesh, order: &[u32], materials: &[Material]) -> Vec<(u32, u32)> {
    if !m
        .materials
        .iter()
        .any(|&i| materials[i as usize].is_emissive())
    {
        return vec![];
    }
    order
        .iter()
        .enumerate()
        .filter(|&(_, &ti)| {
            let v = m.indices[ti as usize].map(|i| m.positions[i as usize]);
            emits(m, ti, &v, materials)
        })
        .map(|(k, &ti)| (k as u32, m.materials[ti as usize]))
        .collect()
}

/// Writes the device structs of one mesh's triangles in object space, in the order `order`,
/// to `out` (texture coordinates and tangents unless their slices are empty); an emissive triangle's `v1.w` counts the
/// mesh's emissive triangles ([`emissive_triangles`]).
fn object_triangles(
    m: &Mesh,
    order: &[u32],
    materials: &[Material],
    ((tris, shading), (uvs, tangents)): MeshStructs,
) {
    let normal_mapped = !tangents.is_empty();
    let textured = !uvs.is_empty();
    let mut emitters = 0;
    let corner = |a: &[Vec2], i: u32| a.get(i as usize).copied().unwrap_or(Vec2::ZERO);
    for (k, &ti) in order.iter().enumerate() {
        let idx = m.indices[ti as usize];
        let material = m.materials[ti as usize];
        let v = idx.map(|i| m.positions[i as usize]);
        let mut light = -1i32;
        if emits(m, ti, &v, materials) {
            light = emitters;
            emitters += 1;
        }
        let geometric = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        let smooth = !m.normals.is_empty();
        let n = if smooth {
            idx.map(|i| {
                let n = m.normals[i as usize].normalize_or_zero();
                if n == Vec3::ZERO { geometric } else { n }
            })
        } else {
            [geometric; 3]
        };
        let t = WorldTriangle {
            v,
            n,
            smooth,
            uv: idx.map(|i| corner(&m.uvs, i)),
            uv1: idx.map(|i| corner(&m.uvs1, i)),
            tangents: m.tangents.get(ti as usize).copied(),
            material,
            object: 0,
        };
        let (tri, sh) = device_triangle(&t, light);
        tris[k] = tri;
        shading[k] = sh;
        if textured {
            uvs[k] = device_uvs(&t);
        }
        if normal_mapped {
            tangents[k] = device_tangents(&t);
        }
    }
}

/// The flat form's device structs in object order, filled a list of [`WorldTriangle`]s at a
/// time.
struct FlatStructs {
    triangles: Vec<GpuTriangle>,
    shading: Vec<GpuTriShading>,
    /// Filled when some material samples a texture (`keep_uvs`).
    uvs: Vec<GpuTriUvs>,
    /// Filled when tangents may be needed (`keep_tangents`).
    tangents: Vec<GpuTriTangents>,
    vertices: Vec<[Vec3; 3]>,
    keep_uvs: bool,
    keep_tangents: bool,
    /// Whether some triangle added had tangents.
    mapped: bool,
}

impl FlatStructs {
    fn new(capacity: usize, keep_tangents: bool, keep_uvs: bool) -> Self {
        let if_kept = |keep: bool| if keep { capacity } else { 0 };
        Self {
            triangles: Vec::with_capacity(capacity),
            shading: Vec::with_capacity(capacity),
            uvs: Vec::with_capacity(if_kept(keep_uvs)),
            tangents: Vec::with_capacity(if_kept(keep_tangents)),
            vertices: Vec::with_capacity(capacity),
            keep_uvs,
            keep_tangents,
            mapped: false,
        }
    }

    fn add(&mut self, world: Vec<WorldTriangle>) {
        use std::mem::take;
        self.mapped |= world.iter().any(|t| t.tangents.is_some());
        // Each triangle's structs made once, and unzipped into the lists in order.
        let structs = world.par_iter().map(|t| device_triangle(t, -1));
        let mut lists = (take(&mut self.triangles), take(&mut self.shading));
        lists.par_extend(structs);
        (self.triangles, self.shading) = lists;
        if self.keep_uvs {
            self.uvs.par_extend(world.par_iter().map(device_uvs));
        }
        if self.keep_tangents {
            self.tangents
                .par_extend(world.par_iter().map(device_tangents));
        }
        self.vertices.par_extend(world.par_iter().map(|t| t.v));
    }
}

/// A triangle's vertices and corner normals on the device; `light` is its index among the
/// emissive triangles (-1: none). A flat-shaded triangle's normals are zero (the kernels then
/// take its geometric normal).
fn device_triangle(t: &WorldTriangle, light: i32) -> (GpuTriangle, GpuTriShading) {
    let n = if t.smooth {
        t.n.map(|n| n.to_array())
    } else {
        [[0.0; 3]; 3]
    };
    (
        GpuTriangle {
            v0: f4(t.v[0], f32::from_bits(t.material)),
            v1: f4(t.v[1], f32::from_bits(light as u32)),
            v2: f4(t.v[2], f32::from_bits(t.object)),
        },
        GpuTriShading { n },
    )
}

/// A triangle's texture coordinates on the device.
fn device_uvs(t: &WorldTriangle) -> GpuTriUvs {
    GpuTriUvs {
        uv01: [t.uv[0].x, t.uv[0].y, t.uv[1].x, t.uv[1].y],
        uv2: [t.uv[2].x, t.uv[2].y, t.uv1[0].x, t.uv1[0].y],
        uv1_12: [t.uv1[1].x, t.uv1[1].y, t.uv1[2].x, t.uv1[2].y],
    }
}

/// A triangle's tangents on the device (zero without).
fn device_tangents(t: &WorldTriangle) -> GpuTriTangents {
    let c = t.tangents.unwrap_or_default().map(|v| v.to_array());
    GpuTriTangents {
        t0: c[0],
        t1: c[1],
        t2: c[2],
    }
}

/// The device camera for an aspect ratio (width / height).
pub fn gpu_camera(c: &Camera, aspect: f32) -> GpuCamera {
    let forward = c.forward.normalize().as_vec3();
    let right = c.forward.cross(c.up).normalize().as_vec3();
    let up = right.cross(forward).normalize();
    let h = (c.yfov as f32 * 0.5).tan();
    GpuCamera {
        origin: f4(c.eye.as_vec3(), 0.0),
        forward: f4(forward, 1.0),
        right: f4(right * h * aspect, 0.0),
        up: f4(up * h, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lights::gpu_lights;
    use crate::render::textures::TexturePack;
    use crate::scene::{Image, TexTransform, TextureRef};
    use crate::scene::{Light, LightKind, MAX_TEXTURE_SIDE, Scene, Wrap};
    use std::sync::Arc;

    /// A 10-unit floor centred at the origin, as the host would upload it.
    fn floor() -> HostScene {
        let v = [
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, -5.0),
        ];
        let world = vec![WorldTriangle {
            v,
            n: [Vec3::Y; 3],
            ..WorldTriangle::default()
        }];
        HostScene::flat(world, &[Material::default()])
    }

    fn light(kind: LightKind, position: glam::DVec3, intensity: f32) -> Light {
        Light {
            name: "l".into(),
            kind,
            position,
            direction: glam::DVec3::NEG_Y,
            color: [1.0; 3],
            intensity,
            light_radius: 0.0,
        }
    }

    #[test]
    fn lights_that_light_the_scene_equally_are_not_starved() {
        let host = floor();
        // A sun of irradiance 2 and a point light 20 units up with I / d² = 2 at the middle.
        // By power alone the sun would get 3 %; the mixture gives it half of the irradiance
        // table's 50 % plus half of that.
        let lights = [
            light(LightKind::Directional, glam::DVec3::ZERO, 2.0),
            light(LightKind::Point, glam::DVec3::new(0.0, 20.0, 0.0), 800.0),
        ];
        let (gpu, cdf) = gpu_lights(&lights, &host, None);
        assert_eq!(gpu.len(), 2);
        eprintln!("bounds {:?} {:?}", host.bounds(), gpu);
        let sun_power = 2.0 * std::f32::consts::PI * 50.0;
        let point_power = 800.0 * 4.0 * std::f32::consts::PI;
        let expect = 0.5 * (0.5 + sun_power / (sun_power + point_power));
        assert!(
            (gpu[0].extra[1] - expect).abs() < 1e-4,
            "{:?}",
            gpu[0].extra
        );
        assert!((gpu[0].extra[1] + gpu[1].extra[1] - 1.0).abs() < 1e-6);
        assert_eq!(*cdf.last().unwrap(), 1.0);
        // A light at the middle counts as 5 % of the diagonal away (I / 0.5 here), not as
        // infinitely bright.
        let close = [
            light(LightKind::Directional, glam::DVec3::ZERO, 1.0),
            light(LightKind::Point, glam::DVec3::ZERO, 1.0),
        ];
        let (gpu, _) = gpu_lights(&close, &host, None);
        let pi = std::f32::consts::PI;
        let expect = 0.5 * (2.0 / 3.0 + 4.0 * pi / (4.0 * pi + 50.0 * pi));
        assert!(
            (gpu[1].extra[1] - expect).abs() < 1e-4,
            "{:?}",
            gpu[1].extra
        );
    }

    fn scene_with(sides: &[u32]) -> Scene {
        let images = sides
            .iter()
            .map(|&s| {
                Arc::new(Image {
                    name: format!("{s}"),
                    width: s,
                    height: s / 2,
                    rgba: vec![[200, 100, 50, 255]; (s * s / 2) as usize],
                })
            })
            .collect();
        let texture_refs = (0..sides.len() as u32)
            .flat_map(|image| {
                [false, true].map(|srgb| TextureRef {
                    image,
                    srgb,
                    wrap_s: Wrap::Repeat,
                    wrap_t: Wrap::Mirror,
                    tex_coord: 0,
                    nearest: false,
                    mipmaps: true,
                    transform: TexTransform::default(),
                })
            })
            .collect();
        Scene {
            images,
            texture_refs,
            ..Scene::default()
        }
    }

    #[test]
    fn textures_pack_their_mip_chains_one_after_another() {
        let pack = TexturePack::new(&scene_with(&[8, 4]), usize::MAX);
        // Each image twice (linear and sRGB): 8×4 → 4×2 → 2×1 → 1×1, and 4×2 → 2×1 → 1×1.
        assert_eq!(pack.textures.len(), 4);
        let big = 32 + 8 + 2 + 1;
        let small = 8 + 2 + 1;
        assert_eq!(pack.texels.len(), 2 * big + 2 * small);
        assert_eq!(pack.textures[1].offset, big as u32);
        assert_eq!(pack.textures[0].flags, 4);
        assert_eq!(pack.textures[1].flags, 4 | TEXTURE_SRGB);
        assert_eq!(pack.refs[3].info, [3, WRAP_REPEAT, WRAP_MIRROR, 0]);
        assert_eq!(pack.bytes(), pack.texels.len() * 4);
        assert_eq!(pack.texels[0], u32::from_le_bytes([200, 100, 50, 255]));
    }

    #[test]
    fn a_tight_budget_halves_the_largest_side() {
        // Two 64×32 chains (linear and sRGB) of 2048 + 512 + 128 + 32 + 8 + 2 + 1 texels each.
        let full = TexturePack::new(&scene_with(&[64]), usize::MAX);
        assert_eq!(full.max_side, MAX_TEXTURE_SIDE);
        let budget = full.bytes() / 2;
        let pack = TexturePack::new(&scene_with(&[64]), budget);
        assert!(pack.bytes() <= budget);
        assert_eq!(pack.max_side, 32);
        assert_eq!((pack.textures[0].width, pack.textures[0].height), (32, 16));
    }
}
