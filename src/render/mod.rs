//! The renderer: owns the OpenCL device, the scene on it and the film, and runs the wavefront
//! stages. It knows nothing of windows; the viewer and the command line drive it alike.

mod adaptive;
pub mod background;
mod blas_refit;
pub mod camera;
pub mod exposure;
pub mod film;
pub mod instancing;
mod lights;
mod load;
mod megakernel;
pub mod multi_device;
mod nodes;
mod readback;
mod refit;
mod sah;
mod settings;
pub mod strategy;
mod textures;
pub mod tonemap;
mod update;
mod upload;
mod wavefront;

pub use adaptive::{AdaptiveStats, min_samples};
pub use instancing::BvhChoice;
pub use lights::gpu_lights;
pub use megakernel::{Band, KernelChoice};
pub use readback::Aovs;
pub use settings::{AdaptiveRule, RenderSettings, Strategy};
pub use textures::TexturePack;
pub use update::{InstanceUpdate, SceneUpdate, UpdateKind};
pub use upload::{Accel, HostScene, gpu_camera, gpu_material, samples_textures};
pub use wavefront::{RenderStats, Stage, StageTimes};

use crate::bvh::Ray;
pub use crate::cl::kernels::NodeForms;
use crate::cl::kernels::{EnvBuffers, Launch, SceneBuffers};
use crate::cl::types::*;
use crate::cl::{Buffer, ClError, Device, DeviceChoice, KernelFeatures, Program};
use crate::scene::{Camera, EnvMap, EnvSampling, Light, RenderFrame, Scene};
use sah::SahBuild;
use std::sync::Arc;
use std::time::Instant;
use strategy::{DeviceFacts, Overrides, SceneFacts};
use wavefront::Frame;

/// Texel memory allowed for a scene's textures (less where the device's largest buffer is
/// smaller); larger sets are downscaled by halves.
pub const TEXTURE_BUDGET_BYTES: usize = 1 << 30;

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
    /// Kernel build time (with the megakernel's first launch, which makes PoCL compile it).
    pub kernel_build_ms: f64,
    /// Whether kernels were built for this scene (false when the last scene's were reused).
    pub kernels_built: bool,
    /// Upload time of the scene buffers (texture mip chains included).
    pub upload_ms: f64,
    /// Textures on the device (one per image and color space).
    pub textures: usize,
    /// Bytes of texels on the device (all mip levels).
    pub texture_bytes: usize,
    /// Largest texture side kept (4096 unless the budget forced less).
    pub texture_max_side: u32,
    /// Triangles left out for a non-finite or absurd vertex.
    pub dropped_triangles: usize,
    /// The acceleration structure: "flat" or "two-level".
    pub bvh: &'static str,
    /// Distinct meshes with a BLAS (two levels; 1 when flat).
    pub meshes: usize,
    /// Instances in the TLAS (two levels; 0 when flat).
    pub instances: usize,
    /// Bytes of every scene buffer on the device (textures included).
    pub device_bytes: usize,
    /// Bytes written to the device by the last load (all of `device_bytes`) or scene update
    /// ([`SceneUpdate::bytes`]).
    pub written_bytes: usize,
}

