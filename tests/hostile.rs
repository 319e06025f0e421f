//! Hand-made hostile files: every dangling index kind, every bad enum, memory bombs (a sparse
//! count, a buffer naming /dev/zero, an EXR header claiming 100000², a node graph listing its
//! children twice at every level, a Zstandard bomb in a KTX2 image), truncated and malformed
//! KTX2, WebP and PNG images inside GLBs, non-finite values in every float field, and
//! out-of-spec values. Each is loaded in-process and must fail with an error naming the JSON
//! path, or load with a warning naming the element; some also go through the binary.

mod common;

use common::{Gltf, ktx2_fixture, penumbra, quad, render_exr, textured_quad};
use penumbra::scene::{EnvMap, Scene, load};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// A scene with one of every element the importer reads: a textured material, a sampler and
/// an image, a camera, a point and a spot light, and a node hierarchy.
fn base() -> Gltf {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let png = {
        let mut bytes = Vec::new();
        let img = image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]));
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .unwrap();
        bytes
    };
    let view = g.bytes_view(&png);
    g.extra.insert(
        "images".into(),
        json!([{"bufferView": view, "mimeType": "image/png"}]),
    );
    g.extra
        .insert("samplers".into(), json!([{"wrapS": 10497, "wrapT": 33071}]));
    g.extra
        .insert("textures".into(), json!([{"source": 0, "sampler": 0}]));
    g.materials[0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let uv = g.float_accessor(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    let m = g.mesh(vec![quad()]);
    g.meshes[m]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    let child = g.node(json!({"mesh": m}));
    g.node(json!({"children": [child], "translation": [0.0, 0.0, -1.0]}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}));
    g.node(json!({"camera": 0, "translation": [0.5, 0.5, 3.0]}));
    g.lights
        .push(json!({"type": "point", "intensity": 5.0, "color": [1.0, 1.0, 1.0]}));
    g.lights.push(json!({"type": "spot", "intensity": 2.0, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.4}}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.0, 2.0, 0.0]}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 1}}, "translation": [0.0, 3.0, 0.0], "rotation": common::LOOK_DOWN}));
    g
}

/// Node indices in [`base`].
const MESH_NODE: usize = 0;
const CAMERA_NODE: usize = 2;
const LIGHT_NODE: usize = 3;

/// The base document as JSON with its buffer embedded as a data URI.
fn base_doc() -> Value {
    let g = base();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::encode(&g.bin)
    );
    g.json(Some(uri))
}

/// Sets the value at a JSON pointer, creating objects on the way.
fn set(doc: &mut Value, pointer: &str, value: Value) {
    let mut at = doc;
    for key in pointer.split('/').skip(1) {
        at = match at {
            Value::Array(a) => &mut a[key.parse::<usize>().unwrap()],
            Value::Object(o) => o.entry(key).or_insert(json!({})),
            _ => panic!("{pointer}: {key} is not in an object or array"),
        };
    }
    *at = value;
}

fn write(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    let p = dir.join(format!("{name}.gltf"));
    std::fs::write(&p, serde_json::to_vec(doc).unwrap()).unwrap();
    p
}

/// Loads `doc` in-process: the error text, or the scene.
fn try_load(doc: &Value, name: &str) -> Result<Scene, String> {
    let dir = tempfile::tempdir().unwrap();
    load(&write(dir.path(), name, doc)).map_err(|e| e.to_string())
}

fn assert_fails(doc: &Value, name: &str, expect: &str) {
    match try_load(doc, name) {
        Ok(_) => panic!("{name}: loaded, expected an error naming {expect}"),
        Err(e) => {
            assert!(e.contains(expect), "{name}: '{e}' does not name {expect}");
            assert!(e.contains(&format!("{name}.gltf")), "names the file: {e}");
            assert!(!e.contains('\n'), "one line: {e}");
        }
    }
}

fn assert_warns(doc: &Value, name: &str, expect: &str) -> Scene {
    let s = try_load(doc, name).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(
        s.warnings.iter().any(|w| w.contains(expect)),
        "{name}: no warning naming {expect}: {:?}",
        s.warnings
    );
    s
}

#[test]
fn the_base_scene_loads_without_warnings() {
    let s = try_load(&base_doc(), "base").unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.triangle_count(), 2);
    assert_eq!(s.cameras.len(), 1);
    assert_eq!(s.lights.len(), 2);
    assert!(s.materials[0].textures.base_color.is_some());
}

#[test]
fn every_dangling_index_names_its_json_path() {
    let light = format!("/nodes/{LIGHT_NODE}/extensions/KHR_lights_punctual/light");
    let camera = format!("/nodes/{CAMERA_NODE}/camera");
    let mesh = format!("/nodes/{MESH_NODE}/mesh");
    let cases: Vec<(&str, &str)> = vec![
        (&mesh, "nodes[0].mesh"),
        (
            "/meshes/0/primitives/0/material",
            "meshes[0].primitives[0].material",
        ),
        (
            "/meshes/0/primitives/0/attributes/POSITION",
            "meshes[0].primitives[0].attributes[\"POSITION\"]",
        ),
        (
            "/meshes/0/primitives/0/attributes/TEXCOORD_0",
            "meshes[0].primitives[0].attributes[\"TEXCOORD_0\"]",
        ),
        (
            "/meshes/0/primitives/0/indices",
            "meshes[0].primitives[0].indices",
        ),
        ("/accessors/0/bufferView", "accessors[0].bufferView"),
        ("/bufferViews/0/buffer", "bufferViews[0].buffer"),
        ("/images/0/bufferView", "images[0].bufferView"),
        ("/textures/0/source", "textures[0].source"),
        ("/textures/0/sampler", "textures[0].sampler"),
        (
            "/materials/0/pbrMetallicRoughness/baseColorTexture/index",
            "materials[0].pbrMetallicRoughness.baseColorTexture.index",
        ),
        (&camera, "nodes[2].camera"),
        ("/scene", "scene"),
        ("/scenes/0/nodes/0", "scenes[0].nodes[0]"),
        ("/nodes/1/children/0", "nodes[1].children[0]"),
        (&light, "nodes[3].extensions.KHR_lights_punctual.light"),
    ];
    for (i, (pointer, path)) in cases.into_iter().enumerate() {
        let mut doc = base_doc();
        set(&mut doc, pointer, json!(99));
        assert_fails(&doc, &format!("dangling-{i}"), &format!("{path}: index"));
    }
}

#[test]
fn every_bad_enum_names_its_json_path() {
    let cases: Vec<(&str, Value, &str)> = vec![
        (
            "/meshes/0/primitives/0/mode",
            json!(99),
            "meshes[0].primitives[0].mode",
        ),
        ("/cameras/0/type", json!("fisheye"), "cameras[0].type"),
        (
            "/extensions/KHR_lights_punctual/lights/0/type",
            json!("laser"),
            "extensions.KHR_lights_punctual.lights[0].type",
        ),
        (
            "/materials/0/alphaMode",
            json!("SHINY"),
            "materials[0].alphaMode",
        ),
        ("/samplers/0/wrapS", json!(1234), "samplers[0].wrapS"),
        ("/samplers/0/magFilter", json!(7), "samplers[0].magFilter"),
        (
            "/accessors/0/componentType",
            json!(9999),
            "accessors[0].componentType",
        ),
        ("/accessors/0/type", json!("VEC9"), "accessors[0].type"),
        ("/bufferViews/0/target", json!(1), "bufferViews[0].target"),
    ];
    for (i, (pointer, value, path)) in cases.into_iter().enumerate() {
        let mut doc = base_doc();
        set(&mut doc, pointer, value);
        assert_fails(&doc, &format!("enum-{i}"), &format!("{path}: invalid"));
    }
}

