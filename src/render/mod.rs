//! The renderer: owns the OpenCL device, the scene on it and the film, and runs the wavefront
//! stages. It knows nothing of windows; the viewer and the command line drive it alike.

mod settings;
pub mod tonemap;
mod upload;

pub use settings::{RenderSettings, Strategy};
pub use upload::{HostScene, TexturePack, gpu_camera, gpu_lights};

use crate::bvh::{Bvh, Ray};
use crate::cl::kernels::{EnvBuffers, Launch, SceneBuffers};
use crate::cl::types::*;
use crate::cl::{Buffer, ClError, DeviceChoice, Gpu, KernelFeatures, Program};
use crate::scene::{AlphaMode, Camera, EnvMap, EnvSampling, Light, Scene};
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

/// Texel memory allowed for a scene's textures (less where the device's largest buffer is
/// smaller); larger sets are downscaled by halves.
pub const TEXTURE_BUDGET_BYTES: usize = 1 << 30;

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
    /// Upload time of the scene buffers (texture mip chains included).
    pub upload_ms: f64,
    /// Textures on the device (one per image and color space).
    pub textures: usize,
    /// Bytes of texels on the device (all mip levels).
    pub texture_bytes: usize,
    /// Largest texture side kept (4096 unless the budget forced less).
    pub texture_max_side: u32,
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
    /// Ray cone (width, spread angle) per slot, for texture filtering.
    cones: Buffer<[f32; 2]>,
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
    /// Features of the loaded scene (without the environment map's).
    scene_features: KernelFeatures,
    /// The lights as last given, to rebuild the light table.
    lights: Vec<Light>,
    environment: Option<(Arc<EnvMap>, EnvSampling)>,
    env: EnvBuffers,
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
        let env = EnvBuffers {
            info: GpuEnvironment::default(),
            texels: Buffer::from_slice(&gpu, &[0.0; 3])?,
            marginal: Buffer::from_slice(&gpu, &[1.0])?,
            conditional: Buffer::from_slice(&gpu, &[1.0])?,
        };
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
            scene_features: KernelFeatures::default(),
            lights: Vec::new(),
            environment: None,
            env,
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
        let mut host = HostScene::new(&world, bvh, &scene.materials);
        host.scale_emitter_power(&upload::emissive_texture_means(scene));
        let used = |f: &dyn Fn(&crate::scene::Material) -> bool| scene.materials.iter().any(f);
        self.scene_features = KernelFeatures {
            triangle_lights: !host.emissive.is_empty(),
            textures: used(&|m| m.textures.any()),
            normal_maps: used(&|m| m.textures.normal.is_some()) && !host.tangents.is_empty(),
            alpha: used(&|m| m.alpha != AlphaMode::Opaque),
            transmission: used(&|m| m.transmission > 0.0),
            env_map: false,
            thin_walls: used(&|m| m.transmission > 0.0 && m.thickness <= 0.0),
            unlit: used(&|m| m.unlit),
        };
        let budget = self
            .gpu
            .device
            .max_mem_alloc_size()
            .map_or(TEXTURE_BUDGET_BYTES, |m| {
                (m as usize).min(TEXTURE_BUDGET_BYTES)
            });
        let pack = TexturePack::new(scene, budget);
        let kernel_build_ms = self.ensure_program()?;
        self.lights = lights.to_vec();
        let (glights, cdf) = self.light_table(&host);
        let placeholder = [GpuTriTangents::default()];
        let tangents: &[GpuTriTangents] = if host.tangents.is_empty() {
            &placeholder
        } else {
            &host.tangents
        };
        let buffers = SceneBuffers {
            nodes: Buffer::from_slice(&self.gpu, &host.bvh.nodes)?,
            triangles: Buffer::from_slice(&self.gpu, &host.triangles)?,
            shading: Buffer::from_slice(&self.gpu, &host.shading)?,
            tangents: Buffer::from_slice(&self.gpu, tangents)?,
            tex_refs: Buffer::from_slice(&self.gpu, &pack.refs)?,
            textures: Buffer::from_slice(&self.gpu, &pack.textures)?,
            texels: Buffer::from_slice(&self.gpu, &pack.texels)?,
            materials: Buffer::from_slice(&self.gpu, &host.materials)?,
            lights: Buffer::from_slice(&self.gpu, &glights)?,
            light_cdf: Buffer::from_slice(&self.gpu, &cdf)?,
        };
        self.light_count = glights.len() as u32;
        self.update_env_info(&glights);
        let stats = SceneStats {
            triangles: host.triangles.len(),
            nodes: host.bvh.nodes.len(),
            sah_cost: host.bvh.sah_cost,
            bvh_build_ms,
            kernel_build_ms,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - kernel_build_ms,
            textures: pack.textures.len(),
            texture_bytes: pack.bytes(),
            texture_max_side: pack.max_side,
        };
        self.scene = Some((buffers, host));
        self.reset()?;
        Ok(stats)
    }

    /// Builds the kernels when the scene's features (with the environment's) changed; returns
    /// the build time in milliseconds (0 when the kernels were reused).
    fn ensure_program(&mut self) -> Result<f64, ClError> {
        let features = KernelFeatures {
            env_map: self.environment.is_some(),
            ..self.scene_features
        };
        if self
            .program
            .as_ref()
            .is_some_and(|p| p.features == features)
        {
            return Ok(0.0);
        }
        let t = Instant::now();
        self.program = Some(Program::build(&self.gpu, features)?);
        Ok(t.elapsed().as_secs_f64() * 1e3)
    }

    /// The light list and selection table for the current lights and environment.
    fn light_table(&self, host: &HostScene) -> (Vec<GpuLight>, Vec<f32>) {
        let env_luminance = self
            .environment
            .as_ref()
            .map(|(_, t)| t.mean_luminance * self.settings.env_intensity);
        gpu_lights(&self.lights, host, env_luminance)
    }

    /// Fills the environment constants from the settings and the light list.
    fn update_env_info(&mut self, lights: &[GpuLight]) {
        let Some((map, table)) = self.environment.as_ref() else {
            self.env.info = GpuEnvironment::default();
            return;
        };
        let light = lights
            .iter()
            .position(|l| l.position[3].to_bits() == LIGHT_ENVIRONMENT);
        let (sin, cos) = self.settings.env_rotation.to_radians().sin_cos();
        self.env.info = GpuEnvironment {
            scale: [
                self.settings.env_intensity,
                table.norm,
                light.map_or(0.0, |i| lights[i].extra[1]),
                0.0,
            ],
            rotation: [cos, sin, 0.0, 0.0],
            width: map.width,
            height: map.height,
            light: light.map_or(u32::MAX, |i| i as u32),
            pad: 0,
        };
    }

    /// Rebuilds the light table on the device (after lights, environment or its intensity
    /// changed).
    fn upload_lights(&mut self) -> Result<(), ClError> {
        let Some((_, host)) = self.scene.as_ref() else {
            return Ok(());
        };
        let (glights, cdf) = self.light_table(host);
        let Some((buffers, _)) = self.scene.as_mut() else {
            return Ok(());
        };
        buffers.lights = Buffer::from_slice(&self.gpu, &glights)?;
        buffers.light_cdf = Buffer::from_slice(&self.gpu, &cdf)?;
        self.light_count = glights.len() as u32;
        self.update_env_info(&glights);
        Ok(())
    }

    /// Sets (or with `None` removes) the environment map: it lights the scene with importance
    /// sampling and MIS, and replaces the uniform sky. Rebuilds the kernels when the map appears
    /// or goes. Resets the film.
    pub fn set_environment(&mut self, map: Option<EnvMap>) -> Result<(), ClError> {
        match map {
            Some(map) => {
                let table = map.sampling();
                let texels: Vec<f32> = map.texels.iter().flatten().copied().collect();
                self.env.texels = Buffer::from_slice(&self.gpu, &texels)?;
                self.env.marginal = Buffer::from_slice(&self.gpu, &table.marginal)?;
                self.env.conditional = Buffer::from_slice(&self.gpu, &table.conditional)?;
                self.environment = Some((Arc::new(map), table));
            }
            None => self.environment = None,
        }
        if self.scene.is_some() {
            self.ensure_program()?;
        }
        self.upload_lights()?;
        self.reset()
    }

    /// The environment map on the device, for tests.
    pub fn env_buffers(&self) -> &EnvBuffers {
        &self.env
    }

    /// The environment map, if one is set.
    pub fn environment(&self) -> Option<&EnvMap> {
        self.environment.as_ref().map(|(m, _)| m.as_ref())
    }

    /// Sets the thin lens: `lens_radius` in scene units (0: pinhole) and the distance of the
    /// plane in focus along the view axis. Resets the film.
    pub fn set_lens(&mut self, lens_radius: f32, focus_distance: f32) -> Result<(), ClError> {
        self.settings.lens_radius = lens_radius.max(0.0);
        self.settings.focus_distance = focus_distance.max(1e-6);
        self.apply_lens();
        self.reset()
    }

    fn apply_lens(&mut self) {
        self.camera.origin[3] = self.settings.lens_radius;
        self.camera.forward[3] = self.settings.focus_distance;
    }

    /// The distance along the view axis to the surface seen through pixel (x, y) (pixel
    /// coordinates, fractional allowed) of the current camera, from the host BVH; `None`
    /// where the pixel sees nothing. For click-to-focus: pass it to [`Renderer::set_lens`].
    pub fn focus_distance_at(&self, x: f32, y: f32) -> Option<f32> {
        let (_, host) = self.scene.as_ref()?;
        let c = &self.camera;
        let fx = x / self.settings.width.max(1) as f32;
        let fy = y / self.settings.height.max(1) as f32;
        let v = |a: [f32; 4]| glam::Vec3::new(a[0], a[1], a[2]);
        let forward = v(c.forward);
        let dir = forward + (2.0 * fx - 1.0) * v(c.right) + (1.0 - 2.0 * fy) * v(c.up);
        let unit = dir.normalize();
        let ray = Ray {
            origin: v(c.origin),
            direction: unit,
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        let hit = host.bvh.intersect(&ray, &host.vertices)?;
        Some(hit.t * unit.dot(forward.normalize()))
    }

    /// Replaces the lights without touching the BVH. Resets the film.
    pub fn set_lights(&mut self, lights: &[Light]) -> Result<(), ClError> {
        if self.scene.is_none() {
            return Ok(());
        }
        self.lights = lights.to_vec();
        self.upload_lights()?;
        self.reset()
    }

    /// Sets the camera. Resets the film.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<(), ClError> {
        self.camera = gpu_camera(camera, self.settings.aspect());
        self.apply_lens();
        self.reset()
    }

    /// Applies settings, resizing buffers as needed. Resets the film.
    pub fn set_settings(&mut self, settings: &RenderSettings) -> Result<(), ClError> {
        let aspect_changed = settings.aspect() != self.settings.aspect();
        let env_changed = settings.env_intensity != self.settings.env_intensity
            || settings.env_rotation != self.settings.env_rotation;
        self.settings = settings.clone();
        self.apply_lens();
        if env_changed && self.environment.is_some() {
            self.upload_lights()?;
        }
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
            cones: Buffer::new(gpu, slots)?,
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
                &f.cones,
                slots,
            )?);
            for bounce in 0..=self.settings.bounces + 1 {
                frame.bounce = bounce;
                let (qi, qo) = if bounce % 2 == 0 { (0, 1) } else { (1, 0) };
                launches.push(program.extend(
                    gpu,
                    scene,
                    &f.paths,
                    &f.queues[qi],
                    &self.counters,
                    &f.hits,
                    slots,
                )?);
                launches.push(program.shade(
                    gpu,
                    &frame,
                    &self.env,
                    scene,
                    &f.paths,
                    &f.queues[qi],
                    &f.hits,
                    &f.queues[qo],
                    &f.shadow_rays,
                    &self.counters,
                    &f.cones,
                    slots,
                )?);
                launches.push(program.connect(
                    gpu,
                    scene,
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
