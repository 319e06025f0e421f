//! Posing a two-level scene whose meshes deformed: each deformed mesh's BLAS refitted in the
//! mesh's own space ([`refit_blases`]), then, where the instances keep their BLASes, only what
//! the pose changed written over the device's buffers in place
//! ([`Renderer::write_refitted_blases`]): the deformed meshes' triangles, shading data and
//! tangents and their BLAS nodes (binary and 4-wide) in their ranges, the instances and the
//! TLAS (every instance is placed again: the render space follows the posed bounds), the
//! small instances' world-space copies, the materials and the light table. The other meshes'
//! ranges, texture coordinates, colours and textures stay as they are on the device.

use super::instancing::{instanced_objects, render_from_world};
use super::update::write_tlas;
use super::upload::{HostScene, PosedMesh, gpu_material};
use super::{Accel, Renderer, lights};
use crate::bvh::{Blas, Update, WideBvh};
use crate::cl::ClError;
use crate::cl::types::DeviceWideNode;
use crate::scene::{Light, Mesh, Object, RenderFrame, Scene, distinct_meshes};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// The BLASes of a posed two-level scene, refitted from those on the device
/// ([`refit_blases`]).
pub(super) struct RefittedBlases {
    /// Each distinct mesh with its BLAS, in [`super::instancing::plan`]'s order (for
    /// [`super::instancing::Blases::Built`]).
    pub blases: Vec<(Arc<Mesh>, Blas)>,
    /// Per BLAS, whether its mesh deformed (a new mesh, the tree refitted or built over it).
    pub deformed: Vec<bool>,
    /// Whether a refit passed its cost bound and that BLAS was built anew.
    pub rebuilt: bool,
    /// Whether every instance places the BLAS it placed on the device (the same mesh
    /// numbering): the device's ranges can be written in place.
    pub same_places: bool,
}

/// What [`Renderer::write_refitted_blases`] wrote (host time, ms).
pub(super) struct BlasWrite {
    /// The deformed BLASes' device nodes made and the TLAS built.
    pub bvh_ms: f64,
    /// The deformed meshes' structs made and everything written to the device.
    pub upload_ms: f64,
    /// Bytes written to the device.
    pub bytes: usize,
}

/// The BLASes of `scene`'s distinct meshes made from those of `host`, the two-level scene on
/// the device before the pose: each mesh's old BLAS refitted over it in its own space, the
/// same topology (built anew past its cost bound: [`Blas::refit_over`]). `None` when the
/// instances place other objects or a mesh's index list changed: the scene is built again.
pub(super) fn refit_blases(scene: &Scene, host: &HostScene) -> Option<RefittedBlases> {
    let Accel::TwoLevel(two) = &host.accel else {
        return None;
    };
    let objects = instanced_objects(scene);
    if objects != host.layout.objects || two.instances.len() != objects.len() {
        return None;
    }
    let placed: Vec<&Object> = objects
        .iter()
        .map(|&o| &scene.objects[o as usize])
        .collect();
    // A mesh that deformation split from others (each deformed object gets its own copy)
    // refits the BLAS its instance had.
    let (meshes, mesh_of) = distinct_meshes(&placed);
    let same_places = meshes.len() == two.blases.len()
        && mesh_of
            .iter()
            .zip(&two.instances)
            .all(|(&m, inst)| m == inst.blas);
    let built: Vec<((Arc<Mesh>, Blas), bool, Update)> = meshes
        .par_iter()
        .map(|&i| {
            let mesh = &placed[i].mesh;
            let old = two.blases.get(two.instances[i].blas as usize)?;
            let deformed = !old.reads(mesh);
            let (blas, update) = old.refit_over(mesh)?;
            Some(((Arc::clone(mesh), blas), deformed, update))
        })
        .collect::<Option<_>>()?;
    Some(RefittedBlases {
        rebuilt: built.iter().any(|b| b.2 == Update::Rebuilt),
        deformed: built.iter().map(|b| b.1).collect(),
        blases: built.into_iter().map(|b| b.0).collect(),
        same_places,
    })
}

/// A deformed BLAS's device nodes: its index, its mesh, the BLAS, its binary nodes (empty
/// when the device lacks them) and its 4-wide nodes with the tree they were made from (when
/// the device has them).
type DeformedBlas = (
    usize,
    Arc<Mesh>,
    Blas,
    Vec<crate::cl::types::DeviceBvhNode>,
    Option<(Vec<DeviceWideNode>, WideBvh)>,
);

