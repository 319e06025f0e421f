//! `penumbra render SCENE -o OUT.{exr,png}`: a headless render with a JSON summary; with
//! `--frames`, a sequence of the scene's animation, one image and one summary line a frame.

use super::RenderArgs;
use super::animate::{self, Frame};
use crate::args::{EnvChoice, Prepared};
use crate::cl::{DeviceChoice, DeviceSet};
use crate::denoise::{DenoiseReport, Denoiser};
use crate::image_io::{Format, OutputFile, encode_exr, encode_exr_channels};
use crate::render::background::{self, Background, unpremultiply};
use crate::render::exposure::{self, ExposureMode};
use crate::render::tonemap::{ToneMapper, encode_rgba_png, to_rgba8};
use crate::render::{RenderSettings, Renderer, SceneStats, film, multi_device};
use crate::shard::{Shard, ShardInfo};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::time::Instant;

/// Samples per pixel when `--spp` is not given.
pub const DEFAULT_SPP: u32 = 64;

/// Image width and height when `--width`, `--height` are not given.
pub const DEFAULT_SIZE: (u32, u32) = (640, 480);

/// Renders and writes the image; prints the summary line on stdout.
pub fn run(args: &RenderArgs) -> Result<()> {
    let started = Instant::now();
    // The devices first: a list that names none, or options one device must take, are
    // refused before the output is opened.
    let devices = device_choices(args)?;
    let frames = args.animation.frames(&args.output)?;
    // The output is checked (and opened) before the scene is read: a path that cannot be
    // written fails now, not after the render (a sequence's first frame's).
    let mut output = Some(OutputFile::open(&frames[0].output)?);
    if args.aovs && output.as_ref().is_some_and(|o| o.format != Format::Exr) {
        anyhow::bail!(
            "{}: --aovs writes the guide buffers as EXR layers: the output must end in .exr",
            args.output.display()
        );
    }
    let mut settings = args.common.settings(DEFAULT_SIZE)?;
    args.strategy.apply(&mut settings);
    settings.noise_threshold = args.noise_threshold;
    settings.adaptive_rule = args.adaptive_rule;
    // The denoiser reads the guide buffers.
    settings.aovs = args.aovs || args.denoise;
    let spp = args.common.sampling.spp.unwrap_or(DEFAULT_SPP);
    if let Some(k) = args.sample_start
        && k.checked_add(spp).is_none()
    {
        anyhow::bail!(
            "--sample-start {k} with --spp {spp} runs past the sequence's last sample (4294967295)"
        );
    }
    let mut prepared = args.common.prepare(Some(&args.scene))?;
    let clip = args.animation.clip(&prepared)?;
    if let Some(c) = clip {
        animate::pose(&mut prepared, c, frames[0].time.unwrap_or(0.0));
    }
    settings.env_intensity *= prepared.env_scale;
    let environment = match prepared.environment.take() {
        Some(EnvChoice::Map(map)) => Some(map),
        _ => None,
    };
    // Each device its own renderer: context, kernels and the scene on it, all set up at once,
    // each on its own thread: the first sample waits for the slowest device (PoCL's kernel
    // build takes about 8 s), not for the sum. One device says it compiles kernels.
    let setup_started = Instant::now();
    let set_up = std::thread::scope(|scope| {
        let threads: Vec<_> = (devices.iter().enumerate())
            .map(|(i, device)| {
                let (settings, prepared, environment) = (&settings, &prepared, &environment);
                scope.spawn(move || -> Result<(Renderer, DeviceSetup)> {
                    let t = Instant::now();
                    let mut renderer = args.common.open_renderer_on(device, settings)?;
                    renderer.announce_builds(i == 0);
                    if let Some(map) = environment {
                        renderer.set_environment(Some(map.clone()))?;
                    }
                    let stats = renderer
                        .load_scene(&prepared.scene, &prepared.lights)
                        .with_context(|| format!("{}", args.scene.display()))?;
                    renderer.set_camera(&prepared.camera)?;
                    let ms = t.elapsed().as_secs_f64() * 1e3;
                    Ok((renderer, DeviceSetup { stats, ms }))
                })
            })
            .collect();
        (threads.into_iter())
            .map(|t| t.join().expect("a device's setup does not panic"))
            .collect::<Result<Vec<_>>>()
    })?;
    let setup_ms = setup_started.elapsed().as_secs_f64() * 1e3;
    let (mut renderers, device_setups): (Vec<Renderer>, Vec<DeviceSetup>) =
        set_up.into_iter().unzip();
    let scene_stats = device_setups[0].stats.clone();
    if scene_stats.dropped_triangles > 0 {
        log::warn!(
            "{}: {} triangles with a non-finite or absurd (beyond 1e30) vertex dropped",
            args.scene.display(),
            scene_stats.dropped_triangles
        );
    }
    if settings.lens_radius > 0.0 && args.common.lens.focus_distance.is_none() {
        // Focus on what the image centre sees (else the scene's centre), the same on every
        // device.
        let focus = renderers[0]
            .focus_distance_at(settings.width as f32 * 0.5, settings.height as f32 * 0.5)
            .unwrap_or_else(|| {
                let bounds = prepared.scene.bounds();
                (bounds.center() - prepared.camera.eye)
                    .dot(prepared.camera.forward)
                    .max(1e-3 * bounds.diagonal()) as f32
            });
        for renderer in &mut renderers {
            renderer.set_lens(settings.lens_radius, focus)?;
        }
    }

    // The denoiser is built before the samples: its kernels fail now, not after the render.
    let denoiser = if args.denoise {
        let t = Instant::now();
        let denoiser = Denoiser::new(&renderers[0].device, args.denoiser)?;
        Some((denoiser, t.elapsed().as_secs_f64() * 1e3))
    } else {
        None
    };
    let mut setup = Setup {
        settings,
        spp,
        scene_stats,
        device_setups,
        setup_ms,
        started,
        denoiser,
        clip,
    };
    for (k, frame) in frames.iter().enumerate() {
        // Each later frame: the scene posed anew and brought up to date on the renderer (the
        // film restarts, the seed stays).
        let mut update_ms = None;
        let mut update = None;
        let mut update_bytes = None;
        if k > 0
            && let Some(c) = clip
        {
            let t = Instant::now();
            let applied = animate::pose(&mut prepared, c, frame.time.unwrap_or(0.0));
            let mut kinds = Vec::new();
            let mut bytes = Vec::new();
            for renderer in &mut renderers {
                let u = renderer.update_scene(
                    &prepared.scene,
                    &prepared.lights,
                    applied.deformed > 0,
                )?;
                renderer.set_camera(&prepared.camera)?;
                kinds.push(u.kind);
                bytes.push(u.bytes);
            }
            update_ms = Some(t.elapsed().as_secs_f64() * 1e3);
            update = kinds.first().copied();
            update_bytes = bytes.first().copied();
        }
        let output = match output.take() {
            Some(first) => first,
            None => OutputFile::open(&frame.output)?,
        };
        let animation = serde_json::json!({
            "clips": animate::clips_json(&prepared),
            "clip": clip.map(|c| prepared.scene.animation.clips[c].name.clone()),
            "time": clip.map(|_| frame.time.unwrap_or(0.0)),
            "frame": frame.number,
            "scene_update_ms": update_ms,
            "scene_update": update,
            "scene_update_bytes": update_bytes,
            "shutter": args.animation.shutter.unwrap_or(0.0),
        });
        render_frame(
            args,
            &mut setup,
            &mut renderers,
            &mut prepared,
            frame,
            output,
            animation,
        )?;
    }
    Ok(())
}

