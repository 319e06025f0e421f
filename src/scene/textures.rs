//! Textures on the host: decoded images, the way materials use them (sampler, texture
//! coordinate set, `KHR_texture_transform`), sRGB conversion and box-filtered mip chains.

use rayon::prelude::*;

/// The largest texture side kept; larger images lose their finest mip levels.
pub const MAX_TEXTURE_SIDE: u32 = 4096;

/// A decoded image: 8-bit RGBA texels, row by row from the top, as stored in the file
/// (color images sRGB-encoded; the material slot says how to read them).
#[derive(Clone)]
pub struct Image {
    /// Image name or URI, for messages.
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels, `width × height`.
    pub rgba: Vec<[u8; 4]>,
}

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Image({:?}, {}x{})", self.name, self.width, self.height)
    }
}

/// A sampler's wrap mode for coordinates outside [0, 1].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// Tile.
    #[default]
    Repeat,
    /// Use the edge texel.
    Clamp,
    /// Tile, flipping every other copy.
    Mirror,
}

impl From<gltf::texture::WrappingMode> for Wrap {
    fn from(w: gltf::texture::WrappingMode) -> Self {
        use gltf::texture::WrappingMode as M;
        match w {
            M::Repeat => Wrap::Repeat,
            M::ClampToEdge => Wrap::Clamp,
            M::MirroredRepeat => Wrap::Mirror,
        }
    }
}

/// `KHR_texture_transform`: `uv' = T(offset) · R(rotation) · S(scale) · uv`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexTransform {
    /// Translation.
    pub offset: [f32; 2],
    /// Rotation in radians (counter-clockwise in UV space as the extension defines it).
    pub rotation: f32,
    /// Scale.
    pub scale: [f32; 2],
}

impl Default for TexTransform {
    fn default() -> Self {
        Self {
            offset: [0.0; 2],
            rotation: 0.0,
            scale: [1.0; 2],
        }
    }
}

impl TexTransform {
    /// The two rows of the 3×2 matrix the extension specifies.
    pub fn rows(&self) -> [[f32; 3]; 2] {
        let (s, c) = self.rotation.sin_cos();
        let [sx, sy] = self.scale;
        let [ox, oy] = self.offset;
        [[c * sx, s * sy, ox], [-s * sx, c * sy, oy]]
    }

    /// Applies the transform to `uv`.
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let [a, b] = self.rows();
        [
            a[0] * uv[0] + a[1] * uv[1] + a[2],
            b[0] * uv[0] + b[1] * uv[1] + b[2],
        ]
    }
}

/// How a material slot uses an image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into `Scene::images`.
    pub image: u32,
    /// Whether the color channels are sRGB-encoded (base color and emissive slots).
    pub srgb: bool,
    /// Wrap mode along U.
    pub wrap_s: Wrap,
    /// Wrap mode along V.
    pub wrap_t: Wrap,
    /// Texture coordinate set (0 or 1), after the transform's override.
    pub tex_coord: u32,
    /// Nearest-texel lookups (the sampler's magFilter is NEAREST).
    pub nearest: bool,
    /// Whether coarser levels are used for minification (false when the sampler's minFilter
    /// has no mipmaps).
    pub mipmaps: bool,
    /// The texture transform.
    pub transform: TexTransform,
}

/// The texture slots of a material: indices into `Scene::texture_refs`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    /// Base color (sRGB RGB, linear alpha).
    pub base_color: Option<u32>,
    /// Metallic (B) and roughness (G).
    pub metallic_roughness: Option<u32>,
    /// Tangent-space normal map.
    pub normal: Option<u32>,
    /// Emission (sRGB).
    pub emissive: Option<u32>,
    /// `KHR_materials_transmission` texture (R).
    pub transmission: Option<u32>,
    /// `KHR_materials_clearcoat` clearcoatTexture (R).
    pub clearcoat: Option<u32>,
    /// `KHR_materials_clearcoat` clearcoatRoughnessTexture (G).
    pub clearcoat_roughness: Option<u32>,
    /// `KHR_materials_clearcoat` clearcoatNormalTexture.
    pub clearcoat_normal: Option<u32>,
    /// `KHR_materials_sheen` sheenColorTexture (sRGB RGB).
    pub sheen_color: Option<u32>,
    /// `KHR_materials_sheen` sheenRoughnessTexture (A).
    pub sheen_roughness: Option<u32>,
    /// `KHR_materials_anisotropy` anisotropyTexture (RG direction, B strength).
    pub anisotropy: Option<u32>,
    /// `KHR_materials_iridescence` iridescenceTexture (R).
    pub iridescence: Option<u32>,
    /// `KHR_materials_iridescence` iridescenceThicknessTexture (G).
    pub iridescence_thickness: Option<u32>,
    /// `KHR_materials_diffuse_transmission` diffuseTransmissionTexture (A).
    pub diffuse_transmission: Option<u32>,
    /// `KHR_materials_diffuse_transmission` diffuseTransmissionColorTexture (sRGB RGB).
    pub diffuse_transmission_color: Option<u32>,
}