#[test]
fn objects_the_gltf_crate_would_unwrap_are_checked() {
    let mut doc = base_doc();
    doc["cameras"][0] = json!({"type": "perspective", "orthographic": {"xmag": 1.0, "ymag": 1.0, "zfar": 10.0, "znear": 0.1}});
    assert_fails(&doc, "camera-object", "cameras[0]");

    let mut doc = base_doc();
    doc["images"][0].as_object_mut().unwrap().remove("mimeType");
    assert_fails(&doc, "image-mime", "images[0].mimeType");

    let mut doc = base_doc();
    doc["images"][0] = json!({});
    assert_fails(&doc, "image-source", "images[0]");

    let mut doc = base_doc();
    doc["extensions"]["KHR_lights_punctual"]["lights"][1]
        .as_object_mut()
        .unwrap()
        .remove("spot");
    assert_fails(
        &doc,
        "spot-object",
        "extensions.KHR_lights_punctual.lights[1].spot",
    );
}

#[test]
fn a_sparse_count_bomb_is_refused_before_anything_is_allocated() {
    let mut doc = base_doc();
    let accessors = doc["accessors"].as_array_mut().unwrap();
    accessors.push(json!({
        "componentType": 5126, "type": "VEC3", "count": 4_000_000_000u64,
        "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125},
                   "values": {"bufferView": 0}}
    }));
    let bomb = accessors.len() - 1;
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(bomb);
    assert_fails(&doc, "sparse-bomb", &format!("accessors[{bomb}].count"));

    let mut doc = base_doc();
    doc["accessors"][0]["sparse"] = json!({"count": 1_000_000, "indices": {"bufferView": 0, "componentType": 5125}, "values": {"bufferView": 0}});
    assert_fails(&doc, "sparse-count", "accessors[0].sparse.count");
}

#[test]
fn buffers_are_read_only_from_regular_files_and_never_past_their_length() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let run = |doc: &Value, name: &str| load(&write(d, name, doc)).map_err(|e| e.to_string());

    let mut doc = base_doc();
    doc["buffers"][0]["uri"] = json!("/dev/zero");
    let e = run(&doc, "absolute").unwrap_err();
    assert!(
        e.contains("buffers[0].uri") && e.contains("relative"),
        "{e}"
    );

    // A link to a device outside the folder is refused for where it leads; a device inside
    // the allowed folders (a pipe here) for what it is, before anything is read.
    std::os::unix::fs::symlink("/dev/zero", d.join("zero.bin")).unwrap();
    doc["buffers"][0]["uri"] = json!("zero.bin");
    let e = run(&doc, "dev-zero").unwrap_err();
    assert!(e.contains("buffers[0].uri") && e.contains("outside"), "{e}");
    let made = std::process::Command::new("mkfifo")
        .arg(d.join("pipe.bin"))
        .status()
        .unwrap();
    assert!(made.success());
    doc["buffers"][0]["uri"] = json!("pipe.bin");
    let e = run(&doc, "pipe").unwrap_err();
    assert!(
        e.contains("buffers[0].uri") && e.contains("not a regular file"),
        "{e}"
    );

    doc["buffers"][0]["uri"] = json!(".");
    let e = run(&doc, "folder").unwrap_err();
    assert!(e.contains("not a regular file"), "{e}");

    doc["buffers"][0]["uri"] = json!("https://example.com/a.bin");
    let e = run(&doc, "remote").unwrap_err();
    assert!(e.contains("buffers[0].uri"), "{e}");

    doc["buffers"][0]["uri"] = json!("%FF%FE.bin");
    let e = run(&doc, "bad-utf8").unwrap_err();
    assert!(e.contains("buffers[0].uri"), "{e}");

    std::fs::write(d.join("short.bin"), [0u8; 16]).unwrap();
    doc["buffers"][0]["uri"] = json!("short.bin");
    let e = run(&doc, "short").unwrap_err();
    assert!(e.contains("buffers[0]") && e.contains("declared"), "{e}");

    let mut doc = base_doc();
    doc["buffers"][0]["byteLength"] = json!(1u64 << 40);
    let e = run(&doc, "long").unwrap_err();
    assert!(e.contains("buffers[0]: byteLength"), "{e}");
}

#[test]
fn oversized_images_are_refused_from_their_header() {
    // 20000 × 1 pixels: small when compressed, past the side limit.
    let mut png = Vec::new();
    image::GrayImage::new(20000, 1)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let mut doc = base_doc();
    doc["images"][0] = json!({"uri": format!("data:image/png;base64,{}", base64::encode(&png))});
    let s = assert_warns(&doc, "wide-image", "images[0]");
    assert!(
        s.warnings.iter().any(|w| w.contains("more than the limit")),
        "{:?}",
        s.warnings
    );
    assert!(
        s.materials[0].textures.base_color.is_none(),
        "the texture is left out"
    );
}

#[test]
fn an_exr_header_claiming_100000_squared_is_refused_without_reading_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.exr");
    penumbra::image_io::write_exr(&path, 2, 2, &[[1.0; 3]; 4]).unwrap();
    // Rewrite the data and display windows (box2i: xMin, yMin, xMax, yMax) to 100000².
    let mut bytes = std::fs::read(&path).unwrap();
    let mut patched = 0;
    for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes
            .windows(name.len())
            .position(|w| w == name)
            .expect("the attribute is in the header")
            + name.len()
            + 4;
        bytes[at + 8..at + 12].copy_from_slice(&99_999i32.to_le_bytes());
        bytes[at + 12..at + 16].copy_from_slice(&99_999i32.to_le_bytes());
        patched += 1;
    }
    assert_eq!(patched, 2);
    std::fs::write(&path, &bytes).unwrap();
    let e = EnvMap::load(&path).unwrap_err();
    assert!(e.contains("huge.exr") && e.contains("100000×100000"), "{e}");
}

#[test]
fn a_node_graph_listing_children_twice_at_every_level_is_capped() {
    let mut doc = base_doc();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    // 40 levels, each listing the next twice: 2^40 paths to the mesh node.
    for level in 0..40 {
        let next = first + level + 1;
        nodes.push(json!({"children": [next, next]}));
    }
    nodes.push(json!({"mesh": 0}));
    doc["scenes"][0]["nodes"] = json!([first]);
    let e = try_load(&doc, "graph-bomb").unwrap_err();
    assert!(e.contains("nodes[") && e.contains("more than"), "{e}");

    let mut doc = base_doc();
    doc["nodes"][1]["children"] = json!([0, 1]);
    let e = try_load(&doc, "cycle").unwrap_err();
    assert!(e.contains("nodes[") && e.contains("a cycle"), "{e}");
}

#[test]
fn unusable_transforms_skip_the_node_with_one_warning() {
    let mut doc = base_doc();
    doc["nodes"][1]["rotation"] = json!([0.0, 0.0, 0.0, 0.0]);
    let s = assert_warns(&doc, "zero-quat", "nodes[1]: rotation is a zero quaternion");
    assert_eq!(s.triangle_count(), 0, "the mesh below it is skipped");

    let mut doc = base_doc();
    doc["nodes"][0]["matrix"] = json!(vec![0.0; 16]);
    let s = assert_warns(&doc, "singular", "nodes[0]: matrix is singular");
    assert_eq!(s.triangle_count(), 0);

    let mut doc = base_doc();
    // 1e39 overflows f32; node transforms are read in f64, so the world transform overflows
    // when it becomes the f32 render frame (or the f32 value is not finite).
    doc["nodes"][0]["translation"] = json!([1e39, 0.0, 0.0]);
    let s = assert_warns(&doc, "infinite", "nodes[0]: ");
    assert!(
        s.warnings
            .iter()
            .any(|w| w.starts_with("nodes[0]: ") && w.contains("skipped")),
        "{:?}",
        s.warnings
    );
    assert_eq!(s.triangle_count(), 0);

    let mut doc = base_doc();
    doc["nodes"][0]["scale"] = json!([1e30, 1e30, 1e30]);
    doc["nodes"][1]["scale"] = json!([1e30, 1e30, 1e30]);
    assert_warns(&doc, "overflow", "nodes[0]: its world transform");
}