/// The devices `--device` names, one renderer each; several only where each device's film can
/// be summed: not with adaptive sampling, whose convergence is decided on one film, nor with
/// guide buffers (`--aovs`, `--denoise`), whose sums are floats that a sum of films would
/// round in another order.
fn device_choices(args: &RenderArgs) -> Result<Vec<DeviceChoice>> {
    let set = args.common.device.device_set()?;
    let indices = match &set {
        DeviceSet::One(choice) => return Ok(vec![choice.clone()]),
        set => set
            .indices(&crate::cl::list_devices()?)
            .map_err(anyhow::Error::msg)?,
    };
    if indices.len() > 1 {
        for (given, option) in [
            (args.noise_threshold.is_some(), "--noise-threshold"),
            (args.aovs, "--aovs"),
            (args.denoise, "--denoise"),
            (args.animation.shutter.is_some_and(|s| s > 0.0), "--shutter"),
        ] {
            if given {
                return Err(super::UsageError(format!(
                    "{option} renders on one device, not on --device {}",
                    args.common
                        .device
                        .device
                        .as_deref()
                        .unwrap_or("(PENUMBRA_DEVICE)")
                ))
                .into());
            }
        }
    }
    Ok(indices.into_iter().map(DeviceChoice::Index).collect())
}

/// What every frame of a render shares.
struct Setup {
    settings: RenderSettings,
    spp: u32,
    scene_stats: SceneStats,
    /// Each device's setup.
    device_setups: Vec<DeviceSetup>,
    /// Wall milliseconds of the devices' setup, all at once (the slowest device's).
    setup_ms: f64,
    started: Instant,
    /// With `--denoise`: the denoiser and the milliseconds its kernels and weights took to load.
    denoiser: Option<(Denoiser, f64)>,
    /// The clip played, if any.
    clip: Option<usize>,
}

