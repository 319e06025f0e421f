//! Typed wrappers over the kernels: the only positional kernel arguments in penumbra, and with
//! the buffers (`buffer`) and the host memory policy (`host_memory`) the only `unsafe` code.
//! Each wrapper takes exactly the kernel's arguments, launches it under its stage name and
//! returns the profiling event; the test-only kernels' wrappers are in `test_program`.
#![allow(unsafe_code)]

mod denoise;
mod test_program;

use super::types::*;
use super::{Buffer, ClError, Device, KernelFeatures, Stage, build_program, call_err};
use bytemuck::Pod;
use opencl3::event::Event;
use opencl3::kernel::{ExecuteKernel, Kernel};
use std::sync::OnceLock;
use test_program::TestKernels;

pub use denoise::{
    ColorSource, ConvArgs, DenoiseKernels, FilmCount, GuideSums, PlaneCurve, TileWindow,
};

// Also named from here by the renderer, the scene loader and the benchmarks.
pub use super::host_memory::{OpeningMemory, map_file};
pub use super::scene_buffers::{EnvBuffers, NodeForms, SceneBuffers};

/// A launched kernel: its name and profiling event.
pub struct Launch {
    /// The kernel's name.
    pub stage: &'static str,
    /// The event, for profiling.
    pub event: Event,
}

impl Launch {
    /// Kernel run time in milliseconds from the profiling timestamps (waits for the event).
    pub fn millis(&self) -> f64 {
        let start = self.event.profiling_command_start().unwrap_or(0);
        let end = self.event.profiling_command_end().unwrap_or(start);
        end.saturating_sub(start) as f64 * 1e-6
    }
}

/// The built program with every production kernel.
pub struct Program {
    generate: Kernel,
    extend: Kernel,
    shade: Kernel,
    connect: Kernel,
    advance: Kernel,
    accumulate: Kernel,
    trace_closest: Kernel,
    trace_any: Kernel,
    trace_closest_wide: Kernel,
    trace_any_wide: Kernel,
    megakernel: Kernel,
    converge: Kernel,
    converge_dilate: Kernel,
    /// Work-group size of the megakernel (see `megakernel_local_size`).
    mega_local_size: usize,
    /// The test-only kernels, built on first use (never in production).
    tests: OnceLock<TestKernels>,
    local_size: usize,
    /// Features it was built with.
    pub features: KernelFeatures,
}

fn kernel(program: &opencl3::program::Program, name: &str) -> Result<Kernel, ClError> {
    Kernel::create(program, name).map_err(|e| ClError::Build(format!("{name}: {e}")))
}

/// Rounds `n` up to a multiple of `local` (and at least one group).
fn global_size(n: usize, local: usize) -> usize {
    n.max(1).div_ceil(local) * local
}

/// Band `index` of `count` over `items` work items in groups of `local`: contiguous ranges
/// of whole groups, so that rounding a band's launch up to whole groups never reaches into the
/// next band (only the last band is rounded up, past the end, where the kernels return). The
/// bands cover every item once; with more bands than groups some are empty. A band starts at
/// group ⌊index · groups / count⌋, so band k·m of count·m starts where band k of count does:
/// the rest of a sample can be split m times finer after any band.
pub fn band_items(
    items: usize,
    local: usize,
    index: usize,
    count: usize,
) -> std::ops::Range<usize> {
    let local = local.max(1);
    let groups = items.div_ceil(local);
    let count = count.max(1);
    let start = (index * groups / count * local).min(items);
    let end = ((index + 1) * groups / count * local).min(items);
    start..end
}