/// The path tracer on one OpenCL device.
pub struct Renderer {
    /// The device, context and queue.
    pub device: Device,
    program: Option<Program>,
    scene: Option<(SceneBuffers, HostScene)>,
    frame: Option<Frame>,
    counters: Buffer<u32>,
    stats_buffer: Buffer<u64>,
    settings: RenderSettings,
    /// The world camera as last given (the device's is in render space).
    world_camera: Option<Camera>,
    camera: DeviceCamera,
    light_count: u32,
    /// What the kernel strategy knows of the device.
    device_facts: DeviceFacts,
    /// The environment's overrides of the kernel strategy.
    overrides: Overrides,
    /// What the kernel strategy knows of the loaded scene (its features without the
    /// environment map's).
    facts: SceneFacts,
    /// The lights as last given, to rebuild the light table.
    lights: Vec<Light>,
    environment: Option<(Arc<EnvMap>, EnvSampling)>,
    env: EnvBuffers,
    samples: u32,
    stats: RenderStats,
    pending: Vec<(Stage, Launch)>,
    /// Whether frames run as the megakernel (else the wavefront): [`KernelChoice`] resolved by
    /// [`strategy::runs_megakernel`].
    megakernel: bool,
    /// The acceleration structure the next scene load builds.
    bvh_choice: BvhChoice,
    /// A kernel build says so on stderr ([`Renderer::announce_builds`]).
    announce_builds: bool,
    /// Overrides the device's small-mesh rule (see [`Renderer::set_small_mesh`]).
    small_mesh: Option<usize>,
    /// Distinct triangles from which a two-level scene is loaded with quick BLASes first (see
    /// [`Renderer::set_quick_first`]).
    quick_first: Option<usize>,
    /// The SAH BLASes building behind the quick ones of the scene on the device.
    sah: Option<SahBuild>,
    /// The meshes whose SAH BLASes start building once the quick scene's first samples are
    /// in (see [`Renderer::swap_in_sah`]).
    sah_waiting: Option<Vec<Arc<crate::scene::Mesh>>>,
    /// An animated scene's packed textures with a fingerprint of what they were packed from
    /// (see `Renderer::texture_pack`).
    texture_cache: Option<(u64, Arc<TexturePack>)>,
    /// Node arrays uploaded beyond those the kernels in use traverse (see
    /// [`Renderer::set_node_forms`]).
    extra_forms: NodeForms,
    /// The index in the random sequence of the next sample `render` takes: 0 after a reset,
    /// advanced by every sample rendered ([`Renderer::set_next_sample`]).
    next_sample: u32,
    /// Whether resets keep the film ([`Renderer::hold_film`]).
    film_held: bool,
    /// The film as last read back (sums and counts), kept for the next read.
    readback: Vec<film::FilmPixel>,
    /// Adaptive sampling's pixel states as last read back (`PIXEL_*` bits).
    state_readback: Vec<u32>,
    /// Whether a convergence check ran since the last reset.
    adaptive_checked: bool,
    /// Pixels the last convergence check left active (`None` before the first).
    active_pixels: Option<u32>,
    /// A check was enqueued whose count `active_pixels` does not hold yet.
    active_stale: bool,
}

impl Renderer {
    /// Opens the device.
    pub fn new(choice: &DeviceChoice) -> Result<Self, ClError> {
        let device = Device::open(choice)?;
        let device_facts = DeviceFacts::of(device.is_cpu());
        let counters = Buffer::new(&device, COUNTER_SLOTS)?;
        let stats_buffer = Buffer::new(&device, STAT_SLOTS)?;
        let env = EnvBuffers {
            info: DeviceEnvironment::default(),
            texels: Buffer::from_slice(&device, &[0.0; 3])?,
            marginal: Buffer::from_slice(&device, &[1.0])?,
            conditional: Buffer::from_slice(&device, &[1.0])?,
        };
        let mut r = Self {
            device,
            program: None,
            scene: None,
            frame: None,
            counters,
            stats_buffer,
            settings: RenderSettings::default(),
            world_camera: None,
            camera: DeviceCamera::default(),
            light_count: 0,
            device_facts,
            overrides: Overrides::from_env(),
            facts: SceneFacts::default(),
            lights: Vec::new(),
            environment: None,
            env,
            samples: 0,
            stats: RenderStats::default(),
            pending: Vec::new(),
            megakernel: false,
            bvh_choice: BvhChoice::Auto,
            announce_builds: true,
            small_mesh: None,
            quick_first: None,
            sah: None,
            sah_waiting: None,
            texture_cache: None,
            extra_forms: NodeForms::NONE,
            next_sample: 0,
            film_held: false,
            readback: Vec::new(),
            state_readback: Vec::new(),
            adaptive_checked: false,
            active_pixels: None,
            active_stale: false,
        };
        r.set_kernel(KernelChoice::Auto)?;
        Ok(r)
    }

    /// Builds the BVH of the scene's visible objects, uploads the scene and its lights, and
    /// (re)builds the kernels when the scene's features changed. The scene goes to the device
    /// in a render space around its robust middle ([`RenderFrame::around`]). Resets the film.
    pub fn load_scene(&mut self, scene: &Scene, lights: &[Light]) -> Result<SceneStats, ClError> {
        let bounds = scene.bounds();
        self.load_scene_in(scene, lights, RenderFrame::around(&bounds))
    }

