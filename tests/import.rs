//! glTF import of small fixtures made here, and bad files that must fail with one clear line.

mod common;

use common::{Gltf, Prim, penumbra, quad};
use penumbra::scene::{LightKind, load};
use serde_json::json;
use std::path::Path;

fn one_quad_scene() -> Gltf {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![quad()]);
    g.node(json!({"mesh": m}));
    g
}

#[test]
fn glb_gltf_with_bin_and_embedded_buffers_load_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let g = one_quad_scene();
    for path in [
        g.write_glb(dir.path(), "a"),
        g.write_gltf(dir.path(), "b"),
        g.write_gltf_embedded(dir.path(), "c"),
    ] {
        let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.triangle_count(), 2, "{}", path.display());
        let t = s.world_triangles();
        assert_eq!(t[1].v[2], glam::Vec3::new(0.0, 1.0, 0.0));
        assert!(!t[0].smooth, "no NORMAL: flat shading");
        assert_eq!(t[0].n[0], glam::Vec3::Z, "flat normal from the winding");
    }
}

#[test]
fn node_hierarchy_composes_transforms() {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![quad()]);
    let child = g.node(json!({"mesh": m, "translation": [1.0, 0.0, 0.0]}));
    g.node(json!({"children": [child], "scale": [2.0, 2.0, 2.0], "translation": [0.0, 0.0, 5.0]}));
    let dir = tempfile::tempdir().unwrap();
    let s = load(&g.write_glb(dir.path(), "h")).unwrap();
    let t = s.world_triangles();
    // parent(scale 2, then +5 z) * child(+1 x): vertex (0,0,0) -> (2, 0, 5).
    assert_eq!(t[0].v[0], glam::Vec3::new(2.0, 0.0, 5.0));
    assert_eq!(t[0].v[1], glam::Vec3::new(4.0, 0.0, 5.0));
}

#[test]
fn node_transforms_keep_f64_precision_at_survey_coordinates() {
    // Two quads 0.25 apart at x ≈ 1.2e7, where f32 steps by 1: read as f32 both would land on
    // the same point. One is placed by TRS, the other by a matrix.
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![quad()]);
    g.node(json!({"mesh": m, "translation": [12345678.25, 0.0, 0.0]}));
    let mut matrix = [0.0f64; 16];
    for i in 0..4 {
        matrix[5 * i] = 1.0;
    }
    matrix[12] = 12345678.5;
    g.node(json!({"mesh": m, "matrix": matrix}));
    let dir = tempfile::tempdir().unwrap();
    let s = load(&g.write_glb(dir.path(), "survey")).unwrap();
    let x: Vec<f64> = s
        .objects
        .iter()
        .map(|o| o.world_from_object.w_axis.x)
        .collect();
    assert_eq!(x, [12345678.25, 12345678.5]);
}

#[test]
fn non_indexed_and_unsupported_modes() {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let tri = Prim {
        indices: vec![],
        ..quad()
    };
    let tri = Prim {
        positions: tri.positions[..3].to_vec(),
        ..tri
    };
    let lines = Prim { mode: 1, ..quad() };
    let m = g.mesh(vec![tri, lines]);
    g.node(json!({"mesh": m}));
    let dir = tempfile::tempdir().unwrap();
    let s = load(&g.write_glb(dir.path(), "n")).unwrap();
    assert_eq!(
        s.triangle_count(),
        1,
        "the non-indexed triangle is imported"
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("not triangles")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn cameras_lights_and_materials_are_read() {
    let mut g = one_quad_scene();
    g.materials[0]["emissiveFactor"] = json!([1.0, 0.5, 0.25]);
    g.materials[0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] =
        json!(4.0);
    g.materials[0]["doubleSided"] = json!(true);
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 3.0]}));
    g.lights
        .push(json!({"type": "point", "intensity": 5.0, "color": [1.0, 0.0, 0.0]}));
    g.lights.push(json!({"type": "spot", "intensity": 2.0, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.4}}));
    g.lights
        .push(json!({"type": "directional", "intensity": 3.0}));
    for i in 0..3 {
        g.node(json!({"extensions": {"KHR_lights_punctual": {"light": i}}, "translation": [0.0, 2.0, 0.0], "rotation": common::LOOK_DOWN}));
    }
    let dir = tempfile::tempdir().unwrap();
    let s = load(&g.write_glb(dir.path(), "l")).unwrap();
    assert_eq!(s.cameras.len(), 1);
    assert!((s.cameras[0].yfov - 0.5).abs() < 1e-6);
    assert!((s.cameras[0].eye - glam::DVec3::new(0.0, 0.0, 3.0)).length() < 1e-9);
    assert!((s.cameras[0].forward - glam::DVec3::NEG_Z).length() < 1e-9);
    assert_eq!(s.lights.len(), 3);
    assert!(!s.default_rig);
    let kinds: Vec<_> = s.lights.iter().map(|l| l.kind).collect();
    assert_eq!(kinds[0], LightKind::Point);
    assert!(matches!(kinds[1], LightKind::Spot { .. }));
    assert_eq!(kinds[2], LightKind::Directional);
    assert_eq!(s.lights[0].intensity, 5.0);
    assert_eq!(s.lights[0].color, [1.0, 0.0, 0.0]);
    // Rotated -90 degrees about x, the light's -Z points down.
    assert!((s.lights[2].direction - glam::DVec3::NEG_Y).length() < 1e-6);
    let m = &s.materials[0];
    assert_eq!(m.emission, [4.0, 2.0, 1.0], "emissiveFactor x strength");
    assert!(m.double_sided);
    assert_eq!(m.specular_factor, 0.0);
}

