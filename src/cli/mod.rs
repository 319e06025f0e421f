//! The command line: `view` (default), `render`, `devices`, `bench`.

pub mod bench;
mod devices;
mod render;

use crate::cl::DeviceChoice;
use crate::render::{RenderSettings, Strategy};
use crate::scene::{Camera, EnvMap, Light, Scene, Shadows, load_or_bundled};
use anyhow::{Result, bail};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// penumbra: an interactive OpenCL path tracer for glTF scenes.
#[derive(Parser, Debug)]
#[command(name = "penumbra", version, args_conflicts_with_subcommands = true)]
pub struct Cli {
    /// What to do; without a command, the viewer opens.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Viewer options when no command is given.
    #[command(flatten)]
    pub view: ViewArgs,
}

/// The commands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the interactive viewer (the default).
    View(ViewArgs),
    /// Render a scene headless to an image; prints a JSON summary on stdout.
    Render(RenderArgs),
    /// List OpenCL platforms and devices with the index --device takes.
    Devices,
    /// Benchmarks: ray throughput and error against time.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

/// Options every rendering command shares.
#[derive(Args, Debug, Clone)]
pub struct CommonArgs {
    /// OpenCL device: gpu, cpu or an index from `penumbra devices` (default: first GPU, else
    /// first CPU; also PENUMBRA_DEVICE).
    #[arg(long)]
    pub device: Option<String>,
    /// Image width in pixels.
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height in pixels.
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel.
    #[arg(long)]
    pub spp: Option<u32>,
    /// Bounces after the first hit (0 = direct light only).
    #[arg(long, default_value_t = RenderSettings::default().bounces)]
    pub bounces: u32,
    /// Seed of the random sequence.
    #[arg(long, default_value_t = RenderSettings::default().seed)]
    pub seed: u32,
    /// Camera of the glTF file to use (index; the automatic camera when the file has none).
    #[arg(long)]
    pub camera: Option<usize>,
    /// Radius of point and spot lights in scene units (soft shadows); default 2% of the
    /// scene's diagonal. Directional lights get an angular radius of 2·R/diagonal radians.
    #[arg(long, allow_negative_numbers = true)]
    pub light_radius: Option<f32>,
    /// Hard shadows: every light radius 0.
    #[arg(long, conflicts_with = "light_radius")]
    pub hard_shadows: bool,
    /// Uniform sky radiance as R,G,B (or one value for gray); default black.
    #[arg(long, value_parser = parse_color)]
    pub sky: Option<[f32; 3]>,
    /// Environment light: an equirectangular .hdr or .exr image (importance-sampled), or a
    /// uniform color R,G,B / gray value (like --sky). Either replaces the default light rig.
    #[arg(long, value_name = "FILE|COLOR", conflicts_with = "sky")]
    pub env: Option<String>,
    /// Radiance scale of the --env image.
    #[arg(long, default_value_t = RenderSettings::default().env_intensity)]
    pub env_intensity: f32,
    /// Rotation of the --env image about the up (+Y) axis in degrees, counter-clockwise seen
    /// from above.
    #[arg(
        long,
        default_value_t = RenderSettings::default().env_rotation,
        allow_negative_numbers = true
    )]
    pub env_rotation: f32,
    /// Depth of field: thin-lens radius in scene units (0 = pinhole, everything sharp).
    #[arg(long, default_value_t = RenderSettings::default().lens_radius)]
    pub aperture: f32,
    /// Distance from the eye to the plane in focus, along the view axis, in scene units
    /// (default: the distance to what the image centre sees).
    #[arg(long)]
    pub focus_distance: Option<f32>,
    /// Camera position X,Y,Z (replaces the file's camera; use with --look-at).
    #[arg(long, value_parser = parse_vec3, allow_negative_numbers = true, requires = "look_at")]
    pub eye: Option<[f64; 3]>,
    /// Point the camera looks at, X,Y,Z (use with --eye).
    #[arg(long, value_parser = parse_vec3, allow_negative_numbers = true, requires = "eye")]
    pub look_at: Option<[f64; 3]>,
    /// Vertical field of view in degrees (default: the camera's).
    #[arg(long)]
    pub fov: Option<f64>,
}

