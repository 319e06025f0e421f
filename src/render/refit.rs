//! Posing a flat scene in place: each visible triangle flattened anew into render space, the
//! BVH refitted over them (its topology and triangle order kept) and only the device structs
//! that differ from the last pose written, with the nodes, over the old buffers. A refit that
//! made the tree too costly to traverse, or a pose that places other triangles, loads the
//! scene again ([`Renderer::update_scene`]).

use super::upload::FlatRefit;
use super::{Accel, Renderer, lights};
use crate::bvh::WideBvh;
use crate::cl::{Buffer, ClError, Device};
use crate::scene::{Light, RenderFrame, Scene};
use rayon::prelude::*;
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

/// Elements compared and written together: a run of changed chunks is one write.
const CHUNK: usize = 4096;

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
        let (arrays, flatten_ms, refit_ms) =
            match host.refit_flat(scene, space, &materials, tangents) {
                FlatRefit::Refitted(arrays, flatten_ms, refit_ms) => (arrays, flatten_ms, refit_ms),
                FlatRefit::TooCostly => return Ok(Err(NoRefit::TooCostly)),
                FlatRefit::Changed => return Ok(Err(NoRefit::Changed)),
            };
        let t = Instant::now();
        host.scale_emitter_power(&lights::emissive_texture_means(scene));
        let Accel::Flat(bvh) = &host.accel else {
            return Ok(Err(NoRefit::Changed));
        };
        let device = &self.device;
        let mut old = host.posed.take();
        let mut arrays = *arrays;
        arrays.wide = None;
        let mut bytes = 0;
        let mut wide_ms = 0.0;
        if buffers.forms.binary {
            bytes += replace(&mut buffers.nodes, device, &bvh.nodes)?;
        }
        if buffers.forms.wide {
            let fitting = Instant::now();
            let wide = match old.as_mut().and_then(|o| o.wide.take()) {
                Some(mut wide) => {
                    wide.refit(&host.vertices);
                    wide
                }
                None => WideBvh::collapse_for_cpu(bvh),
            };
            wide_ms = fitting.elapsed().as_secs_f64() * 1e3;
            bytes += replace(&mut buffers.wide_nodes, device, &wide.nodes)?;
            arrays.wide = Some(wide);
        }
        let last = old.as_ref();
        bytes += write_changed(
            &mut buffers.triangles,
            device,
            last.map(|o| &o.triangles[..]),
            &arrays.triangles,
        )?;
        bytes += write_changed(
            &mut buffers.shading,
            device,
            last.map(|o| &o.shading[..]),
            &arrays.shading,
        )?;
        if tangents {
            bytes += write_changed(
                &mut buffers.tangents,
                device,
                last.map(|o| &o.tangents[..]),
                &arrays.tangents,
            )?;
        }
        bytes += std::mem::size_of_val(host.materials.as_slice());
        buffers.materials.write(device, &host.materials)?;
        host.spare = old;
        host.posed = Some(arrays);
        self.lights = lights.to_vec();
        self.upload_lights()?;
        if let Some(c) = self.world_camera.clone() {
            self.set_camera(&c)?;
        }
        self.reset()?;
        Ok(Ok(RefitTimes {
            flatten_ms: space_ms + flatten_ms,
            refit_ms: refit_ms + wide_ms,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - wide_ms,
            bytes,
        }))
    }
}

/// Writes `data` over `buffer` (a new buffer when the length differs); the bytes written.
fn replace<T: bytemuck::Pod>(
    buffer: &mut Buffer<T>,
    device: &Device,
    data: &[T],
) -> Result<usize, ClError> {
    if buffer.len() == data.len() {
        buffer.write(device, data)?;
    } else {
        *buffer = Buffer::from_slice(device, data)?;
    }
    Ok(std::mem::size_of_val(data))
}

/// Writes the chunks of `new` that differ from `old` (the last data written) over `buffer`,
/// a run of changed chunks at a time; all of `new` without `old` or when a length differs.
/// The bytes written.
fn write_changed<T: bytemuck::Pod + Send + Sync>(
    buffer: &mut Buffer<T>,
    device: &Device,
    old: Option<&[T]>,
    new: &[T],
) -> Result<usize, ClError> {
    let Some(old) = old.filter(|o| o.len() == new.len() && buffer.len() == new.len()) else {
        return replace(buffer, device, new);
    };
    let changed: Vec<bool> = new
        .par_chunks(CHUNK)
        .zip(old.par_chunks(CHUNK))
        .map(|(a, b)| bytemuck::cast_slice::<T, u8>(a) != bytemuck::cast_slice::<T, u8>(b))
        .collect();
    let mut bytes = 0;
    let mut c = 0;
    while c < changed.len() {
        if !changed[c] {
            c += 1;
            continue;
        }
        let first = c;
        while c < changed.len() && changed[c] {
            c += 1;
        }
        let run = &new[first * CHUNK..(c * CHUNK).min(new.len())];
        buffer.write_at(device, first * CHUNK, run)?;
        bytes += std::mem::size_of_val(run);
    }
    Ok(bytes)
}
