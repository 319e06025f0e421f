//! The thin-lens camera: a sharp edge stays sharp in the plane of focus and blurs by the
//! circle of confusion elsewhere; focus distances from the host BVH.

mod common;

use common::{Gltf, Prim, render_exr};
use penumbra::cl::DeviceChoice;
use penumbra::render::Renderer;
use serde_json::json;
use std::path::{Path, PathBuf};

/// An emissive rectangle (x < 0) beside a black one (x > 0) at z = 0, seen from z = 5 with a
/// vertical field of view of 0.4 rad; both reach beyond the image.
fn edge(dir: &Path) -> PathBuf {
    let mut g = Gltf::default();
    let light = g.lambert([0.0; 3], [1.0; 3], 1.0, false);
    let black = g.lambert([0.0; 3], [0.0; 3], 1.0, false);
    let square = |x0: f32, x1: f32, m: usize| {
        Prim::triangles(
            vec![
                [x0, -2.0, 0.0],
                [x1, -2.0, 0.0],
                [x1, 2.0, 0.0],
                [x0, 2.0, 0.0],
            ],
            vec![0, 1, 2, 0, 2, 3],
            m,
        )
    };
    let mesh = g.mesh(vec![square(-6.0, 0.0, light), square(0.0, 6.0, black)]);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.4, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 5.0]}));
    g.write_glb(dir, "edge")
}

/// Pixels of the middle row that are neither dark nor fully lit.
fn blurred_pixels(px: &[[f32; 3]], width: usize, height: usize) -> usize {
    let row = &px[(height / 2) * width..(height / 2 + 1) * width];
    row.iter().filter(|p| p[0] > 0.03 && p[0] < 0.97).count()
}

#[test]
fn out_of_focus_edges_blur_by_the_circle_of_confusion() {
    let dir = tempfile::tempdir().unwrap();
    let scene = edge(dir.path());
    let out = dir.path().join("e.exr");
    let render = |extra: &[&str]| {
        let mut args = vec![
            "--width",
            "64",
            "--height",
            "16",
            "--spp",
            "64",
            "--bounces",
            "0",
        ];
        args.extend_from_slice(extra);
        render_exr(&scene, &out, &args)
    };
    // Pinhole, and the lens focused on the edge's plane: only the pixel on the edge is mixed.
    let (_, pinhole) = render(&[]);
    assert!(blurred_pixels(&pinhole, 64, 16) <= 2);
    let (summary, sharp) = render(&["--aperture", "0.2", "--focus-distance", "5"]);
    assert_eq!(summary["nonfinite_samples"], 0);
    assert!(blurred_pixels(&sharp, 64, 16) <= 2);
    // Focused at 2.5 with a lens of radius 0.5, a point of the plane z = 0 spreads over a
    // circle of radius 0.5·(5 − 2.5)/2.5 = 0.5 units there, 3.9 pixels (a pixel covers
    // 2·5·tan(0.2)/16 = 0.127 units); pixels within about 0.8 radii of the edge are mixed.
    let (_, blurred) = render(&["--aperture", "0.5", "--focus-distance", "2.5"]);
    let n = blurred_pixels(&blurred, 64, 16);
    assert!((4..=10).contains(&n), "{n} mixed pixels");
    // Defocus moves no energy: the row's mean stays half lit.
    let row_mean = |px: &[[f32; 3]]| px[8 * 64..9 * 64].iter().map(|p| p[0]).sum::<f32>() / 64.0;
    assert!((row_mean(&blurred) - row_mean(&pinhole)).abs() < 0.02);
    // Without --focus-distance the lens focuses on what the image centre sees.
    let (summary, _) = render(&["--aperture", "0.2"]);
    let f = summary["focus_distance"].as_f64().unwrap();
    assert!((f - 5.0).abs() < 1e-3, "auto focus at {f}");
}

#[test]
fn focus_distance_at_measures_along_the_view_axis() {
    let dir = tempfile::tempdir().unwrap();
    let scene = penumbra::scene::load(&edge(dir.path())).unwrap();
    let choice: DeviceChoice = common::test_device().parse().unwrap();
    let mut r = Renderer::new(&choice).unwrap();
    let settings = penumbra::render::RenderSettings {
        width: 64,
        height: 16,
        ..Default::default()
    };
    r.set_settings(&settings).unwrap();
    r.load_scene(&scene, &scene.lights).unwrap();
    r.set_camera(&scene.cameras[0]).unwrap();
    // The plane z = 0 is 5 away along the axis wherever the pixel looks.
    for (x, y) in [(32.0, 8.0), (5.5, 2.0), (60.0, 15.0)] {
        let d = r.focus_distance_at(x, y).unwrap();
        assert!((d - 5.0).abs() < 1e-4, "pixel ({x}, {y}): {d}");
    }
    r.set_lens(0.1, 5.0).unwrap();
    assert_eq!(r.settings().lens_radius, 0.1);
    assert_eq!(r.settings().focus_distance, 5.0);
}
