//! `--background env|transparent|COLOR` on the default OpenCL device: what escaped camera rays
//! show changes, the lighting does not. A white Lambertian sphere under a uniform environment
//! reflects exactly the environment's radiance (a white furnace), so every pixel the sphere
//! covers, even partly, has the same straight color whatever the background.

mod common;

use common::{penumbra, white_sphere};
use std::path::Path;

const SIZE: usize = 24;

/// Renders `scene` to `out` under a uniform environment of 0.5 with `extra` options; returns
/// the JSON summary.
fn render(scene: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let size = SIZE.to_string();
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--width",
        &size,
        "--height",
        &size,
        "--spp",
        "32",
        "--bounces",
        "3",
        "--env",
        "0.5",
        "--exposure",
        "0",
    ];
    args.extend_from_slice(extra);
    let o = penumbra(&args);
    assert!(
        o.status.success(),
        "render {extra:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("one JSON line on stdout")
}

/// An EXR's RGBA pixels (A = 1 when the file has no alpha channel).
fn read_rgba(path: &Path) -> Vec<[f32; 4]> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |r, _| (r.width(), vec![[0f32; 4]; r.width() * r.height()]),
        |(w, px), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b, a];
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.layer_data.channel_data.pixels.1
}

fn has_alpha(path: &Path) -> bool {
    let meta = exr::meta::MetaData::read_from_file(path, false).unwrap();
    meta.headers[0].channels.list.iter().any(|c| c.name == *"A")
}

fn png(path: &Path) -> image::RgbaImage {
    image::open(path).unwrap().to_rgba8()
}

const CORNERS: [(usize, usize); 4] = [(0, 0), (SIZE - 1, 0), (0, SIZE - 1), (SIZE - 1, SIZE - 1)];
const CENTRE: (usize, usize) = (SIZE / 2, SIZE / 2);

#[test]
fn the_background_changes_escaped_camera_rays_only() {
    let dir = tempfile::tempdir().unwrap();
    let scene = white_sphere(dir.path(), false);
    let at = |px: &[[f32; 4]], (x, y): (usize, usize)| px[y * SIZE + x];

    // env (the default): the environment shows in the corners; no alpha channel.
    let env = dir.path().join("env.exr");
    let summary = render(&scene, &env, &[]);
    assert_eq!(summary["background"], "env");
    assert!(!has_alpha(&env));
    let env_px = read_rgba(&env);
    for c in CORNERS {
        assert!(
            (at(&env_px, c)[1] - 0.5).abs() < 1e-4,
            "{:?}",
            at(&env_px, c)
        );
    }

    for kernel in ["wavefront", "megakernel"] {
        // transparent: A is the coverage, RGB premultiplied; the corners are empty.
        let t = dir.path().join(format!("t-{kernel}.exr"));
        let summary = render(
            &scene,
            &t,
            &["--background", "transparent", "--kernel", kernel],
        );
        assert_eq!(summary["background"], "transparent");
        assert!(has_alpha(&t), "{kernel}: no A channel");
        let px = read_rgba(&t);
        for c in CORNERS {
            assert_eq!(at(&px, c), [0.0; 4], "{kernel}: corner {c:?}");
        }
        assert_eq!(at(&px, CENTRE)[3], 1.0, "{kernel}");
        // The lighting is unchanged: the sphere still reflects the environment's 0.5, and
        // so does every partly covered pixel once unpremultiplied.
        // (Grazing samples on the faceted sphere with smooth normals stray a little.)
        let (mut edges, mut sum, mut covered) = (0, 0.0, 0.0);
        for p in px.iter().filter(|p| p[3] > 0.0) {
            assert!((p[1] / p[3] - 0.5).abs() < 0.15, "{kernel}: {p:?}");
            if p[3] < 1.0 {
                edges += 1;
                sum += p[1];
                covered += p[3];
            }
        }
        assert!(edges > 8, "{kernel}: only {edges} partly covered pixels");
        let edge = sum / covered;
        assert!(
            (edge - 0.5).abs() < 0.03,
            "{kernel}: edge pixels' color {edge}"
        );
        let sphere_env = at(&env_px, CENTRE)[1];
        assert!((at(&px, CENTRE)[1] - sphere_env).abs() < 0.03, "{kernel}");

        // The PNG: alpha 0 in the corners, 255 on the sphere.
        let tp = dir.path().join(format!("t-{kernel}.png"));
        render(
            &scene,
            &tp,
            &["--background", "transparent", "--kernel", kernel],
        );
        let img = png(&tp);
        for (x, y) in CORNERS {
            assert_eq!(img.get_pixel(x as u32, y as u32)[3], 0, "{kernel}");
        }
        let centre = *img.get_pixel(CENTRE.0 as u32, CENTRE.1 as u32);
        assert_eq!(centre[3], 255);

        // A color: exactly that color where nothing was hit, the same sphere elsewhere.
        let cp = dir.path().join(format!("c-{kernel}.png"));
        let summary = render(&scene, &cp, &["--background", "0,1,0", "--kernel", kernel]);
        assert_eq!(summary["background"], "0,1,0");
        let img = png(&cp);
        for (x, y) in CORNERS {
            assert_eq!(img.get_pixel(x as u32, y as u32).0, [0, 255, 0, 255]);
        }
        let c = *img.get_pixel(CENTRE.0 as u32, CENTRE.1 as u32);
        for i in 0..3 {
            assert!(
                c[i].abs_diff(centre[i]) <= 2,
                "{kernel}: {c:?} against {centre:?}"
            );
        }
    }
    // Both kernels see the same camera rays: the same coverage.
    let (w, m) = (
        read_rgba(&dir.path().join("t-wavefront.exr")),
        read_rgba(&dir.path().join("t-megakernel.exr")),
    );
    assert!(w.iter().zip(&m).all(|(a, b)| a[3] == b[3]));
}

#[test]
fn a_bad_background_is_one_line_naming_the_option() {
    let dir = tempfile::tempdir().unwrap();
    let scene = white_sphere(dir.path(), false);
    let out = dir.path().join("x.png");
    for bad in ["purple", "0,0,2"] {
        let o = penumbra(&[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--background",
            bad,
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(
            err.starts_with("penumbra: error:") && err.contains("--background"),
            "{err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
}
