//! `penumbra bench converge SCENE --reference REF.exr`: error against run time.
//!
//! For each configuration (direct-light strategy × Russian roulette) the film is cleared and
//! rendered progressively; at every power of two of samples per pixel the wall time of the
//! renders so far, their kernel time, and the RMSE and relMSE of the image against the
//! reference are recorded. An unbiased estimator's MSE falls as 1/time: slope −1 on log–log
//! axes. A curve that flattens is bias (or a reference that does not match the render).

use super::curve::{Curve, Step, time_to};
use super::stats::{ImageError, image_error};
use super::{device_json, device_line, plot};
use crate::args::CommonArgs;
use crate::cpu_time::process_cpu_seconds;
use crate::date::today;
use crate::denoise::{Denoiser, Quality};
use crate::image_io::read_exr;
use crate::render::{AdaptiveRule, RenderSettings, Strategy, min_samples};
use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `bench converge`.
#[derive(Args, Debug, Clone)]
pub struct ConvergeArgs {
    /// glTF or GLB file; the bundled Cornell box when absent.
    pub scene: Option<PathBuf>,
    /// Reference image (linear EXR) of the same scene, camera and bounces, e.g. from
    /// `penumbra render --spp 65536` or scripts/mitsuba_reference.py. Its size is the
    /// render size unless --width/--height are given (they must then match).
    #[arg(long)]
    pub reference: PathBuf,
    /// Shared options (`--spp` is the most samples per pixel, default 1024).
    #[command(flatten)]
    pub common: CommonArgs,
    /// Configurations, comma-separated: mis, bsdf, lights, each optionally with "+rr"
    /// (Russian roulette from bounce 3); default all six.
    #[arg(long, value_delimiter = ',', value_parser = parse_config)]
    pub configs: Vec<Config>,
    /// Stop a configuration after the step that passes this many seconds of rendering.
    #[arg(long, default_value_t = 60.0, value_parser = crate::args::parse_seconds)]
    pub max_seconds: f64,
    /// Fit the slopes over the steps with at least this many samples per pixel.
    #[arg(long, default_value_t = 4)]
    pub fit_from: u32,
    /// Leave out the punctual lights (the file's and the default rig), so that all light comes
    /// from emissive geometry, which every strategy reaches (BSDF sampling never hits a
    /// punctual light).
    #[arg(long)]
    pub no_punctual: bool,
    /// Also run each configuration with adaptive sampling at this noise threshold
    /// (`render --noise-threshold`), as a curve of its own named "CONFIG+adaptive".
    #[arg(long, value_parser = crate::args::parse_positive)]
    pub adaptive: Option<f32>,
    /// The adaptive curve's rule (`render --adaptive-rule`): error or cost.
    #[arg(
        long,
        value_name = "RULE",
        default_value = "error",
        requires = "adaptive"
    )]
    pub adaptive_rule: AdaptiveRule,
    /// Also denoise each step's image as `render --denoise` does, as a curve of its own named
    /// "CONFIG+denoise" whose time adds that one denoising to the renders'. Both curves then
    /// render with the guide buffers on.
    #[arg(long)]
    pub denoise: bool,
    /// The denoiser's network with --denoise: full, small or large.
    #[arg(
        long,
        value_name = "NETWORK",
        default_value = "full",
        requires = "denoise"
    )]
    pub denoiser: Quality,
    /// Write the steps as CSV here.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write a log-log plot of relMSE against time here (PNG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Title line of the plot (default: the scene's file name).
    #[arg(long)]
    pub title: Option<String>,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// One sampling configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// Direct-light strategy.
    pub strategy: Strategy,
    /// Russian roulette on.
    pub russian_roulette: bool,
}

impl Config {
    /// Every configuration, in the order they are plotted.
    pub const ALL: [Config; 6] = [
        Config::new(Strategy::Mis, false),
        Config::new(Strategy::Mis, true),
        Config::new(Strategy::Lights, false),
        Config::new(Strategy::Lights, true),
        Config::new(Strategy::Bsdf, false),
        Config::new(Strategy::Bsdf, true),
    ];

    const fn new(strategy: Strategy, russian_roulette: bool) -> Self {
        Self {
            strategy,
            russian_roulette,
        }
    }

    /// "mis", "lights+rr", ...
    pub fn name(&self) -> String {
        let s = match self.strategy {
            Strategy::Mis => "mis",
            Strategy::Bsdf => "bsdf",
            Strategy::Lights => "lights",
        };
        if self.russian_roulette {
            format!("{s}+rr")
        } else {
            s.to_string()
        }
    }
}