    /// [`Renderer::load_scene`] in the render space `space`; the camera, lens and lights
    /// follow it.
    pub fn load_scene_in(
        &mut self,
        scene: &Scene,
        lights: &[Light],
        space: RenderFrame,
    ) -> Result<SceneStats, ClError> {
        // The first-view probe's quick BLASes, when it left them: taken either way, so that
        // they are not kept beside the scene's own.
        let ready = scene.take_quick_blases();
        let how = match self.quick_first {
            Some(from) => instancing::Blases::Quick { from, ready },
            None => instancing::Blases::Sah,
        };
        self.load_with(scene, lights, space, how, None)
    }

    /// Whether loading `scene` would build kernels (its features differ from the built ones'),
    /// predicted from its materials before the upload, with the loaded scene's size and
    /// structure: for a "Compiling kernels…" notice.
    pub fn would_build_for(&self, scene: &Scene) -> bool {
        let any = |f: &dyn Fn(&crate::scene::Material) -> bool| scene.materials.iter().any(f);
        let facts = SceneFacts {
            features: KernelFeatures {
                two_level: self.facts.features.two_level,
                triangle_pieces: self.facts.features.triangle_pieces,
                ..load::scene_features(scene, any(&|m| m.is_emissive()), true)
            },
            ..self.facts
        };
        self.program
            .as_ref()
            .is_none_or(|p| p.features != self.features_for(&facts))
    }

    /// Whether setting (`on`) or removing the environment map would build kernels.
    pub fn would_build_for_env(&self, on: bool) -> bool {
        self.scene.is_some()
            && self
                .program
                .as_ref()
                .is_some_and(|p| p.features.env_map != on)
    }

    /// The features to build the kernels with for a scene of `facts`, with the environment
    /// map where one is set, for the kernels in use ([`strategy::kernel_strategy`]).
    fn features_for(&self, facts: &SceneFacts) -> KernelFeatures {
        let facts = SceneFacts {
            features: KernelFeatures {
                env_map: self.environment.is_some(),
                aovs: self.settings.aovs,
                ..facts.features
            },
            ..*facts
        };
        strategy::kernel_strategy(&self.device_facts, self.megakernel, &facts, &self.overrides)
    }

    /// Builds the kernels when the loaded scene's features (with the environment's and the
    /// kernel strategy's) changed; returns the build time in milliseconds (0 when the kernels
    /// were reused).
    fn ensure_program(&mut self) -> Result<f64, ClError> {
        let features = self.features_for(&self.facts);
        if self
            .program
            .as_ref()
            .is_some_and(|p| p.features == features)
        {
            return Ok(0.0);
        }
        // A cold build takes seconds (the drivers cache built programs on disk: see README).
        if self.announce_builds {
            eprintln!("penumbra: compiling kernels…");
        }
        let t = Instant::now();
        self.program = Some(Program::build(&self.device, features)?);
        Ok(t.elapsed().as_secs_f64() * 1e3)
    }

