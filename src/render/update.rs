//! Bringing the scene on the device to a new pose ([`Renderer::update_scene`]), and moving
//! instances of a two-level scene without rebuilding it: the moved instances' transforms and a
//! new TLAS, written over the old ones in the device buffers (no reallocation, no BLAS
//! build). The meshes' triangles and shading data stay in object space on the device, so
//! nothing else is written (a moved light also rewrites the small light table). A flat scene
//! is refitted (`render/refit.rs`); a two-level one whose meshes deformed has their BLASes refitted
//! and is loaded again over them (every buffer written again in place; no BLAS built).

use super::blas_refit::refit_blases;
use super::instancing::{Blases, instanced_objects, render_from_world};
use super::refit::NoRefit;
use super::upload::InstanceLayout;
use super::upload::piece_copies;
use super::{Accel, Renderer};
use crate::bvh::TwoLevel;
use crate::bvh::WideBvh;
use crate::cl::kernels::SceneBuffers;
use crate::cl::types::DeviceWideNode;
use crate::cl::{ClError, Device};
use crate::scene::{Light, Scene, is_sane};
use std::time::Instant;

/// What [`Renderer::move_instances`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InstanceUpdate {
    /// Instances moved.
    pub moved: usize,
    /// TLAS rebuild and upload, host time.
    pub ms: f64,
    /// Bytes written to the device.
    pub bytes: usize,
}

/// How [`Renderer::update_scene`] brought the device up to date.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum UpdateKind {
    /// Instances moved in place (two levels, no mesh changed): a new TLAS, no mesh BVH.
    Moved,
    /// A flat scene's BVH refitted over its posed triangles, what changed written in place; or
    /// a two-level scene's deformed meshes' BLASes refitted in their own spaces, the TLAS built
    /// again and the scene's buffers written again in place (no BLAS built).
    Refitted,
    /// The refit took the BVH past its cost bound ([`crate::bvh::REFIT_MAX_GROWTH`]): a flat
    /// scene was built and loaded again; on two levels, the deformed meshes' BLASes were
    /// refitted, the ones past the bound built anew, and the scene loaded again over them.
    Rebuilt,
    /// The scene was loaded again (other triangles placed).
    Reloaded,
}

/// What [`Renderer::update_scene`] did and what it took (host time, ms).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SceneUpdate {
    /// How.
    pub kind: UpdateKind,
    /// The render space found and the posed triangles flattened (a refit's).
    pub flatten_ms: f64,
    /// BVH work: the refit, the TLAS, or the whole build of a reload.
    pub bvh_ms: f64,
    /// Writing to the device (a reload's textures, lights and kernels check included).
    pub upload_ms: f64,
    /// Bytes written to the device (a reload: every scene buffer).
    pub bytes: usize,
}

impl Renderer {
    /// Brings the device up to date with `scene` (the loaded scene after an animation pose)
    /// and `lights`, in the render space a fresh load of this pose would take (so a
    /// sequence's frame is its single render), in the cheapest way that gives the same
    /// image: moved instances in place where only transforms changed and the scene is on two
    /// levels; a flat scene's BVH refitted and what changed written in place
    /// (`render/refit.rs`), built again when the refit took it past its cost bound; else the
    /// scene loaded again, the old buffers written in place where their sizes agree and the
    /// textures packed once (kernels are kept when the scene's features stay the same).
    /// Resets the film.
    pub fn update_scene(
        &mut self,
        scene: &Scene,
        lights: &[Light],
        deformed: bool,
    ) -> Result<SceneUpdate, ClError> {
        let t = Instant::now();
        let space = crate::scene::RenderFrame::around(&scene.bounds());
        // The render space of a deformed pose is found over all its triangles anew.
        let space_ms = t.elapsed().as_secs_f64() * 1e3;
        // Moving instances keeps the render space: only a space a fresh load would take too.
        if !deformed
            && space == self.space()
            && let Some(u) = self.move_instances(scene)?
        {
            self.set_lights(lights)?;
            return Ok(SceneUpdate {
                kind: UpdateKind::Moved,
                flatten_ms: 0.0,
                bvh_ms: u.ms,
                upload_ms: t.elapsed().as_secs_f64() * 1e3 - u.ms,
                bytes: u.bytes,
            });
        }
        let kind = match self.refit_flat(scene, lights)? {
            Ok(r) => {
                return Ok(SceneUpdate {
                    kind: UpdateKind::Refitted,
                    flatten_ms: space_ms + r.flatten_ms,
                    bvh_ms: r.refit_ms,
                    upload_ms: r.upload_ms,
                    bytes: r.bytes,
                });
            }
            Err(NoRefit::TooCostly) => UpdateKind::Rebuilt,
            Err(NoRefit::Changed) => UpdateKind::Reloaded,
        };
        // Quick BLASes whose SAH trees are still to come are not refitted: the load builds
        // SAH trees, which refits then keep.
        let pending = self.sah_pending();
        let fitting = Instant::now();
        let refitted = (self.scene.as_ref())
            .filter(|_| !pending)
            .and_then(|(_, host)| refit_blases(scene, host));
        let refit_ms = fitting.elapsed().as_secs_f64() * 1e3;
        // Deformed meshes of a two-level scene: what changed written in place where it can be.
        let refitted = match refitted {
            Some(r) => match self.write_refitted_blases(scene, lights, space, r)? {
                Ok(w) => {
                    return Ok(SceneUpdate {
                        kind: UpdateKind::Refitted,
                        flatten_ms: 0.0,
                        bvh_ms: refit_ms + w.bvh_ms,
                        upload_ms: w.upload_ms,
                        bytes: w.bytes,
                    });
                }
                Err(r) => Some(r),
            },
            None => None,
        };
        let (kind, how) = match refitted {
            Some(r) => {
                let kind = if r.rebuilt {
                    UpdateKind::Rebuilt
                } else {
                    UpdateKind::Refitted
                };
                (kind, Blases::Built(r.blases))
            }
            None => (kind, Blases::Sah),
        };
        let old = self.scene.take();
        let old = old.map(|(buffers, _)| buffers);
        let stats = self.load_with(scene, lights, space, how, old)?;
        let bvh_ms = refit_ms + stats.bvh_build_ms;
        Ok(SceneUpdate {
            kind,
            flatten_ms: 0.0,
            bvh_ms,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - bvh_ms,
            bytes: stats.device_bytes,
        })
    }

