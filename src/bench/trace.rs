//! `penumbra bench trace SCENE`: rays per second of the traversal kernels alone.
//!
//! Three ray sets of width × height rays each are made on the host (see `rays`): primary,
//! diffuse first bounce and shadow rays (the secondary rays start from the primary hits, in
//! pixel order, cycling through them when some primary rays missed). Each is uploaded once, traced `--warmup` times untimed, then `--runs` times; the
//! reported time is the median kernel time from OpenCL profiling events. Every result is then
//! checked against the host traversal (`Bvh::intersect` / `occluded`) on a deterministic
//! subset of at least `--validate` rays (all of them with `--validate 0`).

use super::rays::{self, LightTargets, MISS};
use super::stats::median;
use super::{device_json, device_line, thousands};
use crate::args::{CameraArgs, DeviceArgs, ShadowArgs, SizeArgs, prepare};
use crate::cl::kernels::{Launch, SceneBuffers};
use crate::cl::types::{COUNT_OVERFLOW, COUNTER_SLOTS, DeviceHit, DeviceRay};
use crate::cl::{Buffer, Device, Program, call_err};
use crate::date::today;
use crate::render::{
    Accel, BvhChoice, HostScene, InstanceUpdate, RenderSettings, Renderer, gpu_camera,
};
use crate::scene::LightKind;
use anyhow::{Context, Result, anyhow};
use clap::Args;
use glam::Vec3;
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `bench trace`.
#[derive(Args, Debug, Clone)]
pub struct TraceArgs {
    /// glTF or GLB file; the bundled Cornell box when absent.
    pub scene: Option<PathBuf>,
    /// The device.
    #[command(flatten)]
    pub device: DeviceArgs,
    /// Size of the primary ray grid (default 1280×720, see `BenchCommand::Trace`).
    #[command(flatten)]
    pub size: SizeArgs,
    /// The camera the primary rays start from.
    #[command(flatten)]
    pub camera: CameraArgs,
    /// Seed of the diffuse and shadow ray directions.
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Timed launches per ray set (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Untimed launches before the timed ones.
    #[arg(long, default_value_t = 2)]
    pub warmup: usize,
    /// Rays of each set checked against the host traversal (every k-th ray; 0 checks all).
    #[arg(long, default_value_t = 262_144)]
    pub validate: usize,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Time the kernels of the 4-wide BVH (the megakernel's, CPU devices) instead of the
    /// binary BVH's (the wavefront's).
    #[arg(long)]
    pub wide: bool,
    /// The acceleration structure: flat, two-level (a BLAS per distinct mesh under a TLAS of
    /// instances) or auto (two levels for scenes of 4 M triangles or more that instancing
    /// shrinks eightfold, and for any of 16 M or more).
    #[arg(long, default_value = "auto")]
    pub bvh: BvhChoice,
}

/// Agreement of device results with the host traversal.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Check {
    /// Rays compared.
    pub checked: u64,
    /// Same triangle and distance (or both missed / same occlusion).
    pub matches: u64,
    /// Different triangles at the same distance (within 1e-5 relative): exact ties, counted
    /// as agreement.
    pub ties: u64,
    /// Real disagreements: a hit against a miss, or different distances.
    pub mismatches: u64,
}

impl Check {
    fn add(self, o: Check) -> Check {
        Check {
            checked: self.checked + o.checked,
            matches: self.matches + o.matches,
            ties: self.ties + o.ties,
            mismatches: self.mismatches + o.mismatches,
        }
    }
}

/// Timing and validation of one ray set.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SetResult {
    /// primary, diffuse or shadow.
    pub kind: &'static str,
    /// closest or any (hit query).
    pub query: &'static str,
    /// Rays in the set.
    pub rays: usize,
    /// Rays that hit something (closest) or were occluded (any).
    pub hits: usize,
    /// Median kernel time of the timed launches.
    pub median_ms: f64,
    /// Fastest timed launch.
    pub min_ms: f64,
    /// Slowest timed launch.
    pub max_ms: f64,
    /// rays / median time.
    pub rays_per_second: f64,
    /// Agreement with the host traversal.
    pub validation: Check,
    /// Rays per second of the host reference traversal while validating (all threads).
    pub host_rays_per_second: f64,
    /// The process's CPU time per timed launch (all threads; 10 ms resolution over the
    /// runs), where the platform says: on a shared CPU device, work per launch.
    pub cpu_ms: Option<f64>,
}