impl Program {
    /// Builds the kernels for `features`.
    pub fn build(device: &Device, features: KernelFeatures) -> Result<Self, ClError> {
        let program = build_program(device, features)?;
        let k = |stage: Stage| kernel(&program, stage.name());
        let max_group = device.device.max_work_group_size().unwrap_or(64).max(1);
        Ok(Self {
            generate: k(Stage::Generate)?,
            extend: k(Stage::Extend)?,
            shade: k(Stage::Shade)?,
            connect: k(Stage::Connect)?,
            advance: k(Stage::Advance)?,
            accumulate: k(Stage::Accumulate)?,
            trace_closest: kernel(&program, "trace_closest")?,
            trace_any: kernel(&program, "trace_any")?,
            trace_closest_wide: kernel(&program, "trace_closest_wide")?,
            trace_any_wide: kernel(&program, "trace_any_wide")?,
            megakernel: k(Stage::Megakernel)?,
            converge: k(Stage::Converge)?,
            converge_dilate: kernel(&program, "converge_dilate")?,
            mega_local_size: megakernel_local_size(features.lanes).min(max_group),
            tests: OnceLock::new(),
            local_size: 64.min(max_group),
            features,
        })
    }

    fn run(
        &self,
        device: &Device,
        stage: &'static str,
        kernel: &Kernel,
        n: usize,
        set: impl FnOnce(&mut ExecuteKernel),
    ) -> Result<Launch, ClError> {
        self.run_local(device, stage, kernel, 0..n, self.local_size, set)
    }

    /// Launches `kernel` over the work items `items` (a global offset when they do not start
    /// at 0; the kernels read their item with `get_global_id`, which includes it).
    fn run_local(
        &self,
        device: &Device,
        stage: &'static str,
        kernel: &Kernel,
        items: std::ops::Range<usize>,
        local_size: usize,
        set: impl FnOnce(&mut ExecuteKernel),
    ) -> Result<Launch, ClError> {
        let mut exec = ExecuteKernel::new(kernel);
        set(&mut exec);
        if items.start > 0 {
            exec.set_global_work_offset(items.start);
        }
        exec.set_global_work_size(global_size(items.len(), local_size))
            .set_local_work_size(local_size);
        // SAFETY: every wrapper below sets exactly the kernel's arguments, in order, with the
        // types the kernel declares; buffers outlive the launch because the queue is in order
        // and every reader of results waits on it.
        let event = unsafe { exec.enqueue_nd_range(&device.queue) }.map_err(call_err(stage))?;
        Ok(Launch { stage, event })
    }

    /// `generate`: camera rays for every slot of the wave; resets the queue counters.
    #[allow(clippy::too_many_arguments)]
    pub fn generate(
        &self,
        device: &Device,
        frame: &DeviceFrame,
        camera: &DeviceCamera,
        paths: &Buffer<DevicePath>,
        queue: &Buffer<u32>,
        counters: &Buffer<u32>,
        cones: &Buffer<[f32; 2]>,
        state: &Buffer<u32>,
        aov_paths: &Buffer<[f32; 4]>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(
            device,
            Stage::Generate.name(),
            &self.generate,
            slots,
            |e| unsafe {
                e.set_arg(frame)
                    .set_arg(camera)
                    .set_arg(&paths.mem())
                    .set_arg(&queue.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&cones.mem())
                    .set_arg(&state.mem())
                    .set_arg(&aov_paths.mem());
            },
        )
    }

    /// `extend`: closest hits of the queued paths' rays (alpha-tested with `HAS_ALPHA`).
    #[allow(clippy::too_many_arguments)]
    pub fn extend(
        &self,
        device: &Device,
        scene: &SceneBuffers,
        paths: &Buffer<DevicePath>,
        queue: &Buffer<u32>,
        counters: &Buffer<u32>,
        hits: &Buffer<DeviceHit>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(
            device,
            Stage::Extend.name(),
            &self.extend,
            slots,
            |e| unsafe {
                set_geometry(e, scene.nodes.mem(), scene);
                set_surfaces(e, scene);
                e.set_arg(&paths.mem())
                    .set_arg(&queue.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&hits.mem());
            },
        )
    }

