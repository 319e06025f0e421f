//! The scene as uploaded ([`HostScene`]): its device structs in BVH order (flat: world space,
//! one per placed triangle; two levels: object space, one per mesh triangle), the emissive
//! triangles of the light table, and the host reference traversal for picking and tests.

use super::accel::{Accel, InstanceLayout};
use super::repose::{CHUNK, changed_chunks};
use super::structs::{gpu_material, luminance, samples_textures};
use super::triangles::{
    FlatStructs, emissive_triangles, object_triangles, split_by, triangle_area,
};
use crate::bvh::{Blas, Ray, TwoLevel, WideBvh};
use crate::cl::types::*;
use crate::scene::{Material, Mesh, RenderFrame, Scene, WorldTriangle, robust_bounds_of};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::mem::take;

/// The device arrays [`HostScene::fill_meshes`] writes every mesh's structs into: triangles,
/// shading, texture coordinates, tangents and colours (the last three may be empty).
pub type MeshArrays<'a> = (
    &'a mut [DeviceTriangle],
    &'a mut [DeviceTriShading],
    &'a mut [DeviceTriUvs],
    &'a mut [DeviceTriTangents],
    &'a mut [DeviceTriColors],
);

/// One mesh's device structs in object space and BLAS order
/// ([`HostScene::mesh_structs`]): triangles, shading data and tangents (empty without).
pub type PosedMesh = (
    Vec<DeviceTriangle>,
    Vec<DeviceTriShading>,
    Vec<DeviceTriTangents>,
);

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
    pub triangles: Vec<DeviceTriangle>,
    /// Flat: each triangle's object (index in `Scene::objects`) in BVH order, for picking
    /// (4 bytes a triangle where `triangles` holds 48); empty with two levels.
    pub objects: Vec<u32>,
    /// Flat: world vertices in BVH order (for the host traversal); empty with two levels,
    /// whose BLASes hold their triangles.
    pub vertices: Vec<[Vec3; 3]>,
    /// Corner normals, indexed as `triangles`; moved to the device by `Renderer::load_scene`
    /// (empty after; two levels: always, [`HostScene::fill_meshes`]).
    pub shading: Vec<DeviceTriShading>,
    /// Texture coordinates, indexed as `triangles`; empty when no material samples a texture
    /// ([`samples_textures`]), with two levels, and after `Renderer::load_scene` moved them.
    pub uvs: Vec<DeviceTriUvs>,
    /// Tangents, indexed as `triangles`; empty when no triangle is normal-mapped, with two
    /// levels, and after `Renderer::load_scene` moved them to the device.
    pub tangents: Vec<DeviceTriTangents>,
    /// Vertex colours, indexed as `triangles`; empty when no mesh has them, with two levels,
    /// and after `Renderer::load_scene` moved them to the device.
    pub colors: Vec<DeviceTriColors>,
    /// Materials.
    pub materials: Vec<DeviceMaterial>,
    /// Emissive triangles, in light-table order.
    pub emissive: Vec<Emitter>,
    /// The map from world space to the render space the triangles are in.
    pub space: RenderFrame,
    /// The middle and the diagonal of the robust bounds of the triangles.
    pub(super) middle: (Vec3, f32),
    /// Flat, after a pose was refitted ([`HostScene::refit_flat`]): the device structs as
    /// last written, so that the next pose writes only what differs.
    pub posed: Option<PosedArrays>,
    /// The lists of the pose before, whose memory the next pose is written into.
    pub spare: Option<PosedArrays>,
    /// Flat: how many slots of the tree each object has, by object index (found at the first
    /// pose written in place, [`HostScene::repose_flat`]; empty before).
    pub(super) object_slots: Vec<u32>,
    /// Flat, with `object_slots`: each slot's mesh triangle and its corners (as
    /// [`crate::scene::Placed::corners`]) in tree order, read in order at each pose, and the
    /// index lists they were read from and whether each object mirrored, by object.
    pub(super) slot_corners: (Vec<super::repose::SlotCorners>, SlotSources),
}

