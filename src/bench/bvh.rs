//! `penumbra bench bvh SCENE`: how long the host takes to build the scene's BVH and to update
//! it when one instance moves (see `bvh::report`).

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
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// Runs the benchmark.
pub fn run(args: &BvhArgs) -> Result<()> {
    let t = Instant::now();
    let scene = load(&args.scene)?;
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    let r = crate::bvh::report(&scene, args.runs);
    let threads = rayon::current_num_threads();
    if args.json {
        let mut json = serde_json::json!({
            "benchmark": "bvh",
            "date": today(),
            "scene": scene.source,
            "threads": threads,
            "load_ms": load_ms,
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
    println!(
        "  nodes, depth       {:>12}, {}",
        thousands(r.nodes as u64),
        r.depth
    );
    println!("  load               {:>12.1} ms", load_ms);
    println!("  gather triangles   {:>12.1} ms", r.gather_ms);
    println!("  full build         {:>12.1} ms", r.full_build_ms);
    println!(
        "  flat move          {:>12.1} ms (move one instance, rebuild the flat BVH)",
        r.flat_move_ms
    );
    println!(
        "  two-level build    {:>12.1} ms (every BLAS and the TLAS, host only)",
        r.two_level_build_ms
    );
    println!(
        "  instance move      {:>12.3} ms (new TLAS, host only)",
        r.instance_move_ms
    );
    println!("  refit              {:>12.1} ms", r.refit_ms);
    println!(
        "  SAH cost           {:>12.2} (after the refit {:.2})",
        r.sah_cost, r.refit_sah_cost
    );
    Ok(())
}