/// One device's setup: its scene's figures (BVH, upload and kernel build times) and the wall
/// milliseconds it took, the renderer opened included.
struct DeviceSetup {
    stats: SceneStats,
    ms: f64,
}

/// Poses `prepared` at `time` of `clip` and brings the renderer up to date, keeping its film
/// when `held` (a shutter's later poses).
fn shutter_pose(
    renderer: &mut Renderer,
    prepared: &mut Prepared,
    clip: usize,
    time: f64,
    held: bool,
) -> Result<()> {
    let applied = animate::pose(prepared, clip, time);
    renderer.hold_film(held);
    let updated = renderer
        .update_scene(&prepared.scene, &prepared.lights, applied.deformed > 0)
        .and_then(|_| renderer.set_camera(&prepared.camera));
    renderer.hold_film(false);
    updated?;
    Ok(())
}

/// Renders the loaded scene, writes `frame`'s image to `output` and prints its summary line
/// with the fields of `animation` added.
fn render_frame(
    args: &RenderArgs,
    setup: &mut Setup,
    renderers: &mut [Renderer],
    prepared: &mut Prepared,
    frame: &Frame,
    output: OutputFile,
    animation: serde_json::Value,
) -> Result<()> {
    // The shutter's poses (one without --shutter), each rendering its share of the samples
    // into the same film.
    let poses = match setup.clip {
        Some(_) => args
            .animation
            .shutter_poses(frame.time.unwrap_or(0.0), setup.spp),
        None => vec![(0.0, setup.spp)],
    };
    if let (Some(c), [first, _, ..]) = (setup.clip, &poses[..]) {
        shutter_pose(&mut renderers[0], prepared, c, first.0, false)?;
    }
    let Setup {
        settings,
        spp,
        scene_stats,
        device_setups,
        setup_ms,
        started,
        denoiser,
        clip,
    } = setup;
    let spp = *spp;
    let bar = ProgressBar::new(spp as u64).with_style(
        ProgressStyle::with_template(
            "{spinner} {bar:40} {pos}/{len} spp {elapsed_precise} eta {eta}",
        )
        .expect("the progress template is valid"),
    );
    // A call can take tens of seconds on a CPU: the spinner and the clock keep moving.
    bar.enable_steady_tick(std::time::Duration::from_millis(250));
    // Without a terminal (a log, CI), plain lines every 10% or 2 s instead of the bar.
    let mut lines = (!std::io::stderr().is_terminal()).then(|| ProgressLines::new(spp));
    let start = Instant::now();
    let cpu_start = crate::cpu_time::process_cpu_seconds();
    let sample_start = args.sample_start.unwrap_or(0);
    let shares = if let [renderer] = renderers {
        let poses = Poses {
            clip: *clip,
            list: &poses,
        };
        let done = render_samples(args, renderer, prepared, &poses, spp, &bar, &mut lines)?;
        let seconds = start.elapsed().as_secs_f64();
        vec![multi_device::Share {
            samples: done,
            seconds,
            dropped: false,
        }]
    } else {
        let plan = multi_device::Plan {
            start: sample_start,
            spp,
            keep_all: matches!(args.common.device.device_set()?, DeviceSet::List(_)),
            time_limit: args.time_limit,
            call_size: samples_per_call,
        };
        let lines = std::sync::Mutex::new(lines);
        let progress = |done: u32| {
            bar.set_position(done as u64);
            if let Some(l) = lines.lock().unwrap_or_else(|e| e.into_inner()).as_mut() {
                l.update(done, start.elapsed().as_secs_f64());
            }
        };
        multi_device::render(renderers, &plan, &progress)?
    };
    let done: u32 = shares.iter().map(|s| s.samples).sum();
    let seconds = start.elapsed().as_secs_f64();
    // Process CPU time of the render (on a CPU device, the kernels' threads are ours).
    let cpu_seconds = cpu_start
        .zip(crate::cpu_time::process_cpu_seconds())
        .map(|(a, b)| b - a);
    bar.finish_and_clear();

    // The image and each pixel's coverage, from one read of the film: the subject is metered
    // without the background. With the background cut out, the straight color is metered and
    // tone-mapped.
    let (mut image, mut coverage) = (Vec::new(), Vec::new());
    // Several devices: their films summed, the film of all their samples.
    let mut summed = None;
    if renderers.len() > 1 {
        let film = multi_device::film_sum(renderers)?;
        let counted = settings.cutout || settings.count_coverage;
        let taken = |_| f64::from(done);
        film::image_into(&film, counted, taken, &mut image, Some(&mut coverage));
        summed = Some(film);
    }
    let mut stats = renderers[0].stats().clone();
    for r in &renderers[1..] {
        stats.add(r.stats());
    }
    let device = (renderers.iter())
        .map(|r| r.device.description())
        .collect::<Vec<_>>()
        .join(" + ");
    let indices: Vec<usize> = renderers.iter().map(|r| r.device.info.index).collect();
    let renderer = &mut renderers[0];
    if summed.is_none() {
        renderer.image_into(&mut image, Some(&mut coverage))?;
    }
    let nonfinite_pixels = zero_nonfinite(&mut image);
    if nonfinite_pixels > 0 {
        log::warn!(
            "{}: {nonfinite_pixels} pixels summed to a non-finite value and are written as 0",
            args.scene.display()
        );
    }
    let denoised = match denoiser {
        Some((d, _)) => Some(denoise(renderer, d)?),
        None => None,
    };
    let background = args.common.background;
    let mode = args.common.exposure_for(prepared);
    // A PNG shows the denoised image, metered on itself: it is the better estimate of the
    // converged image, whose metering the raw image's noise shifts (docs/denoiser.md).
    let shown = denoised.as_ref().map_or(&image, |d| &d.image);
    let exposure = exposure_stops(shown, &coverage, background, mode);
    let (w, h) = (settings.width, settings.height);
    let tonemap = args.common.exposure.tonemap;
    let alpha = background.cutout().then_some(&coverage[..]);
    let bytes = match (output.format, args.sample_start) {
        (Format::Exr, None) if args.aovs || denoised.is_some() => {
            let mut channels = denoised.as_ref().map_or_else(Vec::new, |d| d.channels());
            if args.aovs {
                channels.extend(aov_channels(renderer)?);
            }
            encode_exr_channels(w, h, &image, alpha, &channels)?
        }
        (Format::Exr, None) => encode_exr(w, h, &image, alpha)?,
        (Format::Exr, Some(sample_start)) => {
            let info = ShardInfo {
                sample_start,
                samples: done,
                identity: shard_identity(args, prepared, renderer, frame.time)?,
                counted: settings.cutout || settings.count_coverage,
                background: background.name(),
                exposure: (mode != ExposureMode::Auto).then(|| mode.stops(None)),
                tonemap: tonemap.arg_name().into(),
                scene: args.scene.display().to_string(),
                kernel: format!("{:?}", renderer.kernel()).to_lowercase(),
                device: device.clone(),
            };
            Shard {
                width: w,
                height: h,
                info,
                film: match summed.take() {
                    Some(film) => film,
                    None => renderer.film()?,
                },
            }
            .encode()?
        }
        (Format::Png, _) => encode_png(w, h, shown, &coverage, background, exposure, tonemap)?,
    };
    output.write(&bytes)?;
    let adaptive = renderer.adaptive_stats()?;
    if stats.stack_overflows > 0 {
        anyhow::bail!(
            "{}: {} traversal stack overflow(s): the image is wrong",
            args.scene.display(),
            stats.stack_overflows
        );
    }
    // The samples every pixel took, or with adaptive sampling those the pixels took.
    let samples = match &adaptive {
        Some(a) => a.samples as f64,
        None => settings.width as f64 * settings.height as f64 * f64::from(done),
    };
    let mean_spp = samples / (settings.width as f64 * settings.height as f64);
    let rays = (stats.extension_rays + stats.shadow_rays) as f64;
    let first_view = prepared.first_view.as_ref().map(|f| {
        serde_json::json!({
            "interior": f.view.interior,
            "lights_light_view": f.view.lit,
            "lit_fraction": f.view.lit_fraction,
            "coverage": f.view.coverage,
            "sky_fraction": f.view.sky_fraction,
            "key_irradiance": f.view.key_irradiance,
            "shiny_share": f.view.shiny_share,
            "shiny_sky": f.view.shiny_sky,
            "environment_fill": f.fill,
        })
    });
    let mut summary = serde_json::json!({
        "scene": args.scene.display().to_string(),
        "output": frame.output.display().to_string(),
        "device": device,
        "kernel": renderer.kernel(),
        "width": settings.width,
        "height": settings.height,
        "spp": spp,
        "bounces": settings.bounces,
        "seed": settings.seed,
        "strategy": settings.strategy,
        "russian_roulette": settings.russian_roulette.is_some(),
        "light_radius": prepared.shadows.point_radius(),
        "seconds": seconds,
        "samples_per_second": samples / seconds,
        "rays_per_second": rays / seconds,
        "extension_rays": stats.extension_rays,
        "shadow_rays": stats.shadow_rays,
        "load_ms": prepared.load_ms,
        "bvh_build_ms": scene_stats.bvh_build_ms,
        "kernel_build_ms": scene_stats.kernel_build_ms,
        "triangles": scene_stats.triangles,
        "dropped_triangles": scene_stats.dropped_triangles,
        "bvh_nodes": scene_stats.nodes,
        "lights": prepared.lights.len(),
        "default_light_rig": prepared.scene.default_rig,
        "variants": prepared.scene.variants,
        "variant": prepared.scene.variant.map(|v| prepared.scene.variants[v].clone()),
        "nonfinite_samples": stats.nonfinite_samples,
        "textures": scene_stats.textures,
        "texture_bytes": scene_stats.texture_bytes,
        "environment": renderer.environment().map(|m| m.name.clone()),
        "background": background.name(),
        "exposure": exposure,
        "auto_exposure": matches!(mode, ExposureMode::Auto | ExposureMode::Incident(_)),
        "metering": match mode {
            ExposureMode::Auto => "image",
            ExposureMode::Incident(_) => "incident",
            _ => "fixed",
        },
        "tonemap": args.common.exposure.tonemap.arg_name(),
        "camera": {
            "eye": prepared.camera.eye.to_array(),
            "forward": prepared.camera.forward.to_array(),
            "yfov_degrees": prepared.camera.yfov.to_degrees(),
        },
        "first_view": first_view,
        "aperture": renderer.settings().lens_radius,
        "focus_distance": renderer.settings().focus_distance,
        "kernel_ms": stats.stage_ms,
    });
    // Whether the megakernel walked its rays in vector lanes (CPU devices with AVX-512 or AVX2).
    summary["lanes"] = serde_json::json!(renderer.walks_in_lanes());
    // How the lanes loaded their nodes and triangles: "rows" or "gathers" (null without lanes).
    summary["lanes_load"] = serde_json::json!(renderer.lanes_load());
    // Whether the lanes shaded their vertices in batches, in vectors (kernels/cpu/shade_lanes.h).
    summary["lanes_shade"] = serde_json::json!(renderer.shades_in_lanes());
    // Whether the lanes tested a small scene's triangles whole (no tree).
    summary["lanes_small"] = serde_json::json!(renderer.tests_small_scene_in_lanes());
    summary["cpu_seconds"] = serde_json::json!(cpu_seconds);
    summary["samples_per_cpu_second"] = serde_json::json!(cpu_seconds.map(|c| samples / c));
    // Added after the literal, which is at serde_json's macro recursion limit.
    for (key, value) in [
        ("bvh", serde_json::json!(scene_stats.bvh)),
        ("meshes", serde_json::json!(scene_stats.meshes)),
        ("instances", serde_json::json!(scene_stats.instances)),
        ("device_bytes", serde_json::json!(scene_stats.device_bytes)),
        ("nonfinite_pixels", serde_json::json!(nonfinite_pixels)),
        ("samples", serde_json::json!(samples as u64)),
        ("mean_spp", serde_json::json!(mean_spp)),
        ("noise_threshold", serde_json::json!(args.noise_threshold)),
        (
            "adaptive_rule",
            serde_json::json!(args.noise_threshold.map(|_| args.adaptive_rule.name())),
        ),
        ("time_limit", serde_json::json!(args.time_limit)),
        ("aovs", serde_json::json!(args.aovs)),
        (
            "converged_share",
            serde_json::json!(adaptive.as_ref().map(|a| a.converged_share)),
        ),
        (
            "mean_error",
            serde_json::json!(adaptive.as_ref().map(|a| a.mean_error)),
        ),
    ] {
        summary[key] = value;
    }
    let w_h = f64::from(w) * f64::from(h);
    summary["setup_ms"] = serde_json::json!(setup_ms);
    summary["devices"] = (shares.iter().zip(&indices).zip(device_setups.iter()))
        .map(|((share, index), setup)| {
            serde_json::json!({
                "index": index,
                "setup_ms": setup.ms,
                "bvh_build_ms": setup.stats.bvh_build_ms,
                "upload_ms": setup.stats.upload_ms,
                "kernel_build_ms": setup.stats.kernel_build_ms,
                "samples": share.samples,
                "share": f64::from(share.samples) / f64::from(done.max(1)),
                "seconds": share.seconds,
                "samples_per_second": w_h * f64::from(share.samples) / share.seconds.max(1e-9),
                "dropped": share.dropped,
            })
        })
        .collect();
    summary["denoise"] = serde_json::json!(denoised.is_some());
    if let (Some(d), Some((denoiser, build_ms))) = (&denoised, denoiser) {
        summary["denoiser"] = serde_json::json!(denoiser.quality().name());
        summary["denoiser_build_ms"] = serde_json::json!(build_ms);
        summary["denoise_ms"] = serde_json::json!(d.ms);
        summary["denoise_kernel_ms"] = serde_json::json!(d.report.kernel_ms);
        let t = d.report.tiling;
        summary["denoise_tiling"] = serde_json::json!({
            "tiles": t.count(),
            "across": t.across,
            "down": t.down,
            "tile_width": t.tile_w,
            "tile_height": t.tile_h,
        });
    }
    if let serde_json::Value::Object(fields) = animation {
        for (key, value) in fields {
            summary[key] = value;
        }
    }
    let taken = if adaptive.is_some() || done < spp {
        format!("{mean_spp:.1} of at most {spp} spp")
    } else {
        format!("{spp} spp")
    };
    let denoised_in = denoised.as_ref().map_or_else(String::new, |d| {
        format!(", denoised in {}", duration(d.ms * 1e-3))
    });
    let on_devices = if shares.len() > 1 {
        let parts: Vec<String> = (shares.iter().zip(&indices).zip(device_setups.iter()))
            .map(|((share, index), setup)| {
                let rate = w_h * f64::from(share.samples) / share.seconds.max(1e-9);
                format!(
                    "{index}: {} spp ({:.0} %, {:.2} M samples/s, set up in {}{})",
                    share.samples,
                    100.0 * f64::from(share.samples) / f64::from(done.max(1)),
                    rate * 1e-6,
                    duration(setup.ms * 1e-3),
                    if share.dropped {
                        ", dropped: too slow"
                    } else {
                        ""
                    }
                )
            })
            .collect();
        format!(" on devices {}", parts.join(", "))
    } else {
        String::new()
    };
    eprintln!(
        "penumbra: wrote {}: {w}×{h} pixels, {taken}, rendered in {}{on_devices}{denoised_in} ({} in all)",
        frame.output.display(),
        duration(seconds),
        duration(started.elapsed().as_secs_f64())
    );
    println!("{summary}");
    Ok(())
}