/// The indices of the rays to check: every k-th so that at least `want` are checked.
fn sample_indices(n: usize, want: usize) -> Vec<usize> {
    let stride = if want == 0 || want >= n { 1 } else { n / want };
    (0..n).step_by(stride.max(1)).collect()
}

fn same_t(a: f32, b: f32) -> bool {
    a == b || (a - b).abs() <= 1e-5 * a.abs().max(b.abs())
}

/// Compares closest hits with the host traversal.
fn check_closest(host: &HostScene, rays: &[DeviceRay], hits: &[DeviceHit], want: usize) -> Check {
    sample_indices(rays.len(), want)
        .into_par_iter()
        .map(|i| {
            let host = host.intersect(&rays::to_host(&rays[i]));
            let dev = hits[i];
            let mut c = Check {
                checked: 1,
                ..Check::default()
            };
            match host {
                None if dev.prim == MISS => c.matches = 1,
                Some(h) if dev.prim != MISS && same_t(h.t, dev.t) => {
                    // The same triangle must be in the same instance (shading reads its
                    // transforms); another triangle at the same distance is a tie.
                    if h.prim == dev.prim && h.instance == dev.instance {
                        c.matches = 1;
                    } else if h.prim == dev.prim {
                        c.mismatches = 1;
                    } else {
                        c.ties = 1;
                    }
                }
                _ => c.mismatches = 1,
            }
            c
        })
        .reduce(Check::default, Check::add)
}

/// Compares occlusion with the host traversal.
fn check_any(host: &HostScene, rays: &[DeviceRay], occluded: &[u32], want: usize) -> Check {
    sample_indices(rays.len(), want)
        .into_par_iter()
        .map(|i| {
            let host = host.occluded(&rays::to_host(&rays[i]));
            let agree = host == (occluded[i] != 0);
            Check {
                checked: 1,
                matches: agree as u64,
                ties: 0,
                mismatches: (!agree) as u64,
            }
        })
        .reduce(Check::default, Check::add)
}

/// The kernel times of the timed launches (ms), and the process's CPU time over them per
/// launch (ms, all threads; `None` where the platform does not say): on a CPU device shared
/// with other work, CPU time per launch follows the kernel's work where wall time does not.
struct Times {
    ms: Vec<f64>,
    cpu_ms: Option<f64>,
}

/// Launches `launch` `warmup` times untimed, then `runs` times; returns the kernel times.
fn time_launches(
    device: &Device,
    warmup: usize,
    runs: usize,
    mut launch: impl FnMut() -> Result<Launch>,
) -> Result<Times> {
    let mut times = Vec::with_capacity(runs);
    let mut cpu_start = None;
    for i in 0..warmup + runs {
        if i == warmup {
            cpu_start = crate::cpu_time::process_cpu_seconds();
        }
        let l = launch()?;
        device
            .queue
            .finish()
            .map_err(call_err("waiting for a traversal kernel"))?;
        if i >= warmup {
            times.push(l.millis());
        }
    }
    let cpu_ms = cpu_start
        .zip(crate::cpu_time::process_cpu_seconds())
        .map(|(a, b)| (b - a) * 1e3 / runs.max(1) as f64);
    Ok(Times { ms: times, cpu_ms })
}