fn parse_config(s: &str) -> Result<Config, String> {
    Config::ALL
        .into_iter()
        .find(|c| c.name() == s.trim())
        .ok_or_else(|| {
            format!("'{s}' is not a configuration (mis, bsdf, lights, each optionally +rr)")
        })
}

/// Runs the benchmark.
pub fn run(args: &ConvergeArgs) -> Result<()> {
    let (ref_w, ref_h, reference) = read_exr(&args.reference)?;
    if args.common.size.width.is_some_and(|w| w != ref_w)
        || args.common.size.height.is_some_and(|h| h != ref_h)
    {
        bail!(
            "{}: the reference is {ref_w}×{ref_h}, not the --width/--height given",
            args.reference.display()
        );
    }
    let mut settings = args.common.settings((ref_w, ref_h))?;
    settings.aovs = args.denoise;
    let max_spp = args.common.sampling.spp.unwrap_or(1024);
    let configs = if args.configs.is_empty() {
        Config::ALL.to_vec()
    } else {
        args.configs.clone()
    };
    let mut prepared = args.common.prepare(args.scene.as_deref())?;
    let source = prepared.scene.source.clone();
    if args.no_punctual {
        prepared.lights.clear();
    }
    if !prepared.lights.is_empty() && configs.iter().any(|c| c.strategy == Strategy::Bsdf) {
        log::warn!(
            "{source} has {} punctual light(s), which BSDF sampling never reaches: \
             the bsdf curves will flatten (bias); --no-punctual leaves them out",
            prepared.lights.len()
        );
    }

    let mut renderer = args.common.open_renderer(&settings)?;
    // The environment map lights the scene as it does in `render` (the references come from
    // `render`).
    if let Some(crate::args::EnvChoice::Map(map)) = prepared.environment.take() {
        renderer.set_environment(Some(map))?;
    }
    let scene_stats = renderer
        .load_scene(&prepared.scene, &prepared.lights)
        .with_context(|| source.clone())?;
    if renderer.host_scene().is_some_and(|h| h.emissive.is_empty())
        && prepared.lights.is_empty()
        && renderer.environment().is_none()
    {
        bail!("{source}: no light is left (no emissive triangles and --no-punctual)");
    }
    renderer.set_camera(&prepared.camera)?;
    let mut denoiser = args
        .denoise
        .then(|| Denoiser::new(&renderer.device, args.denoiser))
        .transpose()?;
    // Warm up: buffers, kernel caches, device clocks (and the denoiser's tensors).
    renderer.render(1)?;
    if let Some(threshold) = args.adaptive {
        // And the convergence check's kernels, whose first launch PoCL compiles (about 0.2 s,
        // which the first adaptive curve would otherwise carry).
        renderer.set_settings(&RenderSettings {
            noise_threshold: Some(threshold),
            adaptive_rule: args.adaptive_rule,
            ..settings.clone()
        })?;
        renderer.render(min_samples(threshold))?;
    }
    if let Some(d) = denoiser.as_mut() {
        denoise(&mut renderer, d)?;
    }

    let base_seed = settings.seed;
    let mut curves = Vec::new();
    // Each configuration uniform, then adaptive when asked (the same seed: the same samples
    // until pixels converge).
    let thresholds: Vec<Option<f32>> = std::iter::once(None)
        .chain(args.adaptive.map(Some))
        .collect();
    let runs = configs
        .iter()
        .enumerate()
        .flat_map(|(ci, config)| thresholds.iter().map(move |t| (ci, config, *t)));
    for (ci, config, threshold) in runs {
        settings.strategy = config.strategy;
        settings.russian_roulette = config.russian_roulette.then_some(3);
        settings.seed = base_seed.wrapping_add(ci as u32 + 1);
        settings.noise_threshold = threshold;
        settings.adaptive_rule = args.adaptive_rule;
        renderer.set_settings(&settings)?;
        let name = match threshold {
            Some(_) => format!("{}+adaptive", config.name()),
            None => config.name(),
        };
        let mut steps = Vec::new();
        let mut denoised_steps = Vec::new();
        let mut seconds = 0.0;
        let mut cpu_seconds = 0.0;
        let mut spp = 0;
        let mut next = 1;
        // An adaptive render ends where no pixel is left active.
        while spp < max_spp && seconds <= args.max_seconds && renderer.active_pixels() != Some(0) {
            let (start, cpu_start) = (Instant::now(), process_cpu_seconds());
            renderer.render(next - spp)?;
            seconds += start.elapsed().as_secs_f64();
            if let (Some(a), Some(b)) = (cpu_start, process_cpu_seconds()) {
                cpu_seconds += b - a;
            }
            spp = next;
            let kernel_seconds = renderer.stats().kernel_ms() * 1e-3;
            let ImageError { rmse, relmse } = image_error(&renderer.image()?, &reference);
            steps.push(Step {
                spp,
                seconds,
                kernel_seconds,
                cpu_seconds,
                rmse,
                relmse,
            });
            if let Some(d) = denoiser.as_mut() {
                // This step's image denoised: the renders' time and one denoising.
                let (image, denoise_seconds, denoise_cpu_seconds) = denoise(&mut renderer, d)?;
                let ImageError { rmse, relmse } = image_error(&image, &reference);
                denoised_steps.push(Step {
                    spp,
                    seconds: seconds + denoise_seconds,
                    kernel_seconds,
                    cpu_seconds: cpu_seconds + denoise_cpu_seconds,
                    rmse,
                    relmse,
                });
            }
            next = (spp * 2).min(max_spp);
        }
        if renderer.stats().stack_overflows > 0 {
            bail!("{source}: traversal stack overflow: the images are wrong");
        }
        if !args.json {
            eprintln!("penumbra: {name}: {spp} spp in {seconds:.2} s");
        }
        let denoised_name = format!("{name}+denoise");
        curves.push(Curve::fit(name, steps, args.fit_from));
        if !denoised_steps.is_empty() {
            curves.push(Curve::fit(denoised_name, denoised_steps, args.fit_from));
        }
    }

    let date = today();
    let device = renderer.device.description();
    let scene_name = args
        .scene
        .as_ref()
        .and_then(|p| p.file_name())
        .map_or_else(|| source.clone(), |n| n.to_string_lossy().into_owned());
    if let Some(path) = &args.csv {
        write_csv(path, &curves)?;
    }
    if let Some(path) = &args.plot {
        let title = args.title.clone().unwrap_or_else(|| {
            format!(
                "{scene_name}: {}×{}, {} bounces",
                settings.width, settings.height, settings.bounces
            )
        });
        plot::convergence(path, &title, &format!("{device} — {date}"), &curves)?;
    }
    if args.json {
        let summary = serde_json::json!({
            "benchmark": "converge",
            "date": date,
            "scene": source,
            "reference": args.reference.display().to_string(),
            "device": device_json(&renderer.device),
            "width": settings.width,
            "height": settings.height,
            "bounces": settings.bounces,
            "max_spp": max_spp,
            "max_seconds": args.max_seconds,
            "noise_threshold": args.adaptive,
            "adaptive_rule": args.adaptive.map(|_| args.adaptive_rule.name()),
            "denoiser": args.denoise.then(|| args.denoiser.name()),
            "fit_from": args.fit_from,
            "punctual_lights": prepared.lights.len(),
            "light_radius": if prepared.lights.is_empty() { 0.0 } else { prepared.shadows.point_radius() },
            "triangles": scene_stats.triangles,
            "curves": curves,
        });
        println!("{summary}");
        return Ok(());
    }
    println!(
        "penumbra bench converge — {source} against {} — {date}",
        args.reference.display()
    );
    println!("device   {}", device_line(&renderer.device));
    println!(
        "render   {}×{}, {} bounces, {} punctual light(s), up to {max_spp} spp or {} s per \
         configuration; slopes fitted from {} spp",
        settings.width,
        settings.height,
        settings.bounces,
        prepared.lights.len(),
        args.max_seconds,
        args.fit_from
    );
    println!();
    println!(
        "{:<20} {:>6} {:>10} {:>10} {:>12} {:>12}",
        "config", "spp", "seconds", "kernel s", "RMSE", "relMSE"
    );
    for c in &curves {
        for s in &c.steps {
            println!(
                "{:<20} {:>6} {:>10.4} {:>10.4} {:>12.4e} {:>12.4e}",
                c.config, s.spp, s.seconds, s.kernel_seconds, s.rmse, s.relmse
            );
        }
    }
    println!();
    println!(
        "{:<20} {:>6} {:>12} {:>12} {:>11} {:>12}",
        "config", "spp", "relMSE", "slope/time", "slope/spp", "efficiency"
    );
    let fmt = |s: Option<f64>| s.map_or_else(|| "-".into(), |v| format!("{v:.3}"));
    for c in &curves {
        let last = c.steps.last();
        println!(
            "{:<20} {:>6} {:>12.4e} {:>12} {:>11} {:>12.4e}",
            c.config,
            last.map_or(0, |s| s.spp),
            last.map_or(0.0, |s| s.relmse),
            fmt(c.slope_time),
            fmt(c.slope_spp),
            c.efficiency
        );
    }
    println!();
    println!("efficiency = 1 / (relMSE × seconds) at the last step; slope −1 = unbiased");
    for line in curves.iter().filter_map(|c| adaptive_gain(&curves, c)) {
        println!("{line}");
    }
    if args.denoise {
        println!(
            "CONFIG+denoise: each step's image denoised ({} network); its seconds add that \
             one denoising to the renders'",
            args.denoiser.name()
        );
    }
    Ok(())
}