/// Renders `spp` samples a pixel on one device, in calls sized to the time a sample takes,
/// stopping early at `--time-limit` or once adaptive sampling left no pixel active; returns
/// the samples a pixel taken.
fn render_samples(
    args: &RenderArgs,
    renderer: &mut Renderer,
    prepared: &mut Prepared,
    poses: &Poses,
    spp: u32,
    bar: &ProgressBar,
    lines: &mut Option<ProgressLines>,
) -> Result<u32> {
    let start = Instant::now();
    renderer.set_next_sample(args.sample_start.unwrap_or(0));
    let mut done = 0;
    // The fewest samples a call first, then calls sized by the time a sample took.
    let mut chunk = MIN_SAMPLES_PER_CALL;
    let (mut pose, mut pose_end) = (0, poses.list[0].1);
    while done < spp {
        if done == pose_end
            && let (Some(c), Some(&(time, samples))) = (poses.clip, poses.list.get(pose + 1))
        {
            pose += 1;
            pose_end += samples;
            shutter_pose(renderer, prepared, c, time, true)?;
        }
        // The last check left no pixel active: more samples would add nothing.
        if renderer.active_pixels() == Some(0) {
            break;
        }
        if args
            .time_limit
            .is_some_and(|limit| start.elapsed().as_secs_f64() >= limit)
        {
            break;
        }
        let mut n = chunk.min(spp - done).min(pose_end - done);
        if let Some(limit) = args.time_limit {
            // The call sized to end near the limit, at a sample's time measured so far.
            let left = limit - start.elapsed().as_secs_f64();
            let per_sample = start.elapsed().as_secs_f64() / f64::from(done.max(1));
            if done > 0 && per_sample > 0.0 {
                n = n.min(((left / per_sample).ceil() as u32).max(1));
            } else {
                n = n.min(1);
            }
        }
        let call = Instant::now();
        renderer.render(n)?;
        chunk = samples_per_call(call.elapsed().as_secs_f64() / f64::from(n));
        done += n;
        bar.set_position(done as u64);
        if let Some(l) = lines.as_mut() {
            l.update(done, start.elapsed().as_secs_f64());
        }
    }
    Ok(done)
}