fn set_result(
    kind: &'static str,
    query: &'static str,
    rays: usize,
    hits: usize,
    times: &Times,
    (validation, host_seconds): (Check, f64),
) -> SetResult {
    let (cpu_ms, times) = (times.cpu_ms, &times.ms);
    let median_ms = median(times);
    SetResult {
        kind,
        query,
        rays,
        hits,
        median_ms,
        min_ms: times.iter().copied().fold(f64::INFINITY, f64::min),
        max_ms: times.iter().copied().fold(0.0, f64::max),
        rays_per_second: if median_ms > 0.0 {
            rays as f64 / (median_ms * 1e-3)
        } else {
            0.0
        },
        validation,
        host_rays_per_second: validation.checked as f64 / host_seconds.max(1e-9),
        cpu_ms,
    }
}

/// Runs `check` and returns its result with its duration in seconds.
fn timed(check: impl FnOnce() -> Check) -> (Check, f64) {
    let start = Instant::now();
    let c = check();
    (c, start.elapsed().as_secs_f64())
}

/// Everything a closest-hit run needs on the device.
struct Tracer<'a> {
    device: &'a Device,
    program: &'a Program,
    scene: &'a SceneBuffers,
    counters: Buffer<u32>,
    warmup: usize,
    runs: usize,
    wide: bool,
}

impl Tracer<'_> {
    /// Times closest-hit traversal of `rays`; returns the hits and the times.
    fn closest(&self, rays: &[DeviceRay]) -> Result<(Vec<DeviceHit>, Times)> {
        let buf = Buffer::from_slice(self.device, rays)?;
        let hits = Buffer::<DeviceHit>::new(self.device, rays.len())?;
        let times = time_launches(self.device, self.warmup, self.runs, || {
            let (p, s, c) = (self.program, self.scene, &self.counters);
            Ok(if self.wide {
                p.trace_closest_wide(self.device, s, &buf, &hits, c)?
            } else {
                p.trace_closest(self.device, s, &buf, &hits, c)?
            })
        })?;
        let mut out = hits.read(self.device)?;
        out.truncate(rays.len());
        Ok((out, times))
    }

    /// Times any-hit traversal of `rays`; returns the occlusion flags and the times.
    fn any(&self, rays: &[DeviceRay]) -> Result<(Vec<u32>, Times)> {
        let buf = Buffer::from_slice(self.device, rays)?;
        let occluded = Buffer::<u32>::new(self.device, rays.len())?;
        let times = time_launches(self.device, self.warmup, self.runs, || {
            let (p, s, c) = (self.program, self.scene, &self.counters);
            Ok(if self.wide {
                p.trace_any_wide(self.device, s, &buf, &occluded, c)?
            } else {
                p.trace_any(self.device, s, &buf, &occluded, c)?
            })
        })?;
        let mut out = occluded.read(self.device)?;
        out.truncate(rays.len());
        Ok((out, times))
    }
}

/// With `PENUMBRA_DUMP_TRACE=DIR` (flat BVH only): the wide nodes, the triangles (vertices only)
/// and each ray set with the device's hits, as raw little-endian arrays in DIR, for timing the
/// same traversal outside OpenCL (`scripts/experiments/native_trace/` at commit b156327).
fn dump_trace(
    dir: &str,
    host: &HostScene,
    sets: &[(&str, &[DeviceRay], &[DeviceHit])],
) -> Result<()> {
    use crate::cl::types::DeviceTriangle;
    let Accel::Flat(bvh) = &host.accel else {
        anyhow::bail!("PENUMBRA_DUMP_TRACE needs --bvh flat");
    };
    let nodes = crate::bvh::WideBvh::collapse_for_cpu(bvh).nodes;
    let tris: Vec<DeviceTriangle> = host
        .vertices
        .iter()
        .map(|v| DeviceTriangle {
            v0: v[0].extend(0.0).to_array(),
            v1: v[1].extend(0.0).to_array(),
            v2: v[2].extend(0.0).to_array(),
        })
        .collect();
    let path = |name: &str| std::path::Path::new(dir).join(name);
    std::fs::create_dir_all(dir)?;
    std::fs::write(path("nodes.bin"), bytemuck::cast_slice(&nodes))?;
    std::fs::write(path("tris.bin"), bytemuck::cast_slice(&tris))?;
    for (name, rays, hits) in sets {
        std::fs::write(
            path(&format!("{name}_rays.bin")),
            bytemuck::cast_slice(rays),
        )?;
        std::fs::write(
            path(&format!("{name}_hits.bin")),
            bytemuck::cast_slice(hits),
        )?;
    }
    Ok(())
}

