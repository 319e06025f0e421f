//! Accuracy against an independent renderer: the bundled Lambertian Cornell box rendered by
//! Mitsuba 3 (scripts/mitsuba_reference.py, tests/references/README.md) and by penumbra must
//! agree within noise. Writes the actual and difference images on failure.

mod common;

use common::{output_dir, render_exr};
use std::path::Path;

#[test]
fn cornell_box_agrees_with_mitsuba() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let (w, h, reference) =
        penumbra::image_io::read_exr(&root.join("tests/references/cornell-box-mitsuba-64.exr"))
            .unwrap();
    assert_eq!((w, h), (64, 64));
    let out = output_dir("reference");
    let actual_path = out.join("cornell-box-actual.exr");
    let (summary, actual) = render_exr(
        &root.join("assets/cornell-box.glb"),
        &actual_path,
        &[
            "--width",
            "64",
            "--height",
            "64",
            "--bounces",
            "8",
            "--hard-shadows",
            "--spp",
            "1024",
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0);

    // Compare 8x8-pixel block means channel by channel, relative to the reference block.
    let block = 8;
    let mut worst = 0.0f64;
    let mut sum_rel = 0.0f64;
    let mut n = 0;
    let mut sums = [[0.0f64; 2]; 3];
    for by in 0..h as usize / block {
        for bx in 0..w as usize / block {
            for c in 0..3 {
                let (mut a, mut r) = (0.0f64, 0.0f64);
                for y in by * block..(by + 1) * block {
                    for x in bx * block..(bx + 1) * block {
                        a += actual[y * 64 + x][c] as f64;
                        r += reference[y * 64 + x][c] as f64;
                    }
                }
                sums[c][0] += a;
                sums[c][1] += r;
                if r > 1e-3 * (block * block) as f64 {
                    let rel = (a - r).abs() / r;
                    worst = worst.max(rel);
                    sum_rel += rel;
                    n += 1;
                }
            }
        }
    }
    let mean_rel = sum_rel / n as f64;
    // The image-wide mean per channel shows bias that block noise could hide.
    let bias: Vec<f64> = sums.iter().map(|s| s[0] / s[1] - 1.0).collect();
    eprintln!(
        "penumbra vs Mitsuba: worst block {:.2}%, mean block {:.2}%, channel bias {:?}",
        worst * 100.0,
        mean_rel * 100.0,
        bias
    );
    let ok = worst < 0.05 && mean_rel < 0.015 && bias.iter().all(|b| b.abs() < 0.01);
    if !ok {
        let diff: Vec<[f32; 3]> = actual
            .iter()
            .zip(&reference)
            .map(|(a, r)| [0, 1, 2].map(|c| (a[c] - r[c]).abs()))
            .collect();
        penumbra::image_io::write_exr(&out.join("cornell-box-difference.exr"), 64, 64, &diff)
            .unwrap();
    }
    assert!(
        ok,
        "penumbra vs Mitsuba: worst block {:.2}%, mean block {:.2}%, channel bias {:?}; \
         actual and difference images in {}",
        worst * 100.0,
        mean_rel * 100.0,
        bias,
        out.display()
    );
}