/// A flat scene's pose-dependent device structs in BVH order: triangles, corner normals and
/// tangents (empty without normal maps). Texture coordinates and colours do not change with
/// a pose. The lists are written again at the next pose (their memory faulted in once: fresh
/// lists cost a quarter of a 1 M-triangle update in page faults, 2026-12-07).
pub struct PosedArrays {
    /// Vertices, material, light and object.
    pub triangles: Vec<DeviceTriangle>,
    /// Corner normals.
    pub shading: Vec<DeviceTriShading>,
    /// Tangents; empty without normal maps.
    pub tangents: Vec<DeviceTriTangents>,
    /// The 4-wide nodes as on the device, when it has them: refitted after the first pose
    /// ([`WideBvh::refit`]) rather than collapsed again (the optimal collapse took a third of a
    /// 1 M-triangle update, 2026-12-07).
    pub wide: Option<WideBvh>,
    /// The lists the pose was flattened into, in object order.
    flattened: FlatStructs,
}

impl PosedArrays {
    /// Lists of `n` zeroed structs (tangents too when `tangents`), to be written in place.
    pub(super) fn filled(n: usize, tangents: bool) -> Self {
        Self {
            triangles: vec![DeviceTriangle::default(); n],
            shading: vec![DeviceTriShading::default(); n],
            tangents: vec![DeviceTriTangents::default(); if tangents { n } else { 0 }],
            wide: None,
            flattened: FlatStructs::default(),
        }
    }
}

/// Which chunks ([`CHUNK`] elements) of a pose's device lists ([`PosedArrays`]) differ from
/// the last pose's, to be written: triangles, corner normals and tangents (empty without).
pub struct Dirty {
    /// Chunks of triangles.
    pub triangles: Vec<bool>,
    /// Chunks of corner normals.
    pub shading: Vec<bool>,
    /// Chunks of tangents.
    pub tangents: Vec<bool>,
}

/// The objects' index lists and mirroring that [`HostScene::slot_corners`] were read from.
pub(super) type SlotSources = (Vec<Vec<[u32; 3]>>, Vec<bool>);

/// What [`HostScene::refit_flat`] made of a new pose of a flat scene.
pub enum FlatRefit {
    /// The BVH refitted, the pose's device structs in [`HostScene::posed`]; which of their
    /// chunks changed, and the host time of flattening and of the refit (ms).
    Refitted(Dirty, f64, f64),
    /// The refit took the BVH's SAH cost past [`crate::bvh::REFIT_MAX_GROWTH`] times its
    /// build's: the scene must be built again.
    TooCostly,
    /// The pose placed other triangles (an object shown or hidden, a triangle dropped or
    /// kept, another mesh): the scene must be loaded again.
    Changed,
}

impl HostScene {
    /// The flat form of `world` (render space, in object order): converted to the device
    /// structs and dropped before the BVH is built, then the structs are put in BVH order one
    /// array at a time, so that the large intermediate triangles and two orders of the same
    /// data are never held together.
    pub fn flat(world: Vec<WorldTriangle>, materials: &[Material]) -> Self {
        let normal_mapped = world.iter().any(|t| t.tangents.is_some());
        let colored = world.iter().any(|t| t.colors.is_some());
        let textured = samples_textures(materials);
        let mut structs = FlatStructs::new(world.len(), normal_mapped, textured, colored);
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
        let (structs, dropped) = flat_structs(scene, space, materials, None);
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
            colors,
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
        let colors = if colors.is_empty() {
            colors
        } else {
            gather(colors, &bvh.tri_indices)
        };
        let emissive = flat_emitters(&mut triangles, &vertices, materials, None);
        let objects = triangles.par_iter().map(|t| t.v2[3].to_bits()).collect();
        Self {
            vertices,
            objects,
            uvs,
            colors,
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
        (triangles, shading, tangents): (
            Vec<DeviceTriangle>,
            Vec<DeviceTriShading>,
            Vec<DeviceTriTangents>,
        ),
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
            colors: vec![],
            materials: materials.iter().map(gpu_material).collect(),
            emissive,
            space: RenderFrame::default(),
            middle,
            posed: None,
            spare: None,
            object_slots: vec![],
            slot_corners: Default::default(),
        }
    }

