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

/// A closed room 6 × 2.7 × 4 m (the inside of a box, faces inward) seen from inside by its own
/// camera, looking at the far wall; `spot` adds a narrow spot light that lights a disc of that
/// wall (a room partly lit by its own lights); `open_top` leaves out the
/// ceiling (the sky reaches in).
fn room_glb(dir: &std::path::Path, name: &str, spot: bool, open_top: bool) -> PathBuf {
    let mut g = common::Gltf::default();
    let white = g.lambert([0.8; 3], [0.0; 3], 1.0, false);
    let (positions, outward) = common::cuboid([-3.0, 0.0, -2.0], [3.0, 2.7, 2.0]);
    let mut indices: Vec<u32> = outward.chunks(3).flat_map(|t| [t[0], t[2], t[1]]).collect();
    if open_top {
        // The +y quad is the fourth: its two triangles.
        indices.drain(18..24);
    }
    let mesh = g.mesh(vec![common::Prim::triangles(positions, indices, white)]);
    g.node(serde_json::json!({"mesh": mesh}));
    g.cameras.push(
        serde_json::json!({"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}),
    );
    g.node(serde_json::json!({"camera": 0, "translation": [0.0, 1.4, 1.8]}));
    if spot {
        g.lights
            .push(serde_json::json!({"type": "spot", "intensity": 40.0,
            "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.3}}));
        // In the middle of the room, facing the far wall (a light looks down −z).
        g.node(
            serde_json::json!({"extensions": {"KHR_lights_punctual": {"light": 0}},
            "translation": [0.0, 1.4, 0.0]}),
        );
    }
    g.write_glb(dir, name)
}

#[test]
fn an_environment_is_added_only_where_the_sky_reaches() {
    let dir = output_dir("first_image_closed_rooms");
    let run = |name: &str, spot: bool, open_top: bool, extra: &[&str]| {
        let glb = room_glb(&dir, name, spot, open_top);
        let png = dir.join(format!("{name}.png"));
        let o = render_small(&glb, &png, extra);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (summary, png)
    };
    // A dark closed room: no environment (it could not get in; the image stayed black), but
    // the interior's lamps, which replace the default rig (placed outside) and light it.
    let (s, png) = run("dark", false, false, &[]);
    let (median, _, black) = png_stats(&png);
    assert_eq!(s["first_view"]["sky_fraction"], 0.0, "{s}");
    assert!(s["environment"].is_null(), "{s}");
    assert_eq!(s["default_light_rig"], false, "{s}");
    assert_eq!(s["lights"], 2, "{s}");
    assert!(
        black < 0.1 && median > 0.15,
        "the dark room renders {black:.2} black, at median {median:.3}"
    );
    // A closed room that its own spot light lights in part keeps that light alone, and the
    // studio environment, asked for, would have added nothing to it.
    let (s, _) = run("spot", true, false, &[]);
    let lit = s["first_view"]["lit_fraction"].as_f64().unwrap();
    assert!(lit > 0.0 && lit < 0.25, "{s}");
    assert!(s["environment"].is_null(), "{s}");
    assert_eq!(s["lights"], 1, "{s}");
    // Converged enough (linear, 64 spp) to show that the environment adds nothing.
    let glb = dir.join("spot.glb");
    let mean = |extra: &[&str]| {
        let exr = dir.join("spot.exr");
        let args = [
            &["--width", "48", "--height", "36", "--spp", "64"][..],
            extra,
        ]
        .concat();
        let (s, px) = common::render_exr(&glb, &exr, &args);
        let sum: f64 = px.iter().map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0).sum();
        (s, sum / px.len() as f64)
    };
    let (_, alone) = mean(&[]);
    let (s, with_env) = mean(&["--env", "studio"]);
    assert_eq!(s["environment"], "studio", "{s}");
    assert!(
        alone > 0.0 && (with_env / alone - 1.0).abs() < 0.05,
        "the spot-lit room's mean: {alone:.4} alone, {with_env:.4} with the environment"
    );
    // Without a ceiling the sky gets in: the studio environment lights the room.
    let (s, _) = run("open", false, true, &[]);
    assert!(
        s["first_view"]["sky_fraction"].as_f64().unwrap() > 0.05,
        "{s}"
    );
    assert_eq!(s["environment"], "studio", "{s}");
}
