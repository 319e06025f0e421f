//! The megakernel (whole paths per work item, CPU devices) against the wavefront (queued
//! stages, GPUs): both must compute the same estimator. Independent renders of the Cornell box
//! with several seeds give per-block means and their standard errors for each kernel; the
//! means must agree within noise.

mod common;

use common::render_exr;
use std::path::Path;

const SIZE: usize = 32;
const BLOCK: usize = 8;
const SEEDS: u32 = 8;

/// Per 8×8 block and channel: the mean over seeds of the block mean, and its variance (of the
/// mean over seeds), from `SEEDS` renders of `kernel`.
fn block_stats(kernel: &str, dir: &Path, seed0: u32) -> (Vec<f64>, Vec<f64>) {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let blocks = (SIZE / BLOCK) * (SIZE / BLOCK) * 3;
    let mut sum = vec![0.0f64; blocks];
    let mut sum2 = vec![0.0f64; blocks];
    for s in 0..SEEDS {
        let out = dir.join(format!("{kernel}-{s}.exr"));
        let seed = (seed0 + s).to_string();
        let size = SIZE.to_string();
        let (summary, px) = render_exr(
            &scene,
            &out,
            &[
                "--kernel",
                kernel,
                "--width",
                &size,
                "--height",
                &size,
                "--spp",
                "16",
                "--bounces",
                "6",
                "--seed",
                &seed,
            ],
        );
        assert_eq!(
            summary["kernel"],
            if kernel == "megakernel" {
                "Megakernel"
            } else {
                "Wavefront"
            }
        );
        assert_eq!(summary["nonfinite_samples"], 0);
        for (b, (s1, s2)) in sum.iter_mut().zip(sum2.iter_mut()).enumerate() {
            let (c, blk) = (b % 3, b / 3);
            let (bx, by) = (blk % (SIZE / BLOCK), blk / (SIZE / BLOCK));
            let mut m = 0.0;
            for y in by * BLOCK..(by + 1) * BLOCK {
                for x in bx * BLOCK..(bx + 1) * BLOCK {
                    m += px[y * SIZE + x][c] as f64;
                }
            }
            m /= (BLOCK * BLOCK) as f64;
            *s1 += m;
            *s2 += m * m;
        }
    }
    let n = SEEDS as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / n).collect();
    let var: Vec<f64> = sum2
        .iter()
        .zip(&mean)
        .map(|(s2, m)| (s2 / n - m * m).max(0.0) * n / (n - 1.0) / n)
        .collect();
    (mean, var)
}

#[test]
fn megakernel_and_wavefront_agree_within_noise() {
    let dir = tempfile::tempdir().unwrap();
    let (mw, vw) = block_stats("wavefront", dir.path(), 100);
    let (mm, vm) = block_stats("megakernel", dir.path(), 200);
    let mut z2 = 0.0;
    let mut worst = 0.0f64;
    let mut n = 0;
    for i in 0..mw.len() {
        let se = (vw[i] + vm[i]).sqrt();
        if mw[i] < 1e-4 && mm[i] < 1e-4 {
            continue; // a black block in both
        }
        assert!(se > 0.0, "block {i}: no noise in {} / {}", mw[i], mm[i]);
        let z = (mm[i] - mw[i]) / se;
        worst = worst.max(z.abs());
        z2 += z * z;
        n += 1;
    }
    assert!(n >= 24, "enough lit blocks ({n})");
    // With 8 seeds a side z is t-distributed with ~14 degrees of freedom: |z| > 5 has a
    // probability below 1e-3 per block, and the mean of z² is about 1.2.
    let mean_z2 = z2 / n as f64;
    assert!(worst < 5.0, "a block differs by {worst:.2} standard errors");
    assert!(mean_z2 < 2.5, "mean z² {mean_z2:.2} over {n} blocks");
    // A real difference is seen: a 3% brighter image fails the same test.
    let mut z2_biased = 0.0;
    for i in 0..mw.len() {
        let se = (vw[i] + vm[i]).sqrt();
        if se > 0.0 {
            let z = (mm[i] * 1.03 - mw[i]) / se;
            z2_biased += z * z;
        }
    }
    assert!(z2_biased / n as f64 > 2.5, "the test can see a 3% bias");
}

#[test]
fn the_same_seed_traces_the_same_paths_in_both_kernels() {
    // Both kernels draw the same random numbers for the same (pixel, sample, seed) and shade
    // with the same code, so they trace the same rays.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let dir = tempfile::tempdir().unwrap();
    let args = |k: &'static str| {
        vec![
            "--kernel",
            k,
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "4",
            "--bounces",
            "5",
        ]
    };
    let (a, pa) = render_exr(&scene, &dir.path().join("w.exr"), &args("wavefront"));
    let (b, pb) = render_exr(&scene, &dir.path().join("m.exr"), &args("megakernel"));
    let rays = |v: &serde_json::Value| {
        v["rays_per_second"].as_f64().unwrap() * v["seconds"].as_f64().unwrap()
    };
    let (ra, rb) = (rays(&a), rays(&b));
    assert!((ra - rb).abs() <= 1e-6 * ra + 2.0, "{ra} rays against {rb}");
    let (ma, mb) = (common::mean_gray(&pa), common::mean_gray(&pb));
    assert!((ma - mb).abs() <= 1e-3 * ma, "mean {ma} against {mb}");
}