#[test]
fn out_of_spec_cameras_lights_and_materials_are_skipped_or_clamped() {
    let mut doc = base_doc();
    doc["cameras"][0]["perspective"]["yfov"] = json!(4.0);
    let s = assert_warns(&doc, "yfov", "cameras[0].perspective.yfov");
    assert_eq!(s.cameras.len(), 1);
    assert_eq!(s.cameras[0].name, "auto", "the automatic camera");

    let mut doc = base_doc();
    doc["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = json!(-1.0);
    doc["extensions"]["KHR_lights_punctual"]["lights"][1]["color"] = json!([1.0, 1e39, 0.0]);
    let s = assert_warns(&doc, "lights", "extensions.KHR_lights_punctual.lights[0]");
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("extensions.KHR_lights_punctual.lights[1]")),
        "{:?}",
        s.warnings
    );
    assert!(s.lights.iter().all(|l| l.name.starts_with("default")) || s.default_rig);

    let mut doc = base_doc();
    doc["extensions"]["KHR_lights_punctual"]["lights"][1]["spot"] =
        json!({"innerConeAngle": 1.0, "outerConeAngle": 3.0});
    let s = assert_warns(&doc, "spot", "lights[1].spot");
    let spot = s
        .lights
        .iter()
        .find_map(|l| match l.kind {
            penumbra::scene::LightKind::Spot { inner, outer } => Some((inner, outer)),
            _ => None,
        })
        .unwrap();
    assert!(0.0 <= spot.0 && spot.0 < spot.1 && spot.1 <= std::f32::consts::FRAC_PI_2);

    let mut doc = base_doc();
    let m = &mut doc["materials"][0];
    m["pbrMetallicRoughness"]["metallicFactor"] = json!(5.0);
    m["pbrMetallicRoughness"]["baseColorFactor"] = json!([2.0, -1.0, 0.5, 1.0]);
    m["emissiveFactor"] = json!([1e39, 0.5, -3.0]);
    m["extensions"] = json!({"KHR_materials_ior": {"ior": 0.5}});
    let s = assert_warns(&doc, "factors", "materials[0]");
    let w = material_warning(&s);
    assert!(w.contains("metallicFactor") && w.contains("ior 0.5"), "{w}");
    assert_eq!(
        s.warnings
            .iter()
            .filter(|w| w.contains("materials[0]"))
            .count(),
        1,
        "one warning per material"
    );
    let mat = &s.materials[0];
    assert_eq!(mat.metallic, 1.0);
    assert_eq!(mat.base_color, [1.0, 0.0, 0.5, 1.0]);
    assert_eq!(mat.emission, [1.0, 0.5, 0.0]);
    assert_eq!(mat.ior, 1.5);
}

/// The warning about `materials[0]`.
fn material_warning(s: &Scene) -> &str {
    s.warnings
        .iter()
        .find(|w| w.contains("materials[0]"))
        .expect("a warning about materials[0]")
}

/// Runs `penumbra render` and returns (exit code, stderr).
fn render(args: &[&str]) -> (Option<i32>, String) {
    let out = std::env::temp_dir().join("penumbra-hostile.exr");
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["-o", out.to_str().unwrap(), "--width", "8", "--height", "8"]);
    let o = penumbra(&all);
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn the_binary_ends_hostile_files_with_exit_1_and_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc = base_doc();
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.bin")).unwrap();
    doc["buffers"][0]["uri"] = json!("zero.bin");
    let zero = write(dir.path(), "zero", &doc);
    let mut doc = base_doc();
    doc["meshes"][0]["primitives"][0]["mode"] = json!(99);
    let mode = write(dir.path(), "mode", &doc);
    for (path, expect) in [
        (&zero, "buffers[0].uri"),
        (&mode, "meshes[0].primitives[0].mode"),
    ] {
        let (code, err) = render(&[path.to_str().unwrap(), "--spp", "1"]);
        assert_eq!(code, Some(1), "{err}");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(
            err.starts_with("penumbra: error: ") && err.contains(expect),
            "{err}"
        );
    }
}

#[test]
fn usage_errors_are_one_line_with_exit_2() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let s = scene.to_str().unwrap();
    for (args, expect) in [
        (vec![s, "--no-such-flag"], "--no-such-flag"),
        (vec![s, "--spp", "-1"], "--spp"),
        (vec![s, "--spp", "4294967296"], "--spp"),
        (vec![s, "--exposure", "nan"], "--exposure"),
        (vec![s, "--exposure", "1000"], "--exposure"),
        (vec![s, "--aperture", "inf"], "--aperture"),
        (vec![s, "--aperture", "-1"], "--aperture"),
        (vec![s, "--focus-distance", "0"], "--focus-distance"),
        (vec![s, "--fov", "180"], "--fov"),
        (vec![s, "--fov", "NaN"], "--fov"),
        (vec![s, "--light-radius=-inf"], "--light-radius"),
        (vec![s, "--env-intensity", "1e39"], "--env-intensity"),
        (vec![s, "--env-rotation", "inf"], "--env-rotation"),
        (vec![s, "--ev100", "1e30"], "--ev100"),
        (vec![s, "--ev100", "nan"], "--ev100"),
        (vec![s, "--eye", "0,0,nan", "--look-at", "0,0,0"], "--eye"),
        (
            vec![s, "--look-at", "0,0,1e999", "--eye", "1,1,1"],
            "--look-at",
        ),
        (vec![], "<SCENE>"),
    ] {
        let (code, err) = render(&args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: one line: {err}");
        assert!(
            err.starts_with("penumbra: error: ") && err.contains(expect),
            "{args:?}: {err}"
        );
    }
    for flag in ["--help", "--version"] {
        let o = penumbra(&[flag]);
        assert_eq!(o.status.code(), Some(0), "{flag}");
        assert!(!o.stdout.is_empty(), "{flag} prints on stdout");
    }
}

/// Loads a textured quad whose image is `image` in-process (as a GLB).
fn load_textured(image: &[u8], mime: &str, extension: Option<&str>, name: &str) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let path = textured_quad(image, mime, extension).write_glb(dir.path(), name);
    load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Asserts that the scene left its one texture out with one warning naming `images[0]`.
fn assert_image_left_out(s: &Scene, name: &str, expect: &str) {
    let about: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("images[0]"))
        .collect();
    assert_eq!(about.len(), 1, "{name}: {:?}", s.warnings);
    assert!(
        about[0].contains("cannot decode") && about[0].contains(expect),
        "{name}: '{}' does not say {expect}",
        about[0]
    );
    assert!(!about[0].contains('\n'), "{name}: one line");
    assert!(s.materials[0].textures.base_color.is_none(), "{name}");
}

/// Writes a little-endian `u32` (or `u64` when `wide`) into a copy of `bytes`.
fn patch(bytes: &[u8], at: usize, value: u64, wide: bool) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let n = if wide { 8 } else { 4 };
    out[at..at + n].copy_from_slice(&value.to_le_bytes()[..n]);
    out
}

