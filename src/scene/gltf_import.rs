//! glTF 2.0 import (`.gltf` with external or embedded buffers, and `.glb`): the file's buffers,
//! the walk of the node graph placing meshes, cameras and lights, and the scene's bounds.
//! Materials, meshes and the texture table are read in the submodules of those names.

use super::accessor::BufferData;
use super::animation::{self, Animation, Driven, Rig, RigData};
use super::compression;
use super::pose::{check_nesting, node_matrix};
use super::repeats::{self, Layering};
use super::variants;
use super::{
    Camera, Light, LightKind, Material, Mesh, Object, Scene, SceneError, default_light_rig, limits,
    sources, validate,
};
use glam::{DMat4, DVec3};
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

mod colors;
mod materials;
mod meshes;
mod texture_table;

use materials::import_material;
use meshes::{deforms, import_mesh, read_meshes_ahead};
use texture_table::{TextureTable, decode_images, texture_sources};

/// Vertical field of view of the automatic camera.
pub const AUTO_YFOV: f64 = 0.8;

/// Loads a glTF or GLB file. Every problem with the file is a one-line [`SceneError`].
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, None)
}

/// [`load`] reading the files its URIs name from inside the file's folder or, when given,
/// inside `asset_root` (`--asset-root`).
pub fn load_with(path: &Path, asset_root: Option<&Path>) -> Result<Scene, SceneError> {
    let fail = |message: String| SceneError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let meta = std::fs::metadata(path).map_err(|e| fail(format!("cannot read file: {e}")))?;
    if !meta.is_file() {
        return Err(fail("cannot read file: not a regular file".into()));
    }
    let bytes =
        sources::Bytes::of_file(path).map_err(|e| fail(format!("cannot read file: {e}")))?;
    let folders =
        sources::Folders::new(path.parent().unwrap_or(Path::new("")), asset_root).map_err(&fail)?;
    load_owned(bytes, Some(&folders), &path.display().to_string()).map_err(fail)
}

/// Loads glTF or GLB bytes; external files are resolved against `base` and read only from
/// inside it.
pub fn load_from_bytes(bytes: &[u8], base: Option<&Path>, source: &str) -> Result<Scene, String> {
    let folders = base.map(|b| sources::Folders::new(b, None)).transpose()?;
    load_owned(
        sources::Bytes::Owned(bytes.to_vec()),
        folders.as_ref(),
        source,
    )
}

/// [`load_owned`] of bytes with no external files (for tests of [`sources::Bytes`]).
#[cfg(test)]
fn load_bytes(bytes: sources::Bytes) -> Result<Scene, String> {
    load_owned(bytes, None, "test")
}

