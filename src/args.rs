//! The command-line option groups that `cli` and `bench` share (clap), each with its checks,
//! and the loading of a scene with them (`prepare`).
//!
//! `CommonArgs` flattens every group a rendering command takes; a command that needs fewer
//! (`bench trace`) flattens only those.

use crate::cl::{DeviceChoice, DeviceSet};
use crate::cli::first_image;
use crate::render::background::Background;
use crate::render::exposure::ExposureMode;
use crate::render::tonemap::ToneMapper;
use crate::render::{BvhChoice, KernelChoice, RenderSettings, Renderer, Strategy};
use crate::scene::limits::MAX_INTENSITY;
use crate::scene::{Camera, EnvMap, Light, Scene, Shadows, load_or_bundled_with};
use anyhow::{Result, bail};
use clap::Args;
use std::path::{Path, PathBuf};

pub use crate::cli::first_image::EnvChoice;

/// The largest image side accepted.
pub const MAX_SIDE: u32 = 16384;
/// The most bounces accepted.
pub const MAX_BOUNCES: u32 = 256;

/// The OpenCL device.
#[derive(Args, Debug, Clone, Default)]
pub struct DeviceArgs {
    /// OpenCL device: gpu, cpu or an index from `penumbra devices`; for `render`, also all
    /// or a list of indices (0,2) whose devices share the samples; also read from
    /// PENUMBRA_DEVICE (default: the first GPU, else the first CPU).
    #[arg(long, value_parser = parse_device)]
    pub device: Option<String>,
}

/// A `--device` that names devices there are: a list of indices is checked against
/// `penumbra devices` (without OpenCL, the opening says so later).
fn parse_device(s: &str) -> Result<String, String> {
    let set: DeviceSet = s.parse()?;
    if let Ok(devices) = crate::cl::list_devices() {
        set.indices(&devices)?;
    }
    Ok(s.to_string())
}

impl DeviceArgs {
    /// The devices from `--device` or `PENUMBRA_DEVICE`.
    pub fn device_set(&self) -> Result<DeviceSet> {
        DeviceSet::from_arg_or_env(self.device.as_deref()).map_err(anyhow::Error::msg)
    }

    /// The device of a command that renders on one; `all` or a list is refused.
    pub fn device_choice(&self) -> Result<DeviceChoice> {
        match self.device_set()? {
            DeviceSet::One(choice) => Ok(choice),
            set => bail!("--device {set:?}: this command renders on one device"),
        }
    }
}

/// The image size.
#[derive(Args, Debug, Clone, Default)]
pub struct SizeArgs {
    /// Image width in pixels (default: 640 for render, 960 for the viewer).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=MAX_SIDE as i64))]
    pub width: Option<u32>,
    /// Image height in pixels (default: 480 for render, 600 for the viewer).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=MAX_SIDE as i64))]
    pub height: Option<u32>,
}

impl SizeArgs {
    /// Width and height, `default` where not given; rejects absurd sizes.
    pub fn size(&self, default: (u32, u32)) -> Result<(u32, u32)> {
        let width = self.width.unwrap_or(default.0);
        let height = self.height.unwrap_or(default.1);
        for (name, v) in [("--width", width), ("--height", height)] {
            if v == 0 || v > MAX_SIDE {
                bail!("{name} {v} is out of range (1..={MAX_SIDE})");
            }
        }
        Ok((width, height))
    }
}

