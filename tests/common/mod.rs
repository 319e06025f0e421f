//! Helpers shared by the integration tests: a tiny glTF writer for fixtures, and running the
//! binary.
#![allow(dead_code)]

pub mod stats;

use serde_json::{Value, json};
use std::f32::consts::FRAC_1_SQRT_2;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A node rotation of −90° about x: the node's −Z (where cameras and lights point) faces −Y.
pub const LOOK_DOWN: [f32; 4] = [-FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2];

/// One mesh primitive of a fixture.
pub struct Prim {
    /// Positions.
    pub positions: Vec<[f32; 3]>,
    /// Normals (empty for none).
    pub normals: Vec<[f32; 3]>,
    /// Triangle indices (empty: non-indexed).
    pub indices: Vec<u32>,
    /// Material index.
    pub material: Option<usize>,
    /// glTF mode (4 = triangles).
    pub mode: u32,
}

impl Prim {
    /// An indexed triangle list.
    pub fn triangles(positions: Vec<[f32; 3]>, indices: Vec<u32>, material: usize) -> Self {
        Self {
            positions,
            normals: vec![],
            indices,
            material: Some(material),
            mode: 4,
        }
    }
}

/// A glTF document under construction; `nodes`, `materials` etc. are raw JSON values.
#[derive(Default)]
pub struct Gltf {
    /// Binary buffer contents.
    pub bin: Vec<u8>,
    /// Accessors.
    pub accessors: Vec<Value>,
    /// Buffer views.
    pub views: Vec<Value>,
    /// Meshes.
    pub meshes: Vec<Value>,
    /// Nodes.
    pub nodes: Vec<Value>,
    /// Materials.
    pub materials: Vec<Value>,
    /// KHR_lights_punctual lights.
    pub lights: Vec<Value>,
    /// Cameras.
    pub cameras: Vec<Value>,
    /// extensionsUsed.
    pub used: Vec<String>,
    /// extensionsRequired.
    pub required: Vec<String>,
    /// More top-level entries (images, textures, samplers).
    pub extra: serde_json::Map<String, Value>,
}