impl MaterialTextures {
    /// Whether any slot holds a texture.
    pub fn any(&self) -> bool {
        self.base_color.is_some()
            || self.metallic_roughness.is_some()
            || self.normal.is_some()
            || self.emissive.is_some()
            || self.transmission.is_some()
            || self.clearcoat.is_some()
            || self.clearcoat_roughness.is_some()
            || self.clearcoat_normal.is_some()
            || self.sheen_color.is_some()
            || self.sheen_roughness.is_some()
            || self.anisotropy.is_some()
            || self.iridescence.is_some()
            || self.iridescence_thickness.is_some()
            || self.diffuse_transmission.is_some()
            || self.diffuse_transmission_color.is_some()
    }

    /// Whether a slot holds a tangent-space normal map (the base's or the clearcoat's).
    pub fn normal_mapped(&self) -> bool {
        self.normal.is_some() || self.clearcoat_normal.is_some()
    }
}

/// sRGB-encoded 8-bit value to linear.
pub fn srgb_to_linear(v: u8) -> f32 {
    let c = v as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value to the nearest sRGB-encoded 8-bit value.
pub fn linear_to_srgb(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let c = if v <= 0.0031308 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0 + 0.5) as u8
}

/// One mip level.
#[derive(Clone, Debug)]
pub struct MipLevel {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Texels.
    pub rgba: Vec<[u8; 4]>,
}

/// The mip chain of an image down to 1×1, each level a 2×2 box filter of the one above (in
/// linear space when `srgb`; an odd side folds its last texel into the previous one's box).
/// Levels wider or taller than `max_side` are dropped.
pub fn mip_chain(image: &Image, srgb: bool, max_side: u32) -> Vec<MipLevel> {
    let mut levels = vec![MipLevel {
        width: image.width,
        height: image.height,
        rgba: image.rgba.clone(),
    }];
    while let Some(last) = levels.last()
        && (last.width > 1 || last.height > 1)
    {
        let next = downsample(last, srgb);
        if levels[0].width > max_side || levels[0].height > max_side {
            levels[0] = next;
        } else {
            levels.push(next);
        }
    }
    levels
}