/// Which camera, or where the camera is.
#[derive(Args, Debug, Clone, Default)]
pub struct CameraArgs {
    /// Camera of the glTF file to use, by index (default: the file's first camera, else an
    /// automatic one).
    #[arg(long, allow_negative_numbers = true)]
    pub camera: Option<usize>,
    /// Camera position X,Y,Z in scene units, with --look-at (default: the chosen camera's).
    #[arg(long, value_parser = parse_vec3, allow_negative_numbers = true, requires = "look_at")]
    pub eye: Option<[f64; 3]>,
    /// Point the camera looks at, X,Y,Z in scene units, with --eye (default: the chosen
    /// camera's).
    #[arg(long, value_parser = parse_vec3, allow_negative_numbers = true, requires = "eye")]
    pub look_at: Option<[f64; 3]>,
    /// Vertical field of view in degrees (default: the camera's).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_fov)]
    pub fov: Option<f64>,
    /// A view saved in the viewer (V), by name, from the views file beside the scene
    /// (SCENE.views.json) (default: none).
    #[arg(long, value_name = "NAME", conflicts_with_all = ["camera", "eye"])]
    pub view: Option<String>,
}

impl CameraArgs {
    /// Rejects a field of view outside (0, 180) degrees.
    pub fn check(&self) -> Result<()> {
        if let Some(f) = self.fov
            && !(f > 0.0 && f < 180.0)
        {
            bail!("--fov {f} is out of range (0..180 degrees)");
        }
        Ok(())
    }

    /// The camera of `scene` these options choose.
    pub fn choose(&self, scene: &Scene) -> Result<Camera> {
        let mut camera = match self.camera {
            None => scene.cameras[0].clone(),
            Some(i) => match scene.cameras.get(i) {
                Some(c) => c.clone(),
                None => bail!(
                    "{}: --camera {i} is out of range (the scene has {} camera(s))",
                    scene.source,
                    scene.cameras.len()
                ),
            },
        };
        if let (Some(eye), Some(target)) = (self.eye, self.look_at) {
            let (eye, target) = (glam::DVec3::from(eye), glam::DVec3::from(target));
            if (target - eye).normalize_or_zero() == glam::DVec3::ZERO {
                bail!("--eye and --look-at are the same point");
            }
            camera = Camera::look_at("command line", eye, target, camera.yfov);
        }
        if let Some(fov) = self.fov {
            camera.yfov = fov.to_radians();
        }
        Ok(camera)
    }
}

/// Depth of field.
#[derive(Args, Debug, Clone)]
pub struct LensArgs {
    /// Depth of field: thin-lens radius in scene units (0 = pinhole, everything sharp).
    #[arg(
        long,
        default_value_t = RenderSettings::default().lens_radius,
        allow_negative_numbers = true,
        value_parser = parse_non_negative
    )]
    pub aperture: f32,
    /// Distance from the eye to the plane in focus, along the view axis, in scene units
    /// (default: the distance to what the image centre sees).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_positive)]
    pub focus_distance: Option<f32>,
}

/// Samples per pixel, bounces and the random sequence.
#[derive(Args, Debug, Clone)]
pub struct SamplingArgs {
    /// Samples per pixel (default: 64 for render, endless in the viewer).
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Bounces after the first hit, a count (0 = direct light only).
    #[arg(long, allow_negative_numbers = true, default_value_t = RenderSettings::default().bounces,
          value_parser = clap::value_parser!(u32).range(0..=MAX_BOUNCES as i64))]
    pub bounces: u32,
    /// Seed of the random sequence, an integer.
    #[arg(long, allow_negative_numbers = true, default_value_t = RenderSettings::default().seed)]
    pub seed: u32,
}

/// How large the lights are, which sets how soft their shadows are.
#[derive(Args, Debug, Clone, Default)]
pub struct ShadowArgs {
    /// Radius of point and spot lights in scene units (soft shadows); directional lights get
    /// an angular radius of 2·R/diagonal radians (default: 2% of the scene's diagonal).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_non_negative)]
    pub light_radius: Option<f32>,
    /// Hard shadows: every light radius 0 (default: off, soft shadows).
    #[arg(long, conflicts_with = "light_radius")]
    pub hard_shadows: bool,
}

impl ShadowArgs {
    /// Rejects a negative or non-finite light radius.
    pub fn check(&self) -> Result<()> {
        if let Some(r) = self.light_radius
            && !(r.is_finite() && r >= 0.0)
        {
            bail!("--light-radius {r} must be a finite number >= 0");
        }
        Ok(())
    }
}

