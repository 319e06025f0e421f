//! Material extensions the gltf crate does not parse, read from the material's raw
//! `extensions` JSON: `KHR_materials_clearcoat`, `KHR_materials_sheen`,
//! `KHR_materials_anisotropy`, `KHR_materials_iridescence`,
//! `KHR_materials_diffuse_transmission` and `KHR_materials_dispersion`.

use super::TextureTable;
use crate::scene::Material;
use crate::scene::textures::MaterialTextures;
use serde_json::Value;

/// Reads the extensions into `material` and its texture slots.
pub(super) fn read_extensions(
    m: &gltf::Material,
    document: &gltf::Document,
    table: &mut TextureTable,
    material: &mut Material,
    warnings: &mut Vec<String>,
) {
    let what = format!("material {}", m.index().unwrap_or(0));
    let mut reader = Reader {
        document,
        table,
        what: &what,
        warnings,
    };
    if let Some(x) = m.extension_value("KHR_materials_clearcoat") {
        reader.clearcoat(x, material);
    }
    if let Some(x) = m.extension_value("KHR_materials_sheen") {
        reader.sheen(x, material);
    }
    if let Some(x) = m.extension_value("KHR_materials_anisotropy") {
        reader.anisotropy(x, material);
    }
    if let Some(x) = m.extension_value("KHR_materials_iridescence") {
        reader.iridescence(x, material);
    }
    if let Some(x) = m.extension_value("KHR_materials_diffuse_transmission") {
        reader.diffuse_transmission(x, material);
    }
    if let Some(x) = m.extension_value("KHR_materials_dispersion") {
        // 20 / Abbe number; any value >= 0 is valid (above 1 exaggerates).
        material.dispersion = Reader::non_negative(x, "dispersion", 0.0);
    }
}

struct Reader<'a> {
    document: &'a gltf::Document,
    table: &'a mut TextureTable,
    what: &'a str,
    warnings: &'a mut Vec<String>,
}

impl Reader<'_> {
    /// A number of the extension object, clamped to [0, 1]; `default` when absent or not a
    /// number.
    fn unit(x: &Value, key: &str, default: f32) -> f32 {
        x.get(key)
            .and_then(Value::as_f64)
            .map_or(default, |v| (v as f32).clamp(0.0, 1.0))
    }

    /// A textureInfo (or normalTextureInfo) object: the texture with its texCoord and
    /// `KHR_texture_transform`. A missing texture is a warning and leaves the slot empty.
    fn texture(&mut self, x: &Value, key: &str, srgb: bool) -> Option<u32> {
        let info = x.get(key)?;
        let what = format!("{} {key}", self.what);
        let Some(texture) = info
            .get("index")
            .and_then(Value::as_u64)
            .and_then(|i| self.document.textures().nth(i as usize))
        else {
            self.warnings
                .push(format!("{what}: no such texture; the factor alone is used"));
            return None;
        };
        let tex_coord = info.get("texCoord").and_then(Value::as_u64).unwrap_or(0) as u32;
        let transform = info
            .get("extensions")
            .and_then(|e| e.get("KHR_texture_transform"));
        self.table
            .add(texture, tex_coord, transform, srgb, &what, self.warnings)
    }

    fn clearcoat(&mut self, x: &Value, material: &mut Material) {
        material.clearcoat = Self::unit(x, "clearcoatFactor", 0.0);
        material.clearcoat_roughness = Self::unit(x, "clearcoatRoughnessFactor", 0.0);
        material.clearcoat_normal_scale = x
            .get("clearcoatNormalTexture")
            .and_then(|n| n.get("scale"))
            .and_then(Value::as_f64)
            .map_or(1.0, |s| s as f32);
        let t: &mut MaterialTextures = &mut material.textures;
        t.clearcoat = self.texture(x, "clearcoatTexture", false);
        t.clearcoat_roughness = self.texture(x, "clearcoatRoughnessTexture", false);
        t.clearcoat_normal = self.texture(x, "clearcoatNormalTexture", false);
    }

    /// An RGB factor of the extension object, each channel clamped to [0, 1]; `default` where
    /// absent or not a number.
    fn color(x: &Value, key: &str, default: f32) -> [f32; 3] {
        let color = x.get(key).and_then(Value::as_array);
        std::array::from_fn(|i| {
            color
                .and_then(|c| c.get(i))
                .and_then(Value::as_f64)
                .map_or(default, |v| (v as f32).clamp(0.0, 1.0))
        })
    }

    fn sheen(&mut self, x: &Value, material: &mut Material) {
        material.sheen_color = Self::color(x, "sheenColorFactor", 0.0);
        material.sheen_roughness = Self::unit(x, "sheenRoughnessFactor", 0.0);
        let t: &mut MaterialTextures = &mut material.textures;
        t.sheen_color = self.texture(x, "sheenColorTexture", true);
        t.sheen_roughness = self.texture(x, "sheenRoughnessTexture", false);
    }

    fn anisotropy(&mut self, x: &Value, material: &mut Material) {
        material.anisotropy = Self::unit(x, "anisotropyStrength", 0.0);
        material.anisotropy_rotation = x
            .get("anisotropyRotation")
            .and_then(Value::as_f64)
            .filter(|r| r.is_finite())
            .map_or(0.0, |r| r as f32);
        material.textures.anisotropy = self.texture(x, "anisotropyTexture", false);
    }

    /// A non-negative finite number of the extension object; `default` otherwise.
    fn non_negative(x: &Value, key: &str, default: f32) -> f32 {
        x.get(key)
            .and_then(Value::as_f64)
            .filter(|v| v.is_finite() && *v >= 0.0)
            .map_or(default, |v| v as f32)
    }

    fn diffuse_transmission(&mut self, x: &Value, material: &mut Material) {
        material.diffuse_transmission = Self::unit(x, "diffuseTransmissionFactor", 0.0);
        material.diffuse_transmission_color = Self::color(x, "diffuseTransmissionColorFactor", 1.0);
        let t: &mut MaterialTextures = &mut material.textures;
        t.diffuse_transmission = self.texture(x, "diffuseTransmissionTexture", false);
        t.diffuse_transmission_color = self.texture(x, "diffuseTransmissionColorTexture", true);
    }

    fn iridescence(&mut self, x: &Value, material: &mut Material) {
        material.iridescence = Self::unit(x, "iridescenceFactor", 0.0);
        material.iridescence_ior = Self::non_negative(x, "iridescenceIor", 1.3).max(1.0);
        material.iridescence_thickness = [
            Self::non_negative(x, "iridescenceThicknessMinimum", 100.0),
            Self::non_negative(x, "iridescenceThicknessMaximum", 400.0),
        ];
        let t: &mut MaterialTextures = &mut material.textures;
        t.iridescence = self.texture(x, "iridescenceTexture", false);
        t.iridescence_thickness = self.texture(x, "iridescenceThicknessTexture", false);
    }
}
