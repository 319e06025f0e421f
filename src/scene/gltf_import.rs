//! glTF 2.0 import (`.gltf` with external or embedded buffers, and `.glb`).

use super::textures::{Image, MaterialTextures, TexTransform, TextureRef, Wrap, to_rgba8};
use super::{
    AlphaMode, Camera, Light, LightKind, Material, Mesh, Object, Scene, SceneError,
    default_light_rig,
};
use glam::{DMat4, DQuat, DVec3, Vec2, Vec3, Vec4};
use gltf::mesh::Mode;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

mod materials;

/// Extensions penumbra understands (or can safely ignore when rendering).
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
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

    let mut table = TextureTable::default();
    let mut materials = document
        .materials()
        .map(|m| import_material(m, &document, &mut table, &mut warnings))
        .collect::<Vec<_>>();
    let images = decode_images(&document, base, &buffers, &mut table, &mut warnings);
    for m in &mut materials {
        table.drop_missing(&mut m.textures);
    }
    let default_material = materials.len() as u32;
    // The texture coordinate set of each material's normal map (tangents are made for it).
    let normal_sets: Vec<Option<u32>> = materials
        .iter()
        .map(|m| {
            (m.textures.normal)
                .or(m.textures.clearcoat_normal)
                .map(|r| table.refs[r as usize].tex_coord)
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
            let m = import_mesh(
                &mesh,
                &buffer_data,
                default_material,
                &normal_sets,
                &mut warnings,
            )?;
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
        let source = texture.source();
        let next = self.order.len() as u32;
        let image = *self.images.entry(source.index()).or_insert(next);
        if image == next {
            self.order.push(source.index());
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
    buffers: &[gltf::buffer::Data],
    table: &mut TextureTable,
    warnings: &mut Vec<String>,
) -> Vec<Arc<Image>> {
    let all: Vec<gltf::Image> = document.images().collect();
    let base = base.unwrap_or(Path::new("."));
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
            let data = gltf::image::Data::from_source(image.source(), Some(base), buffers)
                .map_err(|e| format!("image {name}: cannot decode: {e}"))?;
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
    let strength = m.emissive_strength().unwrap_or(1.0);
    let emissive = m.emissive_factor().map(|e| e * strength);
    let (specular_factor, specular_color) = match m.specular() {
        Some(s) => (s.specular_factor(), s.specular_color_factor()),
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
    let mut material = Material {
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
        textures,
        normal_scale: normal.as_ref().map_or(1.0, |n| n.scale()),
        unlit: m.unlit(),
        ..Material::default()
    };
    materials::read_extensions(&m, document, table, &mut material, warnings);
    material
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
    normal_sets: &[Option<u32>],
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
        let read_uvs = |set: u32| -> Vec<Vec2> {
            reader
                .read_tex_coords(set)
                .map(|t| t.into_f32().map(Vec2::from).collect())
                .unwrap_or_default()
        };
        let uvs = read_uvs(0);
        let uvs1 = read_uvs(1);
        for (set, list) in [(0, &uvs), (1, &uvs1)] {
            if !list.is_empty() && list.len() != positions.len() {
                return Err(format!(
                    "{what}: TEXCOORD_{set} count differs from POSITION count"
                ));
            }
        }
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
        pad_attribute(&mut out.uvs1, out.positions.len(), &uvs1, positions.len());
        // Tangents at the corners of normal-mapped triangles: the file's, else MikkTSpace's.
        let tangents: Vec<[Vec4; 3]> = match normal_sets.get(material as usize).copied().flatten() {
            None => Vec::new(),
            Some(set) => match reader.read_tangents() {
                Some(t) => {
                    let t: Vec<Vec4> = t.map(Vec4::from).collect();
                    if t.len() != positions.len() {
                        return Err(format!("{what}: TANGENT count differs from POSITION count"));
                    }
                    triangles
                        .iter()
                        .map(|tri| tri.map(|i| t[i as usize]))
                        .collect()
                }
                None => {
                    let set_uvs = if set == 1 { &uvs1 } else { &uvs };
                    if set_uvs.is_empty() {
                        warnings.push(format!(
                            "{what}: the normal map's TEXCOORD_{set} is missing, normal map ignored"
                        ));
                        Vec::new()
                    } else {
                        super::tangents::generate(&positions, &normals, set_uvs, &triangles)
                    }
                }
            },
        };
        pad_attribute(
            &mut out.tangents,
            out.indices.len(),
            &tangents,
            triangles.len(),
        );
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