/// The light from outside the scene.
#[derive(Args, Debug, Clone)]
pub struct EnvArgs {
    /// Uniform sky radiance as linear R,G,B (or one value for gray) (default: black).
    #[arg(long, value_parser = parse_color)]
    pub sky: Option<[f32; 3]>,
    /// Environment light: `neutral`, `studio` or `outdoor` (bundled), `none`, an
    /// equirectangular .hdr or .exr image (importance-sampled), or a uniform color R,G,B / gray
    /// value (like --sky). Any environment replaces the default light rig (default: neutral
    /// when the scene's own lights do not light the view or do not surround its metal and
    /// glass, else none; docs/first-image.md).
    #[arg(
        long,
        value_name = "neutral|studio|outdoor|none|FILE|COLOR",
        conflicts_with = "sky",
        value_parser = parse_env
    )]
    pub env: Option<String>,
    /// Radiance scale of the --env image, a factor.
    #[arg(
        long,
        default_value_t = RenderSettings::default().env_intensity,
        allow_negative_numbers = true,
        value_parser = parse_intensity
    )]
    pub env_intensity: f32,
    /// Rotation of the --env image about the up (+Y) axis in degrees, counter-clockwise seen
    /// from above.
    #[arg(
        long,
        default_value_t = RenderSettings::default().env_rotation,
        allow_negative_numbers = true,
        value_parser = parse_finite
    )]
    pub env_rotation: f32,
}

impl EnvArgs {
    /// The uniform sky radiance: an `--env` color, else `--sky`, else black.
    pub fn sky(&self) -> [f32; 3] {
        match self.env.as_deref().map(parse_color) {
            Some(Ok(c)) => c,
            _ => self.sky.unwrap_or([0.0; 3]),
        }
    }

    /// What `--env` asks for: a color, or an image loaded now; `None` without `--env`.
    pub fn environment(&self) -> Result<Option<EnvChoice>> {
        let arg = match first_image::EnvArg::parse(self.env.as_deref()) {
            first_image::EnvArg::Other(arg) => arg,
            named => return Ok(first_image::environment(&named, None)),
        };
        let arg = arg.as_str();
        if let Ok(c) = parse_color(arg) {
            return Ok(Some(EnvChoice::Color(c)));
        }
        let path = Path::new(arg);
        if !path.is_file() {
            bail!("--env {arg}: neither a color (R,G,B) nor an existing .hdr/.exr file");
        }
        Ok(Some(EnvChoice::Map(
            EnvMap::load(path).map_err(anyhow::Error::msg)?,
        )))
    }
}

/// The most stops `--exposure` may brighten or darken by.
pub const MAX_EXPOSURE: f32 = 64.0;

/// An exposure in stops within ±[`MAX_EXPOSURE`].
fn parse_exposure(s: &str) -> Result<f32, String> {
    within_max_exposure(s, " stops")
}

/// An EV100 within ±[`MAX_EXPOSURE`] (the exposure it sets is within a stop of that).
fn parse_ev100(s: &str) -> Result<f32, String> {
    within_max_exposure(s, "")
}

/// A finite number within ±[`MAX_EXPOSURE`]; `unit` follows the range in the message.
fn within_max_exposure(s: &str, unit: &str) -> Result<f32, String> {
    match parse_finite(s)? {
        v if v.abs() <= MAX_EXPOSURE => Ok(v),
        _ => Err(format!(
            "'{s}' is out of range (-{MAX_EXPOSURE}..={MAX_EXPOSURE}{unit})"
        )),
    }
}