impl Default for CommonArgs {
    /// The command line's defaults: what an empty command line gives.
    fn default() -> Self {
        #[derive(Parser)]
        struct Empty {
            #[command(flatten)]
            common: CommonArgs,
        }
        Empty::parse_from(["penumbra"]).common
    }
}

/// What `--env` asked for.
pub enum EnvChoice {
    /// A uniform radiance.
    Color([f32; 3]),
    /// An environment image.
    Map(EnvMap),
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

/// Options of the viewer.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// glTF or GLB file; the bundled Cornell box when absent.
    pub scene: Option<PathBuf>,
    /// Shared options.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Exit after this many frames (for tests).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Save the final frame to this PNG path on exit (for tests); an EXR beside it.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
}

/// Options of `render`.
#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// glTF or GLB file.
    pub scene: PathBuf,
    /// Output image: .exr (linear radiance) or .png (tone-mapped sRGB). Overwritten if present.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Shared options.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Sampling options.
    #[command(flatten)]
    pub sampling: SamplingArgs,
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
}

/// How paths are sampled (`render`, `bench frame`).
#[derive(Args, Debug, Clone)]
pub struct SamplingArgs {
    /// Direct-light strategy.
    #[arg(long, value_enum, default_value_t = StrategyArg::Mis)]
    pub strategy: StrategyArg,
    /// Disable Russian roulette.
    #[arg(long)]
    pub no_russian_roulette: bool,
}

impl SamplingArgs {
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
    Ok(c)
}

/// The largest image side accepted.
pub const MAX_SIDE: u32 = 16384;
/// The most bounces accepted.
pub const MAX_BOUNCES: u32 = 256;

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
}

impl CommonArgs {
    /// The device choice from `--device` or `PENUMBRA_DEVICE`.
    pub fn device_choice(&self) -> Result<DeviceChoice> {
        DeviceChoice::from_arg_or_env(self.device.as_deref()).map_err(anyhow::Error::msg)
    }

    /// Render settings for a default size; rejects absurd values.
    pub fn settings(&self, default_size: (u32, u32)) -> Result<RenderSettings> {
        let width = self.width.unwrap_or(default_size.0);
        let height = self.height.unwrap_or(default_size.1);
        for (name, v) in [("--width", width), ("--height", height)] {
            if v == 0 || v > MAX_SIDE {
                bail!("{name} {v} is out of range (1..={MAX_SIDE})");
            }
        }
        if self.bounces > MAX_BOUNCES {
            bail!(
                "--bounces {} is out of range (0..={MAX_BOUNCES})",
                self.bounces
            );
        }
        if self.spp == Some(0) {
            bail!("--spp must be at least 1");
        }
        if let Some(r) = self.light_radius
            && !(r.is_finite() && r >= 0.0)
        {
            bail!("--light-radius {r} must be a finite number >= 0");
        }
        for (name, v) in [
            ("--env-intensity", self.env_intensity),
            ("--aperture", self.aperture),
            ("--focus-distance", self.focus_distance.unwrap_or(1.0)),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                bail!("{name} {v} must be a finite number >= 0");
            }
        }
        if self.focus_distance == Some(0.0) {
            bail!("--focus-distance must be greater than 0");
        }
        if !self.env_rotation.is_finite() {
            bail!("--env-rotation {} must be finite", self.env_rotation);
        }
        if let Some(f) = self.fov
            && !(f > 0.0 && f < 180.0)
        {
            bail!("--fov {f} is out of range (0..180 degrees)");
        }
        let sky = match self.env.as_deref().map(parse_color) {
            Some(Ok(c)) => c,
            _ => self.sky.unwrap_or([0.0; 3]),
        };
        Ok(RenderSettings {
            width,
            height,
            bounces: self.bounces,
            seed: self.seed,
            sky,
            env_intensity: self.env_intensity,
            env_rotation: self.env_rotation,
            lens_radius: self.aperture,
            focus_distance: self.focus_distance.unwrap_or(1.0),
            ..RenderSettings::default()
        })
    }

    /// What `--env` asks for: a color, or an image loaded now; `None` without `--env`.
    pub fn environment(&self) -> Result<Option<EnvChoice>> {
        let Some(arg) = self.env.as_deref() else {
            return Ok(None);
        };
        if let Ok(c) = parse_color(arg) {
            return Ok(Some(EnvChoice::Color(c)));
        }
        let path = std::path::Path::new(arg);
        if !path.is_file() {
            bail!("--env {arg}: neither a color (R,G,B) nor an existing .hdr/.exr file");
        }
        Ok(Some(EnvChoice::Map(
            EnvMap::load(path).map_err(anyhow::Error::msg)?,
        )))
    }

    /// Loads the scene (or the bundled one) and applies camera and light options.
    pub fn prepare(&self, path: Option<&std::path::Path>) -> Result<Prepared> {
        let t = std::time::Instant::now();
        let scene = load_or_bundled(path)?;
        let load_ms = t.elapsed().as_secs_f64() * 1e3;
        for w in &scene.warnings {
            log::warn!("{}: {w}", scene.source);
        }
        if scene.default_rig && self.env.is_none() {
            eprintln!(
                "penumbra: {} has no lights; using the default light rig",
                scene.source
            );
        }
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
            if (target - eye).length() < 1e-12 {
                bail!("--eye and --look-at are the same point");
            }
            camera = Camera::look_at("command line", eye, target, camera.yfov);
        }
        if let Some(fov) = self.fov {
            camera.yfov = fov.to_radians();
        }
        let mut scene = scene;
        if self.env.is_some() && scene.default_rig {
            // The environment lights the scene instead of the default rig.
            scene.lights.clear();
            scene.default_rig = false;
        }
        let bounds = scene.bounds();
        let shadows = Shadows::new(self.light_radius, self.hard_shadows, &bounds);
        let lights = shadows.apply(&scene.lights, bounds.diagonal());
        Ok(Prepared {
            scene,
            lights,
            camera,
            load_ms,
            shadows,
        })
    }
}

