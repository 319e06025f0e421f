//! Adaptive sampling (`render --noise-threshold`, docs/adaptive-sampling.md) and the stopping
//! rules, on the test device with both kernels: the expected image is the uniform one (the
//! mean of many adaptive renders agrees with the mean of as many uniform ones within noise),
//! a scene with an easy region (a flat sky around a lit sphere) stops sampling that region
//! early, `--time-limit` stops the render, and bad values fail in one line.

mod common;

use common::{output_dir, penumbra, render_exr, white_sphere_under_panel};
use std::path::Path;

const SIZE: usize = 24;
const BLOCK: usize = 8;
const SEEDS: u32 = 8;

const KERNELS: [&str; 2] = ["megakernel", "wavefront"];

/// Renders `scene` at SIZE² with `kernel` and `extra`; the summary and the pixels.
fn render(
    scene: &Path,
    out: &Path,
    kernel: &str,
    extra: &[&str],
) -> (serde_json::Value, Vec<[f32; 3]>) {
    let size = SIZE.to_string();
    let mut args = vec!["--kernel", kernel, "--width", &size, "--height", &size];
    args.extend_from_slice(extra);
    render_exr(scene, out, &args)
}

/// Per 8×8 block and channel, over `SEEDS` renders: the mean of the block means and the
/// variance of that mean; and the mean samples per pixel the renders took.
fn block_stats(
    scene: &Path,
    dir: &Path,
    kernel: &str,
    extra: &[&str],
) -> (Vec<f64>, Vec<f64>, f64) {
    let n = (SIZE / BLOCK) * (SIZE / BLOCK) * 3;
    let (mut sum, mut sum2) = (vec![0.0f64; n], vec![0.0f64; n]);
    let mut spp = 0.0;
    for seed in 0..SEEDS {
        let seed = (100 + seed).to_string();
        let mut args = vec!["--seed", &seed];
        args.extend_from_slice(extra);
        let (summary, px) = render(scene, &dir.join(format!("{kernel}.exr")), kernel, &args);
        spp += summary["mean_spp"].as_f64().unwrap() / f64::from(SEEDS);
        for b in 0..n {
            let (c, blk) = (b % 3, b / 3);
            let (bx, by) = (blk % (SIZE / BLOCK), blk / (SIZE / BLOCK));
            let mut m = 0.0;
            for y in by * BLOCK..(by + 1) * BLOCK {
                for x in bx * BLOCK..(bx + 1) * BLOCK {
                    m += f64::from(px[y * SIZE + x][c]);
                }
            }
            m /= (BLOCK * BLOCK) as f64;
            sum[b] += m;
            sum2[b] += m * m;
        }
    }
    let k = f64::from(SEEDS);
    let mean: Vec<f64> = sum.iter().map(|s| s / k).collect();
    let var = sum2
        .iter()
        .zip(&mean)
        .map(|(s2, m)| ((s2 / k - m * m) * k / (k - 1.0)).max(0.0) / k)
        .collect();
    (mean, var, spp)
}

#[test]
fn adaptive_renders_average_to_the_uniform_image() {
    let dir = output_dir("adaptive-unbiased");
    let scene = white_sphere_under_panel(&dir, 16, 32);
    for kernel in KERNELS {
        let base = ["--spp", "64", "--sky", "0.3"];
        let (uniform, uniform_var, uniform_spp) = block_stats(&scene, &dir, kernel, &base);
        assert_eq!(uniform_spp, 64.0);
        // With either rule about half the pixels stop, at the minimum (32) or at the check
        // at 48; the others go on to 64.
        for (rule, threshold) in [("error", "0.1"), ("cost", "0.05")] {
            let adaptive_args = [
                &base[..],
                &["--noise-threshold", threshold, "--adaptive-rule", rule],
            ]
            .concat();
            let (adaptive, adaptive_var, adaptive_spp) =
                block_stats(&scene, &dir, kernel, &adaptive_args);
            assert!(
                (32.0..60.0).contains(&adaptive_spp),
                "{kernel}, {rule}: adaptive renders took {adaptive_spp} spp"
            );
            for b in 0..uniform.len() {
                let sigma = (uniform_var[b] + adaptive_var[b]).sqrt();
                let diff = (adaptive[b] - uniform[b]).abs();
                assert!(
                    diff <= 5.0 * sigma + 1e-4 * uniform[b].abs(),
                    "{kernel}, {rule}: block {b}: adaptive mean {} vs uniform {} (σ {sigma})",
                    adaptive[b],
                    uniform[b]
                );
            }
        }
    }
}

#[test]
fn the_cost_rule_stops_pixels_whose_samples_trace_more_rays_sooner() {
    let dir = output_dir("adaptive-cost");
    let scene = white_sphere_under_panel(&dir, 16, 32);
    for kernel in KERNELS {
        let base = [
            "--spp",
            "256",
            "--sky",
            "0.3",
            "--noise-threshold",
            "0.05",
            "--aovs",
        ];
        let mut spp = Vec::new();
        for rule in ["error", "cost"] {
            let out = dir.join(format!("{kernel}-{rule}.exr"));
            let args = [&base[..], &["--adaptive-rule", rule]].concat();
            let (summary, _) = render(&scene, &out, kernel, &args);
            assert_eq!(summary["adaptive_rule"], rule);
            let (_, _, channels) = penumbra::image_io::read_exr_channels(&out).unwrap();
            let (_, samples) = channels
                .into_iter()
                .find(|(n, _)| n == "samples.Y")
                .unwrap();
            spp.push(samples);
        }
        // A sky pixel's samples trace one ray each: the same threshold under both rules, the
        // minimum (48) either way. A sphere pixel's trace at least two (its light sample), so
        // under the cost rule its threshold grows from √2 T at the minimum with its samples:
        // the sphere, which the error rule samples past the minimum, takes fewer.
        let (mut sphere_error, mut sphere_cost, mut sky) = (0.0, 0.0, 0);
        for (e, c) in spp[0].iter().zip(&spp[1]) {
            if *e == 48.0 {
                sky += 1;
            } else {
                sphere_error += e;
                sphere_cost += c;
            }
        }
        assert!(
            sky > SIZE * SIZE / 5,
            "{kernel}: {sky} pixels at the minimum"
        );
        assert!(
            sphere_cost < 0.8 * sphere_error,
            "{kernel}: the pixels past the minimum took {sphere_cost} samples with the cost \
             rule, {sphere_error} with the error rule"
        );
    }
}