#[test]
fn a_scene_without_camera_or_lights_is_framed_and_lit_by_the_default_rig() {
    let dir = tempfile::tempdir().unwrap();
    let s = load(&one_quad_scene().write_glb(dir.path(), "bare")).unwrap();
    assert_eq!(s.cameras.len(), 1, "an automatic camera");
    let c = &s.cameras[0];
    let to_center = (s.bounds().center() - c.eye).normalize();
    assert!(to_center.dot(c.forward) > 0.999, "it looks at the scene");
    assert!(s.default_rig && !s.lights.is_empty());
}

#[test]
fn unsupported_optional_extensions_only_warn() {
    let mut g = one_quad_scene();
    g.use_ext("EXT_lights_ies");
    let dir = tempfile::tempdir().unwrap();
    let s = load(&g.write_glb(dir.path(), "opt")).unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("EXT_lights_ies")));
}

/// Runs `penumbra render` on a bad file: exit code non-zero, one line on stderr naming the
/// file and the problem, no panic.
fn assert_clean_failure(path: &Path, expect: &str) {
    let out = std::env::temp_dir().join("penumbra-bad.exr");
    let o = penumbra(&[
        "render",
        path.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{} should fail", path.display());
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{err}"
    );
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("penumbra: error"))
        .collect();
    assert_eq!(lines.len(), 1, "one error line: {err}");
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(lines[0].contains(name), "names the file: {err}");
    assert!(lines[0].contains(expect), "says '{expect}': {err}");
}

#[test]
fn bad_files_fail_with_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let g = one_quad_scene();

    let glb = g.glb();
    let truncated = d.join("truncated.glb");
    std::fs::write(&truncated, &glb[..glb.len() - 20]).unwrap();
    assert_clean_failure(&truncated, "GLB");

    let gltf = g.write_gltf(d, "missing-bin");
    std::fs::remove_file(d.join("missing-bin.bin")).unwrap();
    assert_clean_failure(&gltf, "buffer");

    let mut bad = Gltf::default();
    bad.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = bad.mesh(vec![Prim::triangles(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![0, 1, 7],
        0,
    )]);
    bad.node(json!({"mesh": m}));
    assert_clean_failure(&bad.write_glb(d, "out-of-range"), "out of range");

    let mut nan = Gltf::default();
    nan.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = nan.mesh(vec![Prim::triangles(
        vec![[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![0, 1, 2],
        0,
    )]);
    nan.node(json!({"mesh": m}));
    assert_clean_failure(&nan.write_glb(d, "nan"), "not finite");

    let mut req = one_quad_scene();
    req.use_ext("KHR_materials_pbrSpecularGlossiness");
    req.required
        .push("KHR_materials_pbrSpecularGlossiness".into());
    assert_clean_failure(
        &req.write_glb(d, "spec-gloss"),
        "extensionsRequired[0]: requires the unsupported extension \
         KHR_materials_pbrSpecularGlossiness",
    );

    assert_clean_failure(&d.join("does-not-exist.glb"), "does not exist");
    let junk = d.join("junk.gltf");
    std::fs::write(&junk, b"{ not json").unwrap();
    assert_clean_failure(&junk, "not a valid glTF");
}

#[test]
fn absurd_options_fail_with_one_clear_line() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let s = scene.to_str().unwrap();
    for (args, expect) in [
        (vec!["--width", "0"], "--width"),
        (vec!["--bounces", "100000"], "--bounces"),
        (vec!["--spp", "0"], "--spp"),
        (vec!["--camera", "9"], "--camera 9"),
        (vec!["--light-radius", "-1"], "--light-radius"),
        (vec!["--device", "banana"], "banana"),
        (vec!["--device", "42"], "no OpenCL device"),
    ] {
        let mut all = vec!["render", s, "-o", "/tmp/penumbra-absurd.exr"];
        all.extend(&args);
        let o = penumbra(&all);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} should fail");
        assert!(!err.contains("panicked"), "{err}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        // A number outside an option's range, or a device that is not there, is a usage
        // error (2); the rest is bad input (1).
        let usage = matches!(
            args[0],
            "--width" | "--bounces" | "--spp" | "--light-radius" | "--device"
        );
        assert_eq!(
            o.status.code(),
            Some(if usage { 2 } else { 1 }),
            "{args:?}: {err}"
        );
    }
}

