//! Guide buffers (`render --aovs`, docs/aovs.md) on the test device with both kernels, in
//! scenes built here whose albedo, normal and depth are known: a diffuse square facing the
//! camera, a mirror that shows a coloured wall behind the camera, and the sky around them.
//! The EXR carries them as named channels beside the image; a PNG output is refused.

mod common;

use common::{Gltf, Prim, output_dir, penumbra, render_exr_env};
use serde_json::{Value, json};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const SIZE: usize = 32;
/// The camera's vertical field of view; the square (half-size 0.5 at distance 2) covers the
/// middle 60 % of the image.
const YFOV: f32 = 0.8;
const DISTANCE: f32 = 2.0;
const KERNELS: [&str; 2] = ["megakernel", "wavefront"];

/// A camera at the origin looking down −z, and a light of zero intensity (so that no default
/// light rig or environment is added: the sky alone lights the scene).
fn camera_and_no_light(g: &mut Gltf) {
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": YFOV, "znear": 0.01}}));
    g.node(json!({"camera": 0}));
    g.lights
        .push(json!({"type": "point", "intensity": 0.0, "color": [1.0, 1.0, 1.0]}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.0, 50.0, 0.0]}));
}

/// A square of half-size `h` in the plane z = `z`, facing +z (`toward_plus`) or −z.
fn square(z: f32, h: f32, toward_plus: bool, material: usize) -> Prim {
    let positions = vec![[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]];
    let indices = if toward_plus {
        vec![0, 1, 2, 0, 2, 3]
    } else {
        vec![0, 2, 1, 0, 3, 2]
    };
    Prim::triangles(positions, indices, material)
}

const BASE: [f32; 3] = [0.2, 0.5, 0.8];

/// A diffuse square of colour BASE at z = −DISTANCE, facing the camera.
fn diffuse_square(dir: &Path) -> PathBuf {
    let mut g = Gltf::default();
    let m = g.lambert(BASE, [0.0; 3], 1.0, true);
    let mesh = g.mesh(vec![square(-DISTANCE, 0.5, true, m)]);
    g.node(json!({"mesh": mesh}));
    camera_and_no_light(&mut g);
    g.write_glb(dir, "square")
}

const TINT: [f32; 3] = [0.9, 0.6, 0.3];
const WALL: [f32; 3] = [0.4, 0.8, 0.2];

/// A smooth metal mirror of colour TINT at z = −DISTANCE facing the camera, and behind the
/// camera (at z = +DISTANCE, facing it) a large diffuse wall of colour WALL, which only the
/// mirror shows.
fn mirror_and_wall(dir: &Path) -> PathBuf {
    let mut g = Gltf::default();
    g.materials.push(json!({
        "pbrMetallicRoughness": {"baseColorFactor": [TINT[0], TINT[1], TINT[2], 1.0],
                                 "metallicFactor": 1.0, "roughnessFactor": 0.0},
        "doubleSided": true
    }));
    let wall = g.lambert(WALL, [0.0; 3], 1.0, true);
    let mesh = g.mesh(vec![
        square(-DISTANCE, 0.5, true, 0),
        square(DISTANCE, 10.0, false, wall),
    ]);
    g.node(json!({"mesh": mesh}));
    camera_and_no_light(&mut g);
    g.write_glb(dir, "mirror")
}

/// Renders `scene` with `--aovs` (and `extra`) by `kernel`; the summary and every channel by
/// name.
fn render(
    scene: &Path,
    out: &Path,
    kernel: &str,
    extra: &[&str],
    env: &[(&str, &str)],
) -> (Value, HashMap<String, Vec<f32>>) {
    let size = SIZE.to_string();
    let mut args = vec![
        "--kernel", kernel, "--width", &size, "--height", &size, "--spp", "8", "--aovs",
    ];
    args.extend_from_slice(extra);
    let (summary, _) = render_exr_env(scene, out, &args, env);
    let (w, h, channels) = penumbra::image_io::read_exr_channels(out).unwrap();
    assert_eq!((w as usize, h as usize), (SIZE, SIZE));
    (summary, channels.into_iter().collect())
}

/// The three channels `names` of `layer` at pixel (x, y).
fn at(
    c: &HashMap<String, Vec<f32>>,
    layer: &str,
    names: [&str; 3],
    x: usize,
    y: usize,
) -> [f32; 3] {
    names.map(|n| c[&format!("{layer}.{n}")][y * SIZE + x])
}

fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
    a.iter().zip(&b).all(|(a, b)| (a - b).abs() <= tol)
}

/// Pixels well inside the square (its middle 8×8) and in the corners (sky only).
fn inside() -> impl Iterator<Item = (usize, usize)> {
    (12..20).flat_map(|y| (12..20).map(move |x| (x, y)))
}
fn corners() -> [(usize, usize); 4] {
    [(0, 0), (SIZE - 1, 0), (0, SIZE - 1), (SIZE - 1, SIZE - 1)]
}