/// For an adaptive curve ("CONFIG+adaptive", or "CONFIG+adaptive+denoise" with --denoise),
/// against the uniform curve of the same name without "+adaptive": the time each takes to the
/// adaptive run's last relMSE, in wall and CPU seconds (the uniform curve interpolated, or
/// extended as 1 / time), and the ratio, the speed-up of adaptive sampling at equal error.
/// `None` for a uniform curve.
fn adaptive_gain(curves: &[Curve], adaptive: &Curve) -> Option<String> {
    let uniform_name = adaptive.config.replacen("+adaptive", "", 1);
    if uniform_name == adaptive.config {
        return None;
    }
    let uniform = curves.iter().find(|c| c.config == uniform_name)?;
    let last = adaptive.steps.last()?;
    let wall = time_to(&uniform.steps, last.relmse, |s| s.seconds)?;
    let cpu = time_to(&uniform.steps, last.relmse, |s| s.cpu_seconds)?;
    Some(format!(
        "{}: to relMSE {:.4e} uniform {wall:.2} s / adaptive {:.2} s wall ({:.2}×), \
         {cpu:.2} / {:.2} CPU s ({:.2}×)",
        adaptive.config,
        last.relmse,
        last.seconds,
        wall / last.seconds.max(1e-12),
        last.cpu_seconds,
        cpu / last.cpu_seconds.max(1e-12),
    ))
}