/// Runs the benchmark.
pub fn run(args: &TraceArgs) -> Result<()> {
    if args.runs == 0 {
        anyhow::bail!("--runs must be at least 1");
    }
    let (width, height) = args.size.size((1280, 720))?;
    args.camera.check()?;
    // Hard shadows: the lights are only shadow ray targets here.
    let hard = ShadowArgs {
        light_radius: None,
        hard_shadows: true,
    };
    let settings = RenderSettings {
        width,
        height,
        bounces: 0,
        seed: 0,
        ..RenderSettings::default()
    };
    let prepared = prepare(args.scene.as_deref(), &args.camera, &hard, false)?;
    let source = prepared.scene.source.clone();
    let mut renderer = Renderer::new(&args.device.device_choice()?)?;
    renderer.set_settings(&settings)?;
    renderer.set_bvh_choice(args.bvh);
    // Traced through the binary or the wide nodes, whichever the device's kernels use.
    renderer.set_node_forms(crate::render::NodeForms::BOTH)?;
    let stats = renderer
        .load_scene(&prepared.scene, &prepared.lights)
        .with_context(|| source.clone())?;
    let instance_move = time_instance_move(&mut renderer, &prepared.scene)?;
    let device = &renderer.device;
    let (Some(program), Some(scene), Some(host)) = (
        renderer.program(),
        renderer.scene_buffers(),
        renderer.host_scene(),
    ) else {
        return Err(anyhow!("{source}: the scene did not load"));
    };
    let mut counters = Buffer::<u32>::new(device, COUNTER_SLOTS)?;
    counters.clear(device)?;
    let tracer = Tracer {
        device,
        program,
        scene,
        counters,
        warmup: args.warmup,
        runs: args.runs,
        wide: args.wide,
    };

    // Primary rays.
    // Rays are made in the render space the scene was uploaded in.
    let camera = gpu_camera(
        &renderer.space().camera(&prepared.camera),
        settings.aspect(),
    );
    let primary = rays::primary_rays(&camera, width, height);
    let (primary_hits, times) = tracer.closest(&primary)?;
    let check = timed(|| check_closest(host, &primary, &primary_hits, args.validate));
    let hit_count = primary_hits.iter().filter(|h| h.prim != MISS).count();
    let mut results = vec![set_result(
        "primary",
        "closest",
        primary.len(),
        hit_count,
        &times,
        check,
    )];

    // Diffuse first-bounce rays from the primary hits.
    let points = rays::surface_points(&primary, &primary_hits, &|h| host.hit_triangle(h));
    if points.is_empty() {
        log::warn!("{source}: no primary ray hit anything; only primary rays timed");
    } else {
        let diffuse = rays::diffuse_rays(&points, primary.len(), args.seed);
        let (hits, times) = tracer.closest(&diffuse)?;
        if let Ok(dir) = std::env::var("PENUMBRA_DUMP_TRACE") {
            dump_trace(
                &dir,
                host,
                &[
                    ("primary", &primary, &primary_hits),
                    ("diffuse", &diffuse, &hits),
                ],
            )?;
        }
        let check = timed(|| check_closest(host, &diffuse, &hits, args.validate));
        let n = hits.iter().filter(|h| h.prim != MISS).count();
        results.push(set_result(
            "diffuse",
            "closest",
            diffuse.len(),
            n,
            &times,
            check,
        ));

        // Shadow rays from the primary hits to the lights.
        let targets = light_targets(&host.space.lights(&prepared.lights), host);
        let shadow = rays::shadow_rays(&points, primary.len(), &targets, args.seed);
        let (occluded, times) = tracer.any(&shadow)?;
        let check = timed(|| check_any(host, &shadow, &occluded, args.validate));
        let n = occluded.iter().filter(|&&o| o != 0).count();
        results.push(set_result("shadow", "any", shadow.len(), n, &times, check));
    }
    let overflows = tracer
        .counters
        .read(device)?
        .get(COUNT_OVERFLOW)
        .copied()
        .unwrap_or(0);
    let total = results
        .iter()
        .fold(Check::default(), |a, r| a.add(r.validation));

    if args.json {
        let summary = serde_json::json!({
            "benchmark": "trace",
            "bvh": if args.wide { "wide" } else { "binary" },
            "date": today(),
            "scene": source,
            "device": device_json(device),
            "width": width,
            "height": height,
            "camera": prepared.camera.name,
            "triangles": stats.triangles,
            "bvh_nodes": stats.nodes,
            "bvh_depth": host.accel.depth(),
            "bvh_levels": stats.bvh,
            "meshes": stats.meshes,
            "instances": stats.instances,
            "device_bytes": stats.device_bytes,
            "sah_cost": stats.sah_cost,
            "load_ms": prepared.load_ms,
            "bvh_build_ms": stats.bvh_build_ms,
            "kernel_build_ms": stats.kernel_build_ms,
            "lights": prepared.lights.len(),
            "emissive_triangles": host.emissive.len(),
            "warmup": args.warmup,
            "runs": args.runs,
            "results": results,
            "checked": total.checked,
            "ties": total.ties,
            "mismatches": total.mismatches,
            "stack_overflows": overflows,
            "instance_move_ms": instance_move.map(|u| u.ms),
            "instance_move_bytes": instance_move.map(|u| u.bytes),
        });
        println!("{summary}");
    } else {
        println!("penumbra bench trace — {source} — {}", today());
        println!("device   {}", device_line(device));
        println!(
            "scene    {} triangles, {} BVH ({} meshes, {} instances), {} nodes (depth {}), SAH \
             cost {:.2}; load {:.0} ms, BVH build {:.0} ms, kernel build {:.0} ms",
            thousands(stats.triangles as u64),
            stats.bvh,
            stats.meshes,
            stats.instances,
            thousands(stats.nodes as u64),
            host.accel.depth(),
            stats.sah_cost,
            prepared.load_ms,
            stats.bvh_build_ms,
            stats.kernel_build_ms
        );
        println!(
            "rays     {}×{} primary from camera '{}'; {} BVH kernels; kernel time from profiling \
             events, median of {} runs after {} warm-up",
            width,
            height,
            prepared.camera.name,
            if args.wide { "4-wide" } else { "binary" },
            args.runs,
            args.warmup
        );
        println!();
        println!(
            "{:<8} {:<7} {:>10} {:>7} {:>10} {:>10} {:>10} {:>11} {:>9} {:>5} {:>10} {:>12}",
            "rays",
            "query",
            "count",
            "hit %",
            "median ms",
            "min ms",
            "max ms",
            "M rays/s",
            "checked",
            "ties",
            "mismatches",
            "host M/s"
        );
        for r in &results {
            println!(
                "{:<8} {:<7} {:>10} {:>7.1} {:>10.3} {:>10.3} {:>10.3} {:>11.2} {:>9} {:>5} {:>10} {:>12.2}",
                r.kind,
                r.query,
                r.rays,
                100.0 * r.hits as f64 / r.rays.max(1) as f64,
                r.median_ms,
                r.min_ms,
                r.max_ms,
                r.rays_per_second * 1e-6,
                r.validation.checked,
                r.validation.ties,
                r.validation.mismatches,
                r.host_rays_per_second * 1e-6
            );
        }
        println!();
        println!(
            "validation: {} rays checked against the host traversal ({} threads), {} mismatches, \
             {} ties, {} stack overflows",
            thousands(total.checked),
            rayon::current_num_threads(),
            total.mismatches,
            total.ties,
            overflows
        );
    }
    if let Some(u) = instance_move
        && !args.json
    {
        println!(
            "instance move: {:.3} ms (new transform, TLAS rebuild, {} bytes written in place)",
            u.ms, u.bytes
        );
    }
    if total.mismatches > 0 || overflows > 0 {
        anyhow::bail!(
            "{source}: the device traversal disagrees with the host on {} of {} rays \
             ({overflows} stack overflows)",
            total.mismatches,
            total.checked
        );
    }
    Ok(())
}