/// How bright the image is shown and written.
#[derive(Args, Debug, Clone, Default)]
pub struct ExposureArgs {
    /// Exposure in stops (default: automatic, metered on the subject as the image converges).
    #[arg(
        long,
        allow_negative_numbers = true,
        conflicts_with = "ev100",
        value_parser = parse_exposure
    )]
    pub exposure: Option<f32>,
    /// Physical exposure: a camera at this EV100, in EV (about 15 for a scene lit by a sun in
    /// lux) (default: automatic, as for --exposure).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_ev100)]
    pub ev100: Option<f32>,
    /// Tone curve: neutral (Khronos PBR Neutral, keeps base colours), aces or linear.
    #[arg(long, default_value = "neutral", value_parser = ToneMapper::from_arg)]
    pub tonemap: ToneMapper,
}

impl ExposureArgs {
    /// How the exposure is chosen: `--exposure`, `--ev100`, else automatically.
    pub fn mode(&self) -> ExposureMode {
        match (self.exposure, self.ev100) {
            (Some(stops), _) => ExposureMode::Manual(stops),
            (None, Some(ev)) => ExposureMode::Ev100(ev),
            (None, None) => ExposureMode::Auto,
        }
    }
}

/// Options every rendering command shares.
#[derive(Args, Debug, Clone)]
pub struct CommonArgs {
    /// The device.
    #[command(flatten)]
    pub device: DeviceArgs,
    /// The image size.
    #[command(flatten)]
    pub size: SizeArgs,
    /// Samples, bounces, seed.
    #[command(flatten)]
    pub sampling: SamplingArgs,
    /// The camera.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Light radius and hard shadows.
    #[command(flatten)]
    pub shadows: ShadowArgs,
    /// Sky and environment light.
    #[command(flatten)]
    pub env: EnvArgs,
    /// Depth of field.
    #[command(flatten)]
    pub lens: LensArgs,
    /// Exposure.
    #[command(flatten)]
    pub exposure: ExposureArgs,
    /// What escaped camera rays show: `env` (the environment), `transparent` (alpha 0 in the
    /// PNG, an A channel in the EXR) or a flat color R,G,B in 0..1 (sRGB, like #RRGGBB / 255).
    /// Lighting is the same either way.
    #[arg(
        long,
        default_value = "env",
        value_name = "env|transparent|COLOR",
        value_parser = parse_background
    )]
    pub background: Background,
    /// Kernels: wavefront (queued stages per bounce), megakernel (whole paths per work item)
    /// or auto (the megakernel on CPU devices, the wavefront elsewhere).
    #[arg(long, default_value = "auto", value_parser = parse_kernel)]
    pub kernel: KernelChoice,
    /// The `KHR_materials_variants` variant to show, by name (default: the file's default
    /// materials).
    #[arg(long, value_name = "NAME")]
    pub variant: Option<String>,
    /// Acceleration structure: flat (one BVH over every triangle), two-level (a BLAS per
    /// distinct mesh under a TLAS of instances) or auto (two levels for scenes of 4 M triangles
    /// or more that instancing shrinks eightfold, and for any of 16 M or more).
    #[arg(long, default_value = "auto")]
    pub bvh: BvhChoice,
    /// A folder whose files the scene may also read: by default a buffer or image URI must
    /// lead to a file inside the scene file's folder (docs/robustness.md)
    /// (default: the scene file's folder).
    #[arg(long, value_name = "DIR", value_parser = parse_folder)]
    pub asset_root: Option<PathBuf>,
}

/// An existing folder.
fn parse_folder(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if path.is_dir() {
        Ok(path)
    } else {
        Err(format!("'{s}' is not an existing folder"))
    }
}

fn parse_background(s: &str) -> Result<Background, String> {
    s.parse()
}

fn parse_kernel(s: &str) -> Result<KernelChoice, String> {
    s.parse()
}

impl Default for CommonArgs {
    /// The command line's defaults: what an empty command line gives.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Empty {
            #[command(flatten)]
            common: CommonArgs,
        }
        <Empty as clap::Parser>::parse_from(["penumbra"]).common
    }
}

