//! Host-side costs a user waits for when a scene opens: the binned-SAH BVH build (triangles per
//! second on generated soups of 100k and 1M triangles and, when PENUMBRA_BVH_SCENE names a glTF
//! file such as the room of `penumbra bench generate`, on that scene's world triangles), the
//! same builds timed in process CPU time (all threads; on a machine shared with other work the
//! wall time says little), the refit of the 1M soup, and glTF loading (the bundled Cornell box
//! and, when PENUMBRA_SCENES is set, StanfordBunny). Sample sizes are small so that
//! `cargo bench --bench bvh` finishes in a few minutes on two cores.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

/// `n` small triangles scattered through the unit cube (a deterministic hash, no RNG crate):
/// the kind of soup a scanned mesh or a scene of many objects gives the builder.
fn soup(n: usize) -> Vec<[Vec3; 3]> {
    let hash = |mut x: u32| {
        x ^= x >> 16;
        x = x.wrapping_mul(0x7feb_352d);
        x ^= x >> 15;
        x = x.wrapping_mul(0x846c_a68b);
        x ^ (x >> 16)
    };
    let unit = |i: usize, k: u32| (hash(hash(i as u32) ^ k) >> 8) as f32 / 16_777_216.0;
    (0..n)
        .map(|i| {
            let c = Vec3::new(unit(i, 1), unit(i, 2), unit(i, 3));
            let d = |k: u32| (Vec3::new(unit(i, k), unit(i, k + 1), unit(i, k + 2)) - 0.5) * 0.01;
            [c + d(4), c + d(7), c + d(10)]
        })
        .collect()
}

/// CPU time this process has used, all threads together (Linux: the scheduler's per-thread
/// run time in nanoseconds, `/proc/self/task/*/schedstat`); `None` elsewhere.
fn process_cpu_time() -> Option<Duration> {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(Duration::from_nanos(ns))
}

fn bvh_build(c: &mut Criterion) {
    let mut inputs: Vec<(String, Vec<[Vec3; 3]>)> = [100_000usize, 1_000_000]
        .into_iter()
        .map(|n| (n.to_string(), soup(n)))
        .collect();
    if let Some(path) = std::env::var_os("PENUMBRA_BVH_SCENE") {
        let scene = penumbra::scene::load(&PathBuf::from(path)).expect("PENUMBRA_BVH_SCENE loads");
        inputs.push((
            "scene".into(),
            scene.world_triangles().iter().map(|t| t.v).collect(),
        ));
    }
    // The builds in wall time, then in CPU time: criterion's "time" of `bvh_build_cpu` is the
    // CPU time of every thread, so RAYON_NUM_THREADS=1 and =2 give the builder's parallel
    // overhead, and a loaded machine distorts it far less than the wall time.
    for cpu_time in [false, true] {
        if cpu_time && process_cpu_time().is_none() {
            continue;
        }
        let name = if cpu_time {
            "bvh_build_cpu"
        } else {
            "bvh_build"
        };
        let mut group = c.benchmark_group(name);
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(5));
        for (name, tris) in &inputs {
            group.throughput(Throughput::Elements(tris.len() as u64));
            group.bench_with_input(BenchmarkId::from_parameter(name), tris, |b, tris| {
                let build = || black_box(penumbra::bvh::build(black_box(tris)));
                if !cpu_time {
                    return b.iter(build);
                }
                b.iter_custom(|iters| {
                    let cpu = || process_cpu_time().unwrap_or_default();
                    let start = cpu();
                    for _ in 0..iters {
                        build();
                    }
                    cpu().saturating_sub(start)
                })
            });
        }
        group.finish();
    }

    // Refit after every vertex moved a little (the topology stays, the boxes change).
    let mut group = c.benchmark_group("bvh_refit");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let n = 1_000_000;
    let tris = soup(n);
    let moved: Vec<[Vec3; 3]> = tris
        .iter()
        .map(|t| t.map(|v| v + Vec3::new(v.y, v.z, v.x) * 0.01))
        .collect();
    let mut bvh = penumbra::bvh::build(&tris);
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function(BenchmarkId::from_parameter(n), |b| {
        b.iter(|| bvh.refit(black_box(&moved)))
    });
    group.finish();
}

fn gltf_load(c: &mut Criterion) {
    let mut group = c.benchmark_group("gltf_load");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    group.bench_function("bundled cornell box", |b| {
        b.iter(|| {
            black_box(penumbra::scene::load_or_bundled(None).expect("the bundled scene loads"))
        })
    });
    if let Some(dir) = std::env::var_os("PENUMBRA_SCENES") {
        let bunny = PathBuf::from(dir).join("StanfordBunny/bunny.glb");
        if bunny.exists() {
            group.bench_function("StanfordBunny", |b| {
                b.iter(|| black_box(penumbra::scene::load(&bunny).expect("the bunny loads")))
            });
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    // No HTML plots: plotters is built here without system fonts (the machines have none;
    // `bench converge`'s plot brings its own font).
    config = Criterion::default().without_plots();
    targets = bvh_build, gltf_load
}
criterion_main!(benches);