/// The film denoised with the guide buffers (as `render --denoise` does it) and the wall and
/// CPU seconds that took: the network's input made from the film on the device, the network,
/// reading the result.
fn denoise(
    renderer: &mut crate::render::Renderer,
    denoiser: &mut Denoiser,
) -> Result<(Vec<[f32; 3]>, f64, f64)> {
    let (start, cpu_start) = (Instant::now(), process_cpu_seconds());
    let (out, _) = denoiser.denoise_film(renderer)?;
    let cpu = match (cpu_start, process_cpu_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    Ok((out, start.elapsed().as_secs_f64(), cpu))
}

fn write_csv(path: &std::path::Path, curves: &[Curve]) -> Result<()> {
    let mut out = String::from("config,spp,seconds,kernel_seconds,rmse,relmse,cpu_seconds\n");
    for c in curves {
        for s in &c.steps {
            out.push_str(&format!(
                "{},{},{},{},{},{},{}\n",
                c.config, s.spp, s.seconds, s.kernel_seconds, s.rmse, s.relmse, s.cpu_seconds
            ));
        }
    }
    std::fs::write(path, out).with_context(|| format!("{}: cannot write CSV", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn configurations_parse_by_name() {
        assert_eq!(
            parse_config("lights+rr"),
            Ok(Config::new(Strategy::Lights, true))
        );
        assert_eq!(parse_config("mis"), Ok(Config::new(Strategy::Mis, false)));
        assert!(parse_config("path").is_err());
        for c in Config::ALL {
            assert_eq!(parse_config(&c.name()), Ok(c));
        }
    }

    #[test]
    fn adaptive_curves_meet_their_uniform_ones_by_name() {
        let curve = |name: &str, seconds: f64| {
            let step = |spp: u32, relmse: f64| Step {
                spp,
                seconds: seconds * spp as f64,
                kernel_seconds: 0.0,
                cpu_seconds: seconds * spp as f64,
                rmse: 0.0,
                relmse,
            };
            Curve::fit(name.into(), vec![step(1, 1.0), step(4, 0.25)], 1)
        };
        // The order `run` records them in with --adaptive and --denoise: the adaptive curves
        // are not next to their uniform ones.
        let curves = [
            curve("mis", 1.0),
            curve("mis+denoise", 2.0),
            curve("mis+adaptive", 0.5),
            curve("mis+adaptive+denoise", 0.5),
        ];
        let lines: Vec<String> = curves
            .iter()
            .filter_map(|c| adaptive_gain(&curves, c))
            .collect();
        assert_eq!(lines.len(), 2, "{lines:?}");
        // The same relMSE in half the time; in a quarter of the denoised curve's time.
        assert!(lines[0].starts_with("mis+adaptive:") && lines[0].ends_with("(2.00×)"));
        assert!(lines[1].starts_with("mis+adaptive+denoise:") && lines[1].ends_with("(4.00×)"));
    }
}
