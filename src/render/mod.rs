//! The renderer: owns the OpenCL device, the scene on it and the film, and runs the wavefront
//! stages. It knows nothing of windows; the viewer and the command line drive it alike.

mod settings;
pub mod tonemap;
mod upload;

pub use settings::{RenderSettings, Strategy};
pub use upload::{HostScene, gpu_camera, gpu_lights};

use crate::bvh::Bvh;
use crate::cl::kernels::{Launch, SceneBuffers};
use crate::cl::types::*;
use crate::cl::{Buffer, ClError, DeviceChoice, Gpu, KernelFeatures, Program};
use crate::scene::{Camera, Light, Scene};
use std::collections::BTreeMap;
use std::time::Instant;

/// Paths in flight per wave on a GPU, and on other devices.
const WAVE_PATHS_GPU: usize = 1 << 21;
const WAVE_PATHS_CPU: usize = 1 << 16;

/// Figures from preparing a scene.
#[derive(Clone, Debug, Default)]
pub struct SceneStats {
    /// Triangles in the BVH.
    pub triangles: usize,
    /// BVH nodes.
    pub nodes: usize,
    /// SAH cost of the BVH.
    pub sah_cost: f32,
    /// Host BVH build time.
    pub bvh_build_ms: f64,
    /// Kernel build time (0 when the kernels were reused).
    pub kernel_build_ms: f64,
    /// Upload time of the scene buffers.
    pub upload_ms: f64,
}

/// Counters of the work done since the last reset.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Extension (closest-hit) rays traced.
    pub extension_rays: u64,
    /// Shadow (any-hit) rays traced.
    pub shadow_rays: u64,
    /// Samples dropped because they were NaN or infinite.
    pub nonfinite_samples: u64,
    /// Traversal stack overflows (must stay 0).
    pub stack_overflows: u64,
    /// Kernel time per stage in milliseconds, from profiling events.
    pub stage_ms: BTreeMap<&'static str, f64>,
}

impl RenderStats {
    /// Sum of all stages' kernel time.
    pub fn kernel_ms(&self) -> f64 {
        self.stage_ms.values().sum()
    }
}

/// Per-resolution device buffers.
struct Frame {
    width: u32,
    height: u32,
    slots: usize,
    film: Buffer<[f32; 4]>,
    paths: Buffer<GpuPath>,
    queues: [Buffer<u32>; 2],
    hits: Buffer<GpuHit>,
    shadow_rays: Buffer<GpuShadowRay>,
}

/// The path tracer on one OpenCL device.
pub struct Renderer {
    /// The device, context and queue.
    pub gpu: Gpu,
    program: Option<Program>,
    scene: Option<(SceneBuffers, HostScene)>,
    frame: Option<Frame>,
    counters: Buffer<u32>,
    stats_buffer: Buffer<u64>,
    settings: RenderSettings,
    camera: GpuCamera,
    light_count: u32,
    samples: u32,
    stats: RenderStats,
    pending: Vec<Launch>,
}

impl Renderer {
    /// Opens the device.
    pub fn new(choice: &DeviceChoice) -> Result<Self, ClError> {
        let gpu = Gpu::open(choice)?;
        let counters = Buffer::new(&gpu, 8)?;
        let stats_buffer = Buffer::new(&gpu, 4)?;
        let mut r = Self {
            gpu,
            program: None,
            scene: None,
            frame: None,
            counters,
            stats_buffer,
            settings: RenderSettings::default(),
            camera: GpuCamera::default(),
            light_count: 0,
            samples: 0,
            stats: RenderStats::default(),
            pending: Vec::new(),
        };
        r.reset()?;
        Ok(r)
    }

    /// Builds the BVH of the scene's visible objects, uploads the scene and its lights, and
    /// (re)builds the kernels when the scene's features changed. Resets the film.
    pub fn load_scene(&mut self, scene: &Scene, lights: &[Light]) -> Result<SceneStats, ClError> {
        let t = Instant::now();
        let world = scene.world_triangles();
        let verts: Vec<[glam::Vec3; 3]> = world.iter().map(|t| t.v).collect();
        let bvh = crate::bvh::build(&verts);
        let bvh_build_ms = t.elapsed().as_secs_f64() * 1e3;

        let t = Instant::now();
        let host = HostScene::new(&world, bvh, &scene.materials);
        let features = KernelFeatures {
            triangle_lights: !host.emissive.is_empty(),
        };
        let mut kernel_build_ms = 0.0;
        if self.program.as_ref().is_none_or(|p| p.features != features) {
            let tk = Instant::now();
            self.program = Some(Program::build(&self.gpu, features)?);
            kernel_build_ms = tk.elapsed().as_secs_f64() * 1e3;
        }
        let (glights, cdf) = gpu_lights(lights, &host, scene.bounds().diagonal());
        let buffers = SceneBuffers {
            nodes: Buffer::from_slice(&self.gpu, &host.bvh.nodes)?,
            triangles: Buffer::from_slice(&self.gpu, &host.triangles)?,
            shading: Buffer::from_slice(&self.gpu, &host.shading)?,
            materials: Buffer::from_slice(&self.gpu, &host.materials)?,
            lights: Buffer::from_slice(&self.gpu, &glights)?,
            light_cdf: Buffer::from_slice(&self.gpu, &cdf)?,
        };
        self.light_count = glights.len() as u32;
        let stats = SceneStats {
            triangles: host.triangles.len(),
            nodes: host.bvh.nodes.len(),
            sah_cost: host.bvh.sah_cost,
            bvh_build_ms,
            kernel_build_ms,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - kernel_build_ms,
        };
        self.scene = Some((buffers, host));
        self.reset()?;
        Ok(stats)
    }

