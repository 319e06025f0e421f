//! The environment light on the default OpenCL device (PoCL in CI): χ² of the kernel's
//! importance sampling against the table's pdf, a white furnace under a uniform environment
//! image, MIS against BSDF-only and light-only estimates, rotation and intensity.

mod common;

use common::stats::chi2;
use common::{Gltf, Prim, render_exr, white_sphere};
use glam::Vec3;
use penumbra::cl::DeviceChoice;
use penumbra::render::Renderer;
use penumbra::scene::{EnvMap, Material, Mesh, Object, Scene};
use serde_json::json;
use std::path::{Path, PathBuf};

fn renderer() -> Renderer {
    let choice: DeviceChoice = common::test_device().parse().expect("a valid test device");
    Renderer::new(&choice).expect("the test's OpenCL device is available")
}

/// One triangle far below the origin, so that a scene loads.
fn speck() -> Scene {
    let mesh = Mesh {
        positions: vec![
            Vec3::new(0.0, -100.0, 0.0),
            Vec3::new(0.01, -100.0, 0.0),
            Vec3::new(0.0, -100.0, 0.01),
        ],
        indices: vec![[0, 1, 2]],
        materials: vec![0],
        ..Mesh::default()
    };
    Scene {
        source: "speck".into(),
        objects: vec![Object {
            name: "speck".into(),
            world_from_object: glam::DMat4::IDENTITY,
            visible: true,
            mesh: mesh.into(),
        }],
        materials: vec![Material::default()],
        ..Scene::default()
    }
}

/// A sky-like map: a gradient, a bright sun and a dark band.
fn test_map() -> EnvMap {
    let (w, h) = (32u32, 16u32);
    let mut texels = vec![];
    for y in 0..h {
        for x in 0..w {
            let mut c = [0.2 + 0.05 * x as f32 / w as f32, 0.3, 0.6 - 0.03 * y as f32];
            if (5..8).contains(&x) && (3..5).contains(&y) {
                c = [40.0, 35.0, 30.0];
            }
            if y == 12 {
                c = [0.0; 3];
            }
            texels.push(c);
        }
    }
    EnvMap {
        name: "test".into(),
        width: w,
        height: h,
        texels,
    }
}

