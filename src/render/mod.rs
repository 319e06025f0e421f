//! The renderer: owns the OpenCL device, the scene on it and the film, and runs the wavefront
//! stages. It knows nothing of windows; the viewer and the command line drive it alike.

pub mod background;
pub mod camera;
pub mod exposure;
pub mod instancing;
mod lights;
mod megakernel;
mod settings;
mod textures;
pub mod tonemap;
mod update;
mod upload;
mod wavefront;

pub use instancing::BvhChoice;
pub use lights::gpu_lights;
pub use megakernel::KernelChoice;
pub use settings::{RenderSettings, Strategy};
pub use textures::TexturePack;
pub use update::InstanceUpdate;
pub use upload::{Accel, HostScene, gpu_camera, gpu_material, samples_textures};
pub use wavefront::{RenderStats, Stage, StageTimes};

use crate::bvh::{Ray, WideBvh};
pub use crate::cl::kernels::NodeForms;
use crate::cl::kernels::{EnvBuffers, Launch, SceneBuffers};
use crate::cl::types::*;
use crate::cl::{
    Buffer, ClError, DeviceChoice, Gpu, KernelFeatures, Lanes, Program, SMALL_SCENE_MAX,
};
use crate::scene::{AlphaMode, Camera, EnvMap, EnvSampling, Light, RenderFrame, Scene};
use std::sync::Arc;
use std::time::Instant;
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
}

/// The kernel features a scene needs; `triangle_lights` and `tangents` come from its upload
/// (emissive triangles with an area, tangents for normal maps).
fn scene_features(scene: &Scene, triangle_lights: bool, tangents: bool) -> KernelFeatures {
    // Only the materials some triangle uses (the importer's default material often is not).
    let in_use = scene.used_materials();
    let materials = || {
        scene
            .materials
            .iter()
            .zip(&in_use)
            .filter(|(_, u)| **u)
            .map(|(m, _)| m)
    };
    let used = |f: &dyn Fn(&crate::scene::Material) -> bool| materials().any(f);
    KernelFeatures {
        triangle_lights,
        textures: used(&|m| m.textures.any()),
        normal_maps: used(&|m| m.textures.normal_mapped()) && tangents,
        alpha: used(&|m| m.alpha != AlphaMode::Opaque),
        transmission: used(&|m| m.transmission > 0.0),
        env_map: false,
        two_level: false,
        triangle_pieces: false,
        thin_walls: used(&|m| m.transmission > 0.0 && m.thickness <= 0.0),
        unlit: used(&|m| m.unlit),
        clearcoat: used(&|m| m.clearcoat > 0.0),
        sheen: used(&|m| m.sheen_color.iter().any(|&c| c > 0.0)),
        diffuse_transmission: used(&|m| m.diffuse_transmission > 0.0),
        iridescence: used(&|m| m.iridescence > 0.0),
        anisotropy: used(&|m| m.anisotropy > 0.0),
        dispersion: used(&|m| m.is_dispersive()),
        tangents: used(&|m| m.anisotropy > 0.0) && tangents,
        lambert_only: materials().all(|m| m.is_lambertian()),
        small_scene: 0,
        lanes: false,
        lanes_shade: false,
        lanes_small: false,
    }
}

/// `KernelFeatures::small_scene` for a scene of `triangles`: the megakernel (CPU devices) tests
/// every triangle of a small flat scene without alpha for every ray, sixteen at a time. The
/// kernels are built for the count rounded up to a whole sixteen (the count itself comes with
/// each frame), so that hiding or showing an object of such a scene mostly builds nothing.
/// Where the megakernel's lanes can shade the scene in batches, they take it instead
/// ([`Renderer::ensure_program`]; [`crate::cl::lanes_megakernel`]).
fn small_scene(cpu: bool, flat: bool, triangles: usize, alpha: bool) -> u32 {
    let small = cpu && flat && !alpha && (1..=small_scene_limit()).contains(&triangles);
    if small {
        triangles.next_multiple_of(crate::cl::types::SMALL_LANES) as u32
    } else {
        0
    }
}

