//! Host-side costs a user waits for when a scene opens: the binned-SAH BVH build (triangles per
//! second on generated soups of 100k and 1M triangles) and glTF loading (the bundled Cornell box
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

fn bvh_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("bvh_build");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for n in [100_000usize, 1_000_000] {
        let tris = soup(n);
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &tris, |b, tris| {
            b.iter(|| black_box(penumbra::bvh::build(black_box(tris))))
        });
    }
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
    // No HTML plots: plotters is built here without system fonts (see docs/benchmarks.md).
    config = Criterion::default().without_plots();
    targets = bvh_build, gltf_load
}
criterion_main!(benches);