/// Checks the middle of the image: albedo `albedo`, normal `normal`, depth DISTANCE along the
/// ray (2 / cos of the pixel's angle from the axis: under 1 % more here).
fn check_inside(c: &HashMap<String, Vec<f32>>, kernel: &str, albedo: [f32; 3], normal: [f32; 3]) {
    for (x, y) in inside() {
        let a = at(c, "albedo", ["R", "G", "B"], x, y);
        assert!(close(a, albedo, 1e-5), "{kernel} ({x}, {y}): albedo {a:?}");
        let n = at(c, "normal", ["X", "Y", "Z"], x, y);
        assert!(close(n, normal, 1e-5), "{kernel} ({x}, {y}): normal {n:?}");
        let depth = c["depth.Z"][y * SIZE + x];
        assert!(
            (DISTANCE..DISTANCE * 1.01).contains(&depth),
            "{kernel} ({x}, {y}): depth {depth}"
        );
    }
}

#[test]
fn a_diffuse_square_gives_its_colour_its_normal_and_its_distance() {
    let dir = output_dir("aovs-square");
    let scene = diffuse_square(&dir);
    for kernel in KERNELS {
        // Lanes forced on: the guide buffers take paths one at a time all the same.
        let out = dir.join(format!("{kernel}.exr"));
        let (summary, c) = render(
            &scene,
            &out,
            kernel,
            &["--sky", "0.3"],
            &[("PENUMBRA_LANES", "1")],
        );
        assert_eq!(summary["aovs"], true);
        assert_eq!(summary["lanes"], false, "{kernel}: no lanes with AOVs");
        check_inside(&c, kernel, BASE, [0.0, 0.0, 1.0]);
        // The sky: its colour as albedo, no normal, no distance.
        for (x, y) in corners() {
            let albedo = at(&c, "albedo", ["R", "G", "B"], x, y);
            assert!(
                close(albedo, [0.3; 3], 1e-5),
                "{kernel}: sky albedo {albedo:?}"
            );
            assert_eq!(at(&c, "normal", ["X", "Y", "Z"], x, y), [0.0; 3]);
            assert_eq!(c["depth.Z"][y * SIZE + x], f32::INFINITY);
        }
        // The image is still there, lit by the sky.
        let centre = (SIZE / 2) * SIZE + SIZE / 2;
        assert!(
            c["G"][centre] > 0.0 && c["G"][centre] < 0.5,
            "{kernel}: image {}",
            c["G"][centre]
        );
    }
}

#[test]
fn a_mirror_shows_the_wall_it_reflects_tinted_by_its_colour() {
    let dir = output_dir("aovs-mirror");
    let scene = mirror_and_wall(&dir);
    let expected = [WALL[0] * TINT[0], WALL[1] * TINT[1], WALL[2] * TINT[2]];
    for kernel in KERNELS {
        let out = dir.join(format!("{kernel}.exr"));
        // A sky brighter than 1: clamped to 1 as an albedo.
        let (_, c) = render(&scene, &out, kernel, &["--sky", "2.5"], &[]);
        // The wall's normal, facing the mirror; the depth is the mirror's.
        check_inside(&c, kernel, expected, [0.0, 0.0, -1.0]);
        for (x, y) in corners() {
            let albedo = at(&c, "albedo", ["R", "G", "B"], x, y);
            assert!(
                close(albedo, [1.0; 3], 1e-6),
                "{kernel}: sky albedo {albedo:?}"
            );
        }
    }
}

#[test]
fn the_exr_names_its_layers_and_adaptive_sampling_adds_its_maps() {
    let dir = output_dir("aovs-layers");
    let scene = diffuse_square(&dir);
    let out = dir.join("layers.exr");
    let (_, c) = render(
        &scene,
        &out,
        "megakernel",
        &["--sky", "0.3", "--noise-threshold", "0.5"],
        &[],
    );
    let mut names: Vec<&str> = c.keys().map(String::as_str).collect();
    names.sort();
    assert_eq!(
        names,
        [
            "B",
            "G",
            "R",
            "albedo.B",
            "albedo.G",
            "albedo.R",
            "depth.Z",
            "error.Y",
            "normal.X",
            "normal.Y",
            "normal.Z",
            "samples.Y"
        ]
    );
    // The --spp given is under the minimum (16 at this threshold): every pixel took all 8,
    // and the sky, whose samples all agree, has no error.
    assert!(
        c["samples.Y"].iter().all(|&s| s == 8.0),
        "{:?}",
        c["samples.Y"]
    );
    assert!(c["error.Y"][0] < 1e-4, "{}", c["error.Y"][0]);
    // The image channels read as the plain EXR's do.
    let (_, _, rgb) = penumbra::image_io::read_exr(&out).unwrap();
    assert_eq!(rgb[40][1], c["G"][40]);
}

#[test]
fn aovs_need_an_exr_output() {
    let dir = output_dir("aovs-png");
    let scene = diffuse_square(&dir);
    let out = dir.join("out.png");
    let o = penumbra(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--aovs",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("--aovs") && err.contains(".exr"), "{err}");
    assert!(!out.exists(), "nothing written");
}
