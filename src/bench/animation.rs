//! `penumbra bench animation SCENE`: the per-frame scene update of an animated scene on the
//! renderer, stage by stage: evaluating the clip (node transforms, joint matrices), deforming
//! the skinned and morphed meshes (skin/morph), flattening the posed triangles into render
//! space, the BVH work (a flat scene's refit, or the build of a rebuild or reload; two levels'
//! TLAS) and the upload of what changed (`Renderer::update_scene`). Frames step through the
//! clip at `--fps`; the first (warm-up) is discarded.

use crate::args::DeviceArgs;
use crate::render::{BvhChoice, RenderSettings, Renderer, UpdateKind};
use crate::scene::load;
use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `bench animation`.
#[derive(Args, Debug, Clone)]
pub struct AnimationBenchArgs {
    /// An animated glTF/GLB file (e.g. Fox/Fox.glb, or `bench generate --skinned`).
    pub scene: PathBuf,
    /// The clip, by name or index (default: the first).
    #[arg(long)]
    pub clip: Option<String>,
    /// Frames measured after the warm-up one.
    #[arg(long, default_value_t = 60)]
    pub frames: u32,
    /// Frames a second: frame n is at n / fps seconds (looping).
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Acceleration structure: flat, two-level or auto (as `render --bvh`).
    #[arg(long, default_value = "auto")]
    pub bvh: BvhChoice,
    /// The OpenCL device the scene is updated on.
    #[command(flatten)]
    pub device: DeviceArgs,
}

/// Milliseconds of each stage, per frame.
#[derive(Default)]
struct Stages {
    evaluate: Vec<f64>,
    deform: Vec<f64>,
    flatten: Vec<f64>,
    bvh: Vec<f64>,
    upload: Vec<f64>,
    total: Vec<f64>,
}

/// Runs the benchmark and prints a table and one JSON line.
pub fn run(args: &AnimationBenchArgs) -> Result<()> {
    if !(args.fps.is_finite() && args.fps > 0.0) {
        bail!("--fps {} must be a finite number > 0", args.fps);
    }
    let mut scene = load(&args.scene)?;
    let animation = std::sync::Arc::clone(&scene.animation);
    if animation.clips.is_empty() {
        bail!("{}: the scene has no animations", args.scene.display());
    }
    let clip = match &args.clip {
        Some(name) => animation
            .find_clip(name)
            .map_err(|e| anyhow::anyhow!("{}: --clip: {e}", args.scene.display()))?,
        None => 0,
    };
    let mut renderer = Renderer::new(&args.device.device_choice()?)?;
    renderer.set_bvh_choice(args.bvh);
    renderer.set_settings(&RenderSettings {
        width: 64,
        height: 64,
        ..RenderSettings::default()
    })?;
    let lights = scene.lights.clone();
    let loaded = renderer
        .load_scene(&scene, &lights)
        .with_context(|| args.scene.display().to_string())?;
    let mut stages = Stages::default();
    let mut kinds: std::collections::BTreeMap<String, u32> = Default::default();
    let mut bytes = 0usize;
    let mut cpu_started = None;
    for frame in 0..=args.frames {
        if frame == 1 {
            cpu_started = crate::cpu_time::process_cpu_seconds();
        }
        let started = Instant::now();
        let t = animation.clip_time(clip, f64::from(frame) / args.fps, true);
        let applied = animation.apply(&mut scene, Some(clip), t);
        let update = renderer.update_scene(&scene, &lights, applied.deformed > 0)?;
        if frame == 0 {
            continue;
        }
        *kinds.entry(kind_name(update.kind).into()).or_default() += 1;
        bytes += update.bytes;
        stages.evaluate.push(applied.evaluate_ms);
        stages.deform.push(applied.deform_ms);
        stages.flatten.push(update.flatten_ms);
        stages.bvh.push(update.bvh_ms);
        stages.upload.push(update.upload_ms);
        stages.total.push(started.elapsed().as_secs_f64() * 1e3);
    }
    // The process's CPU time over the measured frames (every thread; ticks of 10 ms, so
    // meaningful over many frames): on a shared machine the wall times above include the
    // neighbours' share of the cores.
    let cpu_ms = cpu_started
        .zip(crate::cpu_time::process_cpu_seconds())
        .map(|(a, b)| (b - a) * 1e3 / f64::from(args.frames.max(1)));
    let deformed_triangles: usize = animation
        .objects
        .iter()
        .filter(|d| d.rig.is_some())
        .map(|d| scene.objects[d.object].mesh.indices.len())
        .sum();
    let threads = rayon::current_num_threads();
    let cpu = cpu_name();
    let device = renderer.device.description();
    println!(
        "{}: clip '{}' ({:.2} s), {} objects, {deformed_triangles} deformed triangles, {} BVH, \
         {} frames at {} fps, {threads} threads on {cpu}, device {device}",
        args.scene.display(),
        animation.clips[clip].name,
        animation.clips[clip].duration,
        scene.objects.len(),
        loaded.bvh,
        args.frames,
        args.fps,
    );
    println!("| stage | mean ms | max ms |\n|---|---|---|");
    let rows = [
        ("evaluate", &stages.evaluate),
        ("skin/morph", &stages.deform),
        ("flatten", &stages.flatten),
        ("refit/rebuild", &stages.bvh),
        ("upload", &stages.upload),
        ("total", &stages.total),
    ];
    let mut json = serde_json::json!({
        "scene": args.scene.display().to_string(),
        "clip": animation.clips[clip].name,
        "frames": args.frames,
        "objects": scene.objects.len(),
        "deformed_triangles": deformed_triangles,
        "bvh": loaded.bvh,
        "updates": kinds,
        "bytes_per_frame": bytes / args.frames.max(1) as usize,
        "threads": threads,
        "cpu_ms_per_frame": cpu_ms,
        "cpu": cpu,
        "device": device,
        "date": crate::date::today(),
    });
    for (name, values) in rows {
        let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
        let max = values.iter().copied().fold(0.0, f64::max);
        println!("| {name} | {mean:.3} | {max:.3} |");
        json[format!("{}_ms", name.replace(['/', ' '], "_"))] = serde_json::json!(mean);
    }
    println!(
        "updates: {kinds:?}, {:.1} MB written a frame, CPU time {} a frame (all threads)",
        bytes as f64 / 1e6 / args.frames.max(1) as f64,
        cpu_ms.map_or("unknown".into(), |ms| format!("{ms:.1} ms")),
    );
    println!("{json}");
    Ok(())
}

/// The update's name in the table and the JSON.
fn kind_name(kind: UpdateKind) -> &'static str {
    match kind {
        UpdateKind::Moved => "moved",
        UpdateKind::Refitted => "refitted",
        UpdateKind::Rebuilt => "rebuilt",
        UpdateKind::Reloaded => "reloaded",
    }
}

/// The host CPU's model name (Linux), else "unknown CPU".
fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|n| n.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}
