//! Punctual lights against closed-form answers: a Lambertian floor lit from straight above,
//! seen by a narrow camera looking down at the spot below the light. Radiance there is
//! albedo / π × E with E = I / h² for point and spot lights, E for directional lights, and the
//! soft versions (sphere of radius r, disc of directions) must give the same E: they keep the
//! light's power.

mod common;

use common::{Gltf, Prim, render_exr};
use serde_json::{Value, json};
use std::f32::consts::PI;

const ALBEDO: f32 = 0.5;

fn floor_scene(light: Value, light_height: f32) -> Gltf {
    let mut g = Gltf::default();
    let m = g.lambert([ALBEDO; 3], [0.0; 3], 1.0, false);
    let s = 20.0;
    let mesh = g.mesh(vec![Prim::triangles(
        vec![[-s, 0.0, -s], [s, 0.0, -s], [s, 0.0, s], [-s, 0.0, s]],
        vec![0, 2, 1, 0, 3, 2],
        m,
    )]);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.02, "znear": 0.01}}));
    // Looking straight down from 3 units up (rotation -90 degrees about x).
    g.node(json!({"camera": 0, "translation": [0.0, 3.0, 0.0], "rotation": common::LOOK_DOWN}));
    g.lights.push(light);
    g.node(json!({
        "extensions": {"KHR_lights_punctual": {"light": 0}},
        "translation": [0.0, light_height, 0.0],
        "rotation": common::LOOK_DOWN
    }));
    g
}

fn mean_radiance(g: &Gltf, name: &str, extra: &[&str]) -> f32 {
    let dir = tempfile::tempdir().unwrap();
    let scene = g.write_glb(dir.path(), name);
    let out = dir.path().join("o.exr");
    let mut args = vec![
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "256",
        "--bounces",
        "0",
    ];
    args.extend_from_slice(extra);
    let (summary, px) = render_exr(&scene, &out, &args);
    assert_eq!(summary["nonfinite_samples"], 0);
    px.iter().map(|p| p[1]).sum::<f32>() / px.len() as f32
}

fn assert_close(got: f32, want: f32, what: &str) {
    let rel = (got - want).abs() / want;
    assert!(
        rel < 0.02,
        "{what}: {got} vs {want} ({:.2}% off)",
        rel * 100.0
    );
}

#[test]
fn point_light_intensity_is_used_one_to_one_hard_and_soft() {
    let (i, h) = (10.0, 2.0);
    let g = floor_scene(json!({"type": "point", "intensity": i}), h);
    let want = ALBEDO / PI * i / (h * h);
    assert_close(
        mean_radiance(&g, "p", &["--hard-shadows"]),
        want,
        "hard point light",
    );
    assert_close(
        mean_radiance(&g, "p", &["--light-radius", "0.5"]),
        want,
        "sphere light",
    );
}

#[test]
fn spot_light_inside_its_cone_equals_a_point_light() {
    let (i, h) = (7.0, 1.5);
    let g = floor_scene(
        json!({"type": "spot", "intensity": i, "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.6}}),
        h,
    );
    let want = ALBEDO / PI * i / (h * h);
    assert_close(
        mean_radiance(&g, "s", &["--hard-shadows"]),
        want,
        "spot light",
    );
    assert_close(
        mean_radiance(&g, "s", &["--light-radius", "0.2"]),
        want,
        "soft spot light",
    );
}

#[test]
fn spot_light_outside_its_cone_is_dark() {
    // The spot points straight down; tilt the camera's target away by moving the light aside.
    let mut g = floor_scene(
        json!({"type": "spot", "intensity": 7.0, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.2}}),
        1.0,
    );
    g.nodes[2]["translation"] = json!([3.0, 1.0, 0.0]);
    // `--env none`: this scene's light lights nothing in view, which would otherwise bring in
    // the default environment.
    assert_eq!(
        mean_radiance(&g, "s2", &["--hard-shadows", "--env", "none"]),
        0.0
    );
}

#[test]
fn directional_light_irradiance_is_used_one_to_one_hard_and_soft() {
    let e = 3.0;
    let g = floor_scene(json!({"type": "directional", "intensity": e}), 5.0);
    let want = ALBEDO / PI * e;
    assert_close(
        mean_radiance(&g, "d", &["--hard-shadows"]),
        want,
        "hard sun",
    );
    // Angular radius 2 * 4 / diagonal(40 * sqrt 2) = 0.14 rad.
    assert_close(
        mean_radiance(&g, "d", &["--light-radius", "4"]),
        want,
        "soft sun",
    );
}