#[test]
fn ktx2_textures_load_and_broken_ones_are_one_warning_naming_the_image() {
    const KTX2: &str = "image/ktx2";
    const BASISU: Option<&str> = Some("KHR_texture_basisu");
    for file in ["etc1s-alpha.ktx2", "uastc.ktx2", "uastc-alpha.ktx2"] {
        let s = load_textured(&ktx2_fixture(file), KTX2, BASISU, file);
        assert!(s.warnings.is_empty(), "{file}: {:?}", s.warnings);
        assert!(s.materials[0].textures.base_color.is_some(), "{file}");
        assert_eq!((s.images[0].width, s.images[0].height), (30, 22), "{file}");
    }
    let etc1s = ktx2_fixture("etc1s-alpha.ktx2");
    let uastc = ktx2_fixture("uastc.ktx2");
    let raw = ktx2_fixture("uastc-alpha.ktx2");
    // A Zstandard frame of 16 MiB of zeros as the level of a 30×22 UASTC image (768 bytes).
    let bomb = {
        let frame = ruzstd::encoding::compress_to_vec(
            std::io::Read::take(std::io::repeat(0), 16 << 20),
            ruzstd::encoding::CompressionLevel::Fastest,
        );
        let level = u64::from_le_bytes(uastc[80..88].try_into().unwrap()) as usize;
        let mut b = uastc[..level].to_vec();
        b.extend_from_slice(&frame);
        let b = patch(&b, 88, frame.len() as u64, true);
        patch(&b, 96, 16 << 20, true)
    };
    let dfd = u32::from_le_bytes(etc1s[48..52].try_into().unwrap()) as usize;
    let mut block_256 = etc1s.clone();
    block_256[dfd + 16] = 255;
    let sc = "supercompression";
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("cut-header", etc1s[..40].to_vec(), "not a valid KTX2"),
        ("magic-only", etc1s[..12].to_vec(), "not a valid KTX2"),
        ("cut-middle", etc1s[..etc1s.len() / 2].to_vec(), "KTX2"),
        ("cut-last-byte", etc1s[..etc1s.len() - 1].to_vec(), "KTX2"),
        ("uastc-cut", uastc[..uastc.len() - 5].to_vec(), "KTX2"),
        (
            "huge",
            patch(&patch(&etc1s, 20, 100_000, false), 24, 100_000, false),
            "limit",
        ),
        (
            "16384-squared",
            patch(&patch(&uastc, 20, 16384, false), 24, 16384, false),
            "limit",
        ),
        ("zero-height", patch(&etc1s, 24, 0, false), "empty"),
        ("etc1s-zstd", patch(&etc1s, 44, 2, false), sc),
        ("uastc-zlib", patch(&uastc, 44, 3, false), sc),
        ("uastc-basislz", patch(&uastc, 44, 1, false), sc),
        ("scheme-99", patch(&uastc, 44, 99, false), sc),
        ("raw-claims-zstd", patch(&raw, 44, 2, false), "Zstandard"),
        ("vkformat", patch(&uastc, 12, 43, false), "vkFormat"),
        ("cubemap", patch(&etc1s, 36, 6, false), "not 2D"),
        ("volume", patch(&etc1s, 28, 4, false), "not 2D"),
        (
            "levels-max",
            patch(&etc1s, 40, u32::MAX.into(), false),
            "KTX2",
        ),
        (
            "layers-max",
            patch(&etc1s, 32, u32::MAX.into(), false),
            "BasisLZ",
        ),
        ("level-offset", patch(&etc1s, 80, 1 << 62, true), "KTX2"),
        ("level-length", patch(&etc1s, 88, 1 << 62, true), "KTX2"),
        ("sgd-length", patch(&etc1s, 72, 1 << 40, true), "KTX2"),
        ("dfd-length", patch(&etc1s, 52, 0xFFFF_FFF0, false), "KTX2"),
        ("texel-block-256", block_256, "texel block"),
        (
            "uastc-64-squared",
            patch(&patch(&uastc, 20, 64, false), 24, 64, false),
            "Zstandard",
        ),
        ("zstd-bomb", bomb, "more than the 768 bytes"),
    ];
    for (name, bytes, expect) in &cases {
        let s = load_textured(bytes, KTX2, BASISU, name);
        assert_image_left_out(&s, name, expect);
    }
}

#[test]
fn broken_png_and_webp_images_are_one_warning_naming_the_image() {
    let rgba = ktx2_fixture("rgba.png");
    let webp = {
        let mut bytes = Vec::new();
        image::load_from_memory(&rgba)
            .unwrap()
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::WebP,
            )
            .unwrap();
        bytes
    };
    // The lossless bitstream's header: 14 bits of width − 1, 14 of height − 1 (16383², past
    // the pixel limit; image-webp reads 16384 as 0).
    let vp8l = webp.windows(4).position(|w| w == b"VP8L").unwrap() + 9;
    let mut webp_huge = webp.clone();
    webp_huge[vp8l..vp8l + 4].copy_from_slice(&(16382u32 | 16382 << 14 | 1 << 28).to_le_bytes());
    // A PNG whose IHDR (with a correct CRC) claims 100000 × 100000.
    let mut png_huge = rgba.clone();
    png_huge[16..24].copy_from_slice(&[0, 1, 0x86, 0xA0, 0, 1, 0x86, 0xA0]);
    let crc = crc32(&png_huge[12..29]);
    png_huge[29..33].copy_from_slice(&crc.to_be_bytes());
    let webp_ext = Some("EXT_texture_webp");
    for (name, bytes, mime, extension, expect) in [
        (
            "png-cut",
            rgba[..rgba.len() / 2].to_vec(),
            "image/png",
            None,
            "",
        ),
        (
            "png-signature-only",
            rgba[..8].to_vec(),
            "image/png",
            None,
            "",
        ),
        ("png-huge", png_huge, "image/png", None, "limit"),
        ("png-empty", vec![], "image/png", None, ""),
        (
            "webp-cut",
            webp[..webp.len() / 2].to_vec(),
            "image/webp",
            webp_ext,
            "",
        ),
        (
            "webp-header-only",
            webp[..30].to_vec(),
            "image/webp",
            webp_ext,
            "",
        ),
        (
            "webp-16384-squared",
            webp_huge,
            "image/webp",
            webp_ext,
            "limit",
        ),
    ] {
        let s = load_textured(&bytes, mime, extension, name);
        assert_image_left_out(&s, name, expect);
    }
}

/// CRC-32 (ISO-HDLC, as PNG uses).
fn crc32(bytes: &[u8]) -> u32 {
    !bytes.iter().fold(!0u32, |c, &b| {
        (0..8).fold(c ^ b as u32, |c, _| {
            if c & 1 == 1 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            }
        })
    })
}

#[test]
fn texture_extension_sources_are_validated_like_indices() {
    for ext in ["KHR_texture_basisu", "EXT_texture_webp"] {
        for (i, (value, expect)) in [
            (json!({"source": 99}), "source: index out of range"),
            (json!({"source": -1}), "source: invalid value"),
            (json!({"source": "0"}), "source: invalid value"),
            (json!({"source": 0.5}), "source: invalid value"),
            (json!({}), "source: missing"),
            (json!([]), "invalid value"),
        ]
        .into_iter()
        .enumerate()
        {
            let mut doc = base_doc();
            doc["textures"][0]["extensions"] = json!({ext: value});
            doc["extensionsUsed"] = json!([ext]);
            let at = format!("textures[0].extensions.{ext}");
            assert_fails(&doc, &format!("ext-source-{i}"), &at);
            let e = try_load(&doc, "ext-source").unwrap_err();
            assert!(e.contains(&at) && e.contains(expect), "{value}: {e}");
        }
    }
}

/// Every float field the importer reads, as a JSON pointer into [`base_doc`] (extension
/// objects are created on the way).
const FLOAT_FIELDS: &[&str] = &[
    "/nodes/0/translation/0",
    "/nodes/0/rotation/1",
    "/nodes/0/scale/2",
    "/nodes/1/matrix/0",
    "/nodes/1/matrix/15",
    "/nodes/0/weights/0",
    "/meshes/0/weights/0",
    "/materials/0/pbrMetallicRoughness/baseColorFactor/0",
    "/materials/0/pbrMetallicRoughness/baseColorFactor/3",
    "/materials/0/pbrMetallicRoughness/metallicFactor",
    "/materials/0/pbrMetallicRoughness/roughnessFactor",
    "/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/offset/0",
    "/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/scale/1",
    "/materials/0/pbrMetallicRoughness/baseColorTexture/extensions/KHR_texture_transform/rotation",
    "/materials/0/emissiveFactor/1",
    "/materials/0/alphaCutoff",
    "/materials/0/normalTexture/scale",
    "/materials/0/occlusionTexture/strength",
    "/materials/0/extensions/KHR_materials_emissive_strength/emissiveStrength",
    "/materials/0/extensions/KHR_materials_specular/specularFactor",
    "/materials/0/extensions/KHR_materials_specular/specularColorFactor/0",
    "/materials/0/extensions/KHR_materials_ior/ior",
    "/materials/0/extensions/KHR_materials_transmission/transmissionFactor",
    "/materials/0/extensions/KHR_materials_volume/thicknessFactor",
    "/materials/0/extensions/KHR_materials_volume/attenuationDistance",
    "/materials/0/extensions/KHR_materials_volume/attenuationColor/2",
    "/cameras/0/perspective/yfov",
    "/cameras/0/perspective/znear",
    "/cameras/0/perspective/zfar",
    "/cameras/0/perspective/aspectRatio",
    "/extensions/KHR_lights_punctual/lights/0/intensity",
    "/extensions/KHR_lights_punctual/lights/0/color/1",
    "/extensions/KHR_lights_punctual/lights/0/range",
    "/extensions/KHR_lights_punctual/lights/1/spot/innerConeAngle",
    "/extensions/KHR_lights_punctual/lights/1/spot/outerConeAngle",
    "/accessors/0/min/0",
    "/accessors/0/max/1",
];