impl CommonArgs {
    /// Opens the chosen device with the chosen kernel shape and `settings`.
    pub fn open_renderer(&self, settings: &RenderSettings) -> Result<Renderer> {
        self.open_renderer_on(&self.device_choice()?, settings)
    }

    /// Opens `device` with the chosen kernel shape and `settings`.
    pub fn open_renderer_on(
        &self,
        device: &DeviceChoice,
        settings: &RenderSettings,
    ) -> Result<Renderer> {
        let mut renderer = Renderer::new(device)?;
        renderer.set_kernel(self.kernel)?;
        renderer.set_bvh_choice(self.bvh);
        renderer.set_settings(settings)?;
        Ok(renderer)
    }

    /// The device choice from `--device` or `PENUMBRA_DEVICE`.
    pub fn device_choice(&self) -> Result<DeviceChoice> {
        self.device.device_choice()
    }

    /// Render settings for a default size; rejects absurd values.
    pub fn settings(&self, default_size: (u32, u32)) -> Result<RenderSettings> {
        let (width, height) = self.size.size(default_size)?;
        let sampling = &self.sampling;
        if sampling.bounces > MAX_BOUNCES {
            bail!(
                "--bounces {} is out of range (0..={MAX_BOUNCES})",
                sampling.bounces
            );
        }
        if sampling.spp == Some(0) {
            bail!("--spp must be at least 1");
        }
        self.shadows.check()?;
        let (env, lens) = (&self.env, &self.lens);
        for (name, v) in [
            ("--env-intensity", env.env_intensity),
            ("--aperture", lens.aperture),
            ("--focus-distance", lens.focus_distance.unwrap_or(1.0)),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                bail!("{name} {v} must be a finite number >= 0");
            }
        }
        if lens.focus_distance == Some(0.0) {
            bail!("--focus-distance must be greater than 0");
        }
        if !env.env_rotation.is_finite() {
            bail!("--env-rotation {} must be finite", env.env_rotation);
        }
        self.camera.check()?;
        Ok(RenderSettings {
            width,
            height,
            bounces: sampling.bounces,
            seed: sampling.seed,
            sky: env.sky(),
            env_intensity: env.env_intensity,
            env_rotation: env.env_rotation,
            lens_radius: lens.aperture,
            focus_distance: lens.focus_distance.unwrap_or(1.0),
            cutout: self.background.cutout(),
            count_coverage: true,
            ..RenderSettings::default()
        })
    }

    /// What `--env` asks for: a color, or an image loaded now; `None` without `--env`.
    pub fn environment(&self) -> Result<Option<EnvChoice>> {
        self.env.environment()
    }

    /// How the exposure is chosen: `--exposure`, `--ev100`, else automatically.
    pub fn exposure_mode(&self) -> ExposureMode {
        self.exposure.mode()
    }

    /// How the exposure of `prepared` is chosen: `--exposure`, `--ev100`, else by incident
    /// metering where the first view measured the light at the subject, else metered on the
    /// image.
    pub fn exposure_for(&self, prepared: &Prepared) -> ExposureMode {
        match (self.exposure_mode(), prepared.white_radiance) {
            (ExposureMode::Auto, Some(w)) => {
                ExposureMode::Incident(crate::render::exposure::incident_stops(w))
            }
            (mode, _) => mode,
        }
    }

    /// Loads the scene (or the bundled one), applies camera and light options and decides the
    /// first image: the automatic camera gives way to the first view, and the rule "the
    /// scene's lights light the view" decides the environment (`cli/first_image.rs`).
    pub fn prepare(&self, path: Option<&Path>) -> Result<Prepared> {
        let aspect = match (self.size.width, self.size.height) {
            (Some(w), Some(h)) if h > 0 => w as f64 / h as f64,
            _ => 4.0 / 3.0,
        };
        self.prepare_for(path, aspect)
    }

    /// [`CommonArgs::prepare`] for an image of this width over height (the viewer's image is
    /// the window less the overlay's panel).
    pub fn prepare_for(&self, path: Option<&Path>, aspect: f64) -> Result<Prepared> {
        let (mut scene, load_ms) = load(path, self.asset_root.as_deref())?;
        if let Some(name) = &self.variant {
            let v = scene.variant_named(name).map_err(anyhow::Error::msg)?;
            scene.select_variant(Some(v));
        }
        let mut camera = self.camera.choose(&scene)?;
        if let Some(name) = &self.camera.view {
            let Some(path) = path else {
                bail!("--view {name}: views are saved beside a scene file; give one");
            };
            let fov = camera.yfov;
            camera = crate::scene::views::find_view(path, name)?;
            if self.camera.fov.is_some() {
                camera.yfov = fov;
            }
        }
        // `--sky` alone is an explicit choice of lighting too: no automatic environment.
        let env_arg = match (&self.env.env, self.env.sky) {
            (None, Some(_)) => first_image::EnvArg::Off,
            (env, _) => first_image::EnvArg::parse(env.as_deref()),
        };
        let camera_chosen = self.camera.camera.is_some()
            || self.camera.eye.is_some()
            || self.camera.view.is_some()
            || scene.cameras[0].name != crate::scene::framing::AUTO_CAMERA;
        let own_lights = if scene.default_rig {
            Vec::new()
        } else {
            scene.lights.clone()
        };
        let t = std::time::Instant::now();
        let first = first_image::decide(
            &scene,
            &own_lights,
            camera_chosen.then_some(&camera),
            aspect,
        );
        log::info!(
            "{}: loaded in {load_ms:.0} ms, first view in {:.0} ms",
            scene.source,
            t.elapsed().as_secs_f64() * 1e3
        );
        if let Some(cost) = first.view.unprobed_cost {
            log::warn!(
                "{}: each ray would test about {cost:.0} triangles (many lie in one place); \
                 the first view frames its bounds without probing them",
                scene.source
            );
        }
        if let Some(c) = &first.camera {
            camera = c.clone();
            if let Some(fov) = self.camera.fov {
                camera.yfov = fov.to_radians();
            }
        }
        let environment = match env_arg {
            first_image::EnvArg::Auto => first_image::environment(&env_arg, first.environment),
            _ => self.environment()?,
        };
        if environment.is_some() {
            scene.drop_default_rig();
        }
        // The radiance of a white diffuse surface at the subject under the environment, as it
        // will be used: an incident meter's reading at the subject points, each facing as the
        // surface there faces (their `framing::METER_PERCENTILE`).
        let env_radiance = match &environment {
            Some(EnvChoice::Map(m)) => {
                let coarse = m.coarse(64, 32);
                let mut e: Vec<f64> = first
                    .view
                    .subject_normals
                    .iter()
                    .map(|&n| coarse.irradiance(n, self.env.env_rotation))
                    .collect();
                e.sort_by(f64::total_cmp);
                crate::scene::framing::meter_percentile(&e) / std::f64::consts::PI
            }
            Some(EnvChoice::Color(c)) => crate::render::exposure::luminance(*c) as f64,
            None => 0.0,
        } * self.env.env_intensity as f64;
        let env_scale = match env_arg {
            first_image::EnvArg::Auto => first.env_scale(env_radiance),
            _ => 1.0,
        };
        let white_radiance = first.white_radiance(env_radiance * env_scale);
        if env_arg == first_image::EnvArg::Auto {
            match first.environment {
                Some(preset) if first.fill => log::warn!(
                    "{}: its metal and glass would reflect a black world; adding the {} \
                     environment as a fill",
                    scene.source,
                    preset.name()
                ),
                Some(preset) => log::warn!(
                    "{}: its own lights do not light the view; using the {} environment",
                    scene.source,
                    preset.name()
                ),
                None => {}
            }
            if !first.lights.is_empty() {
                // The rig is placed for a view from outside; a room's lamps replace it.
                scene.drop_default_rig();
            }
            scene.lights.extend(first.lights.iter().cloned());
        }
        if scene.default_rig {
            log::warn!(
                "{} has no lights; using the default light rig",
                scene.source
            );
        }
        let mut prepared = finish(scene, camera, &self.shadows, load_ms);
        prepared.environment = environment;
        prepared.first_view = Some(first);
        prepared.env_scale = env_scale as f32;
        prepared.white_radiance = white_radiance;
        Ok(prepared)
    }
}

