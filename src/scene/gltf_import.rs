//! glTF 2.0 import (`.gltf` with external or embedded buffers, and `.glb`).

use super::accessor::{self, Attributes, BufferData};
use super::compression;
use super::pose::{Pose, apply_morph_targets, apply_skin, node_matrix, node_pose, rest_worlds};
use super::textures::{Image, MaterialTextures, TexTransform, TextureRef, Wrap, to_rgba8};
use super::variants::{self, VariantRange};
use super::{
    AlphaMode, Camera, Light, LightKind, Material, Mesh, Object, Scene, SceneError,
    default_light_rig, limits, sources, validate,
};
use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};
use gltf::json::validation::Checked;
use gltf::mesh::Mode;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

mod materials;

/// Vertical field of view of the automatic camera.
pub const AUTO_YFOV: f64 = 0.8;

/// Loads a glTF or GLB file. Every problem with the file is a one-line [`SceneError`].
pub fn load(path: &Path) -> Result<Scene, SceneError> {
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
    load_owned(bytes, path.parent(), &path.display().to_string()).map_err(fail)
}

/// Loads glTF or GLB bytes; external files are resolved against `base`.
pub fn load_from_bytes(bytes: &[u8], base: Option<&Path>, source: &str) -> Result<Scene, String> {
    load_owned(sources::Bytes::Owned(bytes.to_vec()), base, source)
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
fn load_owned(bytes: sources::Bytes, base: Option<&Path>, source: &str) -> Result<Scene, String> {
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
    let rest = rest_worlds(&document, &parsed.precise_nodes);

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
        &rest,
        default_material,
        &normal_sets,
        variant_count,
    );
    // Depth first in document order: the stack pops the last entry, so push in reverse.
    let mut stack: Vec<(gltf::Node, DMat4, usize)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY, 0))
        .collect();
    let mut meshes: HashMap<usize, Arc<Mesh>> = HashMap::new();
    let mut placed = 0usize;
    let mut triangles = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
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
            // (a skin or its own morph weights).
            let pose = node_pose(&node, &mesh, root, &buffer_data, &rest)?;
            let posed = node.skin().is_some() || node.weights().is_some();
            let ahead = (!posed).then(|| read_ahead.remove(&mesh.index())).flatten();
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
                    let mut m = import_mesh(
                        &mesh,
                        root,
                        &buffer_data,
                        &pose,
                        default_material,
                        &normal_sets,
                        &mut warnings,
                    )?;
                    m.keep_variants(
                        variant_count,
                        &format!("meshes[{}]", mesh.index()),
                        &mut warnings,
                    );
                    let m = Arc::new(m);
                    if !posed {
                        meshes.insert(mesh.index(), Arc::clone(&m));
                    }
                    m
                }
            };
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
            triangles += m.indices.len();
            if triangles > limits::MAX_TRIANGLES {
                return Err(format!(
                    "{at}: the scene has more than {} triangles after instancing",
                    limits::MAX_TRIANGLES
                ));
            }
            if !m.indices.is_empty() {
                scene.objects.push(Object {
                    name,
                    // A skinned mesh is placed by its joints alone; its node's transform is
                    // ignored (glTF 2.0 § 3.7.3).
                    world_from_object: if pose.joints.is_empty() {
                        world
                    } else {
                        DMat4::IDENTITY
                    },
                    visible: true,
                    mesh: m,
                });
            }
        }
        if let Some(camera) = node.camera() {
            match import_camera(&camera, &world) {
                Ok(c) => scene.cameras.push(c),
                Err(why) => warn_once(&mut warnings, why),
            }
        }
        if let Some(light) = node.light()
            && let Some(l) = import_light(&light, &world, &mut warnings)
        {
            scene.lights.push(l);
        }
        let children: Vec<gltf::Node> = node.children().collect();
        for child in children.into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
    }

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
    Ok(scene)
}

/// A mesh read ahead of the node walk, with the warnings reading it gave, or why it failed.
type ReadAhead = Result<(Mesh, Vec<String>), String>;