#[test]
fn a_flat_sky_converges_at_the_minimum_and_the_sphere_takes_more() {
    let dir = output_dir("adaptive-sky");
    let scene = white_sphere_under_panel(&dir, 16, 32);
    for kernel in KERNELS {
        let out = dir.join(format!("{kernel}.exr"));
        let args = ["--spp", "256", "--sky", "0.3", "--noise-threshold", "0.05"];
        let (summary, px) = render(&scene, &out, kernel, &args);
        let pixels = (SIZE * SIZE) as f64;
        let samples = summary["samples"].as_f64().unwrap();
        let share = summary["converged_share"].as_f64().unwrap();
        let mean_spp = summary["mean_spp"].as_f64().unwrap();
        // The sky seen straight is exactly 0.3 in every sample: no error, converged at the
        // minimum (48 for 0.05); the lit sphere is noisy and keeps sampling.
        assert!(
            share > 0.2 && share < 1.0,
            "{kernel}: converged share {share}"
        );
        assert!(samples < 256.0 * pixels, "{kernel}: {samples} samples");
        assert!((samples / pixels - mean_spp).abs() < 1e-9);
        assert!(
            (48.0..256.0).contains(&mean_spp),
            "{kernel}: {mean_spp} spp"
        );
        assert!(summary["mean_error"].as_f64().unwrap() > 0.0);
        // A corner sees the sky: its value is the sky's, whatever its sample count.
        for c in px[0] {
            assert!((c - 0.3).abs() < 1e-5, "{kernel}: sky corner {:?}", px[0]);
        }
    }
}

#[test]
fn uniform_renders_report_every_sample() {
    let dir = output_dir("adaptive-uniform");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    let (summary, _) = render(&scene, &dir.join("u.exr"), "megakernel", &["--spp", "8"]);
    assert_eq!(summary["samples"], (SIZE * SIZE * 8) as u64);
    assert_eq!(summary["mean_spp"], 8.0);
    assert!(summary["converged_share"].is_null());
    assert!(summary["noise_threshold"].is_null());
}

#[test]
fn a_time_limit_stops_the_render_before_its_samples() {
    let dir = output_dir("adaptive-time");
    let scene = white_sphere_under_panel(&dir, 8, 16);
    for kernel in KERNELS {
        let out = dir.join(format!("{kernel}.exr"));
        let args = ["--spp", "1000000", "--time-limit", "0.5"];
        let (summary, px) = render(&scene, &out, kernel, &args);
        let mean_spp = summary["mean_spp"].as_f64().unwrap();
        assert!((1.0..1e6).contains(&mean_spp), "{kernel}: {mean_spp} spp");
        assert!(px.iter().all(|p| p.iter().all(|c| c.is_finite())));
    }
}

#[test]
fn bad_stopping_rules_fail_in_one_line() {
    for (flag, value) in [
        ("--noise-threshold", "0"),
        ("--noise-threshold", "-1"),
        ("--noise-threshold", "nan"),
        ("--time-limit", "0"),
        ("--time-limit", "inf"),
    ] {
        let o = penumbra(&["render", "missing.glb", "-o", "x.png", flag, value]);
        assert!(!o.status.success(), "{flag} {value} accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{flag} {value}: {err}");
        assert!(err.contains(flag), "{flag} {value}: {err}");
    }
}

#[test]
fn cutting_the_background_out_leaves_the_object_as_it_was() {
    let dir = output_dir("adaptive-cutout");
    let scene = white_sphere_under_panel(&dir, 16, 32);
    for kernel in KERNELS {
        let args = ["--spp", "128", "--sky", "0.3", "--noise-threshold", "0.3"];
        let (_, shown) = render(
            &scene,
            &dir.join(format!("{kernel}-env.exr")),
            kernel,
            &args,
        );
        let cut = [&args[..], &["--background", "transparent"]].concat();
        let (summary, cutout) =
            render(&scene, &dir.join(format!("{kernel}-cut.exr")), kernel, &cut);
        assert!(summary["converged_share"].as_f64().unwrap() > 0.0);
        // The sky corner: no hit, nothing; the image centre lies on the sphere, far from its
        // edge, so its neighbourhood converges alike either way: it took the same samples and
        // shows the same mean.
        assert_eq!(cutout[0], [0.0; 3], "{kernel}");
        let centre = SIZE / 2 * SIZE + SIZE / 2;
        for c in 0..3 {
            let (a, b) = (cutout[centre][c], shown[centre][c]);
            assert!(
                b > 0.0 && (a - b).abs() <= 1e-5 * b,
                "{kernel}: centre {a} vs {b}"
            );
        }
    }
}