/// A scene ready to render: its lights with the chosen radii and the chosen camera.
pub struct Prepared {
    /// The scene.
    pub scene: Scene,
    /// Lights with radii applied.
    pub lights: Vec<Light>,
    /// The camera.
    pub camera: Camera,
    /// Loading time.
    pub load_ms: f64,
    /// The light radius rule applied to `lights`.
    pub shadows: Shadows,
    /// The environment: asked for with `--env`, or the one the first image needs
    /// ([`CommonArgs::prepare`] only).
    pub environment: Option<EnvChoice>,
    /// What the first-view analysis found ([`CommonArgs::prepare`] only).
    pub first_view: Option<first_image::FirstImage>,
    /// The factor on `--env-intensity` for an environment added as a fill (1 otherwise).
    pub env_scale: f32,
    /// The radiance of a white diffuse surface at the subject, where the first view measured
    /// it: what incident metering exposes ([`CommonArgs::exposure_for`]).
    pub white_radiance: Option<f64>,
}

/// Loads the scene at `path` (or the bundled one), its files read from its folder or
/// `asset_root`, and logs its warnings; the loading time in ms.
fn load(path: Option<&Path>, asset_root: Option<&Path>) -> Result<(Scene, f64)> {
    if let Some(p) = path {
        crate::cli::scene_file::check(p)?;
    }
    let t = std::time::Instant::now();
    let scene = load_or_bundled_with(path, asset_root)?;
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    for w in &scene.warnings {
        log::warn!("{}: {w}", scene.source);
    }
    Ok((scene, load_ms))
}