#[test]
fn non_finite_and_absurd_values_in_every_float_field_load_or_fail_in_one_line() {
    let mut doc = base_doc();
    // Fill the arrays the pointers index into, and the objects they name.
    doc["nodes"][0]["translation"] = json!([0.0, 0.0, 0.0]);
    doc["nodes"][0]["rotation"] = json!([0.0, 0.0, 0.0, 1.0]);
    doc["nodes"][0]["scale"] = json!([1.0, 1.0, 1.0]);
    doc["nodes"][1]["matrix"] = json!([
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0, 1.0
    ]);
    doc["nodes"][1]
        .as_object_mut()
        .unwrap()
        .remove("translation");
    doc["nodes"][0]["weights"] = json!([0.5]);
    doc["meshes"][0]["weights"] = json!([0.5]);
    doc["materials"][0]["normalTexture"] = json!({"index": 0});
    doc["materials"][0]["occlusionTexture"] = json!({"index": 0});
    doc["materials"][0]["alphaMode"] = json!("MASK");
    doc["materials"][0]["extensions"]["KHR_materials_specular"]["specularColorFactor"] =
        json!([1.0, 1.0, 1.0]);
    doc["materials"][0]["extensions"]["KHR_materials_volume"] =
        json!({"attenuationColor": [1.0, 1.0, 1.0]});
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
        json!({"KHR_texture_transform": {"offset": [0.0, 0.0], "scale": [1.0, 1.0]}});
    doc["extensionsUsed"] = json!([
        "KHR_lights_punctual",
        "KHR_materials_specular",
        "KHR_materials_emissive_strength",
        "KHR_materials_ior",
        "KHR_materials_transmission",
        "KHR_materials_volume",
        "KHR_texture_transform"
    ]);
    doc["accessors"][0]["min"] = json!([0.0, 0.0, 0.0]);
    doc["accessors"][0]["max"] = json!([1.0, 1.0, 0.0]);
    try_load(&doc, "float-base").unwrap();
    let mut checked = 0;
    for pointer in FLOAT_FIELDS {
        for value in [
            json!(1e39),
            json!(-1e39),
            json!(3e38),
            json!(-3e38),
            json!(1e-45),
        ] {
            let mut d = doc.clone();
            set(&mut d, pointer, value.clone());
            let name = format!("float-{checked}");
            match try_load(&d, &name) {
                Err(e) => {
                    assert!(!e.contains('\n'), "{pointer} = {value}: {e}");
                    assert!(e.contains(&format!("{name}.gltf")), "{e}");
                }
                Ok(s) => {
                    for (i, m) in s.materials.iter().enumerate() {
                        let finite = m
                            .base_color
                            .iter()
                            .chain(&m.emission)
                            .all(|v| v.is_finite())
                            && [m.metallic, m.roughness, m.ior, m.transmission, m.thickness]
                                .iter()
                                .all(|v| v.is_finite());
                        assert!(finite, "{pointer} = {value}: material {i}: {m:?}");
                    }
                    for l in &s.lights {
                        assert!(
                            l.intensity.is_finite()
                                && l.intensity >= 0.0
                                && l.color.iter().all(|c| c.is_finite() && *c >= 0.0),
                            "{pointer} = {value}: light {:?}",
                            l.name
                        );
                    }
                    for c in &s.cameras {
                        assert!(
                            c.yfov > 0.0 && c.yfov < std::f64::consts::PI && c.eye.is_finite(),
                            "{pointer} = {value}: camera {:?}",
                            c.name
                        );
                    }
                    assert!(
                        s.world_triangles()
                            .iter()
                            .all(|t| t.v.iter().all(|v| v.is_finite())),
                        "{pointer} = {value}: a non-finite vertex"
                    );
                }
            }
            checked += 1;
        }
    }
    assert_eq!(checked, FLOAT_FIELDS.len() * 5);
}

