//! `penumbra bench bvh SCENE`: how long the host takes to build the scene's BVH and to update
//! it when one instance moves (see `scene::bvh_report`).

use super::thousands;
use crate::date::today;
use crate::scene::load;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `bench bvh`.
#[derive(Args, Debug, Clone)]
pub struct BvhArgs {
    /// glTF or GLB file.
    pub scene: PathBuf,
    /// Timed runs of each measurement (the fastest is reported).
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Leave out the flat form (flattening every instance): the figures, and the peak memory,
    /// are then the two-level form's alone.
    #[arg(long)]
    pub two_level_only: bool,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// The process's peak resident memory so far (`VmHWM` of /proc/self/status), where known.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Runs the benchmark.
pub fn run(args: &BvhArgs) -> Result<()> {
    let cold = peak_rss_bytes();
    // The process's baseline: the bundled 32-triangle box loaded and built once, so that the
    // code these steps run is paged in and the threads are started (2.8 MB on the 2-core
    // machine, whatever the scene) before the scene's own memory is counted.
    if let Ok(bundled) = crate::scene::load_or_bundled(None) {
        crate::scene::bvh_report::report(&bundled, 1, false);
    }
    // Every step measured is part of opening a scene, under its allocator policy.
    let _memory = crate::cl::kernels::OpeningMemory::begin();
    let before = peak_rss_bytes();
    let t = Instant::now();
    let scene = load(&args.scene)?;
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    let loaded = peak_rss_bytes();
    let r = crate::scene::bvh_report::report(&scene, args.runs, !args.two_level_only);
    let peak = peak_rss_bytes();
    // The first view (framing probe) as `render` and the viewer decide it before the upload:
    // part of opening a scene without a camera, and of any scene's light test.
    let t = Instant::now();
    let own_lights = if scene.default_rig {
        Vec::new()
    } else {
        scene.lights.clone()
    };
    crate::scene::framing::first_view(&scene, &own_lights, None, 16.0 / 9.0);
    let first_view_ms = t.elapsed().as_secs_f64() * 1e3;
    let first_view_peak = peak_rss_bytes();
    // The two levels the viewer traces first on a large scene: quick BLASes and the TLAS, the
    // BLASes those that the first view's probe built (as the viewer takes them).
    let space = crate::scene::RenderFrame::around(&scene.bounds());
    let t = Instant::now();
    let quick = crate::render::instancing::plan(
        &scene,
        &space,
        crate::render::BvhChoice::TwoLevel,
        crate::render::instancing::AUTO_CPU,
        crate::render::instancing::Blases::Quick {
            from: 0,
            ready: scene.take_quick_blases(),
        },
    );
    let quick_ms = quick.is_some().then(|| t.elapsed().as_secs_f64() * 1e3);
    drop(quick);
    // What loading and building added to the process's peak, per distinct triangle: above
    // the baseline, and above the process's cold start.
    let added = |from: Option<u64>| match (from, peak) {
        (Some(b), Some(p)) if r.unique_triangles > 0 => {
            Some(p.saturating_sub(b) as f64 / r.unique_triangles as f64)
        }
        _ => None,
    };
    let (per_unique, per_unique_cold) = (added(before), added(cold));
    let threads = rayon::current_num_threads();
    if args.json {
        let mut json = serde_json::json!({
            "benchmark": "bvh",
            "date": today(),
            "scene": scene.source,
            "threads": threads,
            "load_ms": load_ms,
            "peak_rss_bytes": peak,
            "load_peak_rss_bytes": loaded,
            "start_rss_bytes": before,
            "cold_start_rss_bytes": cold,
            "first_view_ms": first_view_ms,
            "first_view_peak_rss_bytes": first_view_peak,
            "quick_two_level_build_ms": quick_ms,
            "added_bytes_per_unique_triangle": per_unique,
            "cold_added_bytes_per_unique_triangle": per_unique_cold,
        });
        if let (Some(o), serde_json::Value::Object(m)) =
            (json.as_object_mut(), serde_json::to_value(&r)?)
        {
            o.extend(m);
        }
        println!("{json}");
        return Ok(());
    }
    println!(
        "{} ({} threads, {}, fastest of {} runs)",
        scene.source,
        threads,
        today(),
        r.runs
    );
    println!("  triangles          {:>12}", thousands(r.triangles as u64));
    println!(
        "  unique triangles   {:>12}",
        thousands(r.unique_triangles as u64)
    );
    println!("  instances          {:>12}", thousands(r.instances as u64));
    println!("  load               {:>12.1} ms", load_ms);
    if let (Some(nodes), Some(depth), Some(gather), Some(flat), Some(moved), Some(refit)) = (
        r.nodes,
        r.depth,
        r.gather_ms,
        r.flat_build_ms,
        r.flat_move_ms,
        r.refit_ms,
    ) {
        println!(
            "  nodes, depth       {:>12}, {}",
            thousands(nodes as u64),
            depth
        );
        println!("  gather triangles   {:>12.1} ms", gather);
        println!(
            "  flat build         {:>12.1} ms (one tree over every placed triangle)",
            flat
        );
        println!(
            "  flat move          {:>12.1} ms (move one instance, rebuild the flat BVH)",
            moved
        );
        println!("  refit              {:>12.1} ms", refit);
        println!(
            "  SAH cost           {:>12.2} (after the refit {:.2})",
            r.sah_cost.unwrap_or(0.0),
            r.refit_sah_cost.unwrap_or(0.0)
        );
    }
    println!(
        "  full build         {:>12.1} ms (every BLAS and the TLAS, host only; {} nodes)",
        r.full_build_ms,
        thousands(r.two_level_nodes as u64)
    );
    if let Some(ms) = quick_ms {
        println!(
            "  quick two-level    {:>12.1} ms (quick BLASes and the TLAS: what the viewer traces first)",
            ms
        );
    }
    println!(
        "  instance move      {:>12.3} ms (new TLAS, host only)",
        r.instance_move_ms
    );
    println!(
        "  first view         {:>12.1} ms (framing probe: world vertices and their BVH)",
        first_view_ms
    );
    if let (Some(peak), Some(per), Some(cold), Some(loaded)) =
        (peak, per_unique, per_unique_cold, loaded)
    {
        println!(
            "  peak memory        {:>12.1} MB ({per:.0} bytes a distinct triangle above the \
             baseline, {cold:.0} above the cold start; {:.1} MB after loading)",
            peak as f64 / 1e6,
            loaded as f64 / 1e6
        );
    }
    Ok(())
}