    /// `shade`: emission, a light sample (queued for `connect`) and the next bounce.
    #[allow(clippy::too_many_arguments)]
    pub fn shade(
        &self,
        device: &Device,
        frame: &DeviceFrame,
        env: &EnvBuffers,
        scene: &SceneBuffers,
        paths: &Buffer<DevicePath>,
        queue_in: &Buffer<u32>,
        hits: &Buffer<DeviceHit>,
        queue_out: &Buffer<u32>,
        shadow_rays: &Buffer<DeviceShadowRay>,
        counters: &Buffer<u32>,
        cones: &Buffer<[f32; 2]>,
        aov_paths: &Buffer<[f32; 4]>,
        rays: &Buffer<u32>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(
            device,
            Stage::Shade.name(),
            &self.shade,
            slots,
            |e| unsafe {
                e.set_arg(frame)
                    .set_arg(&env.info)
                    .set_arg(&scene.triangles.mem())
                    .set_arg(&scene.instances.mem());
                set_surfaces(e, scene);
                e.set_arg(&env.texels.mem())
                    .set_arg(&env.marginal.mem())
                    .set_arg(&env.conditional.mem())
                    .set_arg(&scene.lights.mem())
                    .set_arg(&scene.light_cdf.mem())
                    .set_arg(&paths.mem())
                    .set_arg(&queue_in.mem())
                    .set_arg(&hits.mem())
                    .set_arg(&queue_out.mem())
                    .set_arg(&shadow_rays.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&cones.mem())
                    .set_arg(&aov_paths.mem())
                    .set_arg(&rays.mem());
            },
        )
    }

    /// `connect`: traces the queued shadow rays (any hit) and adds the visible contributions.
    pub fn connect(
        &self,
        device: &Device,
        scene: &SceneBuffers,
        shadow_rays: &Buffer<DeviceShadowRay>,
        counters: &Buffer<u32>,
        paths: &Buffer<DevicePath>,
        slots: usize,
    ) -> Result<Launch, ClError> {
        self.run(
            device,
            Stage::Connect.name(),
            &self.connect,
            slots,
            |e| unsafe {
                set_geometry(e, scene.nodes.mem(), scene);
                set_surfaces(e, scene);
                e.set_arg(&shadow_rays.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&paths.mem());
            },
        )
    }

    /// `advance`: counts this bounce's rays and turns the output queue into the next input.
    pub fn advance(
        &self,
        device: &Device,
        counters: &Buffer<u32>,
        stats: &Buffer<u64>,
    ) -> Result<Launch, ClError> {
        self.run(
            device,
            Stage::Advance.name(),
            &self.advance,
            1,
            |e| unsafe {
                e.set_arg(&counters.mem()).set_arg(&stats.mem());
            },
        )
    }

    /// `accumulate`: adds the wave's finished samples to the film (and with adaptive sampling
    /// to the half buffer and sample counts; with `AOVS` the slots' guide records in
    /// `aov_paths` to the AOV sums).
    pub fn accumulate(
        &self,
        device: &Device,
        frame: &DeviceFrame,
        paths: &Buffer<DevicePath>,
        aov_paths: &Buffer<[f32; 4]>,
        film: &AdaptiveFilm,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let pixels = (frame.width * frame.height) as usize;
        self.run(
            device,
            Stage::Accumulate.name(),
            &self.accumulate,
            pixels,
            |e| unsafe {
                e.set_arg(frame)
                    .set_arg(&paths.mem())
                    .set_arg(&film.sum.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&film.half.mem())
                    .set_arg(&film.state.mem())
                    .set_arg(&aov_paths.mem());
                set_aovs(e, &film.aovs);
            },
        )
    }

    /// The convergence check of adaptive sampling: `converge` (each pixel's error against
    /// `threshold`), then `converge_dilate` (converged where the 3×3 neighbourhood is under it;
    /// the active pixels counted in `COUNT_ACTIVE`).
    pub fn converge(
        &self,
        device: &Device,
        frame: &DeviceFrame,
        film: &AdaptiveFilm,
        threshold: f32,
        min_samples: u32,
        counters: &Buffer<u32>,
    ) -> Result<[Launch; 2], ClError> {
        let min_samples = min_samples as f32;
        let pixels = (frame.width * frame.height) as usize;
        let stage = Stage::Converge.name();
        let mark = self.run(device, stage, &self.converge, pixels, |e| unsafe {
            e.set_arg(frame)
                .set_arg(&film.sum.mem())
                .set_arg(&film.half.mem())
                .set_arg(&film.state.mem())
                .set_arg(&film.rays.mem())
                .set_arg(&threshold)
                .set_arg(&min_samples)
                .set_arg(&counters.mem());
        })?;
        let dilate = self.run(device, stage, &self.converge_dilate, pixels, |e| unsafe {
            e.set_arg(frame)
                .set_arg(&film.state.mem())
                .set_arg(&counters.mem());
        })?;
        Ok([mark, dilate])
    }

