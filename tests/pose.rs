//! Skins and morph targets render at the rest pose; quantized attributes read as the
//! dequantizing node transforms say (gltfpack's KHR_mesh_quantization output).

mod common;

use common::{Gltf, Prim};
use penumbra::scene::load;
use serde_json::json;

fn triangle() -> Prim {
    Prim::triangles(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![0, 1, 2],
        0,
    )
}

/// World-space positions of the scene's only object.
fn world_positions(g: &Gltf, name: &str) -> Vec<[f64; 3]> {
    let d = tempfile::tempdir().unwrap();
    let scene = load(&g.write_glb(d.path(), name)).unwrap();
    assert_eq!(scene.objects.len(), 1);
    let o = &scene.objects[0];
    o.mesh
        .positions
        .iter()
        .map(|p| {
            o.world_from_object
                .transform_point3(p.as_dvec3())
                .to_array()
        })
        .collect()
}

fn assert_close(got: &[[f64; 3]], want: &[[f64; 3]]) {
    for (g, w) in got.iter().zip(want) {
        for c in 0..3 {
            assert!((g[c] - w[c]).abs() < 1e-4, "got {got:?}, want {want:?}");
        }
    }
}

#[test]
fn morph_targets_apply_at_the_default_weights_and_the_skin_moves_the_vertices() {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![triangle()]);
    // Target 0 lifts every vertex by 1 in z, target 1 by 10; weights 0.5 and 0.
    let up = g.float_accessor(&[[0.0, 0.0, 1.0]; 3]);
    let up10 = g.float_accessor(&[[0.0, 0.0, 10.0]; 3]);
    // Vertex 0 follows joint 0, vertex 1 joint 1, vertex 2 half of each (u8 joints).
    let joints = g.bytes_view(&[0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0]);
    g.accessors
        .push(json!({"bufferView": joints, "componentType": 5121, "count": 3, "type": "VEC4"}));
    let joints = g.accessors.len() - 1;
    let weights = g.float_accessor(&[
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0],
        [0.5, 0.5, 0.0, 0.0],
    ]);
    let prim = &mut g.meshes[m]["primitives"][0];
    prim["targets"] = json!([{"POSITION": up}, {"POSITION": up10}]);
    prim["attributes"]["JOINTS_0"] = json!(joints);
    prim["attributes"]["WEIGHTS_0"] = json!(weights);
    g.meshes[m]["weights"] = json!([0.5, 0.0]);
    // Joint 0 moves by +10 x; joint 1 sits at +5 y with an inverse bind of −5 y, so it leaves
    // its vertices where they are. The skinned node's own transform is ignored.
    let j0 = g.node(json!({"translation": [10.0, 0.0, 0.0]}));
    let j1 = g.node(json!({"translation": [0.0, 5.0, 0.0]}));
    let mut ibm = vec![[0.0f32; 16]; 2];
    for (k, m) in ibm.iter_mut().enumerate() {
        for i in 0..4 {
            m[i * 5] = 1.0;
        }
        if k == 1 {
            m[13] = -5.0;
        }
    }
    let ibm = g.float_accessor(&ibm);
    g.accessors[ibm]["type"] = json!("MAT4");
    g.extra.insert(
        "skins".into(),
        json!([{"joints": [j0, j1], "inverseBindMatrices": ibm}]),
    );
    g.node(json!({"mesh": m, "skin": 0, "translation": [100.0, 0.0, 0.0]}));
    assert_close(
        &world_positions(&g, "skinned"),
        &[[10.0, 0.0, 0.5], [1.0, 0.0, 0.5], [5.0, 1.0, 0.5]],
    );
}

#[test]
fn node_weights_override_the_mesh_weights() {
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![triangle()]);
    let up = g.float_accessor(&[[0.0, 0.0, 1.0]; 3]);
    g.meshes[m]["primitives"][0]["targets"] = json!([{"POSITION": up}]);
    g.meshes[m]["weights"] = json!([0.5]);
    g.node(json!({"mesh": m, "weights": [2.0]}));
    assert_close(
        &world_positions(&g, "weights"),
        &[[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.0]],
    );
}

#[test]
fn quantized_interleaved_positions_follow_the_dequantizing_node() {
    // u16 positions interleaved with i8 normalized normals (stride 12), as gltfpack writes
    // them, under a node that scales by 1/1000 and offsets by −1.
    let mut g = Gltf::default();
    g.lambert([0.5; 3], [0.0; 3], 1.0, false);
    let m = g.mesh(vec![triangle()]);
    let mut bytes = Vec::new();
    for (p, n) in [
        ([0u16, 0, 0], [0i8, 0, 127]),
        ([1000, 0, 0], [0, 0, 127]),
        ([0, 2000, 500], [0, 0, -128]),
    ] {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
        bytes.extend_from_slice(&[0, 0]);
        bytes.extend(n.map(|c| c as u8));
        bytes.push(0);
    }
    let view = g.bytes_view(&bytes);
    g.views[view]["byteStride"] = json!(12);
    g.accessors
        .push(json!({"bufferView": view, "componentType": 5123, "count": 3, "type": "VEC3"}));
    g.accessors.push(json!({"bufferView": view, "byteOffset": 8, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"}));
    let n = g.accessors.len();
    g.meshes[m]["primitives"][0]["attributes"] = json!({"POSITION": n - 2, "NORMAL": n - 1});
    g.use_ext("KHR_mesh_quantization");
    g.required.push("KHR_mesh_quantization".into());
    g.node(json!({"mesh": m, "scale": [0.001, 0.001, 0.001], "translation": [-1.0, 0.0, 0.0]}));
    assert_close(
        &world_positions(&g, "quantized"),
        &[[-1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [-1.0, 2.0, 0.5]],
    );
    let d = tempfile::tempdir().unwrap();
    let scene = load(&g.write_glb(d.path(), "quantized-normals")).unwrap();
    let normals = &scene.objects[0].mesh.normals;
    assert_eq!(normals[0].to_array(), [0.0, 0.0, 1.0]);
    assert_eq!(normals[2].to_array(), [0.0, 0.0, -1.0]);
}

#[test]
fn the_fox_stands_posed() {
    let Some(dir) = common::scenes_dir() else {
        eprintln!("PENUMBRA_SCENES is not set: skipping the Fox");
        return;
    };
    // The Fox's rest pose is its bind pose: skinned by its 24 joints (joint world × inverse
    // bind matrix, through a −90° x rotation in the skeleton) it lands on its POSITION
    // accessor's min/max (in centimetres, 155 long).
    let scene = load(&dir.join("Fox/Fox.glb")).unwrap();
    let b = scene.bounds();
    let min = [-12.592718, -0.121745, -88.095];
    let max = [12.592718, 78.907188, 66.624863];
    for c in 0..3 {
        assert!((b.min[c] - min[c]).abs() < 1e-3, "{b:?}");
        assert!((b.max[c] - max[c]).abs() < 1e-3, "{b:?}");
    }
}
