//! The command line: `view` (default), `render`, `merge`, `devices`, `bench`.

pub mod animate;
mod devices;
pub mod first_image;
mod merge;
pub mod messages;
mod render;
pub mod scene_file;

use crate::args::{CommonArgs, EnvChoice, StrategyArgs};
use crate::bench;
use anyhow::Result;
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
    /// Add up shards (`render --sample-start … -o SHARD.exr`) into one image, bit for bit the
    /// render of all their samples.
    Merge(MergeArgs),
    /// List OpenCL platforms and devices with the index --device takes.
    Devices,
    /// Benchmarks: ray throughput and error against time.
    #[command(subcommand)]
    Bench(bench::BenchCommand),
}

/// Options of the viewer.
#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// glTF or GLB file; the bundled Cornell box when absent.
    pub scene: Option<PathBuf>,
    /// Shared options.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Exit after this many frames, for tests (default: run until the window closes).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Save the final frame to this PNG path on exit, an EXR beside it, for tests (default:
    /// none; F12 saves screenshots in screenshots/).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Start with the overlay hidden: the image fills the window; Tab shows it (default: off).
    #[arg(long)]
    pub no_overlay: bool,
    /// Append one JSON line per image shown to this file (its size, samples, exposure, and for
    /// the first image after an input the latency from the input in ms), for scripts and tests
    /// (default: none).
    #[arg(long, value_name = "PATH")]
    pub stats_file: Option<PathBuf>,
    /// Start with adaptive sampling at this noise threshold, as the overlay's adaptive box sets
    /// it (M shows its heat maps) (default: off).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::parse_positive)]
    pub noise_threshold: Option<f32>,
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
    /// Direct-light strategy and Russian roulette.
    #[command(flatten)]
    pub strategy: StrategyArgs,
    /// Adaptive sampling: a pixel stops taking samples once its relative error is under this
    /// (0.01 is clean, 0.1 rough); --spp is then the most a pixel takes (default: off).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::parse_positive)]
    pub noise_threshold: Option<f32>,
    /// How --noise-threshold judges a pixel: `error` (its relative error under the threshold,
    /// Cycles' rule) or `cost` (under the threshold times √(rays its samples traced / the
    /// minimum samples): expensive pixels stop sooner; docs/adaptive-sampling.md).
    #[arg(
        long,
        value_name = "RULE",
        default_value = "error",
        requires = "noise_threshold"
    )]
    pub adaptive_rule: crate::render::AdaptiveRule,
    /// Stop after this many seconds of rendering, wall clock; --spp is then the most a pixel
    /// takes (default: none).
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::parse_seconds)]
    pub time_limit: Option<f64>,
    /// Also write guide buffers for a denoiser as layers of the EXR output: albedo.R/G/B,
    /// normal.X/Y/Z, depth.Z, and with --noise-threshold samples.Y and error.Y; needs an .exr
    /// output (default: off).
    #[arg(long)]
    pub aovs: bool,
    /// Render samples K … K+spp−1 of the random sequence: a shard, whose .exr holds the exact
    /// sums `penumbra merge` adds up (docs/farm.md) (default: 0, a plain image).
    #[arg(
        long,
        value_name = "K",
        conflicts_with_all = ["noise_threshold", "time_limit"]
    )]
    pub sample_start: Option<u32>,
    /// After the samples, denoise the image with Open Image Denoise's network on the device
    /// (the guide buffers are kept for it): an .exr keeps the raw image and adds
    /// denoised.R/G/B, a .png is the denoised image (default: off).
    #[arg(long, conflicts_with = "sample_start")]
    pub denoise: bool,
    /// The denoiser's network: full, small (about a third of the work, a little less sharp),
    /// or large (prefilters the albedo and normal guides, then a network about 5 times the
    /// full one's work: closer to the converged image) (default: full).
    #[arg(
        long,
        value_name = "NETWORK",
        default_value = "full",
        requires = "denoise"
    )]
    pub denoiser: crate::denoise::Quality,
    /// Animation: the instant or the frames rendered.
    #[command(flatten)]
    pub animation: animate::AnimationArgs,
}