/// With two levels: moves the object with the most triangles by a thousandth of the scene's
/// size and back, three times, through [`Renderer::move_instances`] (new transform, TLAS
/// rebuild, in-place upload); returns the fastest move. The scene ends where it started.
fn time_instance_move(
    renderer: &mut Renderer,
    scene: &crate::scene::Scene,
) -> Result<Option<InstanceUpdate>> {
    if !matches!(renderer.accel(), Some(Accel::TwoLevel(_))) {
        return Ok(None);
    }
    let Some(i) = (0..scene.objects.len())
        .filter(|&i| scene.objects[i].visible)
        .max_by_key(|&i| scene.objects[i].mesh.indices.len())
    else {
        return Ok(None);
    };
    let mut moved = scene.clone();
    let shift = glam::DMat4::from_translation(glam::DVec3::X * scene.bounds().diagonal() * 1e-3);
    let mut best: Option<InstanceUpdate> = None;
    for run in 0..6 {
        moved.objects[i].world_from_object = if run % 2 == 0 {
            shift * scene.objects[i].world_from_object
        } else {
            scene.objects[i].world_from_object
        };
        if let Some(u) = renderer.move_instances(&moved)?
            && best.is_none_or(|b| u.ms < b.ms)
        {
            best = Some(u);
        }
    }
    Ok(best)
}

