//! Hand-made hostile files: every dangling index kind, every bad enum, memory bombs (a sparse
//! count, a buffer naming /dev/zero, an EXR header claiming 100000², a node graph listing its
//! children twice at every level) and out-of-spec values. Each is loaded in-process and must
//! fail with an error naming the JSON path, or load with a warning naming the element.

mod common;

use common::{Gltf, penumbra, quad};
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

    std::os::unix::fs::symlink("/dev/zero", d.join("zero.bin")).unwrap();
    doc["buffers"][0]["uri"] = json!("zero.bin");
    let e = run(&doc, "dev-zero").unwrap_err();
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
    doc["nodes"][0]["translation"] = json!([1e39, 0.0, 0.0]);
    assert_warns(&doc, "infinite", "nodes[0]: translation, rotation or scale");

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
    let w = s
        .warnings
        .iter()
        .find(|w| w.contains("materials[0]"))
        .unwrap();
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
