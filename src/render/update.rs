//! Moving instances of a two-level scene without rebuilding it: the moved instances' transforms
//! and a new TLAS, written over the old ones in the device buffers (no reallocation, no BLAS
//! build). The meshes' triangles and shading data stay in object space on the device, so
//! nothing else is written (a moved light also rewrites the small light table). A scene whose
//! meshes deformed, or a flat one, is loaded again ([`Renderer::update_scene`]).

use super::instancing::{instanced_objects, render_from_world};
use super::upload::piece_copies;
use super::{Accel, Renderer};
use crate::bvh::WideBvh;
use crate::cl::ClError;
use crate::cl::types::DeviceWideNode;
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
pub enum SceneUpdate {
    /// Instances moved in place (two levels, no mesh changed).
    Moved,
    /// The scene was loaded again (deformed meshes, or a flat BVH).
    Reloaded,
}

impl Renderer {
    /// Brings the device up to date with `scene` (the loaded scene after an animation pose)
    /// and `lights`: moved instances in place where only transforms changed and the scene is
    /// on two levels, else the scene loaded again in a render space around its new bounds (as
    /// a fresh load of this pose would be, so a sequence's frame is its single render), the old
    /// buffers written in place where their sizes agree and the textures packed once
    /// (kernels are kept when the scene's features stay the same). Resets the film.
    pub fn update_scene(
        &mut self,
        scene: &Scene,
        lights: &[Light],
        deformed: bool,
    ) -> Result<SceneUpdate, ClError> {
        if !deformed && self.move_instances(scene)?.is_some() {
            self.set_lights(lights)?;
            return Ok(SceneUpdate::Moved);
        }
        let space = crate::scene::RenderFrame::around(&scene.bounds());
        let old = self.scene.take().map(|(buffers, _)| buffers);
        self.load_with(scene, lights, space, super::instancing::Blases::Sah, old)?;
        Ok(SceneUpdate::Reloaded)
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
        let slots = two.tlas_slots();
        let instances = host.layout.gpu_instances(two);
        let device = &self.device;
        let mut bytes = std::mem::size_of_val(instances.as_slice());
        // The TLAS in each node array the device has (`NodeForms`).
        if buffers.forms.binary {
            let nodes = two.device_tlas();
            buffers.nodes.write_at(device, 0, &nodes)?;
            bytes += std::mem::size_of_val(nodes.as_slice());
        }
        if buffers.forms.wide {
            let mut wide = WideBvh::collapse(&two.tlas).nodes;
            wide.resize(slots, DeviceWideNode::default());
            buffers.wide_nodes.write_at(device, 0, &wide)?;
            bytes += std::mem::size_of_val(wide.as_slice());
        }
        buffers.instances.write_at(device, 0, &instances)?;
        // A moved small instance's world-space triangle copies (the TLAS's pieces).
        for &(i, _, _) in &moved {
            let base = host.layout.copy_bases[i] as usize;
            if base != u32::MAX as usize {
                let mesh = &host.layout.small_meshes[two.instances[i].blas as usize];
                let copies = piece_copies(two, mesh, i);
                buffers.triangles.write_at(device, base, &copies)?;
                bytes += std::mem::size_of_val(copies.as_slice());
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