/// Runs the command line; errors come back as one line for `main` to print.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => view(cli.view),
        Some(Command::View(v)) => view(v),
        Some(Command::Render(r)) => render::run(&r),
        Some(Command::Devices) => devices::run(),
        Some(Command::Bench(b)) => bench::run(b),
    }
}

/// Opens the viewer: checks the options, loads the scene and hands the viewer its
/// configuration.
fn view(args: ViewArgs) -> Result<()> {
    use crate::app::{DEFAULT_SIZE, ViewerConfig};
    // Without a display nothing else is worth loading.
    crate::app::preflight(args.screenshot.as_deref())?;
    let common = &args.common;
    let settings = common.settings(DEFAULT_SIZE)?;
    let prepared = common.prepare(args.scene.as_deref())?;
    let environment = common.environment()?;
    let device = common.device_choice()?;
    // With a lens but no focus distance, focus on what the image centre sees once loaded.
    let autofocus = settings.lens_radius > 0.0 && common.focus_distance.is_none();
    crate::app::run(ViewerConfig {
        path: args.scene,
        scene: prepared.scene,
        lights: prepared.lights,
        shadows: prepared.shadows,
        camera: prepared.camera,
        load_ms: prepared.load_ms,
        settings,
        spp_target: common.spp,
        device,
        env_map: match environment {
            Some(EnvChoice::Map(map)) => Some(map),
            _ => None,
        },
        env_lights: common.env.is_some(),
        autofocus,
        frames: args.frames,
        screenshot: args.screenshot,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// clap's own consistency checks (unique names, valid `requires` and `conflicts_with`);
    /// release builds skip them at run time, so a duplicate option would go unnoticed.
    #[test]
    fn the_command_line_definition_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }

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

    #[test]
    fn absurd_settings_are_rejected() {
        let cli = Cli::parse_from(["penumbra", "render", "a.glb", "-o", "x.exr", "--width", "0"]);
        let Some(Command::Render(r)) = cli.command else {
            panic!("not a render command")
        };
        assert!(r.common.settings((64, 64)).is_err());
    }
}