    /// `trace_closest`: closest hits of arbitrary rays (tests and `bench trace`).
    pub fn trace_closest(
        &self,
        device: &Device,
        bvh: &SceneBuffers,
        rays: &Buffer<DeviceRay>,
        hits: &Buffer<DeviceHit>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_closest", &self.trace_closest);
        self.trace(
            device,
            stage,
            kernel,
            bvh.nodes.mem(),
            bvh,
            rays,
            hits,
            counters,
        )
    }

    /// `trace_any`: occlusion of arbitrary rays (tests and `bench trace`).
    pub fn trace_any(
        &self,
        device: &Device,
        bvh: &SceneBuffers,
        rays: &Buffer<DeviceRay>,
        occluded: &Buffer<u32>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_any", &self.trace_any);
        self.trace(
            device,
            stage,
            kernel,
            bvh.nodes.mem(),
            bvh,
            rays,
            occluded,
            counters,
        )
    }

    /// `trace_closest_wide`: as `trace_closest`, through the 4-wide BVH.
    pub fn trace_closest_wide(
        &self,
        device: &Device,
        bvh: &SceneBuffers,
        rays: &Buffer<DeviceRay>,
        hits: &Buffer<DeviceHit>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_closest_wide", &self.trace_closest_wide);
        self.trace(
            device,
            stage,
            kernel,
            bvh.wide_nodes.mem(),
            bvh,
            rays,
            hits,
            counters,
        )
    }

    /// `trace_any_wide`: as `trace_any`, through the 4-wide BVH.
    pub fn trace_any_wide(
        &self,
        device: &Device,
        bvh: &SceneBuffers,
        rays: &Buffer<DeviceRay>,
        occluded: &Buffer<u32>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let (stage, kernel) = ("trace_any_wide", &self.trace_any_wide);
        self.trace(
            device,
            stage,
            kernel,
            bvh.wide_nodes.mem(),
            bvh,
            rays,
            occluded,
            counters,
        )
    }

    /// The four tracing kernels share their arguments: nodes (binary or wide), triangles,
    /// surfaces, rays, count, results, counters.
    #[allow(clippy::too_many_arguments)]
    fn trace<T: Pod>(
        &self,
        device: &Device,
        stage: &'static str,
        kernel: &Kernel,
        nodes: opencl3::types::cl_mem,
        bvh: &SceneBuffers,
        rays: &Buffer<DeviceRay>,
        out: &Buffer<T>,
        counters: &Buffer<u32>,
    ) -> Result<Launch, ClError> {
        let wide = nodes == bvh.wide_nodes.mem();
        let uploaded = if wide {
            bvh.forms.wide
        } else {
            bvh.forms.binary
        };
        if !uploaded {
            return Err(ClError::Device(format!(
                "{stage}: the scene was uploaded without its {} nodes (Renderer::set_node_forms)",
                if wide { "wide" } else { "binary" }
            )));
        }
        let count = rays.len() as u32;
        self.run(device, stage, kernel, rays.len(), |e| unsafe {
            set_geometry(e, nodes, bvh);
            set_surfaces(e, bvh);
            e.set_arg(&rays.mem())
                .set_arg(&count)
                .set_arg(&out.mem())
                .set_arg(&counters.mem());
        })
    }

    /// The megakernel's work items for `frame` (a pixel each, or with lanes a LANES_TILE-square
    /// of pixels: kernels/cpu/megakernel_lanes.cl) and its work-group size.
    pub fn megakernel_items(&self, frame: &DeviceFrame) -> (usize, usize) {
        let items = if self.features.lanes {
            (frame.width as usize).div_ceil(LANES_TILE)
                * (frame.height as usize).div_ceil(LANES_TILE)
        } else {
            (frame.width * frame.height) as usize
        };
        (items, self.mega_local_size)
    }

