//! The textures materials use: glTF texture infos to the scene's texture slots
//! ([`TextureTable`]), and the decoding of the images they reference, each once, in parallel.

use super::super::textures::{Image, MaterialTextures, TexTransform, TextureRef, Wrap, to_rgba8};
use super::super::{sources, validate};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

/// Texture references collected while importing materials, and the images they need.
#[derive(Default)]
pub(super) struct TextureTable {
    pub(super) refs: Vec<TextureRef>,
    /// glTF image index → index in `Scene::images` (decode order).
    pub(super) images: HashMap<usize, u32>,
    /// glTF image index of each scene image.
    pub(super) order: Vec<usize>,
    /// Scene images that could not be decoded.
    pub(super) failed: Vec<bool>,
    /// The image each glTF texture shows (its `KHR_texture_basisu` or `EXT_texture_webp`
    /// source, else its plain source), if any.
    pub(super) sources: Vec<Option<usize>>,
}

/// The image each texture shows: the first source in range of its `KHR_texture_basisu`
/// source, its `EXT_texture_webp` source and its core `source` (a PNG/JPEG fallback).
pub(super) fn texture_sources(root: &gltf::json::Root) -> Vec<Option<usize>> {
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
            validate::IMAGE_SOURCE_EXTENSIONS
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
    pub(super) fn add(
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
            // A value given but not finite in f32 (1e39 arrives here as null) leaves out the
            // whole transform, with a warning.
            let mut finite = true;
            let mut pair = |key: &str, default: [f32; 2]| {
                let Some(v) = x.get(key) else {
                    return default;
                };
                match v
                    .as_array()
                    .and_then(|a| Some([a.first()?.as_f64()? as f32, a.get(1)?.as_f64()? as f32]))
                {
                    Some(p) if p.iter().all(|c| c.is_finite()) => p,
                    _ => {
                        finite = false;
                        default
                    }
                }
            };
            t.offset = pair("offset", [0.0; 2]);
            t.scale = pair("scale", [1.0; 2]);
            // Any angle is valid: reduced to [0, 2π) in f64 before it becomes f32.
            match x
                .get("rotation")
                .map(|v| v.as_f64().filter(|r| r.is_finite()))
            {
                None => {}
                Some(Some(r)) => t.rotation = r.rem_euclid(std::f64::consts::TAU) as f32,
                Some(None) => finite = false,
            }
            if !finite {
                warnings.push(format!(
                    "{what}: KHR_texture_transform has a value that is not finite in f32; no \
                     transform is used"
                ));
                t = TexTransform::default();
            }
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

    pub(super) fn info(
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
    pub(super) fn drop_missing(&self, slots: &mut MaterialTextures) {
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
pub(super) fn decode_images(
    document: &gltf::Document,
    base: Option<&sources::Folders>,
    buffers: &[sources::Bytes],
    table: &mut TextureTable,
    warnings: &mut Vec<String>,
) -> Vec<Arc<Image>> {
    let all: Vec<gltf::Image> = document.images().collect();
    let budget = sources::DecodeBudget::default();
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
            let data = sources::decode_image(image, base, buffers, &budget).map_err(|e| {
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