/// The meshes that the nodes under `roots` place without a pose of the node's own (no skin, no
/// morph weights), each read once, in parallel: what a scene of many distinct meshes spends
/// most of its loading on (a 64 M-triangle scene of 3,125 meshes). The node walk takes each
/// where it first places it, so the scene, its warnings and its errors are those of reading
/// them there. Meshes are taken in walk order while their triangles (from the accessors'
/// counts) stay within [`limits::MAX_TRIANGLES`]: a file over the limit still fails at the node
/// that crosses it, not after reading every mesh.
fn read_meshes_ahead(
    roots: &[gltf::Node],
    root: &gltf::json::Root,
    data: &BufferData,
    rest: &[DMat4],
    default_material: u32,
    normal_sets: &[Option<(u32, bool)>],
    variant_count: usize,
) -> HashMap<usize, ReadAhead> {
    // The first node placing each mesh, depth first in document order, each node once.
    let mut seen = vec![false; root.nodes.len()];
    let mut stack: Vec<gltf::Node> = roots.iter().rev().cloned().collect();
    let mut first: Vec<gltf::Node> = vec![];
    let mut taken = std::collections::HashSet::new();
    let mut triangles = 0usize;
    while let Some(node) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            continue;
        }
        if let Some(mesh) = node.mesh()
            && node.skin().is_none()
            && node.weights().is_none()
            && taken.insert(mesh.index())
        {
            triangles += mesh
                .primitives()
                .map(|p| {
                    p.indices()
                        .or_else(|| p.get(&gltf::Semantic::Positions))
                        .map_or(0, |a| a.count() / 3)
                })
                .sum::<usize>();
            if triangles > limits::MAX_TRIANGLES {
                break;
            }
            first.push(node.clone());
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev());
    }
    if first.len() < 2 {
        return HashMap::new();
    }
    first
        .par_iter()
        .map(|node| {
            let mesh = node.mesh().expect("a node placing a mesh");
            let mut warnings = vec![];
            let read = node_pose(node, &mesh, root, data, rest).and_then(|pose| {
                let mut m = import_mesh(
                    &mesh,
                    root,
                    data,
                    &pose,
                    default_material,
                    normal_sets,
                    &mut warnings,
                )?;
                let what = format!("meshes[{}]", mesh.index());
                m.keep_variants(variant_count, &what, &mut warnings);
                Ok(m)
            });
            (mesh.index(), read.map(|m| (m, warnings)))
        })
        .collect()
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

/// Texture references collected while importing materials, and the images they need.
#[derive(Default)]
struct TextureTable {
    refs: Vec<TextureRef>,
    /// glTF image index → index in `Scene::images` (decode order).
    images: HashMap<usize, u32>,
    /// glTF image index of each scene image.
    order: Vec<usize>,
    /// Scene images that could not be decoded.
    failed: Vec<bool>,
    /// The image each glTF texture shows (its `KHR_texture_basisu` or `EXT_texture_webp`
    /// source, else its plain source), if any.
    sources: Vec<Option<usize>>,
}

/// The image each texture shows: the first source in range of its `KHR_texture_basisu`
/// source, its `EXT_texture_webp` source and its core `source` (a PNG/JPEG fallback).
fn texture_sources(root: &gltf::json::Root) -> Vec<Option<usize>> {
    root.textures
        .iter()
        .map(|t| {
            let extension = |name: &str| {
                t.extensions
                    .as_ref()
                    .and_then(|e| e.others.get(name))
                    .and_then(|w| w.get("source"))
                    .and_then(serde_json::Value::as_u64)
                    .map(|i| i as usize)
            };
            let core = Some(t.source.value()).filter(|&i| i != u32::MAX as usize);
            super::validate::IMAGE_SOURCE_EXTENSIONS
                .iter()
                .map(|e| extension(e))
                .chain([core])
                .flatten()
                .find(|&i| i < root.images.len())
        })
        .collect()
}