    /// Replaces the lights without touching the BVH. Resets the film.
    pub fn set_lights(&mut self, lights: &[Light], scene_diagonal: f64) -> Result<(), ClError> {
        let Some((buffers, host)) = self.scene.as_mut() else {
            return Ok(());
        };
        let (glights, cdf) = gpu_lights(lights, host, scene_diagonal);
        buffers.lights = Buffer::from_slice(&self.gpu, &glights)?;
        buffers.light_cdf = Buffer::from_slice(&self.gpu, &cdf)?;
        self.light_count = glights.len() as u32;
        self.reset()
    }

    /// Sets the camera. Resets the film.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<(), ClError> {
        self.camera = gpu_camera(camera, self.settings.aspect());
        self.reset()
    }

    /// Applies settings, resizing buffers as needed. Resets the film.
    pub fn set_settings(&mut self, settings: &RenderSettings) -> Result<(), ClError> {
        let aspect_changed = settings.aspect() != self.settings.aspect();
        self.settings = settings.clone();
        if aspect_changed {
            let aspect = settings.aspect();
            let up_len = self.camera.up[0]
                .hypot(self.camera.up[1])
                .hypot(self.camera.up[2]);
            let right_len = self.camera.right[0]
                .hypot(self.camera.right[1])
                .hypot(self.camera.right[2]);
            if right_len > 0.0 {
                let s = up_len * aspect / right_len;
                for i in 0..3 {
                    self.camera.right[i] *= s;
                }
            }
        }
        self.reset()
    }

    /// The current settings.
    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    /// Clears the film and the counters.
    pub fn reset(&mut self) -> Result<(), ClError> {
        if !self.pending.is_empty() {
            self.finish()?;
        }
        self.samples = 0;
        self.stats = RenderStats::default();
        self.counters.clear(&self.gpu)?;
        self.stats_buffer.clear(&self.gpu)?;
        if let Some(f) = self.frame.as_mut() {
            f.film.clear(&self.gpu)?;
        }
        Ok(())
    }

    /// Samples per pixel in the film.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Work counters and stage times since the last reset.
    pub fn stats(&self) -> &RenderStats {
        &self.stats
    }

    /// The host copy of the scene (BVH and triangles in BVH order) for picking.
    pub fn host_scene(&self) -> Option<&HostScene> {
        self.scene.as_ref().map(|(_, h)| h)
    }

    /// The built kernels, for tests and benchmarks.
    pub fn program(&self) -> Option<&Program> {
        self.program.as_ref()
    }

    /// The scene on the device, for tests and benchmarks.
    pub fn scene_buffers(&self) -> Option<&SceneBuffers> {
        self.scene.as_ref().map(|(b, _)| b)
    }

    /// The BVH on the host.
    pub fn bvh(&self) -> Option<&Bvh> {
        self.scene.as_ref().map(|(_, h)| &h.bvh)
    }

    fn ensure_frame(&mut self) -> Result<(), ClError> {
        let (w, h) = (self.settings.width, self.settings.height);
        let pixels = (w * h) as usize;
        let wave = if self.gpu.info.is_gpu {
            WAVE_PATHS_GPU
        } else {
            WAVE_PATHS_CPU
        };
        let slots = pixels * (wave / pixels).max(1);
        if self
            .frame
            .as_ref()
            .is_some_and(|f| f.width == w && f.height == h && f.slots == slots)
        {
            return Ok(());
        }
        self.frame = None; // free the old buffers first
        let gpu = &self.gpu;
        let mut film = Buffer::new(gpu, pixels)?;
        film.clear(gpu)?;
        self.frame = Some(Frame {
            width: w,
            height: h,
            slots,
            film,
            paths: Buffer::new(gpu, slots)?,
            queues: [Buffer::new(gpu, slots)?, Buffer::new(gpu, slots)?],
            hits: Buffer::new(gpu, slots)?,
            shadow_rays: Buffer::new(gpu, slots)?,
        });
        self.samples = 0;
        Ok(())
    }

    /// Renders `spp` more samples per pixel into the film and waits for them.
    pub fn render(&mut self, spp: u32) -> Result<(), ClError> {
        self.start(spp)?;
        self.finish()
    }

    /// Enqueues `spp` more samples per pixel and returns at once, so the host can do other
    /// work (display the last frame) while the device renders; [`Renderer::finish`] waits.
    pub fn start(&mut self, spp: u32) -> Result<(), ClError> {
        let launches = self.enqueue(spp)?;
        self.pending.extend(launches);
        self.gpu
            .queue
            .flush()
            .map_err(crate::cl::call_err("submitting the frame"))
    }

    /// Whether the work [`Renderer::start`] enqueued is done (true when nothing is pending).
    /// Never waits, so a viewer can keep drawing while the device works; the queue is in
    /// order, so the last launch finishing means all have.
    pub fn is_finished(&self) -> Result<bool, ClError> {
        let Some(last) = self.pending.last() else {
            return Ok(true);
        };
        let status = last
            .event
            .command_execution_status()
            .map_err(crate::cl::call_err("polling the frame"))?;
        // CL_COMPLETE is 0; negative values are errors, which `finish` reports.
        Ok(status.0 <= 0)
    }

    /// Waits for the work [`Renderer::start`] enqueued and gathers its statistics.
    pub fn finish(&mut self) -> Result<(), ClError> {
        self.gpu
            .queue
            .finish()
            .map_err(crate::cl::call_err("waiting for the frame"))?;
        let launches = std::mem::take(&mut self.pending);
        self.collect(launches)
    }

    /// Enqueues the stages for `spp` more samples without waiting.
    fn enqueue(&mut self, spp: u32) -> Result<Vec<Launch>, ClError> {
        self.ensure_frame()?;
        let (Some(program), Some((scene, _)), Some(f)) = (
            self.program.as_ref(),
            self.scene.as_ref(),
            self.frame.as_mut(),
        ) else {
            return Err(ClError::Device("no scene is loaded".into()));
        };
        let gpu = &self.gpu;
        let pixels = (f.width * f.height) as usize;
        let per_wave = (f.slots / pixels).max(1) as u32;
        let mut launches = Vec::new();
        let mut done = 0;
        while done < spp {
            let n = per_wave.min(spp - done);
            let slots = pixels * n as usize;
            let mut frame = self.settings.gpu_frame(self.light_count);
            frame.samples_in_wave = n;
            frame.first_sample = self.samples + done;
            launches.push(program.generate(
                gpu,
                &frame,
                &self.camera,
                &f.paths,
                &f.queues[0],
                &self.counters,
                slots,
            )?);
            for bounce in 0..=self.settings.bounces + 1 {
                frame.bounce = bounce;
                let (qi, qo) = if bounce % 2 == 0 { (0, 1) } else { (1, 0) };
                launches.push(program.extend(
                    gpu,
                    &scene.nodes,
                    &scene.triangles,
                    &f.paths,
                    &f.queues[qi],
                    &self.counters,
                    &f.hits,
                    slots,
                )?);
                launches.push(program.shade(
                    gpu,
                    &frame,
                    scene,
                    &f.paths,
                    &f.queues[qi],
                    &f.hits,
                    &f.queues[qo],
                    &f.shadow_rays,
                    &self.counters,
                    slots,
                )?);
                launches.push(program.connect(
                    gpu,
                    &scene.nodes,
                    &scene.triangles,
                    &f.shadow_rays,
                    &self.counters,
                    &f.paths,
                    slots,
                )?);
                launches.push(program.advance(gpu, &self.counters, &self.stats_buffer)?);
            }
            launches.push(program.accumulate(gpu, &frame, &f.paths, &f.film, &self.counters)?);
            done += n;
        }
        self.samples += spp;
        Ok(launches)
    }

    /// Reads counters and profiling times after the queue has finished.
    fn collect(&mut self, launches: Vec<Launch>) -> Result<(), ClError> {
        for l in &launches {
            *self.stats.stage_ms.entry(l.stage).or_default() += l.millis();
        }
        let counters = self.counters.read(&self.gpu)?;
        let stats = self.stats_buffer.read(&self.gpu)?;
        self.stats.extension_rays = stats[0];
        self.stats.shadow_rays = stats[1];
        self.stats.nonfinite_samples = counters[3] as u64;
        self.stats.stack_overflows = counters[4] as u64;
        Ok(())
    }

    /// The film as linear RGB (the mean of the samples), row by row from the top.
    pub fn image(&mut self) -> Result<Vec<[f32; 3]>, ClError> {
        if !self.pending.is_empty() {
            self.finish()?;
        }
        let Some(f) = self.frame.as_ref() else {
            let n = (self.settings.width * self.settings.height) as usize;
            return Ok(vec![[0.0; 3]; n]);
        };
        let film = f.film.read(&self.gpu)?;
        Ok(film
            .iter()
            .map(|p| {
                let n = p[3].max(1.0);
                [p[0] / n, p[1] / n, p[2] / n]
            })
            .collect())
    }
}