/// A frame's shutter poses: the clip and each pose's time and share of the samples (one pose,
/// the frame's own, without `--shutter`).
struct Poses<'a> {
    clip: Option<usize>,
    list: &'a [(f64, u32)],
}

/// Seconds for a person: "0.42 s", "12.3 s", "3 min 07 s".
fn duration(seconds: f64) -> String {
    match seconds {
        s if s < 10.0 => format!("{s:.2} s"),
        s if s < 60.0 => format!("{s:.1} s"),
        s => {
            let whole = s.round() as u64;
            format!("{} min {:02} s", whole / 60, whole % 60)
        }
    }
}

/// Sets pixels with a non-finite or negative channel to 0 and counts them: the kernels drop
/// non-finite samples, but a film's sum of finite samples can still overflow f32, and no
/// such value may reach the file.
fn zero_nonfinite(image: &mut [[f32; 3]]) -> u64 {
    let mut count = 0;
    for p in image.iter_mut() {
        if p.iter().any(|v| !v.is_finite() || *v < 0.0) {
            *p = [0.0; 3];
            count += 1;
        }
    }
    count
}

/// The seconds a call of `render` aims at: the progress moves about this often.
const SECONDS_PER_CALL: f64 = 2.0;

/// At least this many samples a pixel in one call, the first included (fewer only at the
/// end): a large image on a CPU, seconds a sample, still gets most of the gain of back-to-back
/// samples (the bunnies at 960×540: +15 % at 8 a call), at the price of coarser progress.
const MIN_SAMPLES_PER_CALL: u32 = 8;