    /// A flat scene brought to `scene`'s new pose in render space `space` with the same
    /// triangles placed: every visible triangle flattened anew (as a fresh load would, so the
    /// device structs are the same numbers), the BVH refitted over them (its topology and
    /// triangle order kept), the emissive triangles measured again. Leaves the host scene as
    /// it was unless it returns [`FlatRefit::Refitted`] (after [`FlatRefit::TooCostly`] its
    /// tree is spoilt: the scene is loaded again). `tangents`: whether the device holds
    /// tangents.
    pub fn refit_flat(
        &mut self,
        scene: &Scene,
        space: RenderFrame,
        materials: &[Material],
        tangents: bool,
    ) -> FlatRefit {
        match self.repose_flat(scene, space, materials, tangents) {
            Some(Ok((dirty, flatten_ms, refit_ms))) => {
                return FlatRefit::Refitted(dirty, flatten_ms, refit_ms);
            }
            Some(Err(())) => return FlatRefit::TooCostly,
            None => {}
        }
        let Accel::Flat(bvh) = &mut self.accel else {
            return FlatRefit::Changed;
        };
        let t = std::time::Instant::now();
        let mut spare = self.spare.take();
        let reuse = spare.as_mut().map(|l| take(&mut l.flattened));
        let (structs, _) = flat_structs(scene, &space, materials, reuse);
        // The same triangles of the same objects, in the order the tree holds them.
        let same = structs.vertices.len() == bvh.tri_indices.len()
            && structs.tangents.is_empty() != tangents
            && bvh
                .tri_indices
                .par_iter()
                .zip(&self.objects)
                .all(|(&i, &o)| structs.triangles[i as usize].v2[3].to_bits() == o);
        if !same {
            return FlatRefit::Changed;
        }
        let flatten_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        let vertices = &structs.vertices;
        bvh.refit_with(|i| vertices[i]);
        if bvh.needs_rebuild() {
            return FlatRefit::TooCostly;
        }
        let refit_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        let order = &bvh.tri_indices;
        /// `v` in the order `order`, into `out`'s memory.
        fn gather<T: Copy + Send + Sync>(v: &[T], order: &[u32], mut out: Vec<T>) -> Vec<T> {
            out.clear();
            out.par_extend(order.par_iter().map(|&i| v[i as usize]));
            out
        }
        let mut arrays = spare.unwrap_or_else(|| PosedArrays::filled(0, false));
        let mut triangles = gather(&structs.triangles, order, take(&mut arrays.triangles));
        let vertices = gather(vertices, order, take(&mut self.vertices));
        self.emissive = flat_emitters(&mut triangles, &vertices, materials, None);
        arrays.triangles = triangles;
        arrays.shading = gather(&structs.shading, order, take(&mut arrays.shading));
        if tangents {
            arrays.tangents = gather(&structs.tangents, order, take(&mut arrays.tangents));
        }
        arrays.flattened = structs;
        // What differs from the last pose written (all of it without one).
        let mut old = self.posed.take();
        let last = old.as_ref();
        let empty = PosedArrays::filled(0, false);
        let last_or_empty = last.unwrap_or(&empty);
        let dirty = Dirty {
            triangles: changed_chunks(&arrays.triangles, &last_or_empty.triangles),
            shading: changed_chunks(&arrays.shading, &last_or_empty.shading),
            tangents: changed_chunks(&arrays.tangents, &last_or_empty.tangents),
        };
        arrays.wide = old.as_mut().and_then(|o| o.wide.take());
        self.spare = old;
        self.posed = Some(arrays);
        self.vertices = vertices;
        self.space = space;
        self.middle = render_middle(scene, &space);
        self.materials = materials.iter().map(gpu_material).collect();
        FlatRefit::Refitted(
            dirty,
            flatten_ms + t.elapsed().as_secs_f64() * 1e3,
            refit_ms,
        )
    }

