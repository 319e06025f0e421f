//! From linear radiance to display values: exposure, a tone curve, sRGB encoding, and the
//! tone-mapped PNG files made from them.

use anyhow::{Context, Result};
use std::path::Path;

/// Tone curves. Khronos PBR Neutral is the default: under a white light that shows a white
/// diffuse surface at 1, it shows base colours as they are (to within its 0.04 offset, which
/// takes off the dielectric's reflection) up to 0.76 and keeps their hue above; ACES darkens
/// and saturates them (measured in docs/first-image.md).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMapper {
    /// ACES filmic (Narkowicz's fit).
    Aces,
    /// Khronos PBR Neutral (Khronos, 2024).
    #[default]
    PbrNeutral,
    /// Clamp only.
    Linear,
}

impl ToneMapper {
    /// Every tone mapper, for menus.
    pub const ALL: [ToneMapper; 3] = [ToneMapper::PbrNeutral, ToneMapper::Aces, ToneMapper::Linear];

    /// Name shown to users.
    pub fn name(self) -> &'static str {
        match self {
            ToneMapper::Aces => "ACES",
            ToneMapper::PbrNeutral => "Khronos PBR Neutral",
            ToneMapper::Linear => "linear",
        }
    }

    /// The name `--tonemap` takes.
    pub fn arg_name(self) -> &'static str {
        match self {
            ToneMapper::Aces => "aces",
            ToneMapper::PbrNeutral => "neutral",
            ToneMapper::Linear => "linear",
        }
    }

    /// The tone mapper `--tonemap NAME` names, or a one-line error listing the names.
    pub fn from_arg(name: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|t| t.arg_name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|t| t.arg_name()).collect();
                format!("unknown tone mapper {name:?} (one of {})", names.join(", "))
            })
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

/// Khronos PBR Neutral tone mapper: the reference formula (KhronosGroup/ToneMapping,
/// `PBR_Neutral/pbrNeutral.glsl`, 2024): an offset that removes a dielectric's 0.04 reflection
/// near black, linear up to 0.76, then the peak compressed towards 1 and desaturated towards
/// white by a share of what was compressed.
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

/// The inverse of [`srgb_encode`]. Both are also the curve OIDN's albedo prefilter works in
/// (the denoiser's host twin of kernels/denoise/transfer.h's `srgb_forward` / `srgb_inverse`).
pub fn srgb_decode(x: f32) -> f32 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
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

    /// PBR Neutral against values of the reference formula worked by hand: linear below the
    /// knee (less the 0.04 offset, or x − 6.25x² near black), compressed and desaturated
    /// above it, names round-trip.
    #[test]
    fn pbr_neutral_follows_the_reference() {
        let n = |c| ToneMapper::PbrNeutral.apply(c);
        // min 0.1 ≥ 0.08: offset 0.04, peak 0.46 < 0.76: linear.
        let a = n([0.5, 0.3, 0.1]);
        for (x, y) in a.iter().zip([0.46, 0.26, 0.06]) {
            assert!((x - y).abs() < 1e-6, "{a:?}");
        }
        // Near black: offset x − 6.25x² with x = 0.02.
        let b = n([0.02, 0.2, 0.3]);
        let off = 0.02 - 6.25 * 0.02 * 0.02;
        assert!((b[1] - (0.2 - off)).abs() < 1e-6, "{b:?}");
        // White at 1: peak 0.96 → 1 − 0.24²/(0.96 + 0.24 − 0.76) = 0.8691, grey stays grey.
        let w = n([1.0; 3]);
        assert!((w[0] - 0.869_09).abs() < 1e-4 && w[0] == w[2], "{w:?}");
        for t in ToneMapper::ALL {
            assert_eq!(ToneMapper::from_arg(t.arg_name()), Ok(t));
        }
        assert!(
            ToneMapper::from_arg("filmic")
                .unwrap_err()
                .contains("neutral")
        );
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