/// At most this many samples a pixel in one call.
const MAX_SAMPLES_PER_CALL: u32 = 1024;

/// The samples a pixel of the next call, from the seconds one took: as many as fill
/// [`SECONDS_PER_CALL`], and at least [`MIN_SAMPLES_PER_CALL`]. Few large calls are faster
/// than many small ones: a launch of n samples has each pixel's n paths traced one after the
/// other by the megakernel's work item, so the tree's nodes around the pixel's first hits are
/// still cached for the next path (on a CPU, the 1 M-triangle bunnies render 10–20 % faster
/// at 16 samples a launch than at one: Intel Xeon, 2026-12-01). The image
/// is the same bit for bit: the kernels add a pixel's samples to the film one by one.
fn samples_per_call(seconds_per_sample: f64) -> u32 {
    if seconds_per_sample.is_finite() && seconds_per_sample > 0.0 {
        (SECONDS_PER_CALL / seconds_per_sample)
            .clamp(MIN_SAMPLES_PER_CALL as f64, MAX_SAMPLES_PER_CALL as f64) as u32
    } else {
        MAX_SAMPLES_PER_CALL
    }
}

/// Progress as plain lines on stderr: one each 10% of the samples or 2 s, whichever comes first.
struct ProgressLines {
    spp: u32,
    next_percent: u32,
    last: f64,
}