/// [`load_from_bytes`] taking the bytes (a large file mapped, `Bytes::of_file`): a GLB file's
/// binary chunk is read in place and every buffer is freed before the scene's bounds are
/// computed, so that the file and the imported meshes are held together only while the
/// meshes are read.
fn load_owned(
    bytes: sources::Bytes,
    base: Option<&sources::Folders>,
    source: &str,
) -> Result<Scene, String> {
    let _memory = crate::cl::kernels::OpeningMemory::begin();
    let mut warnings = Vec::new();
    let parsed = validate::parse(bytes, &mut warnings)?;
    let document = parsed.document;
    let buffers = sources::load_buffers(&document, base, parsed.blob)?;
    let root = document.as_json();
    let mut buffer_data = BufferData {
        buffers: buffers.iter().map(|b| &b[..]).collect(),
        decoded_views: HashMap::new(),
    };
    buffer_data.decoded_views = compression::decode_meshopt_views(root, &buffer_data.buffers)?;
    check_nesting(&document)?;
    let clips = animation::read_clips(root, &buffer_data, &mut warnings);
    let mut animation = Animation::new(&document, &parsed.precise_nodes, clips);
    let rest = animation.evaluate(None, 0.0);

    let mut table = TextureTable {
        sources: texture_sources(root),
        ..TextureTable::default()
    };
    let mut materials = document
        .materials()
        .map(|m| import_material(m, &document, &mut table, &mut warnings))
        .collect::<Vec<_>>();
    let images = decode_images(&document, base, &buffers, &mut table, &mut warnings);
    for m in &mut materials {
        table.drop_missing(&mut m.textures);
    }
    let default_material = materials.len() as u32;
    // The texture coordinate set tangents are made for: the material's normal map's, else (an
    // anisotropic material's frame) its anisotropy texture's or set 0; `true` for a normal map.
    let normal_sets: Vec<Option<(u32, bool)>> = materials
        .iter()
        .map(|m| {
            let set = |r: u32| table.refs[r as usize].tex_coord;
            match (m.textures.normal).or(m.textures.clearcoat_normal) {
                Some(r) => Some((set(r), true)),
                None if m.anisotropy > 0.0 => Some((m.textures.anisotropy.map_or(0, set), false)),
                None => None,
            }
        })
        .collect();

    let mut scene = Scene {
        source: source.to_string(),
        materials,
        images,
        texture_refs: table.refs,
        ..Scene::default()
    };
    scene.materials.push(Material::default());
    scene.variants = variants::names(document.extension_value("KHR_materials_variants"));
    let variant_count = scene.variants.len();
    let layering: Vec<Layering> = scene.materials.iter().map(Layering::of).collect();

    let roots: Vec<gltf::Node> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(s) => s.nodes().collect(),
        None => document.nodes().collect(),
    };
    let mut read_ahead = read_meshes_ahead(
        &roots,
        root,
        &buffer_data,
        default_material,
        &normal_sets,
        variant_count,
        &layering,
    );
    // The nodes an animation moves; what they or their children place is never a repeat.
    let mut animated = vec![false; root.nodes.len()];
    for channel in animation.clips.iter().flat_map(|c| &c.channels) {
        animated[channel.node] = true;
    }
    // Depth first in document order: the stack pops the last entry, so push in reverse.
    // Each entry: the node, its parent's world transform, its depth, whether an animation
    // moves it.
    let mut stack: Vec<(gltf::Node, DMat4, usize, bool)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY, 0, false))
        .collect();
    let mut meshes: HashMap<usize, Arc<Mesh>> = HashMap::new();
    let mut placements = repeats::Placements::default();
    let mut placed = 0usize;
    let mut triangles = 0usize;
    while let Some((node, parent, depth, moved)) = stack.pop() {
        let moved = moved || animated[node.index()];
        let at = format!("nodes[{}]", node.index());
        placed += 1;
        if placed > limits::MAX_NODE_INSTANCES {
            return Err(format!(
                "{at}: the node graph places more than {} nodes (a child listed more than once?)",
                limits::MAX_NODE_INSTANCES
            ));
        }
        if depth > limits::MAX_NODE_DEPTH {
            return Err(format!(
                "{at}: nested more than {} deep (a cycle?)",
                limits::MAX_NODE_DEPTH
            ));
        }
        // A node whose transform is not usable is left out with everything below it.
        let world = match node_matrix(&node, parsed.precise_nodes.get(node.index())) {
            Ok(local) => parent * local,
            Err(why) => {
                warn_once(
                    &mut warnings,
                    format!("{at}: {why}; the node and its children are skipped"),
                );
                continue;
            }
        };
        // The GPU gets f32: the transform and its inverse must stay finite there too.
        if !world.as_mat4().is_finite() || !world.inverse().as_mat4().is_finite() {
            warn_once(
                &mut warnings,
                format!(
                    "{at}: its world transform is singular or not finite; the node and its children are skipped"
                ),
            );
            continue;
        }
        if let Some(mesh) = node.mesh() {
            let name = node
                .name()
                .or(mesh.name())
                .map(str::to_string)
                .unwrap_or_else(|| format!("mesh {}", mesh.index()));
            // Each mesh is read once, however many nodes place it, unless the node poses it
            // (a skin or morph targets): then it is read unposed and posed by its rig.
            let posed = deforms(&node, &mesh);
            let ahead = (!posed).then(|| read_ahead.remove(&mesh.index())).flatten();
            let mut rig = None;
            let m = match meshes.get(&mesh.index()).filter(|_| !posed) {
                Some(m) => Arc::clone(m),
                None if ahead.is_some() => {
                    // Read ahead: its warnings join the list where it would have been read.
                    let (m, mesh_warnings) = ahead.expect("read ahead")?;
                    warnings.extend(mesh_warnings);
                    let m = Arc::new(m);
                    meshes.insert(mesh.index(), Arc::clone(&m));
                    m
                }
                None => {
                    let mut data = RigData::default();
                    let mut m = import_mesh(
                        &mesh,
                        root,
                        &buffer_data,
                        posed.then_some(&mut data),
                        default_material,
                        &normal_sets,
                        &mut warnings,
                    )?;
                    let what = format!("meshes[{}]", mesh.index());
                    m.keep_variants(variant_count, &what, &mut warnings);
                    if !posed {
                        repeats::drop_repeated_triangles(&mut m, &layering, &what, &mut warnings);
                    }
                    if posed {
                        let r = rig_of(&node, &mesh, m, data, &mut animation, root, &buffer_data)?;
                        let mut m = r.base.clone();
                        let joints = r
                            .skin
                            .map(|s| animation.joint_matrices(s, &rest))
                            .unwrap_or_default();
                        r.pose_into(&r.default_weights, &joints, &mut m);
                        if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
                            return Err(format!(
                                "meshes[{}]: its morph targets or skin move POSITION {i} to a \
                                 non-finite point",
                                mesh.index()
                            ));
                        }
                        rig = Some(Arc::new(r));
                        Arc::new(m)
                    } else {
                        let m = Arc::new(m);
                        meshes.insert(mesh.index(), Arc::clone(&m));
                        m
                    }
                }
            };
            let skinned = rig.as_ref().is_some_and(|r| r.skin.is_some());
            if m.positions.iter().any(|p| {
                let w = world.transform_point3(p.as_dvec3());
                w.abs().max_element().partial_cmp(&limits::MAX_COORDINATE)
                    != Some(std::cmp::Ordering::Less)
            }) {
                warn_once(
                    &mut warnings,
                    format!(
                        "{at}: vertices lie farther than {:e} from the origin; skipped",
                        limits::MAX_COORDINATE
                    ),
                );
                continue;
            }
            // A repeat places nothing new; its camera, light and children still count.
            let repeat = !posed && !moved && placements.repeats(&m, &world, &at);
            triangles += if repeat { 0 } else { m.indices.len() };
            if triangles > limits::MAX_TRIANGLES {
                return Err(format!(
                    "{at}: the scene has more than {} triangles after instancing",
                    limits::MAX_TRIANGLES
                ));
            }
            if !repeat && !m.indices.is_empty() {
                if !animation.clips.is_empty() {
                    animation.objects.push(Driven {
                        object: scene.objects.len(),
                        node: node.index(),
                        rig,
                    });
                }
                scene.objects.push(Object {
                    name,
                    // A skinned mesh is placed by its joints alone; its node's transform is
                    // ignored (glTF 2.0 § 3.7.3).
                    world_from_object: if skinned { DMat4::IDENTITY } else { world },
                    visible: true,
                    mesh: m,
                });
            }
        }
        if let Some(camera) = node.camera() {
            match import_camera(&camera, &world) {
                Ok(c) => {
                    animation.cameras.push((scene.cameras.len(), node.index()));
                    scene.cameras.push(c);
                }
                Err(why) => warn_once(&mut warnings, why),
            }
        }
        if let Some(light) = node.light()
            && let Some(l) = import_light(&light, &world, &mut warnings)
        {
            animation.lights.push((scene.lights.len(), node.index()));
            scene.lights.push(l);
        }
        let children: Vec<gltf::Node> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1, moved));
        }
    }
    warnings.extend(placements.warning());

    drop(buffer_data);
    drop(buffers);
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
    if !animation.clips.is_empty() {
        scene.animation = Arc::new(animation);
    }
    Ok(scene)
}

