//! Moving instances of a two-level scene without rebuilding it: the moved instances' transforms
//! and a new TLAS, written over the old ones in the device buffers (no reallocation, no BLAS
//! build). Shading reads world-space triangles, so the moved instances' triangles are
//! rewritten in place too (their range of the shading buffers, nothing else).

use super::instancing::{placed_objects, render_from_world};
use super::{Accel, Renderer};
use crate::bvh::WideBvh;
use crate::cl::ClError;
use crate::cl::types::{GpuBvhNode, GpuWideNode};
use crate::scene::Scene;
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

impl Renderer {
    /// Brings a two-level scene on the device up to date with the transforms of `scene`'s
    /// objects: the moved instances get their new transforms, the TLAS is rebuilt, and both
    /// are written over the old ones in place. Returns `None`, changing nothing, when that
    /// cannot be done and the scene must be loaded again: the scene on the device is flat, an
    /// object was hidden, shown or given other geometry, or a moved object emits light (the
    /// light table holds its triangles' areas) or has an absurd vertex. Resets the film when
    /// anything moved.
    pub fn move_instances(&mut self, scene: &Scene) -> Result<Option<InstanceUpdate>, ClError> {
        let t = Instant::now();
        let Some((buffers, host)) = self.scene.as_mut() else {
            return Ok(None);
        };
        let Accel::TwoLevel(two) = &host.accel else {
            return Ok(None);
        };
        let objects = placed_objects(scene);
        if objects != host.layout.objects {
            return Ok(None);
        }
        let frame = render_from_world(&host.space);
        let mut moved = vec![];
        for (i, &o) in objects.iter().enumerate() {
            let object = &scene.objects[o as usize];
            let inst = &two.instances[i];
            let blas = &two.blases[inst.blas as usize];
            if object.mesh.indices.len() != blas.triangles.len() {
                return Ok(None);
            }
            let m = frame * object.world_from_object;
            if m == inst.world_from_object {
                continue;
            }
            let range = inst.prim_offset..inst.prim_offset + blas.triangles.len() as u32;
            if host.emissive.iter().any(|(p, _, _)| range.contains(p)) {
                return Ok(None);
            }
            let world = scene.flatten_object(o as usize, &host.space);
            if world.dropped > 0 {
                return Ok(None);
            }
            // The object's triangles in the instance's shading order (its BLAS's).
            let ordered: Vec<_> = blas
                .bvh
                .tri_indices
                .iter()
                .map(|&k| world.triangles[k as usize])
                .collect();
            moved.push((i, m, ordered));
        }
        if moved.is_empty() {
            return Ok(Some(InstanceUpdate::default()));
        }
        let Accel::TwoLevel(two) = &mut host.accel else {
            return Ok(None);
        };
        for (i, m, _) in &moved {
            two.place(*i, *m);
        }
        two.rebuild_tlas();
        let slots = two.tlas_slots();
        let mut nodes = two.tlas.nodes.clone();
        nodes.resize(slots, GpuBvhNode::default());
        let mut wide = WideBvh::collapse(&two.tlas).nodes;
        wide.resize(slots, GpuWideNode::default());
        let instances = host.layout.gpu_instances(two);
        let offsets: Vec<usize> = moved
            .iter()
            .map(|(i, _, _)| two.instances[*i].prim_offset as usize)
            .collect();
        let gpu = &self.gpu;
        buffers.nodes.write_at(gpu, 0, &nodes)?;
        buffers.wide_nodes.write_at(gpu, 0, &wide)?;
        buffers.instances.write_at(gpu, 0, &instances)?;
        let mut bytes = std::mem::size_of_val(nodes.as_slice())
            + std::mem::size_of_val(wide.as_slice())
            + std::mem::size_of_val(instances.as_slice());
        for ((_, _, ordered), at) in moved.iter().zip(offsets) {
            let r = host.rewrite(at, ordered);
            buffers
                .triangles
                .write_at(gpu, at, &host.triangles[r.clone()])?;
            buffers
                .shading
                .write_at(gpu, at, &host.shading[r.clone()])?;
            bytes += std::mem::size_of_val(&host.triangles[r.clone()])
                + std::mem::size_of_val(&host.shading[r.clone()]);
            if !host.tangents.is_empty() {
                buffers
                    .tangents
                    .write_at(gpu, at, &host.tangents[r.clone()])?;
                bytes += std::mem::size_of_val(&host.tangents[r]);
            }
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