#[test]
fn environment_sampling_matches_its_pdf_chi_square() {
    let map = test_map();
    let table = map.sampling();
    let rotations = [0.0f32, 75.0];
    // Šidák: an overall 1% chance of a false failure over both rotations.
    let alpha = 1.0 - 0.99f64.powf(1.0 / rotations.len() as f64);
    let mut r = renderer();
    r.load_scene(&speck(), &[]).unwrap();
    r.set_environment(Some(map.clone())).unwrap();
    for rotation in rotations {
        let settings = penumbra::render::RenderSettings {
            env_rotation: rotation,
            ..r.settings().clone()
        };
        r.set_settings(&settings).unwrap();
        let n = 200_000;
        let mut s = 11u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let u: Vec<[f32; 2]> = (0..n).map(|_| [rnd(), rnd()]).collect();
        let program = r.program().unwrap();
        assert!(program.features.env_map);
        let (samples, eval) = program
            .sample_env_test(&r.device, r.env_buffers(), &u)
            .unwrap();
        // Back into the map's frame: undo the rotation about +Y.
        let (sin, cos) = rotation.to_radians().sin_cos();
        let mut counts = vec![0f64; (map.width * map.height) as usize];
        for (k, s) in samples.iter().enumerate() {
            let d = Vec3::new(s[0], s[1], s[2]);
            assert!((d.length() - 1.0).abs() < 1e-4, "sample {k} not unit: {d}");
            let m = Vec3::new(cos * d.x - sin * d.z, d.y, sin * d.x + cos * d.z);
            let host_pdf = map.pdf(&table, m);
            assert!(
                (s[3] - eval[k]).abs() <= 1e-3 * eval[k].max(1e-3),
                "sample {k}: pdf {} but the miss shader says {}",
                s[3],
                eval[k]
            );
            assert!(
                (s[3] - host_pdf).abs() <= 2e-3 * host_pdf.max(1e-3),
                "sample {k}: pdf {} but the host says {host_pdf}",
                s[3]
            );
            let (x, y) = map.texel_of(m);
            counts[(y * map.width + x) as usize] += 1.0;
        }
        // Expected counts from the luminance × sin θ of each texel, computed here.
        let lum = |c: [f32; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
        let f: Vec<f64> = (0..map.height)
            .flat_map(|y| {
                let sin = ((y as f64 + 0.5) / map.height as f64 * std::f64::consts::PI).sin();
                let map = &map;
                (0..map.width).map(move |x| lum(map.texels[(y * map.width + x) as usize]) * sin)
            })
            .collect();
        let total: f64 = f.iter().sum();
        let expected: Vec<f64> = f.iter().map(|fi| n as f64 * fi / total).collect();
        let observed: Vec<u64> = counts.iter().map(|&o| o as u64).collect();
        let (chi2, dof, p) =
            chi2(&observed, &expected).unwrap_or_else(|e| panic!("rotation {rotation}: {e}"));
        let bins = dof + 1;
        assert!(
            p > alpha,
            "rotation {rotation}: chi2 {chi2} over {bins} bins, p = {p} < {alpha}"
        );
    }
}

/// Writes a `w`×`h` EXR environment; `texel(u, v)` gives the radiance.
fn write_env(
    dir: &Path,
    name: &str,
    w: u32,
    h: u32,
    texel: impl Fn(f32, f32) -> [f32; 3],
) -> PathBuf {
    let mut px = vec![];
    for y in 0..h {
        for x in 0..w {
            px.push(texel(
                (x as f32 + 0.5) / w as f32,
                (y as f32 + 0.5) / h as f32,
            ));
        }
    }
    let path = dir.join(format!("{name}.exr"));
    penumbra::image_io::write_exr(&path, w, h, &px).unwrap();
    path
}

#[test]
fn a_white_sphere_under_a_uniform_environment_disappears() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "uniform", 64, 32, |_, _| [0.5; 3]);
    let scene = white_sphere(dir.path(), false);
    let out = dir.path().join("f.exr");
    let (summary, px) = render_exr(
        &scene,
        &out,
        &[
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "64",
            "--bounces",
            "3",
            "--env",
            env.to_str().unwrap(),
        ],
    );
    assert_eq!(summary["nonfinite_samples"], 0);
    assert_eq!(summary["default_light_rig"], false);
    // A convex albedo-1 Lambertian surface under uniform radiance L reflects exactly L.
    let m = common::mean_gray(&px);
    assert!((m - 0.5).abs() < 0.005, "mean {m}, expected 0.5");
    // The centre 8×8 is all sphere.
    let centre: Vec<[f32; 3]> = (8..16)
        .flat_map(|y| (8..16).map(move |x| y * 24 + x))
        .map(|i| px[i])
        .collect();
    let c = common::mean_gray(&centre);
    assert!((c - 0.5).abs() < 0.01, "sphere mean {c}, expected 0.5");
}

#[test]
fn mis_bsdf_only_and_light_only_agree_under_an_environment_with_a_sun() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "sun", 32, 16, |u, v| {
        if (0.6..0.7).contains(&u) && (0.2..0.3).contains(&v) {
            [30.0, 28.0, 25.0]
        } else {
            [0.3, 0.4, 0.6]
        }
    });
    let scene = white_sphere(dir.path(), true);
    let out = dir.path().join("m.exr");
    let mut means = vec![];
    let mut images = vec![];
    for strategy in ["mis", "bsdf", "lights"] {
        let (summary, px) = render_exr(
            &scene,
            &out,
            &[
                "--width",
                "24",
                "--height",
                "24",
                "--spp",
                "192",
                "--bounces",
                "1",
                "--strategy",
                strategy,
                "--env",
                env.to_str().unwrap(),
            ],
        );
        assert_eq!(summary["nonfinite_samples"], 0);
        means.push(common::mean_gray(&px));
        images.push(px);
    }
    for (s, m) in ["bsdf", "lights"].iter().zip(&means[1..]) {
        let rel = (m - means[0]).abs() / means[0];
        assert!(rel < 0.03, "{s}: mean {m} vs MIS {} ({rel:.4})", means[0]);
    }
    // MIS is less noisy than BSDF sampling alone (squared error against the light-only image).
    let err = |a: &[[f32; 3]], b: &[[f32; 3]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| ((p[1] - q[1]) as f64).powi(2))
            .sum::<f64>()
    };
    assert!(
        err(&images[0], &images[2]) < err(&images[1], &images[2]),
        "MIS is not better than BSDF sampling"
    );
}