impl ProgressLines {
    fn new(spp: u32) -> Self {
        Self {
            spp,
            next_percent: 10,
            last: 0.0,
        }
    }

    fn update(&mut self, done: u32, seconds: f64) {
        let percent = (done as u64 * 100 / self.spp.max(1) as u64) as u32;
        if percent >= self.next_percent || seconds - self.last >= 2.0 {
            eprintln!(
                "penumbra: render {percent}% ({done}/{} spp, {seconds:.1} s)",
                self.spp
            );
            self.next_percent = (percent / 10 + 1) * 10;
            self.last = seconds;
        }
    }
}

/// The exposure in stops `mode` gives `image`: metered on the subject (without the
/// background), on the straight colour when the background is cut out.
pub(super) fn exposure_stops(
    image: &[[f32; 3]],
    coverage: &[f32],
    background: Background,
    mode: ExposureMode,
) -> f32 {
    let straight = background.cutout().then(|| unpremultiply(image, coverage));
    let shown = straight.as_deref().unwrap_or(image);
    mode.stops(exposure::meter_subject(shown, Some(coverage)).as_ref())
}

/// The PNG `render` writes: `image` exposed by `exposure` stops, tone-mapped, the background
/// drawn where `coverage` is short of 1 when it is cut out.
pub(super) fn encode_png(
    w: u32,
    h: u32,
    image: &[[f32; 3]],
    coverage: &[f32],
    background: Background,
    exposure: f32,
    tonemap: ToneMapper,
) -> Result<Vec<u8>> {
    let straight = background.cutout().then(|| unpremultiply(image, coverage));
    let shown = straight.as_deref().unwrap_or(image);
    let mut rgba = to_rgba8(shown, exposure, tonemap);
    background::apply(&mut rgba, coverage, background);
    encode_rgba_png(w, h, &rgba)
}