impl Gltf {
    fn push_data(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let mut view = json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()});
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.views.push(view);
        self.views.len() - 1
    }

    /// Adds raw bytes (an encoded image) as a buffer view; returns its index.
    pub fn bytes_view(&mut self, bytes: &[u8]) -> usize {
        self.push_data(bytes, None)
    }

    /// Adds a float accessor of `N` components (VEC2 or VEC4); returns its index.
    pub fn float_accessor<const N: usize>(&mut self, data: &[[f32; N]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let view = self.push_data(&bytes, Some(34962));
        let kind = format!("VEC{N}");
        self.accessors.push(
            json!({"bufferView": view, "componentType": 5126, "count": data.len(), "type": kind}),
        );
        self.accessors.len() - 1
    }

    fn vec3_accessor(&mut self, data: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        let view = self.push_data(&bytes, Some(34962));
        let mut min = [f32::INFINITY; 3];
        let mut max = [f32::NEG_INFINITY; 3];
        for p in data {
            for i in 0..3 {
                min[i] = min[i].min(p[i]);
                max[i] = max[i].max(p[i]);
            }
        }
        let finite = min.iter().chain(&max).all(|v| v.is_finite());
        let mut acc =
            json!({"bufferView": view, "componentType": 5126, "count": data.len(), "type": "VEC3"});
        if finite {
            acc["min"] = json!(min);
            acc["max"] = json!(max);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Adds a mesh of primitives; returns its index.
    pub fn mesh(&mut self, prims: Vec<Prim>) -> usize {
        let mut out = vec![];
        for p in prims {
            let pos = self.vec3_accessor(&p.positions);
            let mut attributes = json!({"POSITION": pos});
            if !p.normals.is_empty() {
                attributes["NORMAL"] = json!(self.vec3_accessor(&p.normals));
            }
            let mut prim = json!({"attributes": attributes, "mode": p.mode});
            if !p.indices.is_empty() {
                let bytes: Vec<u8> = p.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
                let view = self.push_data(&bytes, Some(34963));
                self.accessors.push(json!({"bufferView": view, "componentType": 5125, "count": p.indices.len(), "type": "SCALAR"}));
                prim["indices"] = json!(self.accessors.len() - 1);
            }
            if let Some(m) = p.material {
                prim["material"] = json!(m);
            }
            out.push(prim);
        }
        self.meshes.push(json!({"primitives": out}));
        self.meshes.len() - 1
    }

    /// Adds a node; returns its index.
    pub fn node(&mut self, node: Value) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    /// Adds a Lambertian material (specularFactor 0) with an optional emission.
    pub fn lambert(
        &mut self,
        color: [f32; 3],
        emission: [f32; 3],
        strength: f32,
        double_sided: bool,
    ) -> usize {
        self.use_ext("KHR_materials_specular");
        self.use_ext("KHR_materials_emissive_strength");
        self.materials.push(json!({
            "pbrMetallicRoughness": {"baseColorFactor": [color[0], color[1], color[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
            "emissiveFactor": emission,
            "doubleSided": double_sided,
            "extensions": {
                "KHR_materials_specular": {"specularFactor": 0.0},
                "KHR_materials_emissive_strength": {"emissiveStrength": strength}
            }
        }));
        self.materials.len() - 1
    }

    /// Declares an extension as used.
    pub fn use_ext(&mut self, name: &str) {
        if !self.used.iter().any(|u| u == name) {
            self.used.push(name.to_string());
        }
    }

    /// The JSON document; `uri` is the buffer's URI (None for GLB).
    pub fn json(&self, uri: Option<String>) -> Value {
        let roots: Vec<usize> = (0..self.nodes.len())
            .filter(|i| {
                !self.nodes.iter().any(|n| {
                    n["children"]
                        .as_array()
                        .is_some_and(|c| c.iter().any(|c| c.as_u64() == Some(*i as u64)))
                })
            })
            .collect();
        let mut buffer = json!({"byteLength": self.bin.len()});
        if let Some(u) = uri {
            buffer["uri"] = json!(u);
        }
        let mut doc = json!({
            "asset": {"version": "2.0", "generator": "penumbra tests"},
            "scene": 0,
            "scenes": [{"nodes": roots}],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "accessors": self.accessors,
            "bufferViews": self.views,
            "buffers": [buffer],
        });
        if !self.cameras.is_empty() {
            doc["cameras"] = json!(self.cameras);
        }
        for (k, v) in &self.extra {
            doc[k] = v.clone();
        }
        let mut used = self.used.clone();
        if !self.lights.is_empty() {
            if !used.iter().any(|u| u == "KHR_lights_punctual") {
                used.push("KHR_lights_punctual".into());
            }
            doc["extensions"] = json!({"KHR_lights_punctual": {"lights": self.lights}});
        }
        if !used.is_empty() {
            doc["extensionsUsed"] = json!(used);
        }
        if !self.required.is_empty() {
            doc["extensionsRequired"] = json!(self.required);
        }
        doc
    }

    /// GLB bytes, written by the library's GLB writer (the one `bench generate` uses).
    pub fn glb(&self) -> Vec<u8> {
        penumbra::bench::generate::glb(&self.json(None), &self.bin)
    }

    /// Writes `name.glb` into `dir`.
    pub fn write_glb(&self, dir: &Path, name: &str) -> PathBuf {
        let p = dir.join(format!("{name}.glb"));
        std::fs::write(&p, self.glb()).unwrap();
        p
    }

    /// Writes `name.gltf` with an external `name.bin` into `dir`.
    pub fn write_gltf(&self, dir: &Path, name: &str) -> PathBuf {
        let bin = format!("{name}.bin");
        std::fs::write(dir.join(&bin), &self.bin).unwrap();
        let p = dir.join(format!("{name}.gltf"));
        std::fs::write(
            &p,
            serde_json::to_vec_pretty(&self.json(Some(bin))).unwrap(),
        )
        .unwrap();
        p
    }

    /// Writes `name.gltf` with the buffer embedded as a base64 data URI.
    pub fn write_gltf_embedded(&self, dir: &Path, name: &str) -> PathBuf {
        let uri = format!("data:application/octet-stream;base64,{}", base64(&self.bin));
        let p = dir.join(format!("{name}.gltf"));
        std::fs::write(&p, serde_json::to_vec(&self.json(Some(uri))).unwrap()).unwrap();
        p
    }
}

fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= c.len() {
                s.push(T[(n >> (18 - 6 * i)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A UV sphere of `radius` at the origin; `inward` flips the winding and normals.
pub fn sphere(
    radius: f32,
    rings: u32,
    segments: u32,
    inward: bool,
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let mut pos = vec![];
    let mut nrm = vec![];
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            let n = [
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ];
            pos.push(n.map(|v| v * radius));
            nrm.push(if inward { n.map(|v| -v) } else { n });
        }
    }
    let mut idx = vec![];
    let w = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let a = r * w + s;
            let b = a + w;
            // Outward-facing (counter-clockwise seen from outside).
            let tris = [[a, a + 1, b], [a + 1, b + 1, b]];
            for t in tris {
                if inward {
                    idx.extend([t[0], t[2], t[1]]);
                } else {
                    idx.extend(t);
                }
            }
        }
    }
    (pos, nrm, idx)
}

/// A unit quad in the z = 0 plane as two triangles with material 0.
pub fn quad() -> Prim {
    Prim::triangles(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        vec![0, 1, 2, 0, 2, 3],
        0,
    )
}

/// A horizontal square at height `y` of half-size `h`, facing up or down: its corners and two
/// triangles.
pub fn horizontal_square(y: f32, h: f32, up: bool) -> (Vec<[f32; 3]>, Vec<u32>) {
    let p = vec![[-h, y, -h], [h, y, -h], [h, y, h], [-h, y, h]];
    let i = if up {
        vec![0, 2, 1, 0, 3, 2]
    } else {
        vec![0, 1, 2, 0, 2, 3]
    };
    (p, i)
}

/// The device the tests use: `PENUMBRA_TEST_DEVICE` (e.g. `gpu` on the H100 machine), else
/// the CPU device (PoCL in CI).
pub fn test_device() -> String {
    std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "cpu".into())
}

/// Runs the penumbra binary with `args` on the test device.
pub fn penumbra(args: &[&str]) -> Output {
    penumbra_env(args, &[])
}

/// [`penumbra`] with environment variables set for the child.
pub fn penumbra_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    let exe = std::env::var("PENUMBRA_TEST_BINARY")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_penumbra").to_string());
    Command::new(exe)
        .args(args)
        .env("PENUMBRA_DEVICE", test_device())
        .envs(env.iter().copied())
        .output()
        .expect("the penumbra binary runs")
}

/// The bits of every channel of an EXR's first layer, by channel name.
pub fn channel_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    use exr::prelude::*;
    penumbra::image_io::read_exr_layer(path)
        .unwrap()
        .channel_data
        .list
        .iter()
        .map(|c| {
            let bits = match &c.sample_data {
                FlatSamples::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
                FlatSamples::U32(v) => v.clone(),
                FlatSamples::F16(v) => v.iter().map(|x| u32::from(x.to_bits())).collect(),
            };
            (c.name.to_string(), bits)
        })
        .collect()
}

/// Runs a render and returns (the JSON summary, the linear image).
pub fn render_exr(scene: &Path, out: &Path, extra: &[&str]) -> (Value, Vec<[f32; 3]>) {
    render_exr_env(scene, out, extra, &[])
}

/// [`render_exr`] with environment variables set for the child.
pub fn render_exr_env(
    scene: &Path,
    out: &Path,
    extra: &[&str],
    env: &[(&str, &str)],
) -> (Value, Vec<[f32; 3]>) {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = penumbra_env(&args, env);
    assert!(
        o.status.success(),
        "render failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: Value = serde_json::from_slice(&o.stdout).expect("one JSON line on stdout");
    let (_, _, px) = penumbra::image_io::read_exr(out).unwrap();
    (summary, px)
}

/// A quad (with texture coordinates) whose material shows `image` (encoded bytes of type
/// `mime`) as its base color texture; the texture names the image through `extension`
/// (`KHR_texture_basisu`, `EXT_texture_webp`) when given, else through its `source`.
pub fn textured_quad(image: &[u8], mime: &str, extension: Option<&str>) -> Gltf {
    let mut g = Gltf::default();
    g.lambert([1.0; 3], [0.0; 3], 1.0, false);
    let view = g.bytes_view(image);
    g.extra.insert(
        "images".into(),
        json!([{"bufferView": view, "mimeType": mime}]),
    );
    let texture = match extension {
        Some(ext) => {
            g.use_ext(ext);
            g.required.push(ext.to_string());
            json!({"extensions": {ext: {"source": 0}}})
        }
        None => json!({"source": 0}),
    };
    g.extra.insert("textures".into(), json!([texture]));
    g.materials[0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let uv = g.float_accessor(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    let m = g.mesh(vec![quad()]);
    g.meshes[m]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(uv);
    g.node(json!({"mesh": m}));
    g
}

/// A file of the KTX2 fixtures (tests/ktx2, made by scripts/ktx2_fixtures.sh).
pub fn ktx2_fixture(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/ktx2")
            .join(name),
    )
    .unwrap()
}

/// The scenes folder, if set.
pub fn scenes_dir() -> Option<PathBuf> {
    std::env::var_os("PENUMBRA_SCENES")
        .map(PathBuf::from)
        .filter(|p| p.is_dir())
}

/// A folder for test outputs kept after the run (actual and difference images).
pub fn output_dir(test: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(test);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The mean over pixels of the channels' mean.
pub fn mean_gray(px: &[[f32; 3]]) -> f64 {
    px.iter()
        .map(|p| (p[0] + p[1] + p[2]) as f64 / 3.0)
        .sum::<f64>()
        / px.len() as f64
}

/// An axis-aligned box from `lo` to `hi` (outward winding, no normals).
pub fn cuboid(lo: [f32; 3], hi: [f32; 3]) -> (Vec<[f32; 3]>, Vec<u32>) {
    let mut p = vec![];
    for i in 0..8 {
        p.push([
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]);
    }
    let quads = [
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    let idx = quads
        .iter()
        .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
        .collect();
    (p, idx)
}

/// A white (albedo 1) Lambertian sphere of radius 1 at the origin seen from z = 4; a floor
/// below it when `floor`.
pub fn white_sphere(dir: &Path, floor: bool) -> PathBuf {
    white_sphere_of(dir, floor, 32, 64)
}

/// [`white_sphere`] with `rings` × `segments` quads (2 × rings × segments triangles).
pub fn white_sphere_of(dir: &Path, floor: bool, rings: u32, segments: u32) -> PathBuf {
    let g = white_sphere_gltf(floor, rings, segments);
    g.write_glb(dir, if floor { "sphere-floor" } else { "sphere" })
}

/// The white sphere on its floor lit only by an emissive panel above it, facing down (light
/// samples that end on a triangle, extension rays that find an emitter).
pub fn white_sphere_under_panel(dir: &Path, rings: u32, segments: u32) -> PathBuf {
    let mut g = white_sphere_gltf(true, rings, segments);
    let light = g.lambert([0.8; 3], [1.0; 3], 6.0, false);
    let (positions, indices) = horizontal_square(3.0, 1.5, false);
    let panel = g.mesh(vec![Prim::triangles(positions, indices, light)]);
    g.node(json!({"mesh": panel}));
    g.write_glb(dir, "sphere-panel")
}

/// The white sphere's document (on its floor or not, a camera, no light), to add to.
pub fn white_sphere_gltf(floor: bool, rings: u32, segments: u32) -> Gltf {
    let mut g = Gltf::default();
    let m = g.lambert([1.0; 3], [0.0; 3], 1.0, false);
    let (positions, normals, indices) = sphere(1.0, rings, segments, false);
    let mut prims = vec![Prim {
        positions,
        normals,
        indices,
        material: Some(m),
        mode: 4,
    }];
    if floor {
        let gray = g.lambert([0.5; 3], [0.0; 3], 1.0, false);
        let (positions, indices) = horizontal_square(-1.0, 5.0, true);
        prims.push(Prim::triangles(positions, indices, gray));
    }
    let mesh = g.mesh(prims);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.0, 4.0]}));
    g
}