impl TextureTable {
    /// Adds a reference to `texture` with a texture coordinate set and an optional
    /// `KHR_texture_transform` object; returns its index.
    fn add(
        &mut self,
        texture: gltf::Texture,
        tex_coord: u32,
        transform: Option<&serde_json::Value>,
        srgb: bool,
        what: &str,
        warnings: &mut Vec<String>,
    ) -> Option<u32> {
        let Some(source) = self.sources.get(texture.index()).copied().flatten() else {
            warnings.push(format!(
                "{what}: textures[{}] has no image penumbra can decode, left out",
                texture.index()
            ));
            return None;
        };
        let next = self.order.len() as u32;
        let image = *self.images.entry(source).or_insert(next);
        if image == next {
            self.order.push(source);
        }
        let mut t = TexTransform::default();
        let mut tex_coord = tex_coord;
        if let Some(x) = transform {
            let pair = |key: &str, default: [f32; 2]| {
                x.get(key)
                    .and_then(|v| v.as_array())
                    .and_then(|a| Some([a.first()?.as_f64()? as f32, a.get(1)?.as_f64()? as f32]))
                    .unwrap_or(default)
            };
            t.offset = pair("offset", [0.0; 2]);
            t.scale = pair("scale", [1.0; 2]);
            t.rotation = x.get("rotation").and_then(|v| v.as_f64()).unwrap_or(0.0) as f32;
            if let Some(set) = x.get("texCoord").and_then(|v| v.as_u64()) {
                tex_coord = set as u32;
            }
        }
        if tex_coord > 1 {
            warnings.push(format!(
                "{what}: TEXCOORD_{tex_coord} is not supported, TEXCOORD_0 is used"
            ));
            tex_coord = 0;
        }
        let sampler = texture.sampler();
        self.refs.push(TextureRef {
            image,
            srgb,
            wrap_s: Wrap::from(sampler.wrap_s()),
            wrap_t: Wrap::from(sampler.wrap_t()),
            tex_coord,
            nearest: sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest),
            mipmaps: !matches!(
                sampler.min_filter(),
                Some(gltf::texture::MinFilter::Nearest | gltf::texture::MinFilter::Linear)
            ),
            transform: t,
        });
        Some(self.refs.len() as u32 - 1)
    }

    fn info(
        &mut self,
        info: Option<gltf::texture::Info>,
        srgb: bool,
        what: &str,
        warnings: &mut Vec<String>,
    ) -> Option<u32> {
        let info = info?;
        let transform = info.texture_transform().map(|t| {
            let mut v = serde_json::json!({
                "offset": t.offset(),
                "rotation": t.rotation(),
                "scale": t.scale(),
            });
            if let Some(set) = t.tex_coord() {
                v["texCoord"] = serde_json::json!(set);
            }
            v
        });
        self.add(
            info.texture(),
            info.tex_coord(),
            transform.as_ref(),
            srgb,
            what,
            warnings,
        )
    }

    /// Clears the slots whose image failed to decode.
    fn drop_missing(&self, slots: &mut MaterialTextures) {
        for slot in [
            &mut slots.base_color,
            &mut slots.metallic_roughness,
            &mut slots.normal,
            &mut slots.emissive,
            &mut slots.transmission,
            &mut slots.clearcoat,
            &mut slots.clearcoat_roughness,
            &mut slots.clearcoat_normal,
            &mut slots.sheen_color,
            &mut slots.sheen_roughness,
            &mut slots.anisotropy,
            &mut slots.iridescence,
            &mut slots.iridescence_thickness,
            &mut slots.diffuse_transmission,
            &mut slots.diffuse_transmission_color,
        ] {
            if let Some(r) = *slot
                && self.failed[self.refs[r as usize].image as usize]
            {
                *slot = None;
            }
        }
    }
}

/// Decodes the images the materials use, in parallel. An image that cannot be read is a
/// warning and its texture slots fall back to the factors.
fn decode_images(
    document: &gltf::Document,
    base: Option<&Path>,
    buffers: &[sources::Bytes],
    table: &mut TextureTable,
    warnings: &mut Vec<String>,
) -> Vec<Arc<Image>> {
    let all: Vec<gltf::Image> = document.images().collect();
    let decoded: Vec<Result<Image, String>> = table
        .order
        .par_iter()
        .map(|&i| {
            let image = &all[i];
            let name = match image.source() {
                gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                    format!("{i} ({uri})")
                }
                _ => image
                    .name()
                    .map_or_else(|| i.to_string(), |n| format!("{i} ({n})")),
            };
            let data = sources::decode_image(image, base, buffers).map_err(|e| {
                let detail = name.strip_prefix(&i.to_string()).unwrap_or_default();
                format!("images[{i}]{detail}: cannot decode: {e}")
            })?;
            to_rgba8(&data, &name)
        })
        .collect();
    let mut images = Vec::with_capacity(decoded.len());
    for d in decoded {
        match d {
            Ok(image) => {
                images.push(Arc::new(image));
                table.failed.push(false);
            }
            Err(e) => {
                warnings.push(format!("{e}; its textures are left out"));
                images.push(Arc::new(Image {
                    name: String::new(),
                    width: 1,
                    height: 1,
                    rgba: vec![[255; 4]],
                }));
                table.failed.push(true);
            }
        }
    }
    images
}

