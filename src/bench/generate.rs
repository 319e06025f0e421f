//! `penumbra bench generate --triangles N -o FILE.glb`: a large scene for traversal and render
//! benchmarks: copies of one mesh (a subdivided sphere, or the geometry of `--from FILE`) in a
//! grid on the floor of a closed room lit by an emissive ceiling panel, with a camera inside
//! the room. Copies are glTF nodes sharing one mesh, so the file stays small. With `--skinned`
//! every copy is a skinned mesh that bends at half height in a looping two-second clip
//! ("bend"), for the animation benchmark.

use crate::scene::{Mesh, load};
use anyhow::{Context, Result, bail};
use clap::Args;
use glam::{DMat3, DMat4, DQuat, DVec3, Vec3};
use serde_json::{Value, json};
use std::collections::HashMap;
use std::path::PathBuf;

/// Options of `bench generate`.
#[derive(Args, Debug, Clone)]
pub struct GenerateArgs {
    /// At least this many triangles (whole copies of the mesh, plus the room).
    #[arg(long, default_value_t = 1_000_000)]
    pub triangles: usize,
    /// Copy the visible geometry of this glTF/GLB file (e.g. StanfordBunny/bunny.glb) instead
    /// of a subdivided sphere (20,480 triangles).
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// Give every copy its own glTF mesh (the same triangles written once per copy), so that
    /// no mesh is shared: a scene of unique meshes, for memory and opening time.
    #[arg(long)]
    pub unique: bool,
    /// Skin every copy to two joints (the base and one at half height) and animate the upper
    /// joint in a looping clip: a scene whose every triangle moves each frame.
    #[arg(long, conflicts_with = "unique")]
    pub skinned: bool,
    /// Output .glb file (overwritten).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// One mesh to instance with the transform that places it in its source.
struct Part {
    mesh: std::sync::Arc<Mesh>,
    world_from_object: DMat4,
}

/// A unit icosphere subdivided `level` times (20·4^level triangles), with smooth normals.
fn icosphere(level: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let ab = mid(a, b, &mut positions);
            let bc = mid(b, c, &mut positions);
            let ca = mid(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    Mesh {
        normals: positions.clone(),
        materials: vec![0; faces.len()],
        positions,
        uvs: Vec::new(),
        indices: faces,
        ..Mesh::default()
    }
}

/// A quad as two triangles, wound counter-clockwise seen from the side `normal` points to.
fn quad(corners: [Vec3; 4], normal: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let winding = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    let order = if winding.dot(normal) >= 0.0 {
        [[0, 1, 2], [0, 2, 3]]
    } else {
        [[0, 2, 1], [0, 3, 2]]
    };
    (corners.to_vec(), order.to_vec())
}

/// Quads merged into one flat-shaded mesh.
fn quads(list: &[([Vec3; 4], Vec3)]) -> Mesh {
    let mut mesh = Mesh::default();
    for &(corners, normal) in list {
        let (p, idx) = quad(corners, normal);
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(p);
        mesh.normals.extend([normal; 4]);
        mesh.indices
            .extend(idx.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    }
    mesh.materials = vec![0; mesh.indices.len()];
    mesh
}

/// The room's inward-facing floor, ceiling and walls.
fn room(lo: Vec3, hi: Vec3) -> Mesh {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    quads(&[
        (
            [
                c(lo.x, lo.y, lo.z),
                c(hi.x, lo.y, lo.z),
                c(hi.x, lo.y, hi.z),
                c(lo.x, lo.y, hi.z),
            ],
            Vec3::Y,
        ),
        (
            [
                c(lo.x, hi.y, lo.z),
                c(hi.x, hi.y, lo.z),
                c(hi.x, hi.y, hi.z),
                c(lo.x, hi.y, hi.z),
            ],
            Vec3::NEG_Y,
        ),
        (
            [
                c(lo.x, lo.y, lo.z),
                c(lo.x, hi.y, lo.z),
                c(lo.x, hi.y, hi.z),
                c(lo.x, lo.y, hi.z),
            ],
            Vec3::X,
        ),
        (
            [
                c(hi.x, lo.y, lo.z),
                c(hi.x, hi.y, lo.z),
                c(hi.x, hi.y, hi.z),
                c(hi.x, lo.y, hi.z),
            ],
            Vec3::NEG_X,
        ),
        (
            [
                c(lo.x, lo.y, lo.z),
                c(hi.x, lo.y, lo.z),
                c(hi.x, hi.y, lo.z),
                c(lo.x, hi.y, lo.z),
            ],
            Vec3::Z,
        ),
        (
            [
                c(lo.x, lo.y, hi.z),
                c(hi.x, lo.y, hi.z),
                c(hi.x, hi.y, hi.z),
                c(lo.x, hi.y, hi.z),
            ],
            Vec3::NEG_Z,
        ),
    ])
}

/// Accumulates the binary chunk, buffer views and accessors of a glTF file.
#[derive(Default)]
struct GlbWriter {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl GlbWriter {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view =
            json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if target != 0 {
            view["target"] = json!(target);
        }
        self.views.push(view);
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    fn vec3(&mut self, v: &[Vec3], bounds: bool) -> usize {
        let flat: Vec<[f32; 3]> = v.iter().map(|p| p.to_array()).collect();
        let view = self.view(bytemuck::cast_slice(&flat), 34962);
        let mut a =
            json!({"bufferView": view, "componentType": 5126, "count": v.len(), "type": "VEC3"});
        if bounds {
            let lo = v.iter().fold(Vec3::splat(f32::INFINITY), |a, &p| a.min(p));
            let hi = v
                .iter()
                .fold(Vec3::splat(f32::NEG_INFINITY), |a, &p| a.max(p));
            a["min"] = json!([lo.x, lo.y, lo.z]);
            a["max"] = json!([hi.x, hi.y, hi.z]);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// A float accessor of `count` elements of `kind` (SCALAR, VEC4, MAT4) from `values`.
    fn floats(&mut self, values: &[f32], count: usize, kind: &str) -> usize {
        let view = self.view(bytemuck::cast_slice(values), 0);
        let mut a =
            json!({"bufferView": view, "componentType": 5126, "count": count, "type": kind});
        if kind == "SCALAR" {
            let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            a["min"] = json!([lo]);
            a["max"] = json!([hi]);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let view = self.view(bytemuck::cast_slice(tris), 34963);
        self.accessors.push(json!({
            "bufferView": view, "componentType": 5125, "count": tris.len() * 3, "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    /// A glTF mesh of one primitive with `material`.
    fn mesh(&mut self, name: &str, m: &Mesh, material: usize) -> Value {
        let mut attributes = json!({"POSITION": self.vec3(&m.positions, true)});
        if m.normals.len() == m.positions.len() {
            attributes["NORMAL"] = json!(self.vec3(&m.normals, false));
        }
        let indices = self.indices(&m.indices);
        json!({"name": name, "primitives": [{
            "attributes": attributes, "indices": indices, "material": material, "mode": 4,
        }]})
    }
}

/// A GLB file: the JSON chunk (padded with spaces) and the binary chunk (padded with zeros) of
/// a glTF document whose one buffer is `bin`.
pub fn glb(gltf: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = gltf.to_string().into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// Skin attributes of `mesh` (written as `json`): joint 0 (the base) below a third of the unit
/// height, joint 1 (the upper one) above two thirds, blended smoothly between.
fn add_skin_attributes(w: &mut GlbWriter, json: &mut Value, mesh: &Mesh, unit_from_object: DMat4) {
    let joints: Vec<u8> = (0..mesh.positions.len())
        .flat_map(|_| [0, 1, 0, 0])
        .collect();
    let weights: Vec<f32> = mesh
        .positions
        .iter()
        .flat_map(|p| {
            let h = unit_from_object.transform_point3(p.as_dvec3()).y as f32;
            let x = ((h - 1.0 / 3.0) * 3.0).clamp(0.0, 1.0);
            let upper = x * x * (3.0 - 2.0 * x);
            [1.0 - upper, upper, 0.0, 0.0]
        })
        .collect();
    let view = w.view(&joints, 34962);
    w.accessors.push(json!({"bufferView": view, "componentType": 5121, "count": mesh.positions.len(), "type": "VEC4"}));
    let attributes = &mut json["primitives"][0]["attributes"];
    attributes["JOINTS_0"] = json!(w.accessors.len() - 1);
    attributes["WEIGHTS_0"] = json!(w.floats(&weights, mesh.positions.len(), "VEC4"));
}

fn lambertian(name: &str, gray: f32) -> Value {
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [gray, gray, gray, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0,
        },
        "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}},
    })
}

fn matrix(m: DMat4) -> Value {
    json!(m.to_cols_array().to_vec())
}

/// Runs the generator.
pub fn run(args: &GenerateArgs) -> Result<()> {
    if args.triangles == 0 || args.triangles > 100_000_000 {
        bail!(
            "--triangles {} is out of range (1..=100000000)",
            args.triangles
        );
    }
    let parts = match &args.from {
        None => vec![Part {
            mesh: icosphere(5).into(),
            world_from_object: DMat4::IDENTITY,
        }],
        Some(path) => {
            let scene = load(path)?;
            let parts: Vec<Part> = scene
                .objects
                .into_iter()
                .filter(|o| o.visible && !o.mesh.indices.is_empty())
                .map(|o| Part {
                    mesh: o.mesh,
                    world_from_object: o.world_from_object,
                })
                .collect();
            if parts.is_empty() {
                bail!("{}: the file has no triangles to copy", path.display());
            }
            parts
        }
    };
    let per_copy: usize = parts.iter().map(|p| p.mesh.indices.len()).sum();
    let copies = args.triangles.div_ceil(per_copy).max(1);

    // Scale the source to a unit-sized object standing on y = 0, centred on x = z = 0.
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in &parts {
        for v in &p.mesh.positions {
            let w = p.world_from_object.transform_point3(v.as_dvec3());
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    let size = (hi - lo).max_element().max(1e-9);
    let normalize = DMat4::from_scale(DVec3::splat(1.0 / size))
        * DMat4::from_translation(-DVec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z)));

    // A grid of copies on the floor of a room, with space in front for the camera.
    let cols = (copies as f64).sqrt().ceil() as usize;
    let rows = copies.div_ceil(cols);
    let spacing = 1.3;
    let half_w = 0.5 * cols as f64 * spacing + 0.8;
    let half_d = 0.5 * rows as f64 * spacing + 0.8;
    let height = (0.6 * half_w.max(half_d)).max(2.5);
    let front = half_d + 0.6 * half_w.max(half_d) + 1.0;
    let room_lo = Vec3::new(-half_w as f32, 0.0, -half_d as f32);
    let room_hi = Vec3::new(half_w as f32, height as f32, front as f32);

    let mut w = GlbWriter::default();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for (i, p) in parts.iter().enumerate() {
        meshes.push(w.mesh(&format!("part{i}"), &p.mesh, 0));
        if args.skinned {
            add_skin_attributes(
                &mut w,
                &mut meshes[i],
                &p.mesh,
                normalize * p.world_from_object,
            );
        }
    }
    let mut skins = Vec::new();
    let mut channels = Vec::new();
    for c in 0..copies {
        if args.unique && c > 0 {
            for (i, p) in parts.iter().enumerate() {
                meshes.push(w.mesh(&format!("part{i}.{c}"), &p.mesh, 0));
            }
        }
        let first_mesh = if args.unique { c * parts.len() } else { 0 };
        let (col, row) = ((c % cols) as f64, (c / cols) as f64);
        let at = DVec3::new(
            (col - 0.5 * (cols - 1) as f64) * spacing,
            0.0,
            (row - 0.5 * (rows - 1) as f64) * spacing,
        );
        // Turn each copy a little so the grid is not perfectly regular.
        let turn = DMat4::from_rotation_y(c as f64 * 2.399_963);
        for (i, p) in parts.iter().enumerate() {
            let unit_from_object = normalize * p.world_from_object;
            if !args.skinned {
                let m = DMat4::from_translation(at) * turn * unit_from_object;
                nodes.push(json!({"name": format!("copy{c}.{i}"), "mesh": first_mesh + i, "matrix": matrix(m)}));
                continue;
            }
            // The base joint places the copy; the upper one, half a unit above it, bends.
            let base = nodes.len();
            nodes.push(json!({"name": format!("copy{c}.{i} base"), "matrix": matrix(DMat4::from_translation(at) * turn), "children": [base + 1]}));
            nodes.push(
                json!({"name": format!("copy{c}.{i} upper"), "translation": [0.0, 0.5, 0.0]}),
            );
            let upper_bind = DMat4::from_translation(DVec3::new(0.0, -0.5, 0.0)) * unit_from_object;
            let binds: Vec<f32> = [unit_from_object, upper_bind]
                .iter()
                .flat_map(|m| m.as_mat4().to_cols_array())
                .collect();
            skins.push(json!({"joints": [base, base + 1], "inverseBindMatrices": w.floats(&binds, 2, "MAT4")}));
            nodes.push(json!({"name": format!("copy{c}.{i}"), "mesh": first_mesh + i, "skin": skins.len() - 1}));
            channels.push(json!({"sampler": 0, "target": {"node": base + 1, "path": "rotation"}}));
        }
    }
    meshes.push(w.mesh("room", &room(room_lo, room_hi), 1));
    nodes.push(json!({"name": "room", "mesh": meshes.len() - 1}));
    let (lx, lz, ly) = (
        0.3 * half_w as f32,
        0.3 * half_d as f32,
        height as f32 - 0.01,
    );
    let c = |x: f32, z: f32| Vec3::new(x, ly, z);
    let panel = quads(&[(
        [c(-lx, -lz), c(lx, -lz), c(lx, lz), c(-lx, lz)],
        Vec3::NEG_Y,
    )]);
    meshes.push(w.mesh("ceiling light", &panel, 2));
    nodes.push(json!({"name": "ceiling light", "mesh": meshes.len() - 1}));

    // The camera near the front wall, looking at the middle of the grid.
    let eye = DVec3::new(0.0, 0.55 * height, front - 0.2);
    let target = DVec3::new(0.0, 0.3, 0.0);
    let fwd = (target - eye).normalize();
    let right = fwd.cross(DVec3::Y).normalize();
    let up = right.cross(fwd);
    let q = DQuat::from_mat3(&DMat3::from_cols(right, up, -fwd));
    nodes.push(json!({
        "name": "camera", "camera": 0,
        "translation": [eye.x, eye.y, eye.z], "rotation": [q.x, q.y, q.z, q.w],
    }));

    let animations = if args.skinned {
        // 0 → +25° → −25° → 0 about z over two seconds, one sampler for every copy.
        let keys = [0.0f32, 0.5, 1.5, 2.0];
        let angles = [0.0f32, 25.0, -25.0, 0.0];
        let rotations: Vec<f32> = angles
            .iter()
            .flat_map(|a| glam::Quat::from_rotation_z(a.to_radians()).to_array())
            .collect();
        let input = w.floats(&keys, keys.len(), "SCALAR");
        let output = w.floats(&rotations, keys.len(), "VEC4");
        json!([{"name": "bend", "channels": channels,
                "samplers": [{"input": input, "output": output, "interpolation": "LINEAR"}]}])
    } else {
        json!([])
    };
    let triangles = copies * per_copy + 14;
    // Every node but the skins' upper joints (their base's children) is a root.
    let children: std::collections::HashSet<u64> = nodes
        .iter()
        .filter_map(|n| n["children"].as_array())
        .flatten()
        .filter_map(Value::as_u64)
        .collect();
    let roots: Vec<usize> = (0..nodes.len())
        .filter(|&i| !children.contains(&(i as u64)))
        .collect();
    while !w.bin.len().is_multiple_of(4) {
        w.bin.push(0);
    }
    let gltf = json!({
        "asset": {"version": "2.0", "generator": "penumbra bench generate"},
        "extensionsUsed": ["KHR_materials_specular", "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "generated", "nodes": roots}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            lambertian("objects", 0.75),
            lambertian("room", 0.6),
            {
                "name": "light",
                "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0},
                "emissiveFactor": [1.0, 0.95, 0.85],
                "extensions": {
                    "KHR_materials_emissive_strength": {"emissiveStrength": 8.0},
                    "KHR_materials_specular": {"specularFactor": 0.0},
                },
            },
        ],
        "cameras": [{"name": "camera", "type": "perspective", "perspective": {
            "yfov": 55f64.to_radians(), "aspectRatio": 16.0 / 9.0, "znear": 0.01,
        }}],
        "skins": skins,
        "animations": animations,
        "accessors": w.accessors,
        "bufferViews": w.views,
        "buffers": [{"byteLength": w.bin.len()}],
    });
    let out = glb(&gltf, &w.bin);
    std::fs::write(&args.output, &out)
        .with_context(|| format!("{}: cannot write the scene", args.output.display()))?;
    println!(
        "{}",
        json!({
            "output": args.output.display().to_string(),
            "triangles": triangles,
            "copies": copies,
            "triangles_per_copy": per_copy,
            "bytes": out.len(),
        })
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_has_the_expected_triangles_and_unit_radius() {
        let m = icosphere(2);
        assert_eq!(m.indices.len(), 320);
        assert!(m.positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-5));
        // Outward winding: every face normal points away from the centre.
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0);
        }
    }

    #[test]
    fn quads_face_their_normal() {
        let m = room(Vec3::ZERO, Vec3::ONE);
        assert_eq!(m.indices.len(), 12);
        for (i, t) in m.indices.iter().enumerate() {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!(
                (b - a).cross(c - a).dot(m.normals[t[0] as usize]) > 0.0,
                "triangle {i}"
            );
        }
    }
}