    /// Fills the device structs of a two-level scene: every mesh's triangles and shading data
    /// once, in object space and BLAS order (`meshes[b]` is BLAS b's mesh), and the light
    /// table's emissive triangles instance by instance (each instance's first light is kept in
    /// `layout.light_bases`). `two`'s instances are in render space; `middle` is the
    /// scene's robust middle and diagonal there (`render_middle`).
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
                let mut tris = vec![DeviceTriangle::default(); n];
                let mut shading = vec![DeviceTriShading::default(); n];
                let out = (
                    (&mut tris[..], &mut shading[..]),
                    (&mut [][..], &mut [][..]),
                    &mut [][..],
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
    /// (`meshes[b]` is BLAS b's mesh) to the front of `triangles` and `shading` (and of `uvs`,
    /// `tangents` and `colors` when not empty), each mesh its own range, in parallel. The renderer writes
    /// them straight into the device buffers ([`crate::cl::Buffer::fill_mapped`]): on a CPU
    /// device no host copy of these arrays (144 bytes a triangle) is made beside them.
    pub fn fill_meshes(
        two: &TwoLevel,
        meshes: &[&Mesh],
        materials: &[Material],
        (triangles, shading, uvs, tangents, colors): MeshArrays,
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
        let color_sizes = sizes_if(!colors.is_empty());
        let parts = split_by(triangles, &sizes)
            .into_iter()
            .zip(split_by(shading, &sizes))
            .zip(
                split_by(uvs, &uv_sizes)
                    .into_iter()
                    .zip(split_by(tangents, &tangent_sizes)),
            )
            .zip(split_by(colors, &color_sizes))
            .map(|((a, b), c)| (a, b, c));
        meshes
            .par_iter()
            .zip(&two.blases)
            .zip(parts.collect::<Vec<_>>())
            .for_each(|((m, blas), out)| {
                object_triangles(m, &blas.bvh.tri_indices, materials, out);
            });
    }

    /// Two levels: the device structs of `mesh` in `blas`'s order, as
    /// [`HostScene::fill_meshes`] writes them (object space): triangles, shading data and,
    /// when `tangents`, tangents (else none). Texture coordinates and colours are left out:
    /// a deformation does not change them.
    pub fn mesh_structs(
        blas: &Blas,
        mesh: &Mesh,
        materials: &[Material],
        tangents: bool,
    ) -> PosedMesh {
        let n = blas.len();
        let mut tris = vec![DeviceTriangle::default(); n];
        let mut shading = vec![DeviceTriShading::default(); n];
        let mut tans = vec![DeviceTriTangents::default(); if tangents { n } else { 0 }];
        let out = (
            (&mut tris[..], &mut shading[..]),
            (&mut [][..], &mut tans[..]),
            &mut [][..],
        );
        object_triangles(mesh, &blas.bvh.tri_indices, materials, out);
        (tris, shading, tans)
    }

    /// Two levels: every emissive triangle measured again where its instance places it now
    /// (area, power before [`HostScene::scale_emitter_power`], centroid), as
    /// [`HostScene::two_level`] measures them, in the same light-table order.
    pub fn measure_emitters(&mut self, materials: &[Material]) {
        let Accel::TwoLevel(two) = &self.accel else {
            return;
        };
        for e in &mut self.emissive {
            let v = two.hit_triangle(e.prim, e.instance);
            let m = &materials[e.material as usize];
            *e = emitter(e.prim, e.instance, &v, e.material, m);
        }
    }

    /// Takes render space `space` for `scene`'s pose: the frame and the robust middle there.
    pub fn set_space(&mut self, scene: &Scene, space: RenderFrame) {
        self.space = space;
        self.middle = render_middle(scene, &space);
    }

    /// Triangles over all placed meshes.
    pub fn triangle_count(&self) -> usize {
        match &self.accel {
            Accel::Flat(_) => self.vertices.len(),
            Accel::TwoLevel(t) => t.triangle_count(),
        }
    }

    /// Scales each emissive triangle's selection power by its material's factor in
    /// `per_material` (see `lights::emissive_texture_means`).
    pub fn scale_emitter_power(&mut self, per_material: &[f32]) {
        for e in &mut self.emissive {
            e.power *= per_material
                .get(e.material as usize)
                .copied()
                .unwrap_or(1.0);
        }
    }

    /// The middle and the diagonal of the scene's robust box (a lone far-away object does not
    /// count, see [`crate::scene::robust_bounds`]), in render space.
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
    pub fn intersect(&self, ray: &Ray) -> Option<DeviceHit> {
        match &self.accel {
            Accel::Flat(b) => b.intersect(ray, &self.vertices).map(|h| DeviceHit {
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
    pub fn object_of(&self, hit: &DeviceHit) -> u32 {
        match &self.accel {
            Accel::Flat(_) => self.objects[hit.prim as usize],
            Accel::TwoLevel(t) => {
                self.layout.objects[t.tlas.tri_indices[hit.instance as usize] as usize]
            }
        }
    }

    /// The world (render space) vertices of a device hit's triangle.
    pub fn hit_triangle(&self, hit: &DeviceHit) -> [Vec3; 3] {
        match &self.accel {
            Accel::Flat(_) => self.vertices[hit.prim as usize],
            Accel::TwoLevel(t) => {
                t.hit_triangle(hit.prim, t.tlas.tri_indices[hit.instance as usize])
            }
        }
    }
}

/// The flat form's device structs of `scene`'s visible objects in render space `space`, in
/// object order, converted one object at a time (never the whole scene's [`WorldTriangle`]s
/// at once), and the number of triangles dropped ([`Scene::flatten`]).
/// `reuse`: the lists of an earlier pose, whose memory is written again (the texture
/// coordinates and colours are then not made).
pub(super) fn flat_structs(
    scene: &Scene,
    space: &RenderFrame,
    materials: &[Material],
    reuse: Option<FlatStructs>,
) -> (FlatStructs, usize) {
    let visible = || scene.objects.iter().filter(|o| o.visible);
    // Tangents are kept when some kept triangle has them (as `flat` decides).
    let maybe_mapped = visible().any(|o| !o.mesh.tangents.is_empty());
    let textured = samples_textures(materials);
    let colored = visible().any(|o| !o.mesh.colors.is_empty());
    let capacity = scene.triangle_count();
    let mut structs = match reuse {
        Some(old) => old.cleared(capacity, maybe_mapped),
        None => FlatStructs::new(capacity, maybe_mapped, textured, colored),
    };
    let dropped = scene.flatten_each(space, |world| structs.add(world));
    if !structs.mapped {
        structs.tangents = Vec::new();
    }
    (structs, dropped)
}

/// The emissive triangles of a flat scene's `triangles` (BVH order, world vertices
/// `vertices`), in that order: each one's light index written into its `v1.w`, and -1 into that
/// of a triangle of an emissive material with no area. With `dirty`, the chunks whose
/// triangles this changed are marked.
pub(super) fn flat_emitters(
    triangles: &mut [DeviceTriangle],
    vertices: &[[Vec3; 3]],
    materials: &[Material],
    mut dirty: Option<&mut [bool]>,
) -> Vec<Emitter> {
    let mut emissive = Vec::new();
    if !materials.iter().any(Material::is_emissive) {
        return emissive;
    }
    // The triangles of emissive materials found in parallel, numbered in order.
    let candidates: Vec<u32> = (0..triangles.len() as u32)
        .into_par_iter()
        .filter(|&k| materials[triangles[k as usize].v0[3].to_bits() as usize].is_emissive())
        .collect();
    for k in candidates {
        let (tri, v) = (&mut triangles[k as usize], &vertices[k as usize]);
        let m = &materials[tri.v0[3].to_bits() as usize];
        let area = triangle_area(v);
        let mut light = u32::MAX;
        if area > 0.0 {
            let sides = if m.double_sided { 2.0 } else { 1.0 };
            let power = luminance(m.emission) * area * std::f32::consts::PI * sides;
            light = emissive.len() as u32;
            emissive.push(Emitter {
                prim: k,
                instance: 0,
                area,
                power,
                centroid: v.iter().sum::<Vec3>() / 3.0,
                material: tri.v0[3].to_bits(),
            });
        }
        if tri.v1[3].to_bits() != light {
            tri.v1[3] = f32::from_bits(light);
            if let Some(d) = dirty.as_deref_mut() {
                d[k as usize / CHUNK] = true;
            }
        }
    }
    emissive
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