/// Options of `merge`.
#[derive(Args, Debug, Clone)]
pub struct MergeArgs {
    /// Shard EXRs of `render --sample-start`, in any order.
    #[arg(required = true, value_name = "SHARD")]
    pub shards: Vec<PathBuf>,
    /// Output image: .exr (itself a shard of all the samples) or .png (tone-mapped as render
    /// writes it). Overwritten if present.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// A command-line usage error found after parsing, such as options that do not go together
/// with several devices: `main` exits with code 2, as for clap's.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// One line for a command-line usage error (`penumbra: error: …`, exit code 2): clap's first
/// line without its `error: ` prefix, and where to find the usage.
pub fn usage_error(e: &clap::Error) -> String {
    // clap's first paragraph says what is wrong; tips and the usage follow a blank line.
    let rendered = e.render().to_string();
    let what: Vec<&str> = rendered
        .lines()
        .map(str::trim)
        .skip_while(|l| l.is_empty())
        .take_while(|l| !l.is_empty())
        .collect();
    let what = what.join(" ");
    let what = what.strip_prefix("error: ").unwrap_or(&what);
    if what.is_empty() {
        return "invalid command line (see penumbra --help)".into();
    }
    format!("{what} (see penumbra --help)")
}

/// Runs the command line; errors come back as one line for `main` to print.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => view(cli.view),
        Some(Command::View(v)) => view(v),
        Some(Command::Render(r)) => render::run(&r),
        Some(Command::Merge(m)) => merge::run(&m),
        Some(Command::Devices) => devices::run(),
        Some(Command::Bench(b)) => bench::run(b),
    }
}

