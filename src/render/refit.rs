//! Posing a flat scene in place: each visible triangle flattened anew into render space, the
//! BVH refitted over them (its topology and triangle order kept) and only the device structs
//! that differ from the last pose written, with the nodes, over the old buffers. A refit that
//! made the tree too costly to traverse, or a pose that places other triangles, loads the
//! scene again ([`Renderer::update_scene`]).

use super::upload::{CHUNK, FlatRefit};
use super::{Accel, Renderer, lights};
use crate::bvh::WideBvh;
use crate::cl::{Buffer, ClError, Device};
use crate::scene::{Light, RenderFrame, Scene};
use std::time::Instant;

/// What [`Renderer::refit_flat`] did, stage by stage (host time, ms).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RefitTimes {
    /// The render space found and the triangles flattened into the device's structs.
    pub flatten_ms: f64,
    /// The BVH refitted (and its 4-wide form, when the device has it).
    pub refit_ms: f64,
    /// Nodes, triangles, shading data and lights written to the device.
    pub upload_ms: f64,
    /// Bytes written to the device.
    pub bytes: usize,
}

/// Why a flat scene could not be refitted.
pub enum NoRefit {
    /// The scene is not flat, or the pose placed other triangles.
    Changed,
    /// The refit took the tree past its cost bound.
    TooCostly,
}

impl Renderer {
    /// Brings a flat scene on the device to `scene`'s new pose (the same triangles of the same
    /// objects, moved or deformed) in the render space a fresh load would take: refits the
    /// BVH and writes what changed in place (see the module). Leaves the film as
    /// [`Renderer::reset`] does.
    pub(super) fn refit_flat(
        &mut self,
        scene: &Scene,
        lights: &[Light],
    ) -> Result<Result<RefitTimes, NoRefit>, ClError> {
        let t = Instant::now();
        let Some((buffers, host)) = self.scene.as_mut() else {
            return Ok(Err(NoRefit::Changed));
        };
        if !matches!(host.accel, Accel::Flat(_)) {
            return Ok(Err(NoRefit::Changed));
        }
        let space = RenderFrame::around(&scene.bounds());
        let materials: Vec<_> = scene.materials.iter().map(|m| space.material(m)).collect();
        let space_ms = t.elapsed().as_secs_f64() * 1e3;
        let tangents = buffers.tangents.len() == buffers.triangles.len();
        let (dirty, flatten_ms, refit_ms) =
            match host.refit_flat(scene, space, &materials, tangents) {
                FlatRefit::Refitted(dirty, flatten_ms, refit_ms) => (dirty, flatten_ms, refit_ms),
                FlatRefit::TooCostly => return Ok(Err(NoRefit::TooCostly)),
                FlatRefit::Changed => return Ok(Err(NoRefit::Changed)),
            };
        let t = Instant::now();
        host.scale_emitter_power(&lights::emissive_texture_means(scene));
        let Accel::Flat(bvh) = &host.accel else {
            return Ok(Err(NoRefit::Changed));
        };
        let Some(posed) = host.posed.as_mut() else {
            return Ok(Err(NoRefit::Changed));
        };
        let device = &self.device;
        let mut bytes = 0;
        let mut wide_ms = 0.0;
        if buffers.forms.binary {
            bytes += replace(&mut buffers.nodes, device, &bvh.nodes)?;
        }
        if buffers.forms.wide {
            let fitting = Instant::now();
            let wide = match posed.wide.take() {
                Some(mut wide) => {
                    wide.refit(&host.vertices);
                    wide
                }
                None => WideBvh::collapse_for_cpu(bvh),
            };
            wide_ms = fitting.elapsed().as_secs_f64() * 1e3;
            bytes += replace(&mut buffers.wide_nodes, device, &wide.nodes)?;
            posed.wide = Some(wide);
        }
        bytes += write_changed(
            &mut buffers.triangles,
            device,
            &posed.triangles,
            &dirty.triangles,
        )?;
        bytes += write_changed(&mut buffers.shading, device, &posed.shading, &dirty.shading)?;
        if tangents {
            bytes += write_changed(
                &mut buffers.tangents,
                device,
                &posed.tangents,
                &dirty.tangents,
            )?;
        }
        bytes += buffers.materials.write(device, &host.materials)?;
        self.follow_pose(lights)?;
        Ok(Ok(RefitTimes {
            flatten_ms: space_ms + flatten_ms,
            refit_ms: refit_ms + wide_ms,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - wide_ms,
            bytes,
        }))
    }
}

impl Renderer {
    /// The last step of a pose written in place: `lights` (in the new render space) as the
    /// light table with the scene's emissive triangles, the camera placed in that space, and
    /// the film reset.
    pub(super) fn follow_pose(&mut self, lights: &[Light]) -> Result<(), ClError> {
        self.lights = lights.to_vec();
        self.upload_lights()?;
        if let Some(c) = self.world_camera.clone() {
            self.set_camera(&c)?;
        }
        self.reset()
    }
}

/// Writes `data` over `buffer` (a new buffer when the length differs); the bytes written.
fn replace<T: bytemuck::Pod>(
    buffer: &mut Buffer<T>,
    device: &Device,
    data: &[T],
) -> Result<usize, ClError> {
    if buffer.len() == data.len() {
        buffer.write(device, data)
    } else {
        *buffer = Buffer::from_slice(device, data)?;
        Ok(std::mem::size_of_val(data))
    }
}

/// Writes the chunks of `data` marked in `dirty` ([`CHUNK`] elements each) over `buffer`, a
/// run of them at a time; all of `data` when the buffer's length differs. The bytes written.
fn write_changed<T: bytemuck::Pod>(
    buffer: &mut Buffer<T>,
    device: &Device,
    data: &[T],
    dirty: &[bool],
) -> Result<usize, ClError> {
    if buffer.len() != data.len() {
        return replace(buffer, device, data);
    }
    let mut bytes = 0;
    let mut c = 0;
    while c < dirty.len() {
        if !dirty[c] {
            c += 1;
            continue;
        }
        let first = c;
        while c < dirty.len() && dirty[c] {
            c += 1;
        }
        let run = &data[first * CHUNK..(c * CHUNK).min(data.len())];
        bytes += buffer.write_at(device, first * CHUNK, run)?;
    }
    Ok(bytes)
}
