//! The first image of every shared scene, rendered with no options (small, few samples): not
//! black, not blown out, the subject covering the frame and itself well exposed (measured on the
//! same render with the background cut out), interiors seen from inside. Skipped
//! (with a note) when PENUMBRA_SCENES is not set.

mod common;

use common::{output_dir, penumbra, scenes_dir};
use std::path::PathBuf;

/// The scenes, without the meshopt copy (the same model as lamborghini.glb; tests/scenes.rs
/// renders it).
fn scene_files() -> Vec<PathBuf> {
    let Some(dir) = scenes_dir() else {
        eprintln!("PENUMBRA_SCENES is not set: skipping the first images");
        return vec![];
    };
    let mut files = vec![];
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        for f in std::fs::read_dir(entry.path())
            .into_iter()
            .flatten()
            .flatten()
        {
            let p = f.path();
            let name = p.to_string_lossy();
            if matches!(p.extension().and_then(|e| e.to_str()), Some("glb" | "gltf"))
                && !name.contains("meshopt")
            {
                files.push(p);
            }
        }
    }
    files.sort();
    files
}

/// Luminance statistics of an sRGB PNG: (median luma in [0, 1] of the pixels that are not black,
/// share of pixels with a channel at 255, share of pixels darker than 2%).
fn png_stats(path: &std::path::Path) -> (f64, f64, f64) {
    let img = image::open(path).unwrap().into_rgb8();
    let mut luma: Vec<f64> = img
        .pixels()
        .map(|p| (0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64) / 255.0)
        .collect();
    let n = luma.len() as f64;
    let clipped = img.pixels().filter(|p| p.0.contains(&255)).count() as f64 / n;
    let black = luma.iter().filter(|&&l| l < 0.02).count() as f64 / n;
    luma.retain(|&l| l >= 0.02);
    luma.sort_by(f64::total_cmp);
    let median = luma.get(luma.len() / 2).copied().unwrap_or(0.0);
    (median, clipped, black)
}

/// Statistics of the subject of a PNG rendered with `--background transparent`: the pixels
/// with alpha ≥ 128 (camera rays mostly hit): (their share of the image, their median luma,
/// the share of them with a channel at 255).
fn subject_stats(path: &std::path::Path) -> (f64, f64, f64) {
    let img = image::open(path).unwrap().into_rgba8();
    let n = (img.width() * img.height()) as f64;
    let subject: Vec<_> = img.pixels().filter(|p| p[3] >= 128).collect();
    let mut luma: Vec<f64> = subject
        .iter()
        .map(|p| (0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64) / 255.0)
        .collect();
    luma.sort_by(f64::total_cmp);
    let median = luma.get(luma.len() / 2).copied().unwrap_or(0.0);
    let clipped = subject.iter().filter(|p| p.0[..3].contains(&255)).count() as f64;
    (
        subject.len() as f64 / n,
        median,
        clipped / subject.len().max(1) as f64,
    )
}

/// The small default render each scene gets here (96×72, 4 spp, 2 bounces), plus `extra`.
fn render_small(
    scene: &std::path::Path,
    out: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--width",
        "96",
        "--height",
        "72",
        "--spp",
        "4",
        "--bounces",
        "2",
    ];
    args.extend_from_slice(extra);
    penumbra(&args)
}

#[test]
fn every_shared_scene_opens_readable() {
    let out = output_dir("first_image");
    let mut failures = Vec::new();
    for scene in scene_files() {
        let name = scene.file_stem().unwrap().to_string_lossy().to_string();
        let png = out.join(format!("{name}.png"));
        let o = render_small(&scene, &png, &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{name}: {err}");
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let view = &summary["first_view"];
        let coverage = view["coverage"].as_f64().unwrap();
        let (median, clipped, black) = png_stats(&png);
        // The same render with the background cut out shows the subject alone.
        let cut = out.join(format!("{name}-subject.png"));
        let o = render_small(&scene, &cut, &["--background", "transparent"]);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (share, subject_median, subject_clipped) = subject_stats(&cut);
        eprintln!(
            "{name}: median luma {median:.2}, clipped {:.0}%, black {:.0}%, coverage {:.0}%, \
             interior {}, env {}; subject {:.0}% of the frame, median luma {subject_median:.2}, \
             clipped {:.0}%",
            clipped * 100.0,
            black * 100.0,
            coverage * 100.0,
            view["interior"],
            summary["environment"],
            share * 100.0,
            subject_clipped * 100.0,
        );
        // The subject itself is exposed: neither dark nor washed out, little of it clipped. (At
        // 4 spp dark noise pulls the metered key down, so bright subjects (a lime car, an
        // emitting ball) show a median up to about 0.85; clipping is what marks blown out.)
        if !(0.12..=0.88).contains(&subject_median) {
            failures.push(format!(
                "{name}: the subject's median luma is {subject_median:.2}"
            ));
        }
        if subject_clipped > 0.12 {
            failures.push(format!(
                "{name}: {:.0}% of the subject clips",
                subject_clipped * 100.0
            ));
        }
        if share < 0.12 {
            failures.push(format!(
                "{name}: the subject fills {:.0}% of the frame",
                share * 100.0
            ));
        }
        if !(0.05..=0.85).contains(&median) {
            failures.push(format!(
                "{name}: median luma {median:.2} (too dark or too bright)"
            ));
        }
        if clipped > 0.15 {
            failures.push(format!("{name}: {:.0}% of pixels clip", clipped * 100.0));
        }
        // Without an environment the background is black: only the subject may not be.
        if black > (1.0 - coverage) + 0.15 {
            failures.push(format!("{name}: {:.0}% of pixels are black", black * 100.0));
        }
        if coverage < 0.12 {
            failures.push(format!(
                "{name}: the subject covers {:.0}%",
                coverage * 100.0
            ));
        }
        let interior = name == "dream-apartment" || name == "hotel-room";
        if view["interior"].as_bool() != Some(interior) {
            failures.push(format!("{name}: interior is {}", view["interior"]));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn auto_exposure_yields_to_exposure_and_ev100() {
    let dir = output_dir("first_image_exposure");
    let png = dir.join("cornell.png");
    for (extra, expected) in [
        (vec!["--exposure", "-2.5"], Some(-2.5)),
        (vec!["--ev100", "0"], Some(-(1.2f64.log2()))),
        (vec![], None),
    ] {
        let mut args = vec![
            "render",
            "-o",
            png.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "2",
        ];
        args.insert(1, "assets/cornell-box.glb");
        args.extend(extra.iter());
        let o = penumbra(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let stops = summary["exposure"].as_f64().unwrap();
        match expected {
            Some(e) => assert!((stops - e).abs() < 1e-4, "{extra:?}: {stops}"),
            None => assert_eq!(summary["auto_exposure"], true),
        }
        // Without a terminal, progress comes as lines.
        assert!(String::from_utf8_lossy(&o.stderr).contains("render 100%"));
    }
}