/// Opens the viewer: checks the options, loads the scene and hands the viewer its
/// configuration.
fn view(args: ViewArgs) -> Result<()> {
    use crate::app::{DEFAULT_SIZE, ViewerConfig};
    // The scene file is the user's first concern: a missing one is reported as missing even
    // without a display. Without a display nothing else is worth loading.
    if let Some(scene) = &args.scene {
        scene_file::check(scene)?;
    }
    crate::app::preflight(args.screenshot.as_deref())?;
    let common = &args.common;
    let mut settings = common.settings(DEFAULT_SIZE)?;
    settings.noise_threshold = args.noise_threshold;
    let aspect = crate::app::image_aspect((settings.width, settings.height), !args.no_overlay);
    let mut prepared = common.prepare_for(args.scene.as_deref(), aspect)?;
    settings.env_intensity *= prepared.env_scale;
    let exposure = common.exposure_for(&prepared);
    // The first view knows an interior; a camera of the file's (or the command line's) counts
    // as inside one when it stands within the scene's bounds.
    let interior = match &prepared.first_view {
        Some(f) => f.view.interior,
        None => {
            let (b, eye) = (prepared.scene.bounds(), prepared.camera.eye);
            eye.cmpge(b.min).all() && eye.cmple(b.max).all()
        }
    };
    let environment = prepared.environment.take();
    // The viewer renders on one device: of several, the first GPU (else the first device).
    let devices = common.device.device_set()?;
    let device = devices.primary();
    if !matches!(devices, crate::cl::DeviceSet::One(_)) {
        let given = common
            .device
            .device
            .as_deref()
            .unwrap_or("(PENUMBRA_DEVICE)");
        let which = match &device {
            crate::cl::DeviceChoice::Index(i) => format!("device {i}"),
            _ => "the first GPU, else the first device".into(),
        };
        crate::message::print(
            "note",
            &format!(
                "--device {given}: the viewer renders on one device, {which} (a list's first \
                 GPU, else its first device); `penumbra render` renders on them all"
            ),
        );
    }
    // With a lens but no focus distance, focus on what the image centre sees once loaded.
    let autofocus = settings.lens_radius > 0.0 && common.lens.focus_distance.is_none();
    crate::app::run(ViewerConfig {
        path: args.scene,
        scene: prepared.scene,
        lights: prepared.lights,
        shadows: prepared.shadows,
        camera: prepared.camera,
        load_ms: prepared.load_ms,
        settings,
        spp_target: common.sampling.spp,
        device,
        env_lights: environment.is_some(),
        kernel: common.kernel,
        bvh: common.bvh,
        env_map: match environment {
            Some(EnvChoice::Map(map)) => Some(map),
            _ => None,
        },
        exposure,
        tone_mapper: common.exposure.tonemap,
        background: common.background,
        autofocus,
        frames: args.frames,
        screenshot: args.screenshot,
        overlay: !args.no_overlay,
        stats_file: args.stats_file,
        interior,
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

    /// The help states the defaults the code uses: the sizes and spp of `render` and the
    /// viewer.
    #[test]
    fn the_help_states_the_defaults_in_use() {
        use clap::CommandFactory;
        let command = Cli::command();
        let render = command.find_subcommand("render").expect("render");
        let help = |name: &str| {
            let arg = render.get_arguments().find(|a| a.get_id() == name);
            arg.and_then(|a| a.get_help()).map(|h| h.to_string())
        };
        let (view_size, render_size) = (crate::app::DEFAULT_SIZE, render::DEFAULT_SIZE);
        let width = format!(
            "default: {} for render, {} for the viewer",
            render_size.0, view_size.0
        );
        let height = format!(
            "default: {} for render, {} for the viewer",
            render_size.1, view_size.1
        );
        let spp = format!("default: {} for render", render::DEFAULT_SPP);
        for (name, expect) in [("width", width), ("height", height), ("spp", spp)] {
            let help = help(name).unwrap_or_default();
            assert!(help.contains(&expect), "--{name}: {help}");
        }
    }

    #[test]
    fn absurd_settings_are_rejected() {
        // Out-of-range sizes and counts are usage errors from clap itself (exit 2).
        for args in [["--width", "0"], ["--spp", "0"], ["--bounces", "100000"]] {
            let line = [
                "penumbra", "render", "a.glb", "-o", "x.exr", args[0], args[1],
            ];
            let e = Cli::try_parse_from(line).expect_err("out of range");
            assert_eq!(e.exit_code(), 2, "{args:?}");
        }
    }

    #[test]
    fn denoise_takes_a_network_and_refuses_shards() {
        let render = |extra: &[&str]| {
            let mut line = vec!["penumbra", "render", "a.glb", "-o", "x.exr"];
            line.extend_from_slice(extra);
            Cli::try_parse_from(line)
        };
        let quality = |extra: &[&str]| match render(extra).expect("parses").command {
            Some(Command::Render(r)) => (r.denoise, r.denoiser),
            other => panic!("not a render: {other:?}"),
        };
        use crate::denoise::Quality;
        assert_eq!(quality(&[]), (false, Quality::Full));
        assert_eq!(quality(&["--denoise"]), (true, Quality::Full));
        assert_eq!(
            quality(&["--denoise", "--denoiser", "small"]),
            (true, Quality::Small)
        );
        // A shard holds sums that only a merge makes an image of: nothing to denoise yet.
        let e = render(&["--denoise", "--sample-start", "0"]).expect_err("a shard");
        assert_eq!(e.kind(), clap::error::ErrorKind::ArgumentConflict);
        assert_eq!(e.exit_code(), 2);
        let line = usage_error(&e);
        assert!(
            line.contains("--denoise") && line.contains("--sample-start") && !line.contains('\n'),
            "{line}"
        );
        // A network without --denoise, or one that does not exist, is a usage error too.
        for extra in [
            &["--denoiser", "small"][..],
            &["--denoise", "--denoiser", "huge"],
        ] {
            let e = render(extra).expect_err("refused");
            assert_eq!(e.exit_code(), 2, "{extra:?}");
        }
    }
}