/// Sizes the lights of `scene` by the light radius rule.
fn finish(scene: Scene, camera: Camera, shadows: &ShadowArgs, load_ms: f64) -> Prepared {
    let bounds = scene.bounds();
    let shadows = Shadows::new(shadows.light_radius, shadows.hard_shadows, &bounds);
    let lights = shadows.apply(&scene.lights, bounds.diagonal());
    Prepared {
        scene,
        lights,
        camera,
        load_ms,
        shadows,
        environment: None,
        first_view: None,
        env_scale: 1.0,
        white_radiance: None,
    }
}

/// Loads the scene at `path` (or the bundled one), chooses its camera and sizes its lights;
/// `environment`: an environment light (`--env`) replaces the default light rig.
pub fn prepare(
    path: Option<&Path>,
    camera: &CameraArgs,
    shadows: &ShadowArgs,
    environment: bool,
) -> Result<Prepared> {
    let (mut scene, load_ms) = load(path, None)?;
    if scene.default_rig && !environment {
        log::warn!(
            "{} has no lights; using the default light rig",
            scene.source
        );
    }
    let camera = camera.choose(&scene)?;
    if environment {
        scene.drop_default_rig();
    }
    Ok(finish(scene, camera, shadows, load_ms))
}

/// How paths are sampled (`render`, `bench frame`).
#[derive(Args, Debug, Clone)]
pub struct StrategyArgs {
    /// Direct-light strategy.
    #[arg(long, value_enum, default_value_t = StrategyArg::Mis)]
    pub strategy: StrategyArg,
    /// Disable Russian roulette (default: off, paths end by Russian roulette).
    #[arg(long)]
    pub no_russian_roulette: bool,
}