    /// Sets (or with `None` removes) the environment map: it lights the scene with importance
    /// sampling and MIS, and replaces the uniform sky. Rebuilds the kernels when the map appears
    /// or goes. Resets the film.
    pub fn set_environment(&mut self, map: Option<EnvMap>) -> Result<(), ClError> {
        match map {
            Some(map) => {
                let table = map.sampling();
                let texels: Vec<f32> = map.texels.iter().flatten().copied().collect();
                self.env.texels = Buffer::from_slice(&self.device, &texels)?;
                self.env.marginal = Buffer::from_slice(&self.device, &table.marginal)?;
                self.env.conditional = Buffer::from_slice(&self.device, &table.conditional)?;
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
        self.settings.focus_distance = focus_distance.max(f32::MIN_POSITIVE);
        self.apply_lens();
        self.reset()
    }

    fn apply_lens(&mut self) {
        let space = self.space();
        self.camera.origin[3] = space.length(self.settings.lens_radius as f64);
        self.camera.forward[3] = space.length(self.settings.focus_distance as f64);
    }

    /// The map from world space to the render space of the scene on the device.
    pub fn space(&self) -> RenderFrame {
        self.scene
            .as_ref()
            .map_or_else(RenderFrame::default, |(_, h)| h.space)
    }

    /// The distance along the view axis to the surface seen through pixel (x, y) (pixel
    /// coordinates, fractional allowed) of the current camera, from the host BVH; `None`
    /// where the pixel sees nothing. For click-to-focus: pass it to [`Renderer::set_lens`].
    pub fn focus_distance_at(&self, x: f32, y: f32) -> Option<f32> {
        let (_, host) = self.scene.as_ref()?;
        let c = &self.camera;
        let fx = x / self.settings.width.max(1) as f32;
        let fy = y / self.settings.height.max(1) as f32;
        let forward = glam::Vec3::new(c.forward[0], c.forward[1], c.forward[2]);
        let ray = camera::primary_ray(c, fx, fy);
        let unit = ray.direction.normalize();
        let ray = Ray {
            direction: unit,
            ..ray
        };
        let hit = host.intersect(&ray)?;
        Some((hit.t * unit.dot(forward.normalize())) / host.space.scale as f32)
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

    /// Sets the camera (in world space). Resets the film.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<(), ClError> {
        self.world_camera = Some(camera.clone());
        self.camera = gpu_camera(&self.space().camera(camera), self.settings.aspect());
        self.apply_lens();
        self.reset()
    }

    /// Applies settings, resizing buffers as needed. Resets the film.
    pub fn set_settings(&mut self, settings: &RenderSettings) -> Result<(), ClError> {
        let aspect_changed = settings.aspect() != self.settings.aspect();
        let env_changed = settings.env_intensity != self.settings.env_intensity
            || settings.env_rotation != self.settings.env_rotation;
        let aovs_changed = settings.aovs != self.settings.aovs;
        self.settings = settings.clone();
        if aovs_changed && self.scene.is_some() {
            self.ensure_program()?;
        }
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

    /// Keeps the film, the sample count and the sequence's next sample through later scene,
    /// camera and settings changes while `held` (a shutter's poses render into one film);
    /// releasing it changes nothing until the next reset.
    pub fn hold_film(&mut self, held: bool) {
        self.film_held = held;
    }

    /// Clears the film and the counters (not while the film is held: [`Renderer::hold_film`]).
    pub fn reset(&mut self) -> Result<(), ClError> {
        if !self.pending.is_empty() {
            self.finish()?;
        }
        if self.film_held {
            return Ok(());
        }
        self.samples = 0;
        self.next_sample = 0;
        self.stats = RenderStats::default();
        self.counters.clear(&self.device)?;
        self.stats_buffer.clear(&self.device)?;
        self.adaptive_checked = false;
        self.active_pixels = None;
        self.active_stale = false;
        if let Some(f) = self.frame.as_mut() {
            f.film.sum.clear(&self.device)?;
            // Adaptive sampling's buffers are only read with it on (kernels/shared/adaptive.h).
            if self.settings.noise_threshold.is_some() {
                f.film.half.clear(&self.device)?;
                f.film.state.clear(&self.device)?;
                f.film.rays.clear(&self.device)?;
            }
            if self.settings.aovs {
                f.film.aovs.clear(&self.device)?;
            }
        }
        Ok(())
    }

    /// Samples per pixel in the film.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The next samples rendered are those of index `index`, `index + 1`, … of the random
    /// sequence (a shard's range, or a device's batch): the film's integer sums make the image
    /// the same whatever order the samples come in (kernels/shared/film.h).
    pub fn set_next_sample(&mut self, index: u32) {
        self.next_sample = index;
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

    /// The acceleration structure on the host.
    pub fn accel(&self) -> Option<&Accel> {
        self.scene.as_ref().map(|(_, h)| &h.accel)
    }

    /// Whether a kernel build says so on stderr (by default it does): of several devices set
    /// up at once, one says it.
    pub fn announce_builds(&mut self, on: bool) {
        self.announce_builds = on;
    }

    /// Chooses the acceleration structure of the scenes loaded from now on.
    pub fn set_bvh_choice(&mut self, choice: BvhChoice) {
        self.bvh_choice = choice;
    }

    /// Sets, for the two-level scenes loaded from now on, the largest mesh whose instances'
    /// triangles become pieces of the top level (`TwoLevel::small_mesh`); `None`: the device's
    /// rule (64 triangles on CPU devices, none on GPUs).
    pub fn set_small_mesh(&mut self, small_mesh: Option<usize>) {
        self.small_mesh = small_mesh;
    }
}
