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