fn import_material(
    m: gltf::Material,
    document: &gltf::Document,
    table: &mut TextureTable,
    warnings: &mut Vec<String>,
) -> Material {
    let pbr = m.pbr_metallic_roughness();
    // Factors outside their ranges are clamped; one warning per material lists the changes.
    let mut fix = Fixes::default();
    let strength = fix.range(
        "emissiveStrength",
        m.emissive_strength().unwrap_or(1.0),
        0.0,
        limits::MAX_INTENSITY,
        1.0,
    );
    let emissive = m
        .emissive_factor()
        .map(|e| fix.range("emissiveFactor", e, 0.0, 1.0, 0.0) * strength);
    let (specular_factor, specular_color) = match m.specular() {
        Some(s) => (
            fix.range("specularFactor", s.specular_factor(), 0.0, 1.0, 1.0),
            s.specular_color_factor()
                .map(|c| fix.range("specularColorFactor", c, 0.0, f32::MAX, 1.0)),
        ),
        None => (1.0, [1.0; 3]),
    };
    let what = format!("material {}", m.index().unwrap_or(0));
    let normal = m.normal_texture();
    let textures = MaterialTextures {
        base_color: table.info(pbr.base_color_texture(), true, &what, warnings),
        metallic_roughness: table.info(pbr.metallic_roughness_texture(), false, &what, warnings),
        normal: normal.as_ref().and_then(|n| {
            let transform = n.extension_value("KHR_texture_transform").cloned();
            table.add(
                n.texture(),
                n.tex_coord(),
                transform.as_ref(),
                false,
                &what,
                warnings,
            )
        }),
        emissive: table.info(m.emissive_texture(), true, &what, warnings),
        transmission: m
            .transmission()
            .and_then(|t| table.info(t.transmission_texture(), false, &what, warnings)),
        ..MaterialTextures::default()
    };
    let volume = m.volume();
    let mut material = Material {
        name: m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material {}", m.index().unwrap_or(0))),
        base_color: pbr
            .base_color_factor()
            .map(|c| fix.range("baseColorFactor", c, 0.0, 1.0, 1.0)),
        metallic: fix.range("metallicFactor", pbr.metallic_factor(), 0.0, 1.0, 1.0),
        roughness: fix.range("roughnessFactor", pbr.roughness_factor(), 0.0, 1.0, 1.0),
        emission: emissive.map(|e| if e.is_finite() { e.max(0.0) } else { 0.0 }),
        double_sided: m.double_sided(),
        ior: fix.ior(m.ior().unwrap_or(1.5)),
        specular_factor,
        specular_color,
        transmission: fix.range(
            "transmissionFactor",
            m.transmission().map_or(0.0, |t| t.transmission_factor()),
            0.0,
            1.0,
            0.0,
        ),
        thickness: fix.range(
            "thicknessFactor",
            volume.as_ref().map_or(0.0, |v| v.thickness_factor()),
            0.0,
            f32::MAX,
            0.0,
        ),
        attenuation_color: volume.as_ref().map_or([1.0; 3], |v| {
            v.attenuation_color()
                .map(|c| fix.range("attenuationColor", c, 0.0, 1.0, 1.0))
        }),
        attenuation_distance: fix.attenuation_distance(
            volume
                .as_ref()
                .map_or(f32::INFINITY, |v| v.attenuation_distance()),
        ),
        alpha: match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask(fix.range(
                "alphaCutoff",
                m.alpha_cutoff().unwrap_or(0.5),
                0.0,
                f32::MAX,
                0.5,
            )),
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        },
        textures,
        normal_scale: fix.range(
            "normalTexture.scale",
            normal.as_ref().map_or(1.0, |n| n.scale()),
            -f32::MAX,
            f32::MAX,
            1.0,
        ),
        unlit: m.unlit(),
        ..Material::default()
    };
    materials::read_extensions(&m, document, table, &mut material, warnings);
    if !fix.0.is_empty() {
        warnings.push(format!(
            "materials[{}]: {}",
            m.index().unwrap_or(0),
            fix.0.join(", ")
        ));
    }
    material
}

