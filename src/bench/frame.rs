//! `penumbra bench frame SCENE`: samples per second of the whole path tracer and where the
//! time goes, stage by stage (kernel time from OpenCL profiling events).

use super::{device_json, device_line, thousands};
use crate::args::{CommonArgs, StrategyArgs};
use crate::date::today;
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `bench frame`.
#[derive(Args, Debug, Clone)]
pub struct FrameArgs {
    /// glTF or GLB file; the bundled Cornell box when absent.
    pub scene: Option<PathBuf>,
    /// Shared options (`--spp` is the timed samples per pixel, default 16; size default
    /// 1920×1080).
    #[command(flatten)]
    pub common: CommonArgs,
    /// Direct-light strategy and Russian roulette.
    #[command(flatten)]
    pub strategy: StrategyArgs,
    /// Untimed samples per pixel rendered first (buffers, caches, clocks).
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Record the guide buffers for a denoiser too, as `render --aovs` does (default: off).
    #[arg(long)]
    pub aovs: bool,
}

/// Runs the benchmark.
pub fn run(args: &FrameArgs) -> Result<()> {
    let mut settings = args.common.settings((1920, 1080))?;
    args.strategy.apply(&mut settings);
    settings.aovs = args.aovs;
    let spp = args.common.sampling.spp.unwrap_or(16);
    let prepared = args.common.prepare(args.scene.as_deref())?;
    let source = prepared.scene.source.clone();
    let mut renderer = args.common.open_renderer(&settings)?;
    let scene_stats = renderer
        .load_scene(&prepared.scene, &prepared.lights)
        .with_context(|| source.clone())?;
    renderer.set_camera(&prepared.camera)?;
    if args.warmup > 0 {
        renderer.render(args.warmup)?;
    }
    renderer.reset()?;

    // One sample per pixel per call, as the viewer renders frames.
    let start = Instant::now();
    for _ in 0..spp {
        renderer.render(1)?;
    }
    let seconds = start.elapsed().as_secs_f64();
    let stats = renderer.stats().clone();
    if stats.stack_overflows > 0 {
        anyhow::bail!(
            "{source}: {} traversal stack overflow(s)",
            stats.stack_overflows
        );
    }
    let samples = settings.width as f64 * settings.height as f64 * spp as f64;
    let rays = (stats.extension_rays + stats.shadow_rays) as f64;
    let kernel_ms = stats.kernel_ms();
    let frame_ms = seconds * 1e3 / spp as f64;

    if args.json {
        let per_frame: serde_json::Map<String, serde_json::Value> = stats
            .stage_ms
            .iter()
            .map(|(k, v)| (k.to_string(), (v / spp as f64).into()))
            .collect();
        let summary = serde_json::json!({
            "benchmark": "frame",
            "date": today(),
            "scene": source,
            "device": device_json(&renderer.device),
            "kernel": renderer.kernel(),
            "width": settings.width,
            "height": settings.height,
            "spp": spp,
            "bounces": settings.bounces,
            "strategy": settings.strategy,
            "russian_roulette": settings.russian_roulette.is_some(),
            "triangles": scene_stats.triangles,
            "lights": prepared.lights.len(),
            "emissive_triangles": renderer.host_scene().map_or(0, |h| h.emissive.len()),
            "load_ms": prepared.load_ms,
            "bvh_build_ms": scene_stats.bvh_build_ms,
            "kernel_build_ms": scene_stats.kernel_build_ms,
            "seconds": seconds,
            "frame_ms": frame_ms,
            "samples_per_second": samples / seconds,
            "rays_per_second": rays / seconds,
            "extension_rays": stats.extension_rays,
            "shadow_rays": stats.shadow_rays,
            "kernel_ms_per_frame": kernel_ms / spp as f64,
            "stage_ms_per_frame": per_frame,
            "nonfinite_samples": stats.nonfinite_samples,
        });
        println!("{summary}");
        return Ok(());
    }
    println!("penumbra bench frame — {source} — {}", today());
    println!("device   {}", device_line(&renderer.device));
    println!(
        "scene    {} triangles, {} lights, {} emissive triangles; BVH build {:.0} ms, kernel \
         build {:.0} ms",
        thousands(scene_stats.triangles as u64),
        prepared.lights.len(),
        renderer.host_scene().map_or(0, |h| h.emissive.len()),
        scene_stats.bvh_build_ms,
        scene_stats.kernel_build_ms
    );
    println!(
        "render   {}×{}, {spp} frames of 1 spp after {} warm-up, {} bounces, {:?}, Russian \
         roulette {}",
        settings.width,
        settings.height,
        args.warmup,
        settings.bounces,
        settings.strategy,
        if settings.russian_roulette.is_some() {
            "on"
        } else {
            "off"
        }
    );
    println!();
    println!(
        "{:.1} M samples/s, {:.1} M rays/s ({} extension + {} shadow rays), {:.2} ms per frame",
        samples / seconds * 1e-6,
        rays / seconds * 1e-6,
        thousands(stats.extension_rays),
        thousands(stats.shadow_rays),
        frame_ms
    );
    println!();
    println!("{:<12} {:>12} {:>8}", "stage", "ms / frame", "share");
    for (stage, ms) in &stats.stage_ms {
        println!(
            "{:<12} {:>12.3} {:>7.1}%",
            stage,
            ms / spp as f64,
            100.0 * ms / kernel_ms.max(1e-12)
        );
    }
    println!(
        "{:<12} {:>12.3} {:>7.1}%",
        "kernels",
        kernel_ms / spp as f64,
        100.0
    );
    println!(
        "{:<12} {:>12.3} {:>7.1}%",
        "wall",
        frame_ms,
        100.0 * frame_ms * spp as f64 / kernel_ms.max(1e-12)
    );
    Ok(())
}