fn downsample(src: &MipLevel, srgb: bool) -> MipLevel {
    let w = (src.width / 2).max(1);
    let h = (src.height / 2).max(1);
    let decode = |v: u8| {
        if srgb {
            srgb_to_linear(v)
        } else {
            v as f32 / 255.0
        }
    };
    let encode = |v: f32| {
        if srgb {
            linear_to_srgb(v)
        } else {
            (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
        }
    };
    // Source texels that fall into destination texel (x, y): 2 per axis, 3 for the last of
    // an odd side.
    let span = |d: u32, dst: u32, src: u32| {
        let lo = (d * 2).min(src - 1);
        let hi = if d + 1 == dst {
            src
        } else {
            (d * 2 + 2).min(src)
        };
        lo..hi.max(lo + 1)
    };
    let mut rgba = vec![[0u8; 4]; (w * h) as usize];
    rgba.par_chunks_mut(w as usize)
        .enumerate()
        .for_each(|(y, row)| {
            let ys = span(y as u32, h, src.height);
            for (x, out) in row.iter_mut().enumerate() {
                let xs = span(x as u32, w, src.width);
                let mut sum = [0.0f32; 4];
                let mut n = 0.0;
                for sy in ys.clone() {
                    for sx in xs.clone() {
                        let t = src.rgba[(sy * src.width + sx) as usize];
                        for c in 0..3 {
                            sum[c] += decode(t[c]);
                        }
                        sum[3] += t[3] as f32 / 255.0;
                        n += 1.0;
                    }
                }
                *out = [
                    encode(sum[0] / n),
                    encode(sum[1] / n),
                    encode(sum[2] / n),
                    (sum[3] / n * 255.0 + 0.5) as u8,
                ];
            }
        });
    MipLevel {
        width: w,
        height: h,
        rgba,
    }
}

/// Converts gltf's decoded pixels to RGBA8 (gray to gray, missing alpha to opaque, 16-bit
/// channels to their high byte).
pub fn to_rgba8(data: &gltf::image::Data, name: &str) -> Result<Image, String> {
    use gltf::image::Format as F;
    let (channels, bytes) = match data.format {
        F::R8 => (1, 1),
        F::R8G8 => (2, 1),
        F::R8G8B8 => (3, 1),
        F::R8G8B8A8 => (4, 1),
        F::R16 => (1, 2),
        F::R16G16 => (2, 2),
        F::R16G16B16 => (3, 2),
        F::R16G16B16A16 => (4, 2),
        other => {
            return Err(format!(
                "image {name}: pixel format {other:?} is not supported"
            ));
        }
    };
    let stride = channels * bytes;
    let count = (data.width * data.height) as usize;
    if data.pixels.len() < count * stride {
        return Err(format!("image {name}: truncated pixel data"));
    }
    // Little-endian 16-bit channels: the high byte is the second.
    let at = |px: &[u8], c: usize| px[c * bytes + bytes - 1];
    let rgba = data
        .pixels
        .par_chunks_exact(stride)
        .take(count)
        .map(|px| match channels {
            1 => [at(px, 0), at(px, 0), at(px, 0), 255],
            2 => [at(px, 0), at(px, 0), at(px, 0), at(px, 1)],
            3 => [at(px, 0), at(px, 1), at(px, 2), 255],
            _ => [at(px, 0), at(px, 1), at(px, 2), at(px, 3)],
        })
        .collect();
    Ok(Image {
        name: name.to_string(),
        width: data.width,
        height: data.height,
        rgba,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_byte() {
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
        }
        assert!((srgb_to_linear(128) - 0.2158605).abs() < 1e-6);
    }

    #[test]
    fn mip_chain_averages_and_ends_at_one_texel() {
        let image = Image {
            name: "t".into(),
            width: 5,
            height: 2,
            rgba: (0..10).map(|i| [i as u8 * 20, 0, 0, 255]).collect(),
        };
        let chain = mip_chain(&image, false, 4096);
        let sizes: Vec<(u32, u32)> = chain.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, vec![(5, 2), (2, 1), (1, 1)]);
        // Level 1 texel 1 covers columns 2..5 of both rows.
        let expect = [2, 3, 4, 7, 8, 9].iter().map(|i| i * 20).sum::<u32>() as f32 / 6.0;
        assert_eq!(chain[1].rgba[1][0], (expect + 0.5) as u8);
        // Level 2 is the mean of level 1: (60 + 110) / 2.
        assert_eq!(chain[2].rgba[0][0], 85);
        // Dropping levels above a side limit.
        let capped = mip_chain(&image, false, 2);
        assert_eq!((capped[0].width, capped[0].height), (2, 1));
    }

    #[test]
    fn srgb_mips_average_in_linear_space() {
        let image = Image {
            name: "t".into(),
            width: 2,
            height: 1,
            rgba: vec![[0, 0, 0, 0], [255, 255, 255, 255]],
        };
        let chain = mip_chain(&image, true, 4096);
        // Linear 0.5 is sRGB 188, not 128.
        assert_eq!(chain[1].rgba[0][0], 188);
        assert_eq!(chain[1].rgba[0][3], 128);
    }

    #[test]
    fn transform_rows_follow_the_extension() {
        let t = TexTransform {
            offset: [0.5, 0.25],
            rotation: std::f32::consts::FRAC_PI_2,
            scale: [2.0, 3.0],
        };
        // uv' = T R S uv: (1, 0) scales to (2, 0), rotates to (0, -2), moves to (0.5, -1.75).
        let p = t.apply([1.0, 0.0]);
        assert!(
            (p[0] - 0.5).abs() < 1e-6 && (p[1] + 1.75).abs() < 1e-6,
            "{p:?}"
        );
    }
}