/// A quad whose material `KHR_materials_variants` switches: red by default, blue in "Blue",
/// green in "Green"; one mapping names a material and one a variant that do not exist.
fn variant_scene(dir: &Path) -> std::path::PathBuf {
    let mut g = Gltf::default();
    g.lambert([0.8, 0.1, 0.1], [0.0; 3], 1.0, true);
    let blue = g.lambert([0.1, 0.1, 0.8], [0.0; 3], 1.0, true);
    let green = g.lambert([0.1, 0.8, 0.1], [0.0; 3], 1.0, true);
    let m = g.mesh(vec![quad()]);
    g.meshes[m]["primitives"][0]["extensions"] = json!({"KHR_materials_variants": {"mappings": [
        {"material": blue, "variants": [0]},
        {"material": green, "variants": [1, 7]},
        {"material": 99, "variants": [0]}
    ]}});
    g.use_ext("KHR_materials_variants");
    g.extra.insert(
        "extensions".into(),
        json!({"KHR_materials_variants": {"variants": [{"name": "Blue"}, {"name": "Green"}]}}),
    );
    g.node(json!({"mesh": m}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.5, 0.5, 2.0]}));
    g.write_glb(dir, "variants")
}

#[test]
fn material_variants_switch_the_materials() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = load(&variant_scene(dir.path())).unwrap();
    assert_eq!(s.variants, ["Blue", "Green"]);
    let all =
        |s: &penumbra::scene::Scene, m: u32| s.objects[0].mesh.materials.iter().all(|&x| x == m);
    assert!(all(&s, 0), "the default material");
    assert!(
        !s.warnings.iter().any(|w| w.contains("not supported")),
        "{:?}",
        s.warnings
    );
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("mappings[2]: no such material"))
    );
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("variants that do not exist"))
    );
    let green = s.variant_named("Green").unwrap();
    s.select_variant(Some(green));
    assert!(all(&s, 2));
    s.select_variant(Some(0));
    assert!(all(&s, 1));
    s.select_variant(None);
    assert!(all(&s, 0));
    let e = s.variant_named("Pink").unwrap_err();
    assert!(
        e.contains("no variant \"Pink\"") && e.contains("\"Blue\", \"Green\""),
        "{e}"
    );
}

#[test]
fn variant_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = variant_scene(dir.path());
    let args = [
        "--width", "8", "--height", "8", "--spp", "2", "--sky", "1,1,1",
    ];
    let (summary, px) = common::render_exr(
        &scene,
        &dir.path().join("green.exr"),
        &[&args[..], &["--variant", "Green"]].concat(),
    );
    assert_eq!(summary["variant"], "Green");
    assert_eq!(summary["variants"], json!(["Blue", "Green"]));
    let (r, g) = px.iter().fold((0.0, 0.0), |(r, g), p| (r + p[0], g + p[1]));
    assert!(g > 3.0 * r, "green {g} against red {r}");
    let (summary, _) = common::render_exr(&scene, &dir.path().join("default.exr"), &args);
    assert_eq!(summary["variant"], json!(null));
    let out = dir.path().join("x.exr");
    let o = penumbra(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--variant",
        "Pink",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    // The file's own warnings come first; the error is one line.
    let errors: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
    assert_eq!(errors.len(), 1, "{err}");
    assert!(
        errors[0].starts_with("penumbra: error: ") && errors[0].contains("\"Blue\", \"Green\""),
        "{err}"
    );
}