/// [`SMALL_SCENE_MAX`], or for measuring the limit against the tree another one from
/// `PENUMBRA_SMALL_SCENE_MAX` (0 turns small scenes off; at most 1024).
fn small_scene_limit() -> usize {
    static LIMIT: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *LIMIT.get_or_init(|| {
        std::env::var("PENUMBRA_SMALL_SCENE_MAX")
            .ok()
            .and_then(|v| v.trim().parse::<usize>().ok())
            .map_or(SMALL_SCENE_MAX, |n| n.min(1024))
    })
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
    /// The world camera as last given (the device's is in render space).
    world_camera: Option<Camera>,
    camera: GpuCamera,
    light_count: u32,
    /// Features of the loaded scene (without the environment map's).
    scene_features: KernelFeatures,
    /// Whether the loaded scene walks in lanes; `ensure_program` settles `Lanes::WhenBatched`
    /// once it knows the environment.
    lanes: Lanes,
    /// The lights as last given, to rebuild the light table.
    lights: Vec<Light>,
    environment: Option<(Arc<EnvMap>, EnvSampling)>,
    env: EnvBuffers,
    samples: u32,
    stats: RenderStats,
    pending: Vec<(Stage, Launch)>,
    /// Whether frames run as the megakernel (else the wavefront); see [`KernelChoice`].
    megakernel: bool,
    /// The acceleration structure the next scene load builds.
    bvh_choice: BvhChoice,
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
    /// Node arrays uploaded beyond those the kernels in use traverse (see
    /// [`Renderer::set_node_forms`]).
    extra_forms: NodeForms,
    /// The film as last read back (sums and counts), kept for the next read.
    readback: Vec<[f32; 4]>,
}

/// The BLASes of a background build, with their meshes in the plan's order, and its time (ms).
type BuiltBlases = (Vec<(Arc<crate::scene::Mesh>, crate::bvh::Blas)>, f64);

/// SAH BLASes building on threads of their own behind the quick ones on the device; dropping
/// it stops the build at the next mesh.
struct SahBuild {
    /// The BLASes when done.
    done: std::sync::mpsc::Receiver<BuiltBlases>,
    /// Set to stop the build (a new scene was loaded).
    cancel: Arc<std::sync::atomic::AtomicBool>,
}