#[test]
fn rotation_turns_the_environment_about_up_and_intensity_scales_it() {
    let dir = tempfile::tempdir().unwrap();
    // Bright only around +X (u = 0.75).
    let env = write_env(dir.path(), "east", 64, 32, |u, _| {
        if (0.7..0.8).contains(&u) {
            [2.0, 1.0, 0.5]
        } else {
            [0.0; 3]
        }
    });
    let mut g = Gltf::default();
    let m = g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let mesh = g.mesh(vec![Prim::triangles(
        vec![[0.0, -50.0, 0.0], [0.1, -50.0, 0.0], [0.0, -50.0, 0.1]],
        vec![0, 1, 2],
        m,
    )]);
    g.node(json!({"mesh": mesh}));
    // The glTF camera looks along -Z.
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.1, "znear": 0.01}}));
    g.node(json!({"camera": 0}));
    let scene = g.write_glb(dir.path(), "look");
    let out = dir.path().join("r.exr");
    let look = |rotation: &str, intensity: &str| {
        let (_, px) = render_exr(
            &scene,
            &out,
            &[
                "--width",
                "4",
                "--height",
                "4",
                "--spp",
                "1",
                "--bounces",
                "0",
                "--env",
                env.to_str().unwrap(),
                "--env-rotation",
                rotation,
                "--env-intensity",
                intensity,
            ],
        );
        px
    };
    assert_eq!(
        common::mean_gray(&look("0", "1")),
        0.0,
        "-Z is dark without rotation"
    );
    // Turning the map 90° counter-clockwise seen from above brings +X to -Z.
    let px = look("90", "1");
    assert!(px.iter().all(|p| *p == [2.0, 1.0, 0.5]), "{:?}", px[0]);
    assert_eq!(
        common::mean_gray(&look("-90", "1")),
        0.0,
        "-90° turns +X to +Z"
    );
    let px = look("90", "2.5");
    assert!(px.iter().all(|p| *p == [5.0, 2.5, 1.25]), "{:?}", px[0]);
}

#[test]
fn bad_environment_arguments_fail_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = white_sphere(dir.path(), false);
    let bad = dir.path().join("bad.hdr");
    std::fs::write(&bad, b"not an image").unwrap();
    for env in [bad.to_str().unwrap(), "nowhere.exr", "1,2"] {
        let o = common::penumbra(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            dir.path().join("x.exr").to_str().unwrap(),
            "--env",
            env,
        ]);
        assert!(!o.status.success(), "--env {env} was accepted");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// A smooth thin-walled glass pane over the upper half of the view, the environment a ramp
/// across u (8 texels wide) that is dark behind the camera (where the pane reflects). A pinhole
/// camera looking along −Z sees the same u all down a column, so a viewer sees the pane's half
/// as the ramp beside it, dimmed by the pane's transmittance: as smooth through the glass as
/// through the air (before, the map was read texel by texel past a pane: blocks).
#[test]
fn the_environment_through_a_thin_pane_is_as_smooth_as_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "ramp", 8, 4, |u, _| {
        [if (0.25..0.75).contains(&u) {
            4.0 * u - 1.0
        } else {
            0.0
        }; 3]
    });
    let mut g = Gltf::default();
    g.use_ext("KHR_materials_transmission");
    g.materials.push(json!({
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
                                 "roughnessFactor": 0.0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}
    }));
    let mesh = g.mesh(vec![Prim::triangles(
        vec![
            [-5.0, 0.0, -2.0],
            [5.0, 0.0, -2.0],
            [5.0, 5.0, -2.0],
            [-5.0, 5.0, -2.0],
        ],
        vec![0, 1, 2, 0, 2, 3],
        0,
    )]);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.01}}));
    g.node(json!({"camera": 0}));
    let scene = g.write_glb(dir.path(), "pane");
    for kernel in ["wavefront", "megakernel"] {
        let out = dir.path().join(format!("pane-{kernel}.exr"));
        let (_, px) = render_exr(
            &scene,
            &out,
            &[
                "--kernel",
                kernel,
                "--width",
                "32",
                "--height",
                "16",
                "--spp",
                "256",
                "--bounces",
                "1",
                "--env",
                env.to_str().unwrap(),
            ],
        );
        // Per column, the pane (row 3) over the air (row 12): one transmittance everywhere.
        let ratios: Vec<f64> = (0..32)
            .filter(|&x| px[12 * 32 + x][1] > 0.3)
            .map(|x| px[3 * 32 + x][1] as f64 / px[12 * 32 + x][1] as f64)
            .collect();
        assert!(
            ratios.len() >= 16,
            "{kernel}: enough lit columns ({})",
            ratios.len()
        );
        let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
        assert!(
            (0.85..0.97).contains(&mean),
            "{kernel}: transmittance {mean}"
        );
        for r in &ratios {
            assert!(
                (r / mean - 1.0).abs() < 0.08,
                "{kernel}: column ratios {ratios:?}"
            );
        }
    }
}