impl StrategyArgs {
    /// Applies the strategy and Russian roulette choice to `settings`.
    pub fn apply(&self, settings: &mut RenderSettings) {
        settings.strategy = self.strategy.into();
        if self.no_russian_roulette {
            settings.russian_roulette = None;
        }
    }
}

/// `--strategy` values.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrategyArg {
    /// Light and BSDF sampling with multiple importance sampling.
    Mis,
    /// BSDF sampling only.
    Bsdf,
    /// Light sampling only.
    Lights,
}

impl From<StrategyArg> for Strategy {
    fn from(s: StrategyArg) -> Self {
        match s {
            StrategyArg::Mis => Strategy::Mis,
            StrategyArg::Bsdf => Strategy::Bsdf,
            StrategyArg::Lights => Strategy::Lights,
        }
    }
}

fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not a point: use X,Y,Z"))?;
    match parts.as_slice() {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(format!("'{s}' is not a point: use X,Y,Z")),
    }
}

fn parse_color(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{s}' is not a color: use R,G,B or one number"))?;
    let c = match parts.as_slice() {
        [v] => [*v; 3],
        [r, g, b] => [*r, *g, *b],
        _ => return Err(format!("'{s}' is not a color: use R,G,B or one number")),
    };
    if c.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(format!(
            "'{s}': color values must be finite and not negative"
        ));
    }
    if c.iter().any(|v| *v > MAX_INTENSITY) {
        return Err(format!(
            "'{s}': color values must be at most {MAX_INTENSITY:e}"
        ));
    }
    Ok(c)
}

/// An `--env` value: a list of numbers must be a valid color (checked here, a usage error);
/// anything else is a name or a file, checked when it is loaded.
fn parse_env(s: &str) -> Result<String, String> {
    if s.split(',').all(|p| p.trim().parse::<f32>().is_ok()) {
        parse_color(s)?;
    }
    Ok(s.to_string())
}

/// A radiance scale: finite, ≥ 0 and at most [`MAX_INTENSITY`], so that a scaled environment
/// texel (itself at most that) stays far from f32's overflow.
fn parse_intensity(s: &str) -> Result<f32, String> {
    match parse_non_negative(s)? {
        v if v <= MAX_INTENSITY => Ok(v),
        _ => Err(format!("'{s}' is out of range (0..={MAX_INTENSITY:e})")),
    }
}

/// A finite number (NaN and ±inf are refused).
pub(crate) fn parse_finite(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{s}' is not a finite number")),
    }
}

/// A finite number ≥ 0.
fn parse_non_negative(s: &str) -> Result<f32, String> {
    match parse_finite(s)? {
        v if v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}' must be a finite number >= 0")),
    }
}

/// A finite number > 0.
pub(crate) fn parse_positive(s: &str) -> Result<f32, String> {
    match parse_finite(s)? {
        v if v > 0.0 => Ok(v),
        _ => Err(format!("'{s}' must be a finite number > 0")),
    }
}

/// A vertical field of view in degrees, strictly between 0 and 180.
fn parse_fov(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v < 180.0 => Ok(v),
        _ => Err(format!("'{s}' is not a field of view in degrees (0..180)")),
    }
}

/// A duration in seconds: finite and > 0.
pub(crate) fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "'{s}' is not a duration in seconds (a finite number > 0)"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vectors_parse() {
        assert_eq!(parse_vec3("-278, 273,800"), Ok([-278.0, 273.0, 800.0]));
        assert!(parse_vec3("1,2").is_err());
        assert!(parse_vec3("1,nan,2").is_err());
    }

    #[test]
    fn colors_parse_or_fail_clearly() {
        assert_eq!(parse_color("0.5").unwrap(), [0.5; 3]);
        assert_eq!(parse_color("1,2,3").unwrap(), [1.0, 2.0, 3.0]);
        assert!(parse_color("1,2").is_err());
        assert!(parse_color("-1").is_err());
        assert!(parse_color("nan").is_err());
    }
}