impl Drop for SahBuild {
    fn drop(&mut self) {
        self.cancel
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

impl Renderer {
    /// Opens the device.
    pub fn new(choice: &DeviceChoice) -> Result<Self, ClError> {
        let gpu = Gpu::open(choice)?;
        let counters = Buffer::new(&gpu, COUNTER_SLOTS)?;
        let stats_buffer = Buffer::new(&gpu, STAT_SLOTS)?;
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
            world_camera: None,
            camera: GpuCamera::default(),
            light_count: 0,
            scene_features: KernelFeatures::default(),
            lanes: Lanes::Never,
            lights: Vec::new(),
            environment: None,
            env,
            samples: 0,
            stats: RenderStats::default(),
            pending: Vec::new(),
            megakernel: false,
            bvh_choice: BvhChoice::Auto,
            small_mesh: None,
            quick_first: None,
            sah: None,
            sah_waiting: None,
            extra_forms: NodeForms::NONE,
            readback: Vec::new(),
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

    /// `Some(n)`: a two-level scene of at least n distinct triangles is loaded with quick
    /// BLASes ([`crate::bvh::quick_blas`], several times faster to build) while its SAH BLASes
    /// build on threads behind them; [`Renderer::swap_in_sah`] then loads the scene again with
    /// those, so that the image from then on is the one a plain load gives. The viewer opens
    /// scenes so ([`instancing::QUICK_FIRST_TRIANGLES`]); `None` (the default, `render`):
    /// SAH BLASes at once.
    pub fn set_quick_first(&mut self, from: Option<usize>) {
        self.quick_first = from;
    }

    /// Uploads `extra` node arrays beside those the kernels in use traverse
    /// ([`NodeForms::for_kernels`]: a CPU device's megakernel the wide nodes alone, a GPU's
    /// wavefront the binary ones), now for the loaded scene and at every load: for tests and
    /// `bench trace`, which trace through either array.
    pub fn set_node_forms(&mut self, extra: NodeForms) -> Result<(), ClError> {
        self.extra_forms = extra;
        self.ensure_node_forms()
    }

    /// The node arrays a scene load uploads.
    fn node_forms(&self) -> NodeForms {
        NodeForms::for_kernels(self.megakernel).with(self.extra_forms)
    }

    /// Uploads the node arrays of the loaded scene that [`Renderer::node_forms`] asks for and
    /// it lacks (the kernels or the extra forms changed after the load), with the instances
    /// that name their roots.
    pub(crate) fn ensure_node_forms(&mut self) -> Result<(), ClError> {
        let want = self.node_forms();
        let Some((buffers, host)) = self.scene.as_mut() else {
            return Ok(());
        };
        let add = want.beyond(buffers.forms);
        if add == NodeForms::NONE {
            return Ok(());
        }
        let (nodes, wide) = device_nodes(host, add);
        if let Some(nodes) = nodes {
            buffers.nodes = Buffer::from_slice(&self.gpu, &nodes)?;
        }
        if let Some(wide) = wide {
            buffers.wide_nodes = Buffer::from_slice(&self.gpu, &wide)?;
        }
        buffers.forms = buffers.forms.with(add);
        if let Accel::TwoLevel(two) = &host.accel {
            let instances = host.layout.gpu_instances(two);
            buffers.instances.write_at(&self.gpu, 0, &instances)?;
        }
        Ok(())
    }

    /// Whether SAH BLASes are building (or waiting to) behind the quick ones on the device.
    pub fn sah_pending(&self) -> bool {
        self.sah.is_some() || self.sah_waiting.is_some()
    }

    /// When the SAH BLASes behind the quick ones are done, loads `scene` (the one loaded, as it
    /// is now: moved or hidden objects stay so) with them in the current render space and
    /// resets the film; its figures, the wait for the BLASes (ms) in `bvh_build_ms`. `None`
    /// while they build or when none are. The first call after the quick scene's first
    /// samples starts their build.
    pub fn swap_in_sah(
        &mut self,
        scene: &Scene,
        lights: &[Light],
    ) -> Result<Option<SceneStats>, ClError> {
        // The SAH BLASes start once the quick scene has samples: on a CPU device their
        // threads would otherwise share the cores with the first image.
        if self.samples > 0
            && let Some(meshes) = self.sah_waiting.take()
        {
            self.sah = Self::sah_behind(meshes);
        }
        let Some(build) = &self.sah else {
            return Ok(None);
        };
        let (blases, build_ms) = match build.done.try_recv() {
            Ok(b) => b,
            Err(std::sync::mpsc::TryRecvError::Empty) => return Ok(None),
            // The thread died (it cannot, short of running out of memory): build them here.
            Err(std::sync::mpsc::TryRecvError::Disconnected) => (vec![], 0.0),
        };
        self.sah = None;
        let space = self.space();
        // The quick scene's host side goes first; its buffers take the new contents where the
        // sizes agree (triangles and shading data: the same, reordered).
        let old = self.scene.take().map(|(buffers, _)| buffers);
        let how = instancing::Blases::Built(blases);
        let mut stats = self.load_with(scene, lights, space, how, old)?;
        stats.bvh_build_ms += build_ms;
        Ok(Some(stats))
    }

    /// The meshes of `plan`'s BLASes (of `scene`), in order.
    fn sah_meshes(scene: &Scene, plan: &instancing::Instancing) -> Vec<Arc<crate::scene::Mesh>> {
        plan.mesh_objects
            .iter()
            .map(|&o| scene.objects[o as usize].mesh.clone())
            .collect()
    }

    /// Starts building the SAH BLASes of `meshes` on a pool of threads of
    /// their own, so that the host work of frames (rayon's global pool) never queues behind
    /// them; `None` when no thread could be started (the quick trees then stay).
    fn sah_behind(meshes: Vec<Arc<crate::scene::Mesh>>) -> Option<SahBuild> {
        use rayon::prelude::*;
        use std::sync::atomic::Ordering;
        let pool = rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("sah-blas-{i}"))
            .build()
            .ok()?;
        let cancel = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stop = cancel.clone();
        let (tx, done) = std::sync::mpsc::channel();
        std::thread::Builder::new()
            .name("sah-blas".into())
            .spawn(move || {
                let _memory = crate::cl::kernels::OpeningMemory::begin();
                let t = Instant::now();
                let blases: Option<Vec<_>> = pool.install(|| {
                    meshes
                        .into_par_iter()
                        .map(|m| {
                            (!stop.load(Ordering::Relaxed)).then(|| {
                                let b = crate::bvh::Blas::of_shared_mesh(&m);
                                (m, b)
                            })
                        })
                        .collect()
                });
                if let Some(blases) = blases {
                    // Nobody waits when a new scene replaced this one.
                    let _ = tx.send((blases, t.elapsed().as_secs_f64() * 1e3));
                }
            })
            .ok()?;
        Some(SahBuild { done, cancel })
    }

    /// [`Renderer::load_scene_in`] with BLASes made as `how` says; with quick ones, their SAH
    /// BLASes start building behind them.
    fn load_with(
        &mut self,
        scene: &Scene,
        lights: &[Light],
        space: RenderFrame,
        how: instancing::Blases,
        reuse: Option<SceneBuffers>,
    ) -> Result<SceneStats, ClError> {
        let _memory = crate::cl::kernels::OpeningMemory::begin();
        self.sah = None;
        self.sah_waiting = None;
        let mut behind = None;
        let t = Instant::now();
        let materials: Vec<_> = scene.materials.iter().map(|m| space.material(m)).collect();
        let mut rule = if self.gpu.is_cpu() {
            instancing::AUTO_CPU
        } else {
            instancing::AUTO_GPU
        };
        if let Some(small_mesh) = self.small_mesh {
            rule.small_mesh = small_mesh;
        }
        // Two levels: each BLAS's mesh, whose device structs are written at the upload.
        let mut meshes: Vec<&crate::scene::Mesh> = vec![];
        let (mut host, dropped) = match instancing::plan(scene, &space, self.bvh_choice, rule, how)
        {
            Some(plan) => {
                log::debug!(
                    "BLASes and TLAS in {:.0} ms",
                    t.elapsed().as_secs_f64() * 1e3
                );
                if plan.quick {
                    behind = Some(Self::sah_meshes(scene, &plan));
                }
                // Two levels: nothing is flattened; each mesh goes to the device once.
                meshes = plan
                    .mesh_objects
                    .iter()
                    .map(|&o| scene.objects[o as usize].mesh.as_ref())
                    .collect();
                let mut host = HostScene::two_level(
                    plan.two,
                    &meshes,
                    &materials,
                    upload::render_middle(scene, &space),
                );
                host.layout.objects = plan.objects;
                (host, 0)
            }
            None => HostScene::flatten(scene, &space, &materials),
        };
        let bvh_build_ms = t.elapsed().as_secs_f64() * 1e3;

        let t = Instant::now();
        host.space = space;
        host.scale_emitter_power(&lights::emissive_texture_means(scene));
        // Two levels: the meshes' triangles (BLAS after BLAS), and whether any has tangents.
        let (mesh_triangles, mesh_tangents) = match &host.accel {
            Accel::TwoLevel(two) => (
                two.blases.iter().map(|b| b.len()).sum(),
                meshes.iter().any(|m| !m.tangents.is_empty()),
            ),
            Accel::Flat(_) => (0, false),
        };
        self.scene_features = KernelFeatures {
            two_level: matches!(host.accel, Accel::TwoLevel(_)),
            triangle_pieces: matches!(&host.accel, Accel::TwoLevel(t) if t.has_small_meshes()),
            ..scene_features(
                scene,
                !host.emissive.is_empty(),
                !host.tangents.is_empty() || mesh_tangents,
            )
        };
        self.scene_features.small_scene = small_scene(
            self.gpu.is_cpu(),
            matches!(host.accel, Accel::Flat(_)),
            host.triangles.len(),
            self.scene_features.alpha,
        );
        self.lanes = match &host.accel {
            Accel::Flat(bvh) => crate::cl::lanes_megakernel(
                self.gpu.is_cpu(),
                self.scene_features.alpha,
                host.triangles.len(),
                bvh.largest_leaf(),
            ),
            Accel::TwoLevel(_) => Lanes::Never,
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
        log::debug!(
            "kernels, textures, lights: {:.0} ms",
            t.elapsed().as_secs_f64() * 1e3
        );
        let forms = self.node_forms();
        let (nodes, wide_nodes, instances) = device_accel(&mut host, forms);
        log::debug!("device nodes: {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
        // Triangles and shading data are the device's alone (picking keeps each flat triangle's
        // object, `HostScene::objects`). The flat form's leave the host scene, and each large
        // host array is freed as soon as its buffer is made, so that the two copies (host
        // memory either way with a CPU device) are not all held at once. Two levels write
        // every mesh's straight into the buffers (`HostScene::fill_meshes`), no host copy made;
        // their host triangles are the small instances' world-space copies, which follow the
        // meshes' in the device triangles.
        let triangles = std::mem::take(&mut host.triangles);
        let shading = std::mem::take(&mut host.shading);
        let uvs = std::mem::take(&mut host.uvs);
        let tangents = std::mem::take(&mut host.tangents);
        let tangent_count = if mesh_tangents { mesh_triangles } else { 0 } + tangents.len();
        // Texture coordinates only when some material samples a texture (a superset of the
        // kernels' `HAS_TEXTURES`, which alone reads them); else a placeholder.
        let mesh_uvs = samples_textures(&materials);
        let uv_count = if mesh_uvs { mesh_triangles } else { 0 } + uvs.len();
        let lengths = (
            mesh_triangles + triangles.len(),
            mesh_triangles + shading.len(),
            tangent_count.max(1),
            uv_count.max(1),
        );
        // Two levels trace the meshes' object-space triangles in `triangles`: the separate
        // object-triangle buffer is a placeholder either way.
        let object_tris = [GpuTriangle::default()];
        let bytes = |n: usize, size: usize| n.max(1) * size;
        let sizes = [
            ("BVH nodes", std::mem::size_of_val(nodes.as_slice())),
            (
                "wide BVH nodes",
                std::mem::size_of_val(wide_nodes.as_slice()),
            ),
            ("triangles", lengths.0 * std::mem::size_of::<GpuTriangle>()),
            ("instances", std::mem::size_of_val(instances.as_slice())),
            ("shading", lengths.1 * std::mem::size_of::<GpuTriShading>()),
            ("uvs", lengths.3 * std::mem::size_of::<GpuTriUvs>()),
            (
                "tangents",
                lengths.2 * std::mem::size_of::<GpuTriTangents>(),
            ),
            ("texels", bytes(pack.texels.len(), 4)),
        ];
        log::debug!(
            "device buffers: {}",
            sizes
                .iter()
                .map(|(name, b)| format!("{name} {:.1} MB", *b as f64 / 1e6))
                .collect::<Vec<_>>()
                .join(", ")
        );
        fits_device(
            &sizes,
            self.gpu.device.global_mem_size().ok(),
            self.gpu.device.max_mem_alloc_size().ok(),
        )
        .map_err(ClError::Device)?;
        // The large buffers of the scene replaced (a swap to SAH BLASes), written again in
        // place where the size is the same: no fresh memory to fault in.
        let (old_nodes, old_wide, old_shading, old_uvs, old_tangents, old_triangles, old_instances) =
            match reuse {
                Some(b) => (
                    Some(b.nodes),
                    Some(b.wide_nodes),
                    Some(b.shading),
                    Some(b.uvs),
                    Some(b.tangents),
                    Some(b.triangles),
                    Some(b.instances),
                ),
                None => Default::default(),
            };
        let gpu = &self.gpu;
        let nodes_buffer = put(gpu, old_nodes, &nodes)?;
        drop(nodes);
        let wide_buffer = put(gpu, old_wide, &wide_nodes)?;
        drop(wide_nodes);
        let (shading_buffer, uvs_buffer, tangents_buffer, triangles_buffer) = match &host.accel {
            Accel::Flat(_) => {
                let shading_buffer = put(gpu, old_shading, &shading)?;
                drop(shading);
                let mut uvs = uvs;
                if uvs.is_empty() {
                    uvs.push(GpuTriUvs::default());
                }
                let uvs_buffer = put(gpu, old_uvs, &uvs)?;
                drop(uvs);
                let mut tangents = tangents;
                if tangents.is_empty() {
                    tangents.push(GpuTriTangents::default());
                }
                let tangents_buffer = put(gpu, old_tangents, &tangents)?;
                drop(tangents);
                let triangles_buffer = put(gpu, old_triangles, &triangles)?;
                drop(triangles);
                (
                    shading_buffer,
                    uvs_buffer,
                    tangents_buffer,
                    triangles_buffer,
                )
            }
            Accel::TwoLevel(two) => {
                let mut shading_buffer = sized(gpu, old_shading, lengths.1)?;
                let mut uvs_buffer = sized(gpu, old_uvs, lengths.3)?;
                let mut tangents_buffer = sized(gpu, old_tangents, lengths.2)?;
                let mut triangles_buffer = sized(gpu, old_triangles, lengths.0)?;
                let n = mesh_triangles;
                triangles_buffer.fill_mapped(gpu, |tris| {
                    shading_buffer.fill_mapped(gpu, |sh| {
                        uvs_buffer.fill_mapped(gpu, |uv| {
                            tangents_buffer.fill_mapped(gpu, |tan| {
                                let tan_out = &mut tan[..if mesh_tangents { n } else { 0 }];
                                let uv_out = &mut uv[..if mesh_uvs { n } else { 0 }];
                                let out = (&mut tris[..n], &mut sh[..n], uv_out, tan_out);
                                HostScene::fill_meshes(two, &meshes, &materials, out);
                                tris[n..].copy_from_slice(&triangles);
                                if !mesh_tangents {
                                    tan.fill(GpuTriTangents::default());
                                }
                                if !mesh_uvs {
                                    uv.fill(GpuTriUvs::default());
                                }
                            })
                        })
                    })
                })????;
                (
                    shading_buffer,
                    uvs_buffer,
                    tangents_buffer,
                    triangles_buffer,
                )
            }
        };
        let instances_buffer = put(gpu, old_instances, &instances)?;
        let buffers = SceneBuffers {
            forms,
            nodes: nodes_buffer,
            wide_nodes: wide_buffer,
            triangles: triangles_buffer,
            instances: instances_buffer,
            object_triangles: Buffer::from_slice(&self.gpu, &object_tris)?,
            shading: shading_buffer,
            uvs: uvs_buffer,
            tangents: tangents_buffer,
            tex_refs: Buffer::from_slice(&self.gpu, &pack.refs)?,
            textures: Buffer::from_slice(&self.gpu, &pack.textures)?,
            texels: Buffer::from_slice(&self.gpu, &pack.texels)?,
            materials: Buffer::from_slice(&self.gpu, &host.materials)?,
            lights: Buffer::from_slice(&self.gpu, &glights)?,
            light_cdf: Buffer::from_slice(&self.gpu, &cdf)?,
        };
        drop(instances);
        self.light_count = glights.len() as u32;
        self.update_env_info(&glights);
        let (meshes, instances) = host.accel.instancing();
        let stats = SceneStats {
            triangles: host.triangle_count(),
            nodes: host.accel.node_count(),
            sah_cost: host.accel.sah_cost(),
            bvh_build_ms,
            kernel_build_ms,
            kernels_built: kernel_build_ms > 0.0,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - kernel_build_ms,
            textures: pack.textures.len(),
            texture_bytes: pack.bytes(),
            texture_max_side: pack.max_side,
            dropped_triangles: dropped,
            bvh: host.accel.name(),
            meshes,
            instances,
            device_bytes: buffers.bytes(),
        };
        self.scene = Some((buffers, host));
        // The SAH BLASes start once the quick scene's first image is in ([`Renderer::swap_in_sah`]),
        // not to slow its upload nor that image.
        self.sah_waiting = behind;
        if let Some(c) = self.world_camera.clone() {
            self.set_camera(&c)?;
        }
        let mut stats = stats;
        stats.kernel_build_ms += self.prime_megakernel()?;
        self.reset()?;
        Ok(stats)
    }

    /// Whether loading `scene` would build kernels (its features differ from the built ones'),
    /// predicted from its materials before the upload: for a "Compiling kernels…" notice.
    pub fn would_build_for(&self, scene: &Scene) -> bool {
        let any = |f: &dyn Fn(&crate::scene::Material) -> bool| scene.materials.iter().any(f);
        let features = KernelFeatures {
            env_map: self.environment.is_some(),
            two_level: self.scene_features.two_level,
            triangle_pieces: self.scene_features.triangle_pieces,
            small_scene: self.scene_features.small_scene,
            ..scene_features(scene, any(&|m| m.is_emissive()), true)
        };
        self.program.as_ref().is_none_or(|p| p.features != features)
    }

    /// Whether setting (`on`) or removing the environment map would build kernels.
    pub fn would_build_for_env(&self, on: bool) -> bool {
        self.scene.is_some()
            && self
                .program
                .as_ref()
                .is_some_and(|p| p.features.env_map != on)
    }

    /// Builds the kernels when the scene's features (with the environment's) changed; returns
    /// the build time in milliseconds (0 when the kernels were reused).
    fn ensure_program(&mut self) -> Result<f64, ClError> {
        let mut features = KernelFeatures {
            env_map: self.environment.is_some(),
            ..self.scene_features
        };
        let small_in_lanes = crate::cl::lanes_small(&features);
        features.lanes = match self.lanes {
            Lanes::Never => false,
            Lanes::Always => true,
            Lanes::WhenBatched => {
                small_in_lanes
                    || crate::cl::lanes_shade(&KernelFeatures {
                        lanes: true,
                        small_scene: 0,
                        ..features
                    })
            }
        };
        features.lanes_small = features.lanes && small_in_lanes;
        if features.lanes {
            features.small_scene = 0;
        }
        features.lanes_shade = crate::cl::lanes_shade(&features);
        if self
            .program
            .as_ref()
            .is_some_and(|p| p.features == features)
        {
            return Ok(0.0);
        }
        // A cold build takes seconds (the drivers cache built programs on disk: see README).
        eprintln!("penumbra: compiling kernels…");
        let t = Instant::now();
        self.program = Some(Program::build(&self.gpu, features)?);
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

    /// The acceleration structure on the host.
    pub fn accel(&self) -> Option<&Accel> {
        self.scene.as_ref().map(|(_, h)| &h.accel)
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

    /// The film as linear RGB (the mean of the samples), row by row from the top.
    pub fn image(&mut self) -> Result<Vec<[f32; 3]>, ClError> {
        let mut image = Vec::new();
        self.image_into(&mut image, None)?;
        Ok(image)
    }

    /// [`Renderer::image`] into `image`, and [`Renderer::coverage`] into `coverage`, from one
    /// read of the film: their allocations and the renderer's readback buffer are reused, so
    /// the viewer's frames allocate no film-sized memory.
    pub fn image_into(
        &mut self,
        image: &mut Vec<[f32; 3]>,
        coverage: Option<&mut Vec<f32>>,
    ) -> Result<(), ClError> {
        let read = self.read_film()?;
        let n = (self.settings.width * self.settings.height) as usize;
        let counted = self.settings.cutout || self.settings.count_coverage;
        let samples = self.samples.max(1) as f32;
        image.clear();
        if !read {
            image.resize(n, [0.0; 3]);
        } else if counted {
            // `.w` counts the samples whose camera ray hit: the mean is over all samples.
            image.extend(
                self.readback
                    .iter()
                    .map(|p| [p[0] / samples, p[1] / samples, p[2] / samples]),
            );
        } else {
            image.extend(self.readback.iter().map(|p| {
                let n = p[3].max(1.0);
                [p[0] / n, p[1] / n, p[2] / n]
            }));
        }
        if let Some(coverage) = coverage {
            coverage.clear();
            if read && counted {
                coverage.extend(
                    self.readback
                        .iter()
                        .map(|p| (p[3] / samples).clamp(0.0, 1.0)),
                );
            } else {
                coverage.resize(n, 1.0);
            }
        }
        Ok(())
    }

    /// Each pixel's coverage: the share of its samples whose camera ray hit the scene, with
    /// [`RenderSettings::cutout`] or [`RenderSettings::count_coverage`] (else all 1); with the
    /// image, [`Renderer::image_into`] reads it from the same read of the film.
    pub fn coverage(&mut self) -> Result<Vec<f32>, ClError> {
        let (mut image, mut coverage) = (Vec::new(), Vec::new());
        self.image_into(&mut image, Some(&mut coverage))?;
        Ok(coverage)
    }

    /// Finishes the pending launches and reads the film into [`Renderer::readback`]; false
    /// when no frame exists yet.
    fn read_film(&mut self) -> Result<bool, ClError> {
        if !self.pending.is_empty() {
            self.finish()?;
        }
        let Some(f) = self.frame.as_ref() else {
            return Ok(false);
        };
        f.film.read_into(&self.gpu, &mut self.readback)?;
        Ok(true)
    }
}

/// A buffer holding `data`: `old` written again when it has `data`'s length, else a new one
/// (`old` freed first).
fn put<T: bytemuck::Pod>(
    gpu: &Gpu,
    old: Option<Buffer<T>>,
    data: &[T],
) -> Result<Buffer<T>, ClError> {
    match old {
        Some(mut b) if b.len() == data.len() && !data.is_empty() => {
            b.write(gpu, data)?;
            Ok(b)
        }
        old => {
            drop(old);
            Buffer::from_slice(gpu, data)
        }
    }
}

/// A buffer of `len` elements: `old` when it has that length (its memory written again in
/// place, no fresh pages to fault in), else a new one (contents undefined either way).
fn sized<T: bytemuck::Pod>(
    gpu: &Gpu,
    old: Option<Buffer<T>>,
    len: usize,
) -> Result<Buffer<T>, ClError> {
    match old {
        Some(b) if b.len() == len => Ok(b),
        old => {
            drop(old);
            Buffer::new(gpu, len)
        }
    }
}

/// The device's node arrays (binary and wide, each a placeholder of one node unless `forms`
/// has it) and instances for `host`'s acceleration structure (the instances are a
/// placeholder when flat); fills `host.layout` for two levels.
fn device_accel(
    host: &mut HostScene,
    forms: NodeForms,
) -> (Vec<GpuBvhNode>, Vec<GpuWideNode>, Vec<GpuInstance>) {
    let (nodes, wide) = device_nodes(host, forms);
    let nodes = nodes.unwrap_or_else(|| vec![GpuBvhNode::default()]);
    let wide = wide.unwrap_or_else(|| vec![GpuWideNode::default()]);
    let instances = match &host.accel {
        Accel::Flat(_) => vec![GpuInstance::default()],
        Accel::TwoLevel(two) => {
            // The small instances' world-space copies follow the meshes' triangles.
            let first = two.blases.iter().map(|b| b.len()).sum();
            host.triangles = host.layout.piece_copies(two, first);
            host.layout.gpu_instances(two)
        }
    };
    (nodes, wide, instances)
}

/// The node arrays that `forms` asks for of `host`'s acceleration structure; for two levels
/// each BLAS's root in every array made (in the binary array always: they are counted, not
/// made) goes to `host.layout`.
fn device_nodes(
    host: &mut HostScene,
    forms: NodeForms,
) -> (Option<Vec<GpuBvhNode>>, Option<Vec<GpuWideNode>>) {
    match &host.accel {
        Accel::Flat(bvh) => (
            forms.binary.then(|| bvh.nodes.clone()),
            forms.wide.then(|| WideBvh::collapse_for_cpu(bvh).nodes),
        ),
        Accel::TwoLevel(two) => {
            let nodes = if forms.binary {
                let (nodes, roots, _) = two.device_nodes();
                host.layout.roots = roots;
                Some(nodes)
            } else {
                host.layout.roots = two.device_roots();
                None
            };
            let wide = forms.wide.then(|| {
                let (wide, wide_roots, wide_of) = two.device_wide_nodes();
                host.layout.wide_roots = wide_roots;
                host.layout.wide_of = wide_of;
                wide
            });
            (nodes, wide)
        }
    }
}

/// Checks before any allocation that the scene's buffers fit the device: their sum against
/// `CL_DEVICE_GLOBAL_MEM_SIZE` (`global`) and each against `CL_DEVICE_MAX_MEM_ALLOC_SIZE`
/// (`max_alloc`), so that a scene too large fails with one clear line instead of an allocation
/// error halfway through the upload.
fn fits_device(
    buffers: &[(&str, usize)],
    global: Option<u64>,
    max_alloc: Option<u64>,
) -> Result<(), String> {
    let gb = |b: u64| b as f64 / 1e9;
    let total: usize = buffers.iter().map(|(_, b)| b).sum();
    if let Some(global) = global
        && total as u64 > global
    {
        return Err(format!(
            "the scene needs {:.2} GB of device memory and the device has {:.2} GB \
             (an instanced scene takes less with --bvh two-level)",
            gb(total as u64),
            gb(global)
        ));
    }
    if let Some(max) = max_alloc
        && let Some((name, b)) = buffers.iter().find(|(_, b)| *b as u64 > max)
    {
        return Err(format!(
            "the scene's {name} need a {:.2} GB buffer and the device allows {:.2} GB in one",
            gb(*b as u64),
            gb(max)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod fit_tests {
    use super::{SMALL_SCENE_MAX, fits_device, scene_features, small_scene};
    use crate::scene::{Material, Mesh, Object, Scene};
    use glam::{DMat4, Vec3};

    #[test]
    fn small_flat_scenes_on_a_cpu_skip_the_tree() {
        // Built for whole batches of sixteen: counts within one give the same kernels.
        assert_eq!(small_scene(true, true, 32, false), 32);
        assert_eq!(small_scene(true, true, 22, false), 32);
        assert_eq!(small_scene(true, true, 17, false), 32);
        assert_eq!(
            small_scene(true, true, 36, false),
            48,
            "a box with closed blocks"
        );
        assert_eq!(small_scene(true, true, 1, false), 16);
        assert_eq!(
            small_scene(true, true, SMALL_SCENE_MAX, false),
            SMALL_SCENE_MAX as u32
        );
        assert_eq!(small_scene(true, true, SMALL_SCENE_MAX + 1, false), 0);
        assert_eq!(small_scene(true, true, 0, false), 0, "nothing to test");
        assert_eq!(
            small_scene(false, true, 32, false),
            0,
            "GPUs keep the wavefront"
        );
        assert_eq!(small_scene(true, false, 32, false), 0, "two levels");
        assert_eq!(
            small_scene(true, true, 32, true),
            0,
            "alpha tests need the tree's loop"
        );
    }

    /// One triangle per material index in `uses`, of a scene with `materials`.
    fn scene_using(materials: Vec<Material>, uses: &[u32]) -> Scene {
        let mut mesh = Mesh::default();
        for &m in uses {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([Vec3::ZERO, Vec3::X, Vec3::Y]);
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.materials.push(m);
        }
        let object = Object {
            name: "o".into(),
            world_from_object: DMat4::IDENTITY,
            visible: true,
            mesh: mesh.into(),
        };
        Scene {
            materials,
            objects: vec![object],
            ..Scene::default()
        }
    }

    #[test]
    fn lambert_only_looks_at_the_materials_in_use() {
        let lambert = Material {
            specular_factor: 0.0,
            ..Material::default()
        };
        let glossy = Material::default(); // the importer's fallback: a specular layer
        let features = |uses: &[u32]| {
            scene_features(
                &scene_using(vec![lambert.clone(), glossy.clone()], uses),
                false,
                false,
            )
        };
        assert!(
            features(&[0, 0]).lambert_only,
            "the unused glossy material does not count"
        );
        assert!(!features(&[0, 1]).lambert_only);
        let metal = Material {
            metallic: 1.0,
            ..lambert.clone()
        };
        let scene = scene_using(vec![lambert.clone(), metal], &[0, 1]);
        assert!(!scene_features(&scene, false, false).lambert_only);
    }

    #[test]
    fn scenes_too_large_for_the_device_are_refused_with_a_reason() {
        let buffers = [("triangles", 600), ("shading", 500)];
        assert!(fits_device(&buffers, Some(2000), Some(1000)).is_ok());
        assert!(fits_device(&buffers, None, None).is_ok());
        let total = fits_device(&buffers, Some(1000), Some(1000)).unwrap_err();
        assert!(total.contains("device memory"), "{total}");
        let one = fits_device(&buffers, Some(2000), Some(550)).unwrap_err();
        assert!(one.contains("triangles need"), "{one}");
    }
}
