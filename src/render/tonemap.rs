//! From linear radiance to display values: exposure, a tone curve, sRGB encoding, and the
//! tone-mapped PNG files made from them.

use anyhow::{Context, Result};
use std::path::Path;

/// Tone curves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMapper {
    /// ACES filmic (Narkowicz's fit).
    #[default]
    Aces,
    /// Khronos PBR Neutral.
    PbrNeutral,
    /// Clamp only.
    Linear,
}

impl ToneMapper {
    /// Every tone mapper, for menus.
    pub const ALL: [ToneMapper; 3] = [ToneMapper::Aces, ToneMapper::PbrNeutral, ToneMapper::Linear];

    /// Name shown to users.
    pub fn name(self) -> &'static str {
        match self {
            ToneMapper::Aces => "ACES",
            ToneMapper::PbrNeutral => "Khronos PBR Neutral",
            ToneMapper::Linear => "linear",
        }
    }

    /// Maps one linear RGB value (already exposed) to [0, 1].
    pub fn apply(self, c: [f32; 3]) -> [f32; 3] {
        match self {
            ToneMapper::Aces => c.map(|x| {
                let x = x.max(0.0);
                ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
            }),
            ToneMapper::PbrNeutral => pbr_neutral(c),
            ToneMapper::Linear => c.map(|x| x.clamp(0.0, 1.0)),
        }
    }
}

/// Khronos PBR Neutral tone mapper (reference implementation from the Khronos repository).
fn pbr_neutral(c: [f32; 3]) -> [f32; 3] {
    const START: f32 = 0.8 - 0.04;
    const DESATURATION: f32 = 0.15;
    let mut c = c.map(|x| x.max(0.0));
    let x = c[0].min(c[1]).min(c[2]);
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    c = c.map(|v| v - offset);
    let peak = c[0].max(c[1]).max(c[2]);
    if peak < START {
        return c.map(|v| v.clamp(0.0, 1.0));
    }
    let d = 1.0 - START;
    let new_peak = 1.0 - d * d / (peak + d - START);
    c = c.map(|v| v * new_peak / peak);
    let g = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
    c.map(|v| (v * (1.0 - g) + new_peak * g).clamp(0.0, 1.0))
}

/// sRGB encoding of a linear value in [0, 1].
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Exposure (in stops), tone curve and sRGB encoding of a whole image into RGBA8.
pub fn to_rgba8(image: &[[f32; 3]], exposure: f32, mapper: ToneMapper) -> Vec<u8> {
    use rayon::prelude::*;
    let scale = 2f32.powf(exposure);
    image
        .par_iter()
        .flat_map_iter(|p| {
            let c = if p.iter().all(|v| v.is_finite()) {
                mapper.apply(p.map(|v| v * scale))
            } else {
                [0.0; 3]
            };
            let e = c.map(|v| (srgb_encode(v) * 255.0 + 0.5) as u8);
            [e[0], e[1], e[2], 255]
        })
        .collect()
}

/// Writes an exposed, tone-mapped, sRGB-encoded PNG.
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    exposure: f32,
    mapper: ToneMapper,
) -> Result<()> {
    let rgba = to_rgba8(rgb, exposure, mapper);
    write_rgba_png(path, width, height, &rgba)
}

/// Writes RGBA8 pixels (already tone-mapped) as PNG, every write checked.
pub fn write_rgba_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    crate::image_io::write_file(path, &encode_rgba_png(width, height, rgba)?)
}

/// RGBA8 pixels (already tone-mapped) encoded as PNG.
pub fn encode_rgba_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(rgba, width, height, image::ExtendedColorType::Rgba8)
        .context("cannot encode PNG")?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_are_monotonic_and_bounded() {
        for m in ToneMapper::ALL {
            let mut last = -1.0;
            for i in 0..200 {
                let x = i as f32 * 0.1;
                let y = m.apply([x; 3])[0];
                assert!((0.0..=1.0).contains(&y), "{} at {x}: {y}", m.name());
                assert!(y >= last - 1e-6, "{} not monotonic at {x}", m.name());
                last = y;
            }
        }
    }

    #[test]
    fn srgb_matches_known_values() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_encode(0.18) - 0.4613).abs() < 1e-3);
    }

    #[test]
    fn exposure_doubles_per_stop() {
        let a = to_rgba8(&[[0.1; 3]], 0.0, ToneMapper::Linear)[0];
        let b = to_rgba8(&[[0.05; 3]], 1.0, ToneMapper::Linear)[0];
        assert_eq!(a, b);
    }
}