/// Material values brought into their ranges, with a note for each change.
#[derive(Default)]
struct Fixes(Vec<String>);

impl Fixes {
    /// `v` clamped to `lo..=hi`; NaN becomes `default`.
    fn range(&mut self, name: &str, v: f32, lo: f32, hi: f32, default: f32) -> f32 {
        let out = if v.is_nan() { default } else { v.clamp(lo, hi) };
        if out != v {
            self.0
                .push(format!("{name} {v} is out of range, {out} is used"));
        }
        out
    }

    /// The index of refraction: at least 1, or 0 (the extension's special value, kept as
    /// the smallest ratio the BSDF accepts); anything else becomes the default 1.5.
    fn ior(&mut self, ior: f32) -> f32 {
        if ior == 0.0 {
            1e-3
        } else if ior.is_finite() && ior >= 1.0 {
            ior
        } else {
            self.0
                .push(format!("ior {ior} is below 1 or not finite, 1.5 is used"));
            1.5
        }
    }

    /// `attenuationDistance`: positive (infinite means no absorption).
    fn attenuation_distance(&mut self, d: f32) -> f32 {
        if d > 0.0 {
            d
        } else {
            self.0.push(format!(
                "attenuationDistance {d} is not positive, no absorption is used"
            ));
            f32::INFINITY
        }
    }
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

#[allow(clippy::too_many_arguments)]
fn import_mesh(
    mesh: &gltf::Mesh,
    root: &gltf::json::Root,
    data: &BufferData,
    pose: &Pose,
    default_material: u32,
    normal_sets: &[Option<(u32, bool)>],
    warnings: &mut Vec<String>,
) -> Result<Mesh, String> {
    let mut out = Mesh::default();
    for prim in mesh.primitives() {
        let what = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            warnings.push(format!("{what}: mode {mode:?} is not triangles, skipped"));
            continue;
        }
        let json = &root.meshes[mesh.index()].primitives[prim.index()];
        let attributes = Attributes {
            root,
            data,
            accessors: json
                .attributes
                .iter()
                .filter_map(|(k, v)| match k {
                    Checked::Valid(s) => Some((s.to_string(), v.value())),
                    Checked::Invalid => None,
                })
                .collect(),
            draco: compression::decode_draco(root, data, json, &what)?,
            path: what.clone(),
        };
        let mut positions: Vec<Vec3> = attributes
            .floats::<3>("POSITION")?
            .ok_or_else(|| format!("{what}: POSITION is missing"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("{what}: POSITION {i} is not finite"));
        }
        let mut normals: Vec<Vec3> = attributes
            .floats::<3>("NORMAL")?
            .unwrap_or_default()
            .into_iter()
            .map(|n| {
                let n = Vec3::from(n);
                if n.is_finite() { n } else { Vec3::ZERO }
            })
            .collect();
        if !normals.is_empty() && normals.len() != positions.len() {
            return Err(format!("{what}: NORMAL count differs from POSITION count"));
        }
        let read_uvs = |set: u32| -> Result<Vec<Vec2>, String> {
            Ok(attributes
                .floats::<2>(&format!("TEXCOORD_{set}"))?
                .unwrap_or_default()
                .into_iter()
                .map(Vec2::from)
                .collect())
        };
        let uvs = read_uvs(0)?;
        let uvs1 = read_uvs(1)?;
        for (set, list) in [(0, &uvs), (1, &uvs1)] {
            if !list.is_empty() && list.len() != positions.len() {
                return Err(format!(
                    "{what}: TEXCOORD_{set} count differs from POSITION count"
                ));
            }
        }
        let material = prim
            .material()
            .index()
            .map_or(default_material, |i| i as u32);
        let normal_set = normal_sets.get(material as usize).copied().flatten();
        let mut file_tangents: Vec<Vec4> = match normal_set {
            Some(_) => attributes
                .floats::<4>("TANGENT")?
                .unwrap_or_default()
                .into_iter()
                .map(Vec4::from)
                .collect(),
            None => Vec::new(),
        };
        if !file_tangents.is_empty() && file_tangents.len() != positions.len() {
            return Err(format!("{what}: TANGENT count differs from POSITION count"));
        }
        // Pose the vertices: morph targets in the mesh's space, then the skin.
        apply_morph_targets(
            &attributes,
            json,
            &pose.weights,
            &mut positions,
            &mut normals,
            &mut file_tangents,
        )?;
        if !pose.joints.is_empty() {
            apply_skin(
                &attributes,
                &pose.joints,
                &mut positions,
                &mut normals,
                &mut file_tangents,
            )?;
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!(
                "{what}: its morph targets or skin move POSITION {i} to a non-finite point"
            ));
        }
        let flat: Vec<u32> = match (&attributes.draco, json.indices) {
            (Some(d), _) => d.indices.clone(),
            (None, Some(a)) => bytemuck::cast_vec(
                accessor::read_uints::<1>(root, data, a.value())
                    .map_err(|e| format!("{what}.indices: {e}"))?,
            ),
            (None, None) => (0..positions.len() as u32).collect(),
        };
        if let Some(&bad) = flat.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(format!(
                "{what}: index {bad} is out of range ({} vertices)",
                positions.len()
            ));
        }
        // The triangles: the index list read in place (as triples) or unrolled from a strip or
        // a fan, and the list freed at once.
        let triangles: Vec<[u32; 3]> = match mode {
            Mode::Triangles => bytemuck::cast_slice(&flat[..flat.len() / 3 * 3]).to_vec(),
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
        drop(flat);
        let base = out.positions.len() as u32;
        // Tangents at the corners of normal-mapped triangles: the file's, else MikkTSpace's.
        let tangents: Vec<[Vec4; 3]> = match normal_set {
            None => Vec::new(),
            Some(_) if !file_tangents.is_empty() => triangles
                .iter()
                .map(|tri| tri.map(|i| file_tangents[i as usize]))
                .collect(),
            Some((set, normal_map)) => {
                let set_uvs = if set == 1 { &uvs1 } else { &uvs };
                if set_uvs.is_empty() {
                    // An anisotropic material without texture coordinates takes an arbitrary
                    // frame about the normal (kernels/path.h).
                    if normal_map {
                        warnings.push(format!(
                            "{what}: the normal map's TEXCOORD_{set} is missing, normal map ignored"
                        ));
                    }
                    Vec::new()
                } else {
                    super::tangents::generate(&positions, &normals, set_uvs, &triangles)
                }
            }
        };
        let count = triangles.len();
        pad_attribute(&mut out.tangents, out.indices.len(), tangents, count);
        // Keep the per-vertex arrays aligned when only some primitives have normals or UVs.
        // The first primitive's arrays become the mesh's (moved, not copied).
        let vertices = positions.len();
        pad_attribute(&mut out.normals, base as usize, normals, vertices);
        pad_attribute(&mut out.uvs, base as usize, uvs, vertices);
        pad_attribute(&mut out.uvs1, base as usize, uvs1, vertices);
        append(&mut out.positions, positions);
        if base == 0 {
            append(&mut out.indices, triangles);
        } else {
            out.indices
                .extend(triangles.iter().map(|t| t.map(|i| i + base)));
        }
        if let Some(x) = prim.extension_value("KHR_materials_variants") {
            let start = out.materials.len() as u32;
            out.variants.push(VariantRange {
                triangles: start..start + count as u32,
                default: material,
                materials: variants::mappings(x, default_material as usize, &what, warnings),
            });
        }
        out.materials.extend(std::iter::repeat_n(material, count));
    }
    Ok(out)
}

/// Appends `new` to `dst`: moved when `dst` is empty (a mesh's first primitive), else copied.
fn append<T: Copy>(dst: &mut Vec<T>, new: Vec<T>) {
    if dst.is_empty() {
        *dst = new;
    } else {
        dst.extend_from_slice(&new);
    }
}

/// Appends `new` to `dst`, zero-filling where either side lacks the attribute, so that `dst`
/// stays empty only while no primitive has it.
fn pad_attribute<T: Copy + Default>(dst: &mut Vec<T>, old_len: usize, new: Vec<T>, new_len: usize) {
    if dst.is_empty() && new.is_empty() {
        return;
    }
    dst.resize(old_len, T::default());
    if new.is_empty() {
        dst.extend(std::iter::repeat_n(T::default(), new_len));
    } else {
        append(dst, new);
    }
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