impl Renderer {
    /// Brings a two-level scene on the device to `scene`'s pose in render space `space` with
    /// `refitted`'s BLASes, writing only what changed in place (see the module). Gives the
    /// BLASes back, changing nothing, when that cannot be done and the scene must be loaded
    /// again over them: a BLAS was built anew, the instances place other BLASes, or a
    /// triangle has an absurd vertex (a fresh load flattens the scene). Leaves the film as
    /// [`Renderer::reset`] does.
    pub(super) fn write_refitted_blases(
        &mut self,
        scene: &Scene,
        lights: &[Light],
        space: RenderFrame,
        refitted: RefittedBlases,
    ) -> Result<Result<BlasWrite, RefittedBlases>, ClError> {
        let t = Instant::now();
        if refitted.rebuilt || !refitted.same_places || scene.absurd_triangles() > 0 {
            return Ok(Err(refitted));
        }
        let Some((buffers, host)) = self.scene.as_mut() else {
            return Ok(Err(refitted));
        };
        let Accel::TwoLevel(two) = &mut host.accel else {
            return Ok(Err(refitted));
        };
        let layout = &mut host.layout;
        let materials: Vec<_> = scene.materials.iter().map(|m| space.material(m)).collect();
        let forms = buffers.forms;
        if layout.wide_blases.len() != two.blases.len() {
            layout.wide_blases = vec![None; two.blases.len()];
        }
        // Each deformed BLAS's nodes in its place, in parallel: its binary nodes rebased, its
        // 4-wide tree as on the device (collapsed from the BLAS before the pose, the first
        // time) refitted.
        let deformed: Vec<_> = (refitted.blases)
            .into_iter()
            .zip(&refitted.deformed)
            .enumerate()
            .filter(|(_, (_, d))| **d)
            .map(|(b, (blas, _))| (b, blas, layout.wide_blases[b].take()))
            .collect();
        let (two_now, layout_now) = (&*two, &*layout);
        let made: Vec<DeformedBlas> = deformed
            .into_par_iter()
            .map(|(b, (mesh, blas), wide)| {
                let nodes = if forms.binary {
                    two_now.device_blas(b, &blas, layout_now.roots[b])
                } else {
                    vec![]
                };
                let wide = forms.wide.then(|| {
                    let mut wide = wide.unwrap_or_else(|| two_now.wide_blas(b));
                    wide.refit(&blas.triangles().collect::<Vec<_>>());
                    let root = layout_now.wide_roots[b];
                    (two_now.device_wide_blas(b, &wide, root), wide)
                });
                (b, mesh, blas, nodes, wide)
            })
            .collect();
        let nodes_ms = t.elapsed().as_secs_f64() * 1e3;
        // The deformed meshes' device structs (object space, BLAS order), in parallel.
        let tangents = layout.mesh_tangents;
        let structs: Vec<PosedMesh> = made
            .par_iter()
            .map(|(_, mesh, blas, ..)| HostScene::mesh_structs(blas, mesh, &materials, tangents))
            .collect();
        let device = &self.device;
        let mut bytes = 0;
        // The deformed meshes' ranges: nodes, triangles, shading data, tangents.
        for ((b, _, blas, nodes, wide), (tris, shading, tangents)) in made.into_iter().zip(structs)
        {
            let first = two.firsts[b] as usize;
            if forms.binary {
                let root = layout.roots[b] as usize;
                bytes += buffers.nodes.write_at(device, root, &nodes)?;
            }
            if let Some((nodes, wide)) = wide {
                let root = layout.wide_roots[b] as usize;
                bytes += buffers.wide_nodes.write_at(device, root, &nodes)?;
                layout.wide_blases[b] = Some(wide);
            }
            bytes += buffers.triangles.write_at(device, first, &tris)?;
            bytes += buffers.shading.write_at(device, first, &shading)?;
            if layout.mesh_tangents {
                bytes += buffers.tangents.write_at(device, first, &tangents)?;
            }
            if two.is_small(&blas) {
                layout.small_meshes[b] = tris;
            }
            two.blases[b] = blas;
        }
        // Every instance placed in the new render space, and the TLAS over them.
        let fitting = Instant::now();
        let frame = render_from_world(&space);
        for (i, &o) in layout.objects.iter().enumerate() {
            let object = &scene.objects[o as usize];
            two.place(i, frame * object.world_from_object);
            two.hidden[i] = !object.visible;
        }
        two.rebuild_tlas();
        let tlas_ms = fitting.elapsed().as_secs_f64() * 1e3;
        bytes += write_tlas(buffers, device, two, layout)?;
        // The small instances' world-space copies follow the meshes' triangles.
        if two.has_small_meshes() {
            let first = two.blases.iter().map(|b| b.len()).sum();
            let copies = layout.piece_copies(two, first);
            bytes += buffers.triangles.write_at(device, first, &copies)?;
        }
        host.set_space(scene, space);
        host.materials = materials.iter().map(gpu_material).collect();
        bytes += buffers.materials.write(device, &host.materials)?;
        host.measure_emitters(&materials);
        host.scale_emitter_power(&lights::emissive_texture_means(scene));
        self.follow_pose(lights)?;
        Ok(Ok(BlasWrite {
            bvh_ms: nodes_ms + tlas_ms,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - nodes_ms - tlas_ms,
            bytes,
        }))
    }
}