    /// `megakernel`: `frame.samples_in_wave` whole paths per pixel, from the camera to their
    /// end, added to the film, for the work items `items` (all of
    /// [`Program::megakernel_items`], or a band of them from [`band_items`]); the ray counts go
    /// to the counters that `advance` reads.
    #[allow(clippy::too_many_arguments)]
    pub fn megakernel(
        &self,
        device: &Device,
        frame: &DeviceFrame,
        camera: &DeviceCamera,
        env: &EnvBuffers,
        scene: &SceneBuffers,
        film: &AdaptiveFilm,
        counters: &Buffer<u32>,
        items: std::ops::Range<usize>,
    ) -> Result<Launch, ClError> {
        let local = self.mega_local_size;
        self.run_local(
            device,
            Stage::Megakernel.name(),
            &self.megakernel,
            items,
            local,
            |e| unsafe {
                e.set_arg(frame).set_arg(camera).set_arg(&env.info);
                set_geometry(e, scene.wide_nodes.mem(), scene);
                set_surfaces(e, scene);
                e.set_arg(&env.texels.mem())
                    .set_arg(&env.marginal.mem())
                    .set_arg(&env.conditional.mem())
                    .set_arg(&scene.lights.mem())
                    .set_arg(&scene.light_cdf.mem())
                    .set_arg(&film.sum.mem())
                    .set_arg(&counters.mem())
                    .set_arg(&film.half.mem())
                    .set_arg(&film.state.mem())
                    .set_arg(&film.rays.mem());
                set_aovs(e, &film.aovs);
            },
        )
    }
}

/// The film as the kernels that add samples take it: the sums and counts, and adaptive
/// sampling's half buffer and pixel states (kernels/shared/adaptive.h; untouched unless
/// `DeviceFrame::adaptive`).
pub struct AdaptiveFilm {
    /// Per pixel: the sum of its samples in fixed point, `.w` their count (or the hits among
    /// them): kernels/shared/film.h.
    pub sum: Buffer<[u64; 4]>,
    /// Per pixel: the sum of its even-numbered samples, `.w` their count.
    pub half: Buffer<[f32; 4]>,
    /// Per pixel: the samples it took and its convergence bits (`PIXEL_*`).
    pub state: Buffer<u32>,
    /// Per pixel: the rays its samples traced, extension and light-sample rays together.
    pub rays: Buffer<u32>,
    /// The guide buffers (written with `AOVS` only).
    pub aovs: AovBuffers,
}

/// The guide buffers for a denoiser, per pixel, row by row from the top: sums over the
/// pixel's samples (kernels/shared/aovs.h, docs/aovs.md). Built without `AOVS`, the kernels
/// never touch them and each is a one-element placeholder.
pub struct AovBuffers {
    /// `.xyz` the sum of the samples' albedos (each in [0, 1]), `.w` the samples added: the
    /// pixel's sample count, by which `.xyz` and the normals' sum are divided.
    pub albedo: Buffer<[f32; 4]>,
    /// `.xyz` the sum of the samples' world-space shading normals (unit, or 0 where a sample
    /// recorded none), `.w` 0.
    pub normal: Buffer<[f32; 4]>,
    /// `.x` the sum of the camera distances of the samples' first hits (render space), `.y`
    /// the samples whose camera ray hit.
    pub depth: Buffer<[f32; 2]>,
}

impl AovBuffers {
    /// Buffers for `pixels` pixels, cleared.
    pub fn new(device: &Device, pixels: usize) -> Result<Self, ClError> {
        let mut b = Self {
            albedo: Buffer::new(device, pixels)?,
            normal: Buffer::new(device, pixels)?,
            depth: Buffer::new(device, pixels)?,
        };
        b.clear(device)?;
        Ok(b)
    }

    /// Zeroes the sums.
    pub fn clear(&mut self, device: &Device) -> Result<(), ClError> {
        self.albedo.clear(device)?;
        self.normal.clear(device)?;
        self.depth.clear(device)
    }
}

