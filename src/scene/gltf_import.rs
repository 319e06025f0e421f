//! glTF 2.0 import (`.gltf` with external or embedded buffers, and `.glb`).

use super::{
    AlphaMode, Camera, Light, LightKind, Material, Mesh, Object, Scene, SceneError,
    default_light_rig,
};
use glam::{DMat4, DQuat, DVec3, Vec2, Vec3};
use gltf::mesh::Mode;
use std::path::Path;

/// Extensions penumbra understands (or can safely ignore when rendering).
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
];

/// Vertical field of view of the automatic camera.
pub const AUTO_YFOV: f64 = 0.8;

/// Loads a glTF or GLB file. Every problem with the file is a one-line [`SceneError`].
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let fail = |message: String| SceneError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read file: {e}")))?;
    load_from_bytes(&bytes, path.parent(), &path.display().to_string()).map_err(fail)
}

/// Loads glTF or GLB bytes; external files are resolved against `base`.
pub fn load_from_bytes(bytes: &[u8], base: Option<&Path>, source: &str) -> Result<Scene, String> {
    let mut warnings = Vec::new();
    check_extensions(bytes, &mut warnings)?;
    let gltf = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| format!("not a valid glTF file: {e}"))?;
    let document = gltf.document;
    let buffers = gltf::import_buffers(&document, base, gltf.blob)
        .map_err(|e| format!("cannot load buffers: {e}"))?;
    let buffer_data: Vec<&[u8]> = buffers.iter().map(|b| b.0.as_slice()).collect();

    let materials = document
        .materials()
        .map(import_material)
        .collect::<Vec<_>>();
    let default_material = materials.len() as u32;

    let mut scene = Scene {
        source: source.to_string(),
        materials,
        ..Scene::default()
    };
    scene.materials.push(Material::default());

    let roots: Vec<gltf::Node> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(s) => s.nodes().collect(),
        None => document.nodes().collect(),
    };
    // Depth first in document order: the stack pops the last entry, so push in reverse.
    let mut stack: Vec<(gltf::Node, DMat4, usize)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY, 0))
        .collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 256 {
            return Err(format!(
                "node {} is nested too deeply (a cycle?)",
                node.index()
            ));
        }
        let world = parent * node_matrix(&node);
        if let Some(mesh) = node.mesh() {
            let name = node
                .name()
                .or(mesh.name())
                .map(str::to_string)
                .unwrap_or_else(|| format!("mesh {}", mesh.index()));
            let m = import_mesh(&mesh, &buffer_data, default_material, &mut warnings)?;
            if !m.indices.is_empty() {
                scene.objects.push(Object {
                    name,
                    world_from_object: world,
                    visible: true,
                    mesh: m,
                });
            }
        }
        if let Some(camera) = node.camera() {
            if let gltf::camera::Projection::Perspective(p) = camera.projection() {
                let forward = -world.transform_vector3(DVec3::Z).normalize();
                let up = world.transform_vector3(DVec3::Y).normalize();
                scene.cameras.push(Camera {
                    name: camera
                        .name()
                        .map(str::to_string)
                        .unwrap_or_else(|| format!("camera {}", camera.index())),
                    eye: world.transform_point3(DVec3::ZERO),
                    forward,
                    up,
                    yfov: p.yfov() as f64,
                });
            } else {
                warnings.push(format!(
                    "camera {}: orthographic cameras are not supported, skipped",
                    camera.index()
                ));
            }
        }
        if let Some(light) = node.light() {
            scene.lights.push(import_light(&light, &world));
        }
        let children: Vec<gltf::Node> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }

    let bounds = scene.bounds();
    if scene.cameras.is_empty() {
        scene.cameras.push(Camera::framing(&bounds, AUTO_YFOV));
    }
    let has_emission = scene.objects.iter().any(|o| {
        o.mesh
            .materials
            .iter()
            .any(|&m| scene.materials[m as usize].is_emissive())
    });
    if scene.lights.is_empty() && !has_emission {
        scene.lights = default_light_rig(&bounds);
        scene.default_rig = true;
    }
    scene.warnings = warnings;
    Ok(scene)
}

/// Rejects unsupported required extensions and warns about unsupported optional ones.
fn check_extensions(bytes: &[u8], warnings: &mut Vec<String>) -> Result<(), String> {
    let json: &[u8] = if bytes.starts_with(b"glTF") {
        let glb = gltf::Glb::from_slice(bytes).map_err(|e| format!("not a valid GLB file: {e}"))?;
        return check_extensions_json(&glb.json, warnings);
    } else {
        bytes
    };
    check_extensions_json(json, warnings)
}