#[test]
fn non_finite_vertex_data_is_refused_or_harmless() {
    // POSITION's first float NaN or ±inf: an error naming the attribute.
    for (name, value) in [
        ("nan", f32::NAN),
        ("inf", f32::INFINITY),
        ("ninf", f32::NEG_INFINITY),
    ] {
        let mut g = textured_quad(&ktx2_fixture("rgb.png"), "image/png", None);
        let at = g.views[g.accessors[1]["bufferView"].as_u64().unwrap() as usize]["byteOffset"]
            .as_u64()
            .unwrap() as usize;
        g.bin[at..at + 4].copy_from_slice(&value.to_le_bytes());
        let dir = tempfile::tempdir().unwrap();
        let e = load(&g.write_glb(dir.path(), name))
            .unwrap_err()
            .to_string();
        assert!(e.contains("POSITION") && !e.contains('\n'), "{name}: {e}");
    }
    // Texture coordinates NaN: the scene loads; the texel lookup is the renderer's business
    // (tested through the binary below).
    let mut g = textured_quad(&ktx2_fixture("rgb.png"), "image/png", None);
    let at = g.views[g.accessors[0]["bufferView"].as_u64().unwrap() as usize]["byteOffset"]
        .as_u64()
        .unwrap() as usize;
    g.bin[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    load(&g.write_glb(dir.path(), "uv-nan")).unwrap();
}

#[test]
fn the_binary_renders_hostile_textures_and_values_without_non_finite_samples() {
    let dir = tempfile::tempdir().unwrap();
    let etc1s = ktx2_fixture("etc1s.ktx2");
    let basisu = Some("KHR_texture_basisu");
    let mut files = vec![
        textured_quad(&etc1s, "image/ktx2", basisu).write_glb(dir.path(), "ktx2-ok"),
        textured_quad(&etc1s[..300], "image/ktx2", basisu).write_glb(dir.path(), "ktx2-cut"),
        textured_quad(
            &patch(&patch(&etc1s, 20, 100_000, false), 24, 100_000, false),
            "image/ktx2",
            basisu,
        )
        .write_glb(dir.path(), "ktx2-huge"),
    ];
    let mut g = textured_quad(&ktx2_fixture("rgb.png"), "image/png", None);
    let at = g.views[g.accessors[0]["bufferView"].as_u64().unwrap() as usize]["byteOffset"]
        .as_u64()
        .unwrap() as usize;
    g.bin[at..at + 8].copy_from_slice(&[0, 0, 0xC0, 0x7F, 0, 0, 0x80, 0x7F]);
    files.push(g.write_glb(dir.path(), "uv-nan-inf"));
    let mut doc = base_doc();
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = json!(
        {"KHR_texture_transform": {"offset": [1e39, -1e39], "scale": [1e39, 0.0], "rotation": 1e39}}
    );
    doc["extensions"]["KHR_lights_punctual"]["lights"][1]["spot"] =
        json!({"innerConeAngle": 1e39, "outerConeAngle": -1e39});
    files.push(write(dir.path(), "transform-spot", &doc));
    for file in &files {
        let out = dir.path().join("out.exr");
        let (summary, px) =
            render_exr(file, &out, &["--width", "8", "--height", "8", "--spp", "2"]);
        assert_eq!(summary["nonfinite_samples"], 0, "{}", file.display());
        assert!(
            px.iter().flatten().all(|v| v.is_finite() && *v >= 0.0),
            "{}",
            file.display()
        );
    }
}

/// The base document with its buffer in the file `uri` (relative to the glTF file).
fn base_doc_with_buffer(uri: &str) -> Value {
    base().json(Some(uri.to_string()))
}

#[test]
fn files_outside_the_scene_folder_are_refused_unless_an_asset_root_allows_them() {
    let dir = tempfile::tempdir().unwrap();
    let (scene_dir, outside) = (dir.path().join("scene"), dir.path().join("outside"));
    std::fs::create_dir_all(scene_dir.join("sub")).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::write(outside.join("data.bin"), &base().bin).unwrap();
    std::fs::write(scene_dir.join("inside.bin"), &base().bin).unwrap();
    std::os::unix::fs::symlink(outside.join("data.bin"), scene_dir.join("link.bin")).unwrap();
    std::os::unix::fs::symlink(&outside, scene_dir.join("sub/out")).unwrap();
    let load_uri = |uri: &str, name: &str, root: Option<&Path>| {
        let path = write(&scene_dir, name, &base_doc_with_buffer(uri));
        penumbra::scene::load_with(&path, root).map_err(|e| e.to_string())
    };
    // Every way out: `..`, percent-encoded `..` and slashes, `..` through a subfolder, a
    // symbolic link to a file outside and one to a folder outside.
    for (i, uri) in [
        "../outside/data.bin",
        "%2E%2E/outside/data.bin",
        "..%2Foutside%2Fdata.bin",
        "sub/../../outside/data.bin",
        "link.bin",
        "sub/out/data.bin",
    ]
    .into_iter()
    .enumerate()
    {
        let name = format!("out-{i}");
        let e = load_uri(uri, &name, None).expect_err(uri);
        assert!(
            e.contains("buffers[0].uri")
                && e.contains(&format!("'{uri}'"))
                && e.contains("outside"),
            "{uri}: {e}"
        );
        assert!(!e.contains('\n'), "{e}");
        // The asset root above both folders lets the same file be read.
        let s = load_uri(uri, &name, Some(dir.path())).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(s.triangle_count(), 2, "{uri}");
    }
    // Inside the folder, `..` that stays inside is fine; data: URIs need no folder.
    assert!(load_uri("sub/../inside.bin", "inside", None).is_ok());
    assert!(try_load(&base_doc(), "data-uri").is_ok());
    // An asset root that does not hold the file allows nothing more.
    let e = load_uri(
        "../outside/data.bin",
        "other-root",
        Some(&scene_dir.join("sub")),
    )
    .unwrap_err();
    assert!(e.contains("outside"), "{e}");

    // An image outside: refused (not read), one warning naming the URI, the texture left out.
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([9, 9, 9, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(outside.join("tex.png"), &png).unwrap();
    let mut doc = base_doc();
    doc["images"][0] = json!({"uri": "../outside/tex.png"});
    let path = write(&scene_dir, "image-out", &doc);
    let s = load(&path).unwrap();
    assert!(
        s.warnings.iter().any(|w| w.contains("images[0]")
            && w.contains("'../outside/tex.png'")
            && w.contains("outside the scene")),
        "{:?}",
        s.warnings
    );
    assert!(s.materials[0].textures.base_color.is_none());
    let s = penumbra::scene::load_with(&path, Some(dir.path())).unwrap();
    assert!(
        s.materials[0].textures.base_color.is_some(),
        "{:?}",
        s.warnings
    );

    // Through the binary: exit 1 with one line, and --asset-root lets it render.
    let path = write(
        &scene_dir,
        "cli",
        &base_doc_with_buffer("../outside/data.bin"),
    );
    let (code, err) = render(&[path.to_str().unwrap(), "--spp", "1"]);
    assert_eq!(code, Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("'../outside/data.bin'") && err.contains("--asset-root"),
        "{err}"
    );
    let root = dir.path().to_str().unwrap();
    let (code, err) = render(&[path.to_str().unwrap(), "--spp", "1", "--asset-root", root]);
    assert_eq!(code, Some(0), "{err}");
    let (code, err) = render(&[path.to_str().unwrap(), "--asset-root", "/no/such/folder"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--asset-root"), "{err}");
}

/// Runs `penumbra render SCENE -o OUT` at 8×8 with `extra` options.
fn render_output(scene: &str, out: &str, extra: &[&str]) -> std::process::Output {
    let mut all = vec!["render", scene, "-o", out, "--width", "8", "--height", "8"];
    all.extend_from_slice(extra);
    penumbra(&all)
}

/// [`render_output`]: (exit code, stderr).
fn render_to(scene: &str, out: &str, extra: &[&str]) -> (Option<i32>, String) {
    let o = render_output(scene, out, extra);
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn bundled() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/cornell-box.glb")
        .to_str()
        .unwrap()
        .to_string()
}

#[test]
fn output_paths_are_checked_before_rendering_and_every_write_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let missing_scene = d.join("no-such-scene.glb");
    let missing_scene = missing_scene.to_str().unwrap();
    std::fs::create_dir(d.join("folder.png")).unwrap();
    let folder = d.join("folder.png");
    let no_folder = d.join("no/such/out.png");
    // The output is refused before the scene is even read: the error names the output, not
    // the missing scene.
    for (out, expect) in [
        (folder.to_str().unwrap(), "is a folder"),
        (no_folder.to_str().unwrap(), "output folder does not exist"),
        (
            "/proc/penumbra-test.exr",
            "/proc/penumbra-test.exr: cannot write",
        ),
        ("out.jpg", "must end in .exr or .png"),
    ] {
        let (code, err) = render_to(missing_scene, out, &[]);
        assert_eq!(code, Some(1), "{out}: {err}");
        assert_eq!(err.lines().count(), 1, "{out}: one line: {err}");
        assert!(err.contains(expect), "{out}: {err}");
        assert!(
            !err.contains("no-such-scene"),
            "{out}: checked before the scene: {err}"
        );
        // The OS's message once, without Rust's "(os error N)".
        assert!(!err.contains("os error"), "{out}: {err}");
    }

    // A full device: the render runs, the write fails, exit 1 with one line (PNG and EXR).
    for out in ["/dev/full"] {
        for (ext_flag, what) in [("png", "PNG"), ("exr", "EXR")] {
            // /dev/full has no extension: reach it through a link named for the format.
            let link = d.join(format!("full.{ext_flag}"));
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(out, &link).unwrap();
            let (code, err) = render_to(&bundled(), link.to_str().unwrap(), &["--spp", "1"]);
            assert_eq!(code, Some(1), "{what}: {err}");
            let errors: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
            assert_eq!(errors.len(), 1, "{what}: {err}");
            assert!(
                errors[0].contains("cannot write") && errors[0].contains("No space left"),
                "{what}: {err}"
            );
        }
    }

    // A render that fails leaves no file it created, and an existing file as it was.
    let fresh = d.join("fresh.png");
    let (code, _) = render_to(missing_scene, fresh.to_str().unwrap(), &[]);
    assert_eq!(code, Some(1));
    assert!(
        !fresh.exists(),
        "the output created for the check is removed"
    );
    let old = d.join("old.png");
    std::fs::write(&old, b"old bytes").unwrap();
    let (code, _) = render_to(missing_scene, old.to_str().unwrap(), &[]);
    assert_eq!(code, Some(1));
    assert_eq!(std::fs::read(&old).unwrap(), b"old bytes");
    // A successful render replaces it with a PNG that decodes.
    let (code, err) = render_to(&bundled(), old.to_str().unwrap(), &["--spp", "1"]);
    assert_eq!(code, Some(0), "{err}");
    let png = image::open(&old).unwrap();
    assert_eq!((png.width(), png.height()), (8, 8));
}

/// A Radiance HDR file of `width × height` texels, each the RGBE bytes `rgbe` (flat: widths
/// under 8 are never run-length encoded).
fn hdr_file(path: &Path, width: u32, height: u32, rgbe: [u8; 4]) {
    let mut bytes =
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    for _ in 0..width * height {
        bytes.extend_from_slice(&rgbe);
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn infinite_or_huge_radiance_is_clamped_at_load_with_one_warning() {
    let dir = tempfile::tempdir().unwrap();
    let limit = penumbra::scene::limits::MAX_INTENSITY;
    // The largest exponent: every channel 255/256 × 2^127 ≈ 1.7e38.
    let hdr = dir.path().join("max-exponent.hdr");
    hdr_file(&hdr, 4, 2, [255, 255, 255, 255]);
    let (map, warning) = EnvMap::load_checked(&hdr).unwrap();
    let w = warning.expect("one warning");
    assert!(
        w.contains("max-exponent.hdr") && w.contains("24 values above"),
        "{w}"
    );
    assert!(
        map.texels.iter().flatten().all(|&v| v == limit),
        "clamped to the limit"
    );

    // inf, NaN and negative texels in an EXR: 0, said once.
    let exr = dir.path().join("bad.exr");
    let bad = [
        [f32::INFINITY, 1.0, 1.0],
        [f32::NAN, -5.0, 2.0],
        [1.0, 1.0, 1.0],
        [3e38, 0.5, 0.5],
    ];
    penumbra::image_io::write_exr(&exr, 2, 2, &bad).unwrap();
    let (map, warning) = EnvMap::load_checked(&exr).unwrap();
    let w = warning.expect("one warning");
    assert!(
        w.contains("2 values non-finite")
            && w.contains("1 values negative")
            && w.contains("1 values above"),
        "{w}"
    );
    assert_eq!(map.texels[0], [0.0, 1.0, 1.0]);
    assert_eq!(map.texels[1], [0.0, 0.0, 2.0]);
    assert_eq!(map.texels[3], [limit, 0.5, 0.5]);
    // A clean map has no warning.
    let clean = dir.path().join("clean.hdr");
    hdr_file(&clean, 4, 2, [128, 128, 128, 129]);
    assert!(EnvMap::load_checked(&clean).unwrap().1.is_none());

    // Colors and scales past the limit are usage errors (exit 2).
    let scene = bundled();
    for args in [
        vec!["--env-intensity", "3e38"],
        vec!["--sky", "3e38"],
        vec!["--env", "3e38,0,0"],
        vec!["--background", "env", "--sky", "1,1e13,1"],
    ] {
        let out = dir.path().join("x.exr");
        let (code, err) = render_to(&scene, out.to_str().unwrap(), &args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(args[args.len() - 2]), "{args:?}: {err}");
    }

    // Through the binary: the clamped map at the largest scale renders finite, with one
    // warning line, and the summary counts non-finite samples and pixels (none here).
    let out = dir.path().join("lit.exr");
    let intensity = format!("{limit:e}");
    let o = render_output(
        &scene,
        out.to_str().unwrap(),
        &[
            "--spp",
            "2",
            "--env",
            hdr.to_str().unwrap(),
            "--env-intensity",
            &intensity,
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let warnings: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("radiance clamped"))
        .collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(warnings[0].starts_with("penumbra: warning: "), "{err}");
    let summary: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(summary["nonfinite_samples"].is_u64(), "{summary}");
    assert_eq!(summary["nonfinite_pixels"], json!(0), "{summary}");
    let (_, _, px) = penumbra::image_io::read_exr(&out).unwrap();
    assert!(px.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    assert!(
        px.iter().flatten().any(|v| *v > 1e6),
        "the bright sky shows"
    );
}

#[test]
fn control_characters_in_files_and_paths_never_make_a_second_line() {
    let dir = tempfile::tempdir().unwrap();
    let forged = "x.bin\npenumbra: error: forged\u{1b}[2J";
    // A URI (an error), an extension name (a warning) and a command-line path (an error).
    let mut doc = base_doc();
    doc["buffers"][0]["uri"] = json!(forged);
    let bad_uri = write(dir.path(), "uri", &doc);
    let mut doc = base_doc();
    doc["extensionsUsed"] = json!([format!("EXT_x\npenumbra: error: forged\u{1b}[31m")]);
    let bad_ext = write(dir.path(), "ext", &doc);
    let odd = dir.path().join("odd\nname\u{1b}[0m.gltf");
    let out = dir.path().join("o.exr");
    for (scene, code) in [(&bad_uri, Some(1)), (&bad_ext, Some(0)), (&odd, Some(1))] {
        let (got, err) = render_to(
            scene.to_str().unwrap(),
            out.to_str().unwrap(),
            &["--spp", "1"],
        );
        assert_eq!(got, code, "{err}");
        assert!(!err.contains('\u{1b}'), "no raw escape: {err:?}");
        assert!(
            err.lines().all(|l| l.starts_with("penumbra: ")),
            "every line is one message: {err:?}"
        );
        assert!(
            !err.lines()
                .any(|l| l.starts_with("penumbra: error: forged")),
            "{err:?}"
        );
        assert!(
            err.contains("\\n") && err.contains("\\u{1b}"),
            "escaped: {err:?}"
        );
    }
}

#[test]
fn a_deep_node_chain_fails_before_the_import_walks_it() {
    // 100,000 nested nodes: refused by the linear check (before the rest transforms, which
    // walk each chain to its root) with the node named where the limit is passed.
    let mut doc = base_doc();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    let depth = 100_000;
    for level in 0..depth {
        let mut node = json!({"translation": [0.0, 0.0, 0.0]});
        if level + 1 < depth {
            node["children"] = json!([first + level + 1]);
        }
        nodes.push(node);
    }
    doc["scenes"][0]["nodes"] = json!([first]);
    let e = try_load(&doc, "deep").unwrap_err();
    let limit = penumbra::scene::limits::MAX_NODE_DEPTH;
    assert!(
        e.contains(&format!(
            "nodes[{}]: nested more than {limit} deep",
            first + limit + 1
        )),
        "{e}"
    );
    // At the limit it loads.
    let mut doc = base_doc();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    for level in 0..=limit {
        nodes.push(json!({"children": [first + level + 1]}));
    }
    nodes.push(json!({"mesh": 0}));
    doc["scenes"][0]["nodes"] = json!([first]);
    let s = try_load(&doc, "at-limit");
    assert!(s.is_err(), "one past: the walk's own check");
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes[first + limit]["children"] = json!([]);
    nodes[first + limit]["mesh"] = json!(0);
    let s = try_load(&doc, "at-limit").unwrap();
    assert_eq!(s.triangle_count(), 2, "the mesh at the end of the chain");

    // Parents that form a cycle no scene reaches.
    let mut doc = base_doc();
    let nodes = doc["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    nodes.push(json!({"children": [first + 1]}));
    nodes.push(json!({"children": [first]}));
    let e = try_load(&doc, "cycle-apart").unwrap_err();
    assert!(e.contains("a cycle"), "{e}");
}

#[test]
fn values_the_specification_forbids_are_one_warning_each() {
    type Change = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(&str, Change, &str)> = vec![
        (
            "version",
            Box::new(|d| d["asset"]["version"] = json!("3.0")),
            "asset.version",
        ),
        (
            "min",
            Box::new(|d| d["asset"]["minVersion"] = json!("2.1")),
            "asset.minVersion",
        ),
        (
            "no-prims",
            Box::new(|d| {
                d["meshes"]
                    .as_array_mut()
                    .unwrap()
                    .push(json!({"primitives": []}))
            }),
            "meshes[1]: no primitives",
        ),
        (
            "znear",
            Box::new(|d| d["cameras"][0]["perspective"]["znear"] = json!(0.0)),
            "znear",
        ),
        (
            "zfar",
            Box::new(|d| d["cameras"][0]["perspective"]["zfar"] = json!(0.01)),
            "zfar",
        ),
        (
            "aspect",
            Box::new(|d| d["cameras"][0]["perspective"]["aspectRatio"] = json!(-1.0)),
            "aspectRatio",
        ),
        (
            "range",
            Box::new(|d| d["extensions"]["KHR_lights_punctual"]["lights"][0]["range"] = json!(0.0)),
            "lights[0].range",
        ),
        (
            "matrix-trs",
            Box::new(|d| {
                d["nodes"][0]["matrix"] = json!([
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0
                ]);
                d["nodes"][0]["scale"] = json!([2.0, 2.0, 2.0]);
            }),
            "nodes[0]: has both matrix and",
        ),
        (
            "projective",
            Box::new(|d| {
                d["nodes"][0]["matrix"] = json!([
                    1.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0
                ]);
            }),
            "nodes[0].matrix: its last row",
        ),
        (
            "transform",
            Box::new(|d| {
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
                    json!({"KHR_texture_transform": {"scale": [1e39, 1.0]}});
            }),
            "KHR_texture_transform",
        ),
        (
            // The base mesh has no morph targets: one weight is one too many.
            "weight-count",
            Box::new(|d| d["meshes"][0]["weights"] = json!([0.5])),
            "meshes[0].weights: 1 weights for 0 morph targets",
        ),
        (
            "node-weight-count",
            Box::new(|d| d["nodes"][0]["weights"] = json!([0.5, 0.25])),
            "weights: 2 weights for 0 morph targets",
        ),
        (
            "channel-node",
            channel(99, "translation"),
            "animations[0].channels[0].target.node",
        ),
        (
            // Accessor 0 is VEC3 positions: a rotation needs VEC4.
            "channel-type",
            channel(0, "rotation"),
            "animations[0].channels[0]: its sampler's output",
        ),
    ];
    for (name, change, expect) in cases {
        let mut doc = base_doc();
        change(&mut doc);
        let s = assert_warns(&doc, name, expect);
        let matching = s.warnings.iter().filter(|w| w.contains(expect)).count();
        assert_eq!(matching, 1, "{name}: one warning: {:?}", s.warnings);
    }

    // The material's warning lists every extension factor brought into range.
    let mut doc = base_doc();
    doc["materials"][0]["extensions"] = json!({
        "KHR_materials_clearcoat": {"clearcoatFactor": 3.0},
        "KHR_materials_sheen": {"sheenColorFactor": [2.0, 0.0, 0.0]},
        "KHR_materials_iridescence": {"iridescenceFactor": -1.0},
        "KHR_materials_dispersion": {"dispersion": -1.0},
        "KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 9.0},
        "KHR_materials_anisotropy": {"anisotropyStrength": 2.0, "anisotropyRotation": 1e39}
    });
    let s = assert_warns(&doc, "factors", "materials[0]");
    let w = material_warning(&s);
    for key in [
        "clearcoatFactor 3",
        "sheenColorFactor 2",
        "iridescenceFactor -1",
        "dispersion -1",
        "diffuseTransmissionFactor 9",
        "anisotropyStrength 2",
    ] {
        assert!(w.contains(key), "{key}: {w}");
    }
    let about = |w: &&String| w.contains("materials[0]");
    assert_eq!(s.warnings.iter().filter(about).count(), 1, "one warning");
    let m = &s.materials[0];
    assert_eq!(
        (m.clearcoat, m.anisotropy, m.diffuse_transmission),
        (1.0, 1.0, 1.0)
    );
    assert_eq!(m.iridescence, 0.0);
    // A rotation of 1e39 turns the frame by some angle; it never becomes infinite.
    assert!(
        m.anisotropy_rotation.is_finite(),
        "{}",
        m.anisotropy_rotation
    );
    assert!((0.0..=std::f32::consts::TAU).contains(&m.anisotropy_rotation));

    // A GLB whose header length is shorter than the file.
    let dir = tempfile::tempdir().unwrap();
    let mut glb = quad_glb();
    let real = glb.len();
    glb.extend_from_slice(&[0u8; 64]);
    let path = dir.path().join("long.glb");
    std::fs::write(&path, &glb).unwrap();
    let s = load(&path).unwrap();
    assert!(
        s.warnings.iter().any(|w| w.contains(&format!(
            "header's length {real} is shorter than the file ({} bytes)",
            real + 64
        ))),
        "{:?}",
        s.warnings
    );
}

/// A change adding an animation whose one channel targets `node`'s `path`, with accessor 0 as
/// its sampler's input and output.
fn channel(node: usize, path: &'static str) -> Box<dyn Fn(&mut Value)> {
    Box::new(move |d| {
        d["animations"] = json!([{
            "channels": [{"sampler": 0, "target": {"node": node, "path": path}}],
            "samplers": [{"input": 0, "output": 0}]
        }]);
    })
}

/// A GLB of one quad.
fn quad_glb() -> Vec<u8> {
    let mut g = common::Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![quad()]);
    g.node(json!({"mesh": m}));
    g.glb()
}

#[test]
fn a_buffer_too_large_for_memory_names_its_size() {
    // A sparse 100 GiB buffer file under a 4 GB address-space limit: it can be neither mapped
    // nor read, and the one line says how large it is.
    let dir = tempfile::tempdir().unwrap();
    let g = base();
    let size = 100u64 << 30;
    let bin = std::fs::File::create(dir.path().join("big.bin")).unwrap();
    std::io::Write::write_all(&mut &bin, &g.bin).unwrap();
    bin.set_len(size).unwrap();
    let mut doc = base_doc_with_buffer("big.bin");
    doc["buffers"][0]["byteLength"] = json!(size);
    let scene = write(dir.path(), "big", &doc);
    let exe = env!("CARGO_BIN_EXE_penumbra");
    let out = dir.path().join("o.png");
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(r#"ulimit -v 4000000 && exec "$0" render "$1" -o "$2" --spp 1"#)
        .args([exe, scene.to_str().unwrap(), out.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("buffers[0].uri") && err.contains(&format!("{size} bytes (100.0 GiB)")),
        "{err}"
    );
}

/// One triangle listed `n` times as one mesh, placed by `nodes` (node JSON values).
fn coincident(n: usize, nodes: &[Value]) -> Gltf {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let indices = [0, 1, 2].repeat(n);
    let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let m = g.mesh(vec![common::Prim::triangles(positions, indices, 0)]);
    for node in nodes {
        let mut node = node.clone();
        node["mesh"] = json!(m);
        g.node(node);
    }
    g
}

#[test]
fn coincident_triangles_and_instances_are_dropped_at_load_with_one_warning_each() {
    // A viewer shows one grey triangle. Every ray once tested every copy: 65,536 copies placed
    // by 256 nodes at the same place took 190 s for one sample of 32 × 24 pixels, and 10⁶
    // copies 7 s for 64 × 48.
    let dir = tempfile::tempdir().unwrap();
    let same = vec![json!({"translation": [0.0, 0.0, -1.0]}); 256];
    let placed = coincident(65_536, &same).write_glb(dir.path(), "placed");
    let s = load(&placed).unwrap();
    assert_eq!((s.objects.len(), s.triangle_count()), (1, 1));
    let warned = |needle: &str| s.warnings.iter().filter(|w| w.contains(needle)).count();
    assert_eq!(
        warned("meshes[0]: 65535 of its 65536 triangles repeat another"),
        1,
        "{:?}",
        s.warnings
    );
    assert_eq!(
        warned("255 node(s) place a mesh again"),
        1,
        "{:?}",
        s.warnings
    );
    assert_eq!(s.warnings.len(), 2, "{:?}", s.warnings);

    let single = coincident(10_000_000, &[json!({})]).write_glb(dir.path(), "single");
    let (code, err) = render(&[single.to_str().unwrap(), "--spp", "1"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("meshes[0]: 9999999 of its 10000000 triangles repeat another"),
        "{err}"
    );
    let (code, err) = render(&[placed.to_str().unwrap(), "--spp", "1"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("255 node(s)"), "{err}");

    // Placements that differ are all kept, and so is the back face of a one-sided triangle.
    let apart: Vec<Value> = (0..4)
        .map(|i| json!({"translation": [i as f32, 0.0, 0.0]}))
        .collect();
    let mut g = coincident(1, &apart);
    g.meshes[0]["primitives"][0]["indices"] = json!(g.accessors.len());
    let flipped: Vec<u8> = [0u32, 1, 2, 0, 2, 1, 1, 2, 0]
        .iter()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let view = g.bytes_view(&flipped);
    g.accessors
        .push(json!({"bufferView": view, "componentType": 5125, "count": 9, "type": "SCALAR"}));
    let s = load(&g.write_glb(dir.path(), "apart")).unwrap();
    assert_eq!((s.objects.len(), s.triangle_count()), (4, 8));
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("meshes[0]: 1 of its 3 triangles")),
        "{:?}",
        s.warnings
    );
}