/// The rig of `node`'s mesh `base` (read unposed with its `data`): its skin, read into
/// `animation` and checked against the influences, and its default morph weights.
fn rig_of(
    node: &gltf::Node,
    mesh: &gltf::Mesh,
    base: Mesh,
    data: RigData,
    animation: &mut Animation,
    root: &gltf::json::Root,
    buffer_data: &BufferData,
) -> Result<Rig, String> {
    let mut skin = None;
    if let Some(s) = node.skin() {
        animation.read_skin(root, buffer_data, s.index())?;
        skin = (!animation.skins[s.index()].joints.is_empty()).then_some(s.index());
    }
    let rig = Rig {
        base,
        data,
        skin,
        default_weights: node
            .weights()
            .or(mesh.weights())
            .map(<[f32]>::to_vec)
            .unwrap_or_default(),
    };
    if let Some(s) = skin {
        let joints = animation.skins[s].joints.len();
        rig.check_joints(joints, &format!("meshes[{}]", mesh.index()))?;
    }
    Ok(rig)
}

/// Adds `warning` unless the same one was given already (a node placed many times warns once).
fn warn_once(warnings: &mut Vec<String>, warning: String) {
    if !warnings.contains(&warning) {
        warnings.push(warning);
    }
}

/// A perspective camera placed by `world`, or a warning saying why it is left out.
fn import_camera(camera: &gltf::Camera, world: &DMat4) -> Result<Camera, String> {
    let at = format!("cameras[{}]", camera.index());
    let gltf::camera::Projection::Perspective(p) = camera.projection() else {
        return Err(format!(
            "{at}: orthographic cameras are not supported, skipped"
        ));
    };
    let yfov = p.yfov() as f64;
    if !(yfov > 0.0 && yfov < std::f64::consts::PI) {
        return Err(format!(
            "{at}.perspective.yfov: {yfov} is outside (0, π), camera skipped"
        ));
    }
    Ok(Camera {
        name: camera
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("camera {}", camera.index())),
        eye: world.transform_point3(DVec3::ZERO),
        forward: -world.transform_vector3(DVec3::Z).normalize(),
        up: world.transform_vector3(DVec3::Y).normalize(),
        yfov,
    })
}

