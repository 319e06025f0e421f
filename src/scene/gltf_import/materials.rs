//! glTF materials into [`Material`]s: the metallic-roughness core and the extensions the gltf
//! crate parses, values out of range fixed with a warning ([`import_material`]); and the
//! extensions it does not parse, read from the material's raw `extensions` JSON:
//! `KHR_materials_clearcoat`, `KHR_materials_sheen`, `KHR_materials_anisotropy`,
//! `KHR_materials_iridescence`, `KHR_materials_diffuse_transmission` and
//! `KHR_materials_dispersion`.

use super::super::textures::MaterialTextures;
use super::super::{AlphaMode, Material, limits};
use super::texture_table::TextureTable;
use serde_json::Value;

/// The scene material of glTF material `m`, its textures added to `table`; factors out of
/// range are clamped, with one warning per material.
pub(super) fn import_material(
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
    read_extensions(&m, document, table, &mut material, &mut fix, warnings);
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
pub(super) struct Fixes(Vec<String>);

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

/// Reads the extensions into `material` and its texture slots.
pub(super) fn read_extensions(
    m: &gltf::Material,
    document: &gltf::Document,
    table: &mut TextureTable,
    material: &mut Material,
    fix: &mut Fixes,
    warnings: &mut Vec<String>,
) {
    let what = format!("material {}", m.index().unwrap_or(0));
    let mut reader = Reader {
        document,
        table,
        what: &what,
        fix,
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
        material.dispersion = reader.non_negative(x, "dispersion", 0.0);
    }
}

struct Reader<'a> {
    document: &'a gltf::Document,
    table: &'a mut TextureTable,
    what: &'a str,
    fix: &'a mut Fixes,
    warnings: &'a mut Vec<String>,
}

impl Reader<'_> {
    /// A number of the extension object, clamped to [0, 1] (noted in the material's
    /// warning); `default` when absent or not a number.
    fn unit(&mut self, x: &Value, key: &str, default: f32) -> f32 {
        x.get(key).and_then(Value::as_f64).map_or(default, |v| {
            self.fix.range(key, v as f32, 0.0, 1.0, default)
        })
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
        material.clearcoat = self.unit(x, "clearcoatFactor", 0.0);
        material.clearcoat_roughness = self.unit(x, "clearcoatRoughnessFactor", 0.0);
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

    /// An RGB factor of the extension object, each channel clamped to [0, 1] (noted in the
    /// material's warning); `default` where absent or not a number.
    fn color(&mut self, x: &Value, key: &str, default: f32) -> [f32; 3] {
        let color = x.get(key).and_then(Value::as_array);
        std::array::from_fn(|i| {
            color
                .and_then(|c| c.get(i))
                .and_then(Value::as_f64)
                .map_or(default, |v| {
                    self.fix.range(key, v as f32, 0.0, 1.0, default)
                })
        })
    }

    fn sheen(&mut self, x: &Value, material: &mut Material) {
        material.sheen_color = self.color(x, "sheenColorFactor", 0.0);
        material.sheen_roughness = self.unit(x, "sheenRoughnessFactor", 0.0);
        let t: &mut MaterialTextures = &mut material.textures;
        t.sheen_color = self.texture(x, "sheenColorTexture", true);
        t.sheen_roughness = self.texture(x, "sheenRoughnessTexture", false);
    }

    fn anisotropy(&mut self, x: &Value, material: &mut Material) {
        material.anisotropy = self.unit(x, "anisotropyStrength", 0.0);
        // Any angle is valid: reduced to [0, 2π) in f64, so that one past f32's range (1e39)
        // still turns the frame instead of becoming infinite there.
        material.anisotropy_rotation = x
            .get("anisotropyRotation")
            .and_then(Value::as_f64)
            .filter(|r| r.is_finite())
            .map_or(0.0, |r| r.rem_euclid(std::f64::consts::TAU) as f32);
        material.textures.anisotropy = self.texture(x, "anisotropyTexture", false);
    }

    /// A non-negative finite number of the extension object; `default` when absent, and
    /// (noted in the material's warning) when negative or not finite in f32.
    fn non_negative(&mut self, x: &Value, key: &str, default: f32) -> f32 {
        let Some(v) = x.get(key).and_then(Value::as_f64) else {
            return default;
        };
        if (v as f32).is_finite() && v >= 0.0 {
            return v as f32;
        }
        self.fix.0.push(format!(
            "{key} {v} is negative or not finite, {default} is used"
        ));
        default
    }

    fn diffuse_transmission(&mut self, x: &Value, material: &mut Material) {
        material.diffuse_transmission = self.unit(x, "diffuseTransmissionFactor", 0.0);
        material.diffuse_transmission_color = self.color(x, "diffuseTransmissionColorFactor", 1.0);
        let t: &mut MaterialTextures = &mut material.textures;
        t.diffuse_transmission = self.texture(x, "diffuseTransmissionTexture", false);
        t.diffuse_transmission_color = self.texture(x, "diffuseTransmissionColorTexture", true);
    }

    fn iridescence(&mut self, x: &Value, material: &mut Material) {
        material.iridescence = self.unit(x, "iridescenceFactor", 0.0);
        material.iridescence_ior = self.non_negative(x, "iridescenceIor", 1.3).max(1.0);
        material.iridescence_thickness = [
            self.non_negative(x, "iridescenceThicknessMinimum", 100.0),
            self.non_negative(x, "iridescenceThicknessMaximum", 400.0),
        ];
        let t: &mut MaterialTextures = &mut material.textures;
        t.iridescence = self.texture(x, "iridescenceTexture", false);
        t.iridescence_thickness = self.texture(x, "iridescenceThicknessTexture", false);
    }
}
