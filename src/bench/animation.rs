//! `penumbra bench animation SCENE`: the host's per-frame scene update of an animated scene,
//! stage by stage: evaluating the clip (node transforms, joint matrices), deforming the
//! skinned and morphed meshes, refitting their BVHs from the vertices (a full build when the
//! refit tree's SAH cost has doubled) and rebuilding the top level over every object. Frames step through the
//! clip at `--fps`; the first (warm-up) is discarded.

use crate::bvh::{Blas, Bvh, TwoLevel, Update, build};
use crate::scene::load;
use anyhow::{Result, bail};
use clap::Args;
use glam::Vec3;
use rayon::prelude::*;
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
}

/// Milliseconds of each stage, per frame.
#[derive(Default)]
struct Stages {
    evaluate: Vec<f64>,
    deform: Vec<f64>,
    refit: Vec<f64>,
    tlas: Vec<f64>,
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
    let deforming: Vec<usize> = animation
        .objects
        .iter()
        .filter(|d| d.rig.is_some())
        .map(|d| d.object)
        .collect();
    let triangles = |scene: &crate::scene::Scene, o: usize| -> Vec<[Vec3; 3]> {
        let m = &scene.objects[o].mesh;
        m.indices
            .par_iter()
            .map(|t| t.map(|i| m.positions[i as usize]))
            .collect()
    };
    // Each deforming mesh's BVH, and a top level over every object.
    let mut trees: Vec<Bvh> = deforming
        .iter()
        .map(|&o| build(&triangles(&scene, o)))
        .collect();
    let blases: Vec<Blas> = scene
        .objects
        .iter()
        .map(|o| Blas::of_mesh(&o.mesh.positions, &o.mesh.indices))
        .collect();
    let instances: Vec<(u32, glam::DMat4)> = scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| (i as u32, o.world_from_object))
        .collect();
    let mut two = TwoLevel::from_blases(blases, &instances);
    let mut stages = Stages::default();
    let mut rebuilds = 0;
    for frame in 0..=args.frames {
        let started = Instant::now();
        let t = animation.clip_time(clip, f64::from(frame) / args.fps, true);
        let applied = animation.apply(&mut scene, Some(clip), t);
        let refitting = Instant::now();
        let updates: Vec<Update> = trees
            .iter_mut()
            .zip(&deforming)
            .map(|(tree, &o)| {
                let m = &scene.objects[o].mesh;
                tree.refit_or_rebuild_with(m.indices.len(), |t| {
                    m.indices[t].map(|i| m.positions[i as usize])
                })
            })
            .collect();
        let refit_ms = refitting.elapsed().as_secs_f64() * 1e3;
        let top = Instant::now();
        for (i, o) in scene.objects.iter().enumerate() {
            two.place(i, o.world_from_object);
        }
        two.rebuild_tlas();
        let tlas_ms = top.elapsed().as_secs_f64() * 1e3;
        if frame == 0 {
            continue;
        }
        rebuilds += updates.iter().filter(|&&u| u == Update::Rebuilt).count();
        stages.evaluate.push(applied.evaluate_ms);
        stages.deform.push(applied.deform_ms);
        stages.refit.push(refit_ms);
        stages.tlas.push(tlas_ms);
        stages.total.push(started.elapsed().as_secs_f64() * 1e3);
    }
    let deformed_triangles: usize = deforming
        .iter()
        .map(|&o| scene.objects[o].mesh.indices.len())
        .sum();
    let threads = rayon::current_num_threads();
    let cpu = cpu_name();
    println!(
        "{}: clip '{}' ({:.2} s), {} objects, {deformed_triangles} deformed triangles, \
         {} frames at {} fps, {threads} threads on {cpu}",
        args.scene.display(),
        animation.clips[clip].name,
        animation.clips[clip].duration,
        scene.objects.len(),
        args.frames,
        args.fps,
    );
    println!("| stage | mean ms | max ms |\n|---|---|---|");
    let rows = [
        ("evaluate", &stages.evaluate),
        ("deform", &stages.deform),
        ("refit/rebuild", &stages.refit),
        ("top level", &stages.tlas),
        ("total", &stages.total),
    ];
    let mut json = serde_json::json!({
        "scene": args.scene.display().to_string(),
        "clip": animation.clips[clip].name,
        "frames": args.frames,
        "objects": scene.objects.len(),
        "deformed_triangles": deformed_triangles,
        "rebuilds": rebuilds,
        "threads": threads,
        "cpu": cpu,
    });
    for (name, values) in rows {
        let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
        let max = values.iter().copied().fold(0.0, f64::max);
        println!("| {name} | {mean:.3} | {max:.3} |");
        json[format!("{}_ms", name.replace(['/', ' '], "_"))] = serde_json::json!(mean);
    }
    println!("{json}");
    Ok(())
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