    /// Brings a two-level scene on the device up to date with the transforms of `scene`'s
    /// objects: the moved instances get their new transforms, the TLAS is rebuilt, and both
    /// are written over the old ones in place (the meshes stay as they are, in object space);
    /// a hidden object's instance is left out of the TLAS, a shown one taken back.
    /// With emissive triangles the (small) light table is written anew too: moved lights'
    /// areas and powers, and the instances' new TLAS slots. Returns `None`, changing nothing, when that cannot be done and the scene must
    /// be loaded again: the scene on the device is flat, an object was given other geometry,
    /// or a moved or shown object has an absurd vertex. Resets the film when anything changed.
    pub fn move_instances(&mut self, scene: &Scene) -> Result<Option<InstanceUpdate>, ClError> {
        let t = Instant::now();
        let Some((buffers, host)) = self.scene.as_mut() else {
            return Ok(None);
        };
        let Accel::TwoLevel(two) = &host.accel else {
            return Ok(None);
        };
        let objects = instanced_objects(scene);
        if objects != host.layout.objects {
            return Ok(None);
        }
        let frame = render_from_world(&host.space);
        let mut moved = vec![];
        for (i, &o) in objects.iter().enumerate() {
            let object = &scene.objects[o as usize];
            let inst = &two.instances[i];
            let blas = &two.blases[inst.blas as usize];
            if object.mesh.indices.len() != blas.len() {
                return Ok(None);
            }
            let m = frame * object.world_from_object;
            if m == inst.world_from_object && object.visible != two.hidden[i] {
                continue;
            }
            if !object.visible {
                moved.push((i, m, false));
                continue;
            }
            let world = object.world_from_object;
            if object
                .mesh
                .positions
                .iter()
                .any(|p| !is_sane(world.transform_point3(p.as_dvec3())))
            {
                return Ok(None);
            }
            moved.push((i, m, true));
        }
        if moved.is_empty() {
            return Ok(Some(InstanceUpdate::default()));
        }
        let Accel::TwoLevel(two) = &mut host.accel else {
            return Ok(None);
        };
        for &(i, m, visible) in &moved {
            two.place(i, m);
            two.hidden[i] = !visible;
        }
        two.rebuild_tlas();
        let device = &self.device;
        let mut bytes = write_tlas(buffers, device, two, &host.layout)?;
        // A moved small instance's world-space triangle copies (the TLAS's pieces).
        for &(i, _, _) in &moved {
            let base = host.layout.copy_bases[i] as usize;
            if base != u32::MAX as usize {
                let mesh = &host.layout.small_meshes[two.instances[i].blas as usize];
                let copies = piece_copies(two, mesh, i);
                bytes += buffers.triangles.write_at(device, base, &copies)?;
            }
        }
        for &(i, _, _) in &moved {
            host.replace_emitters(i as u32);
        }
        // Triangle lights name their instances' TLAS slots, which the new TLAS reorders.
        if !host.emissive.is_empty() {
            self.upload_lights()?;
        }
        let update = InstanceUpdate {
            moved: moved.len(),
            ms: t.elapsed().as_secs_f64() * 1e3,
            bytes,
        };
        self.reset()?;
        Ok(Some(update))
    }
}

/// Writes `two`'s TLAS over the device's, in each node array it has (`NodeForms`), and the
/// device instances in TLAS order (`layout`); the bytes written.
pub(super) fn write_tlas(
    buffers: &mut SceneBuffers,
    device: &Device,
    two: &TwoLevel,
    layout: &InstanceLayout,
) -> Result<usize, ClError> {
    let mut bytes = 0;
    if buffers.forms.binary {
        bytes += buffers.nodes.write_at(device, 0, &two.device_tlas())?;
    }
    if buffers.forms.wide {
        let mut wide = WideBvh::collapse(&two.tlas).nodes;
        wide.resize(two.tlas_slots(), DeviceWideNode::default());
        bytes += buffers.wide_nodes.write_at(device, 0, &wide)?;
    }
    bytes += buffers
        .instances
        .write_at(device, 0, &layout.gpu_instances(two))?;
    Ok(bytes)
}