fn check_extensions_json(json: &[u8], warnings: &mut Vec<String>) -> Result<(), String> {
    let value: serde_json::Value =
        serde_json::from_slice(json).map_err(|e| format!("not a valid glTF file: {e}"))?;
    let list = |key: &str| -> Vec<String> {
        value
            .get(key)
            .and_then(|v| v.as_array())
            .map(|a| {
                a.iter()
                    .filter_map(|s| s.as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default()
    };
    for ext in list("extensionsRequired") {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(format!("requires the unsupported extension {ext}"));
        }
    }
    for ext in list("extensionsUsed") {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            warnings.push(format!(
                "optional extension {ext} is not supported and is ignored"
            ));
        }
    }
    Ok(())
}

fn node_matrix(node: &gltf::Node) -> DMat4 {
    let (t, r, s) = node.transform().decomposed();
    let t = DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64);
    let r = DQuat::from_xyzw(r[0] as f64, r[1] as f64, r[2] as f64, r[3] as f64).normalize();
    let s = DVec3::new(s[0] as f64, s[1] as f64, s[2] as f64);
    DMat4::from_scale_rotation_translation(s, r, t)
}

fn import_material(m: gltf::Material) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emissive = m.emissive_factor().map(|e| e * strength);
    let (specular_factor, specular_color) = match m.specular() {
        Some(s) => (s.specular_factor(), s.specular_color_factor()),
        None => (1.0, [1.0; 3]),
    };
    Material {
        name: m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material {}", m.index().unwrap_or(0))),
        base_color: pbr.base_color_factor(),
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        emission: emissive.map(|e| if e.is_finite() { e.max(0.0) } else { 0.0 }),
        double_sided: m.double_sided(),
        ior: m.ior().unwrap_or(1.5),
        specular_factor,
        specular_color,
        transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
        thickness: m.volume().map_or(0.0, |v| v.thickness_factor()),
        attenuation_color: m.volume().map_or([1.0; 3], |v| v.attenuation_color()),
        attenuation_distance: m
            .volume()
            .map_or(f32::INFINITY, |v| v.attenuation_distance()),
        alpha: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
    }
}

fn import_light(light: &gltf::khr_lights_punctual::Light, world: &DMat4) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            inner: inner_cone_angle,
            outer: outer_cone_angle,
        },
    };
    Light {
        name: light
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("light {}", light.index())),
        kind,
        position: world.transform_point3(DVec3::ZERO),
        direction: (-world.transform_vector3(DVec3::Z)).normalize_or(DVec3::NEG_Y),
        color: light.color(),
        intensity: light.intensity().max(0.0),
        radius: 0.0,
    }
}

fn import_mesh(
    mesh: &gltf::Mesh,
    buffers: &[&[u8]],
    default_material: u32,
    warnings: &mut Vec<String>,
) -> Result<Mesh, String> {
    let mut out = Mesh::default();
    for prim in mesh.primitives() {
        let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            warnings.push(format!("{what}: mode {mode:?} is not triangles, skipped"));
            continue;
        }
        let reader = prim.reader(|b| buffers.get(b.index()).copied());
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| format!("{what}: POSITION is missing or unreadable"))?
            .map(Vec3::from)
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("{what}: POSITION {i} is not finite"));
        }
        let normals: Vec<Vec3> = reader
            .read_normals()
            .map(|n| {
                n.map(|n| {
                    let n = Vec3::from(n);
                    if n.is_finite() { n } else { Vec3::ZERO }
                })
                .collect()
            })
            .unwrap_or_default();
        if !normals.is_empty() && normals.len() != positions.len() {
            return Err(format!("{what}: NORMAL count differs from POSITION count"));
        }
        let uvs: Vec<Vec2> = reader
            .read_tex_coords(0)
            .map(|t| t.into_f32().map(Vec2::from).collect())
            .unwrap_or_default();
        let flat: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(&bad) = flat.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!(
                "{what}: index {bad} is out of range ({} vertices)",
                positions.len()
            ));
        }
        let triangles: Vec<[u32; 3]> = match mode {
            Mode::Triangles => flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            Mode::TriangleStrip => (2..flat.len())
                .map(|i| {
                    if i % 2 == 0 {
                        [flat[i - 2], flat[i - 1], flat[i]]
                    } else {
                        [flat[i - 1], flat[i - 2], flat[i]]
                    }
                })
                .collect(),
            _ => (2..flat.len())
                .map(|i| [flat[0], flat[i - 1], flat[i]])
                .collect(),
        };
        let base = out.positions.len() as u32;
        let material = prim
            .material()
            .index()
            .map_or(default_material, |i| i as u32);
        // Keep the per-vertex arrays aligned when only some primitives have normals or UVs.
        pad_attribute(
            &mut out.normals,
            out.positions.len(),
            &normals,
            positions.len(),
        );
        pad_attribute(&mut out.uvs, out.positions.len(), &uvs, positions.len());
        out.positions.extend_from_slice(&positions);
        out.indices
            .extend(triangles.iter().map(|t| t.map(|i| i + base)));
        out.materials
            .extend(std::iter::repeat_n(material, triangles.len()));
    }
    Ok(out)
}

/// Appends `new` to `dst`, zero-filling where either side lacks the attribute, so that `dst`
/// stays empty only while no primitive has it.
fn pad_attribute<T: Copy + Default>(dst: &mut Vec<T>, old_len: usize, new: &[T], new_len: usize) {
    if dst.is_empty() && new.is_empty() {
        return;
    }
    dst.resize(old_len, T::default());
    if new.is_empty() {
        dst.extend(std::iter::repeat_n(T::default(), new_len));
    } else {
        dst.extend_from_slice(new);
    }
}