/// Shadow ray targets: the emissive triangles and the punctual lights of the scene.
fn light_targets(lights: &[crate::scene::Light], host: &crate::render::HostScene) -> LightTargets {
    let mut t = LightTargets {
        triangles: host
            .emissive
            .iter()
            .map(|e| match &host.accel {
                // An emitter names its instance by index, not by TLAS slot as a hit does.
                crate::render::Accel::TwoLevel(two) => two.hit_triangle(e.prim, e.instance),
                crate::render::Accel::Flat(_) => host.hit_triangle(&DeviceHit {
                    prim: e.prim,
                    ..DeviceHit::default()
                }),
            })
            .collect(),
        ..LightTargets::default()
    };
    for l in lights {
        match l.kind {
            LightKind::Directional => t
                .directions
                .push((-l.direction.as_vec3()).normalize_or(Vec3::Y)),
            _ => t.points.push(l.position.as_vec3()),
        }
    }
    let (lo, hi) = match &host.accel {
        crate::render::Accel::Flat(_) => host.vertices.iter().flatten().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        ),
        crate::render::Accel::TwoLevel(two) => {
            let b = two.tlas.child(0, 0).0.union(two.tlas.child(0, 1).0);
            (b.min, b.max)
        }
    };
    t.bounds = (lo, hi);
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_least_the_wanted_rays_are_checked() {
        assert_eq!(sample_indices(10, 0).len(), 10);
        assert_eq!(sample_indices(10, 100).len(), 10);
        let s = sample_indices(1_000_000, 65_536);
        assert!(s.len() >= 65_536 && s.len() < 2 * 65_536);
    }

    #[test]
    fn distances_within_a_relative_tolerance_agree() {
        assert!(same_t(1.0, 1.0));
        assert!(same_t(100.0, 100.0005));
        assert!(!same_t(1.0, 1.001));
    }
}