/// A punctual light placed by `world`; `None` (with a warning) when its color or intensity is
/// negative or not finite. Spot cones are clamped to 0 ≤ inner < outer ≤ π/2.
fn import_light(
    light: &gltf::khr_lights_punctual::Light,
    world: &DMat4,
    warnings: &mut Vec<String>,
) -> Option<Light> {
    use gltf::khr_lights_punctual::Kind;
    let at = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
    let color = light.color();
    let intensity = light.intensity();
    if !(color.iter().all(|c| c.is_finite() && *c >= 0.0)
        && intensity.is_finite()
        && intensity >= 0.0)
    {
        warn_once(
            warnings,
            format!("{at}: color or intensity is negative or not finite, light skipped"),
        );
        return None;
    }
    let clamped = (
        color.map(|c| c.min(limits::MAX_INTENSITY)),
        intensity.min(limits::MAX_INTENSITY),
    );
    if clamped != (color, intensity) {
        warn_once(
            warnings,
            format!(
                "{at}: color or intensity above {:e}, clamped",
                limits::MAX_INTENSITY
            ),
        );
    }
    let (color, intensity) = clamped;
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let (inner, outer) = spot_cone(inner_cone_angle, outer_cone_angle);
            if (inner, outer) != (inner_cone_angle, outer_cone_angle) {
                warn_once(
                    warnings,
                    format!(
                        "{at}.spot: cone angles {inner_cone_angle}, {outer_cone_angle} are \
                         clamped to {inner}, {outer} (0 ≤ inner < outer ≤ π/2)"
                    ),
                );
            }
            LightKind::Spot { inner, outer }
        }
    };
    Some(Light {
        name: light
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("light {}", light.index())),
        kind,
        position: world.transform_point3(DVec3::ZERO),
        direction: (-world.transform_vector3(DVec3::Z)).normalize_or(DVec3::NEG_Y),
        color,
        intensity,
        light_radius: 0.0,
    })
}

/// Spot cone angles clamped to 0 ≤ inner < outer ≤ π/2 (non-finite values take the
/// extension's defaults, 0 and π/4).
fn spot_cone(inner: f32, outer: f32) -> (f32, f32) {
    use std::f32::consts::FRAC_PI_2;
    let outer = if outer.is_finite() {
        outer
    } else {
        FRAC_PI_2 / 2.0
    };
    let inner = if inner.is_finite() { inner } else { 0.0 };
    let outer = outer.clamp(1e-4, FRAC_PI_2);
    let inner = inner.clamp(0.0, outer * 0.9999);
    (inner, outer)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scene loaded from the mapped bundled box is the one loaded from its bytes.
    #[test]
    fn a_mapped_file_loads_as_its_bytes() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
        let read = std::fs::read(&path).unwrap();
        let from_map = load_bytes(sources::Bytes::of_file_mapped_from(&path, 0).unwrap()).unwrap();
        let from_read = load_from_bytes(&read, None, "box").unwrap();
        assert_eq!(from_map.objects.len(), from_read.objects.len());
        for (a, b) in from_map.objects.iter().zip(&from_read.objects) {
            assert_eq!(a.mesh.positions, b.mesh.positions);
            assert_eq!(a.mesh.indices, b.mesh.indices);
            assert_eq!(a.world_from_object, b.world_from_object);
        }
    }
}