/// The denoised image of a render and what the summary says of the call.
struct Denoised {
    image: Vec<[f32; 3]>,
    /// The time the host waited from the film to the denoised image: the network's input made
    /// from the film on the device, the network, the image's read.
    ms: f64,
    report: DenoiseReport,
}

impl Denoised {
    /// The EXR channels that hold it beside the raw image: `denoised.R/G/B`.
    fn channels(&self) -> crate::image_io::Channels {
        ["R", "G", "B"]
            .iter()
            .enumerate()
            .map(|(c, name)| {
                let plane = self.image.iter().map(|p| p[c]).collect();
                (format!("denoised.{name}"), plane)
            })
            .collect()
    }
}

/// Denoises the renderer's film with its guide buffers where they are, on its device.
fn denoise(renderer: &mut Renderer, denoiser: &mut Denoiser) -> Result<Denoised> {
    let start = Instant::now();
    let (mut out, report) = denoiser.denoise_film(renderer)?;
    zero_nonfinite(&mut out);
    Ok(Denoised {
        image: out,
        ms: start.elapsed().as_secs_f64() * 1e3,
        report,
    })
}

/// The identity of a shard ([`crate::shard::identity`]): the scene file's bytes and every
/// setting that changes the linear image — size, bounces, seed, strategy, Russian roulette,
/// sky and environment, lens and focus, background cut out or not (`RenderSettings`), the
/// camera, the lights (with their radius), the environment, the variant and the animation's
/// instant. Not in it: the
/// device, the kernels and the BVH, which change the image only in rounding (a merge of
/// shards from different ones is still the estimate of all their samples); files the scene
/// refers to (a .gltf's buffers and images) and an environment file are named, not read.
fn shard_identity(
    args: &RenderArgs,
    prepared: &crate::args::Prepared,
    renderer: &crate::render::Renderer,
    time: Option<f64>,
) -> Result<String> {
    let scene = std::fs::read(&args.scene)
        .with_context(|| format!("{}: cannot read", args.scene.display()))?;
    let texts = [
        format!("{:?}", renderer.settings()),
        format!("{:?}", prepared.camera),
        format!("{:?}", prepared.lights),
        format!("{:?}", renderer.environment().map(|m| &m.name)),
        format!("{:?}", args.common.env),
        format!("{:?}", prepared.scene.variant),
        args.common.background.name(),
        format!("{time:?}"),
    ];
    let mut parts: Vec<&[u8]> = vec![&scene];
    parts.extend(texts.iter().map(|t| t.as_bytes()));
    Ok(crate::shard::identity(&parts))
}

/// The guide buffers as named EXR channels (docs/aovs.md), with adaptive sampling's samples
/// per pixel and error estimate.
fn aov_channels(renderer: &mut crate::render::Renderer) -> Result<crate::image_io::Channels> {
    let mut channels = Vec::new();
    if let Some(aovs) = renderer.aovs()? {
        for (layer, names, values) in [
            ("albedo", ["R", "G", "B"], &aovs.albedo),
            ("normal", ["X", "Y", "Z"], &aovs.normal),
        ] {
            for (c, name) in names.iter().enumerate() {
                channels.push((
                    format!("{layer}.{name}"),
                    values.iter().map(|v| v[c]).collect(),
                ));
            }
        }
        channels.push(("depth.Z".to_string(), aovs.depth));
    }
    if let Some(errors) = renderer.pixel_errors()? {
        channels.push(("error.Y".to_string(), errors));
    }
    if let Some(samples) = renderer.pixel_samples()? {
        channels.push((
            "samples.Y".to_string(),
            samples.iter().map(|&s| s as f32).collect(),
        ));
    }
    Ok(channels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_people_write_them() {
        assert_eq!(duration(0.4234), "0.42 s");
        assert_eq!(duration(12.34), "12.3 s");
        assert_eq!(duration(187.4), "3 min 07 s");
    }

    #[test]
    fn calls_are_sized_to_the_time_a_sample_takes() {
        assert_eq!(samples_per_call(0.1), 20);
        // A sample as slow as a call, or slower, still shares its call with a few others.
        assert_eq!(samples_per_call(SECONDS_PER_CALL), MIN_SAMPLES_PER_CALL);
        assert_eq!(samples_per_call(60.0), MIN_SAMPLES_PER_CALL);
        assert_eq!(samples_per_call(1e-9), MAX_SAMPLES_PER_CALL);
        // A call too quick to time (or a clock that did not move) takes the most.
        assert_eq!(samples_per_call(0.0), MAX_SAMPLES_PER_CALL);
        assert_eq!(samples_per_call(f64::NAN), MAX_SAMPLES_PER_CALL);
    }
}