/// Sets the three AOV sums, the last arguments of the kernels that add samples.
///
/// # Safety
/// Only for kernels whose next three parameters are exactly those.
unsafe fn set_aovs(e: &mut ExecuteKernel, aovs: &AovBuffers) {
    // SAFETY: the caller's kernel declares these three buffers next, in this order.
    unsafe {
        e.set_arg(&aovs.albedo.mem())
            .set_arg(&aovs.normal.mem())
            .set_arg(&aovs.depth.mem());
    }
}

/// The megakernel's work-group size: 64, or 1 with `lanes`. On PoCL's CPU device a work-group
/// is one task of its thread pool whose work items run one after the other (the kernel's loops
/// defeat vectorisation across work items), so the size only sets the scheduling grain. On the
/// Cornell box (M samples/s, 2-core CPU) groups of 1, 8 and 64 gave 0.108, 0.088 and 0.094,
/// within noise, and 256 gave 0.072, its few groups leaving cores idle at the end of a frame. A
/// lanes work item renders LANES_TILE² pixels, enough for a task alone.
fn megakernel_local_size(lanes: bool) -> usize {
    if lanes { 1 } else { 64 }
}

/// Sets the four geometry arguments every traversing kernel takes first: the nodes (binary or
/// wide), the shading-order triangles, the instances and the object-space triangles (the last
/// two are read with `TWO_LEVEL` only).
///
/// # Safety
/// Only for kernels whose next four parameters are exactly those.
unsafe fn set_geometry(e: &mut ExecuteKernel, nodes: opencl3::types::cl_mem, scene: &SceneBuffers) {
    // SAFETY: the caller's kernel declares these four buffers next, in this order.
    unsafe {
        e.set_arg(&nodes)
            .set_arg(&scene.triangles.mem())
            .set_arg(&scene.instances.mem())
            .set_arg(&scene.object_triangles.mem());
    }
}

/// Sets the eight surface arguments every traversing kernel takes after the triangles, in the
/// order of `SceneSurfaces` (kernels/shared/textures.h).
///
/// # Safety
/// Only for kernels whose next eight parameters are exactly those.
unsafe fn set_surfaces(e: &mut ExecuteKernel, scene: &SceneBuffers) {
    // SAFETY: the caller's kernel declares these eight buffers next, in this order.
    unsafe {
        e.set_arg(&scene.shading.mem())
            .set_arg(&scene.uvs.mem())
            .set_arg(&scene.tangents.mem())
            .set_arg(&scene.colors.mem())
            .set_arg(&scene.materials.mem())
            .set_arg(&scene.tex_refs.mem())
            .set_arg(&scene.textures.mem())
            .set_arg(&scene.texels.mem());
    }
}

#[cfg(test)]
mod tests {
    use super::band_items;

    #[test]
    fn bands_cover_every_item_once_in_whole_groups() {
        for (items, local, count) in [(1000, 64, 3), (64, 64, 5), (4095, 1, 7), (10, 64, 2)] {
            let bands: Vec<_> = (0..count)
                .map(|i| band_items(items, local, i, count))
                .collect();
            let mut next = 0;
            for b in &bands {
                assert_eq!(b.start, next, "{items} items, {count} bands: {bands:?}");
                assert!(b.start % local == 0 || b.is_empty());
                next = b.end;
            }
            assert_eq!(next, items, "{bands:?}");
        }
    }

    #[test]
    fn the_rest_of_a_sample_split_finer_still_covers_every_item_once() {
        // k bands of `count` done, the rest in bands m times finer (the viewer re-plans a
        // sample whose band ran over its budget).
        for (items, local, count, k, m) in
            [(1000, 64, 3, 1, 4), (37, 8, 5, 2, 3), (4095, 1, 7, 6, 9)]
        {
            let mut covered = vec![0u32; items];
            let done = (0..k).map(|i| band_items(items, local, i, count));
            let rest = (k * m..count * m).map(|i| band_items(items, local, i, count * m));
            for b in done.chain(rest) {
                covered[b].iter_mut().for_each(|c| *c += 1);
            }
            assert!(
                covered.iter().all(|&c| c == 1),
                "{items} items, {count} then {} bands",
                count * m
            );
        }
    }
}
