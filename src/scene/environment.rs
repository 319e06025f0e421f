//! The environment light: an equirectangular (latitude-longitude) radiance image around the
//! scene, with the table that importance-samples it by luminance × sin θ.
//!
//! Directions: row 0 of the image is straight up (+Y), the last row straight down; the centre
//! column looks along −Z and u grows towards +X (seen from inside, the image is not mirrored).
//! With φ = 2π(u − ½) and θ = πv, the direction is (sin θ sin φ, cos θ, −sin θ cos φ).

use super::limits;
use glam::Vec3;
use std::f32::consts::PI;
use std::path::Path;

/// Environment images wider than this are box-filtered down by halves on load.
pub const MAX_ENV_WIDTH: u32 = 4096;

/// Checks an environment image's size (from its header) against [`limits::MAX_ENV_SIDE`] and
/// [`limits::MAX_ENV_PIXELS`].
fn check_env_size(width: u64, height: u64) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err("the image is empty".into());
    }
    let side = limits::MAX_ENV_SIDE as u64;
    if width > side || height > side || width * height > limits::MAX_ENV_PIXELS {
        return Err(format!(
            "{width}×{height} pixels is more than the limit for environment images ({side} per \
             side, {} pixels)",
            limits::MAX_ENV_PIXELS
        ));
    }
    Ok(())
}

/// Makes every texel finite and within 0..=[`limits::MAX_INTENSITY`] (non-finite values become
/// 0, negative ones 0, larger ones the limit), so that a scaled texel, its luminance sums and
/// the film's sums of samples stay finite in f32; says what changed, if anything.
fn clamp_radiance(texels: &mut [[f32; 3]]) -> Option<String> {
    let (mut nonfinite, mut negative, mut huge) = (0u64, 0u64, 0u64);
    for v in texels.iter_mut().flatten() {
        if !v.is_finite() {
            nonfinite += 1;
            *v = 0.0;
        } else if *v < 0.0 {
            negative += 1;
            *v = 0.0;
        } else if *v > limits::MAX_INTENSITY {
            huge += 1;
            *v = limits::MAX_INTENSITY;
        }
    }
    let parts: Vec<String> = [
        (nonfinite, "non-finite (set to 0)".to_string()),
        (negative, "negative (set to 0)".to_string()),
        (
            huge,
            format!("above {:e} (clamped to it)", limits::MAX_INTENSITY),
        ),
    ]
    .into_iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} values {what}"))
    .collect();
    (!parts.is_empty()).then(|| format!("radiance clamped: {}", parts.join(", ")))
}

/// An environment image in linear radiance.
#[derive(Clone)]
pub struct EnvMap {
    /// File name, for messages.
    pub name: String,
    /// Width in texels (the full circle of longitude).
    pub width: u32,
    /// Height in texels (pole to pole).
    pub height: u32,
    /// Linear RGB radiance, row 0 at the top.
    pub texels: Vec<[f32; 3]>,
}

impl std::fmt::Debug for EnvMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "EnvMap({:?}, {}x{})", self.name, self.width, self.height)
    }
}

/// The importance-sampling table of an [`EnvMap`]: a 2D CDF over f = luminance × sin θ per
/// texel (the marginal over rows, then one conditional per row), each ending at exactly 1.
#[derive(Clone, Debug, Default)]
pub struct EnvSampling {
    /// Cumulative row probabilities (`height` entries).
    pub marginal: Vec<f32>,
    /// Cumulative column probabilities of each row (`width × height` entries).
    pub conditional: Vec<f32>,
    /// W·H / (Σf · 2π²): a texel's solid-angle pdf is `f × norm / sin θ`.
    pub norm: f32,
    /// Mean luminance over the sphere (solid-angle weighted), for the light selection table.
    pub mean_luminance: f32,
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

impl EnvMap {
    /// Loads a `.hdr` (Radiance RGBE) or `.exr` image. Non-finite and negative values become 0
    /// and values above [`limits::MAX_INTENSITY`] that limit, with one warning; images wider
    /// than [`MAX_ENV_WIDTH`] are halved until they fit.
    pub fn load(path: &Path) -> Result<Self, String> {
        let (map, warning) = Self::load_checked(path)?;
        if let Some(w) = warning {
            log::warn!("{w}");
        }
        Ok(map)
    }

    /// [`EnvMap::load`] returning its warning (texels changed) instead of logging it.
    pub fn load_checked(path: &Path) -> Result<(Self, Option<String>), String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
            return Err(format!("{}: not a regular file", path.display()));
        }
        let too_big = |e: String| format!("{}: {e}", path.display());
        let (width, height, texels) = match ext.as_str() {
            "exr" => {
                // Check every layer's size from the header before any pixel is allocated.
                let layers =
                    crate::image_io::exr_layer_sizes(path).map_err(|e| format!("{e:#}"))?;
                for (w, h, chunks) in layers {
                    check_env_size(w, h).map_err(too_big)?;
                    if chunks > limits::MAX_ENV_PIXELS / 16 {
                        return Err(too_big(format!("{chunks} chunks is too many")));
                    }
                }
                crate::image_io::read_exr(path).map_err(|e| format!("{e:#}"))?
            }
            "hdr" => {
                let cannot = |e: image::ImageError| {
                    format!("{}: cannot read the HDR image: {e}", path.display())
                };
                let open = || image::ImageReader::open(path).map_err(|e| cannot(e.into()));
                let (w, h) = open()?.into_dimensions().map_err(cannot)?;
                check_env_size(w as u64, h as u64).map_err(too_big)?;
                let mut reader = open()?;
                let mut caps = image::Limits::default();
                caps.max_alloc = Some(limits::MAX_ENV_PIXELS * 16);
                reader.limits(caps);
                let image = reader.decode().map_err(cannot)?.into_rgb32f();
                let (w, h) = image.dimensions();
                let texels = image.pixels().map(|p| p.0).collect();
                (w, h, texels)
            }
            _ => {
                return Err(format!(
                    "{}: an environment map must be a .hdr or .exr file",
                    path.display()
                ));
            }
        };
        if width == 0 || height == 0 {
            return Err(format!("{}: the image is empty", path.display()));
        }
        let mut texels = texels;
        let warning = clamp_radiance(&mut texels).map(|c| format!("{}: {c}", path.display()));
        let mut map = Self {
            name: path.display().to_string(),
            width,
            height,
            texels,
        };
        while map.width > MAX_ENV_WIDTH {
            map = map.halved();
        }
        Ok((map, warning))
    }

    /// A map of one radiance everywhere (`height` rows so that sin θ shapes the sampling).
    pub fn uniform(radiance: [f32; 3], width: u32, height: u32) -> Self {
        Self {
            name: "uniform".into(),
            width,
            height,
            texels: vec![radiance; (width * height) as usize],
        }
    }

    fn halved(&self) -> Self {
        let w = (self.width / 2).max(1);
        let h = (self.height / 2).max(1);
        let mut texels = vec![[0.0f32; 3]; (w * h) as usize];
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0.0f32; 3];
                let mut n = 0.0;
                for sy in (2 * y)..(2 * y + 2).min(self.height) {
                    for sx in (2 * x)..(2 * x + 2).min(self.width) {
                        let t = self.texels[(sy * self.width + sx) as usize];
                        for c in 0..3 {
                            sum[c] += t[c];
                        }
                        n += 1.0;
                    }
                }
                texels[(y * w + x) as usize] = sum.map(|s| s / n);
            }
        }
        Self {
            name: self.name.clone(),
            width: w,
            height: h,
            texels,
        }
    }

    /// The sampling table.
    pub fn sampling(&self) -> EnvSampling {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut marginal = Vec::with_capacity(h);
        let mut conditional = Vec::with_capacity(w * h);
        let mut rows = Vec::with_capacity(h);
        let mut total = 0.0f64;
        let mut solid = 0.0f64;
        for y in 0..h {
            let sin = ((y as f64 + 0.5) / h as f64 * std::f64::consts::PI).sin();
            let mut acc = 0.0f64;
            let start = conditional.len();
            for x in 0..w {
                let l = luminance(self.texels[y * w + x]) as f64;
                acc += l * sin;
                conditional.push(acc);
            }
            for (i, c) in conditional[start..].iter_mut().enumerate() {
                // A black row is never picked; keep its table valid anyway.
                *c = if acc > 0.0 {
                    *c / acc
                } else {
                    (i + 1) as f64 / w as f64
                };
            }
            conditional[start + w - 1] = 1.0;
            rows.push(acc);
            total += acc;
            solid += sin * w as f64;
        }
        let mut acc = 0.0;
        for r in &rows {
            acc += r;
            marginal.push(if total > 0.0 { acc / total } else { 0.0 });
        }
        if let Some(last) = marginal.last_mut() {
            *last = 1.0;
        }
        let norm = if total > 0.0 {
            (w * h) as f64 / (total * 2.0 * std::f64::consts::PI * std::f64::consts::PI)
        } else {
            0.0
        };
        EnvSampling {
            marginal: marginal.into_iter().map(|v| v as f32).collect(),
            conditional: conditional.into_iter().map(|v| v as f32).collect(),
            norm: norm as f32,
            mean_luminance: if solid > 0.0 {
                (total / solid) as f32
            } else {
                0.0
            },
        }
    }

    /// The map coordinates (u, v) in [0, 1]² of a unit direction in the map's frame.
    pub fn uv_of(d: Vec3) -> (f32, f32) {
        let u = d.x.atan2(-d.z) / (2.0 * PI) + 0.5;
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        (u.rem_euclid(1.0), v)
    }

    /// The unit direction of map coordinates (u, v).
    pub fn direction(u: f32, v: f32) -> Vec3 {
        let phi = 2.0 * PI * (u - 0.5);
        let theta = PI * v;
        Vec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        )
    }

    /// The map box-filtered to at most `width` × `height` texels (whole blocks of texels
    /// averaged): enough for irradiance, which is smooth.
    pub fn coarse(&self, width: u32, height: u32) -> EnvMap {
        let (bx, by) = (
            self.width.div_ceil(width.max(1)) as usize,
            self.height.div_ceil(height.max(1)) as usize,
        );
        let (w, h) = (self.width as usize, self.height as usize);
        let (cw, ch) = (w.div_ceil(bx), h.div_ceil(by));
        let mut texels = vec![[0.0f32; 3]; cw * ch];
        for (i, t) in texels.iter_mut().enumerate() {
            let (cx, cy) = (i % cw, i / cw);
            let mut n = 0.0;
            for y in cy * by..((cy + 1) * by).min(h) {
                for x in cx * bx..((cx + 1) * bx).min(w) {
                    let p = self.texels[y * w + x];
                    for c in 0..3 {
                        t[c] += p[c];
                    }
                    n += 1.0;
                }
            }
            *t = t.map(|v| v / n);
        }
        EnvMap {
            name: self.name.clone(),
            width: cw as u32,
            height: ch as u32,
            texels,
        }
    }

    /// The luminance of the irradiance on a surface facing `normal` (unit, world space) from
    /// the map turned by `rotation_degrees` about +Y (as `--env-rotation` turns it): what an
    /// incident light meter there reads, its dome towards `normal`. A uniform map of radiance
    /// L gives πL.
    pub fn irradiance(&self, normal: glam::DVec3, rotation_degrees: f32) -> f64 {
        let (s, c) = (rotation_degrees as f64).to_radians().sin_cos();
        // Into the map's frame: undo the rotation about +Y (as kernels/shared/env.h does).
        let n = glam::DVec3::new(
            c * normal.x - s * normal.z,
            normal.y,
            s * normal.x + c * normal.z,
        );
        let (w, h) = (self.width as usize, self.height as usize);
        let texel_solid =
            (2.0 * std::f64::consts::PI / w as f64) * (std::f64::consts::PI / h as f64);
        let mut e = 0.0;
        for y in 0..h {
            let v = (y as f32 + 0.5) / h as f32;
            let sin = (std::f64::consts::PI * v as f64).sin();
            for x in 0..w {
                let d = Self::direction((x as f32 + 0.5) / w as f32, v).as_dvec3();
                let cos = d.dot(n);
                if cos > 0.0 {
                    e += luminance(self.texels[y * w + x]) as f64 * cos * sin * texel_solid;
                }
            }
        }
        e
    }

    /// The texel a direction (in the map's frame) falls into.
    pub fn texel_of(&self, d: Vec3) -> (u32, u32) {
        let (u, v) = Self::uv_of(d);
        let x = ((u * self.width as f32) as u32).min(self.width - 1);
        let y = ((v * self.height as f32) as u32).min(self.height - 1);
        (x, y)
    }

    /// The solid-angle pdf of sampling direction `d` (map frame) with `table`, as the kernel
    /// computes it: f(texel) × norm / sin θ, with f = luminance × sin θ(texel centre).
    pub fn pdf(&self, table: &EnvSampling, d: Vec3) -> f32 {
        let (x, y) = self.texel_of(d);
        let sin_centre = ((y as f32 + 0.5) / self.height as f32 * PI).sin();
        let sin = (1.0 - d.y * d.y).max(0.0).sqrt();
        if sin <= 0.0 {
            return 0.0;
        }
        let l = luminance(self.texels[(y * self.width + x) as usize]);
        l * sin_centre * table.norm / sin
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_and_coordinates_invert() {
        for &(u, v) in &[(0.5, 0.5), (0.75, 0.3), (0.1, 0.9), (0.99, 0.01)] {
            let d = EnvMap::direction(u, v);
            let (u2, v2) = EnvMap::uv_of(d);
            assert!((u - u2).abs() < 1e-5 && (v - v2).abs() < 1e-5, "{u},{v}");
        }
        assert!((EnvMap::direction(0.5, 0.5) - Vec3::NEG_Z).length() < 1e-6);
        assert!((EnvMap::direction(0.75, 0.5) - Vec3::X).length() < 1e-6);
        assert!((EnvMap::direction(0.2, 0.0) - Vec3::Y).length() < 1e-6);
    }

    /// A uniform map gives πL on a surface facing any way; a map bright in its upper half
    /// alone gives a surface facing up (the sky) all of it and one facing down none, and
    /// turning the map moves the bright half where the meter faces.
    #[test]
    fn irradiance_is_that_of_the_dome_the_meter_faces() {
        use glam::DVec3;
        let uniform = EnvMap::uniform([2.0; 3], 64, 32);
        for n in [
            DVec3::Y,
            DVec3::NEG_Z,
            DVec3::new(1.0, 1.0, 0.0).normalize(),
        ] {
            let e = uniform.irradiance(n, 30.0);
            assert!((e / (2.0 * PI as f64) - 1.0).abs() < 2e-3, "{n}: {e}");
        }
        let mut sky = EnvMap::uniform([0.0; 3], 64, 32);
        for t in &mut sky.texels[..64 * 16] {
            *t = [1.0; 3];
        }
        assert!((sky.irradiance(DVec3::Y, 0.0) / PI as f64 - 1.0).abs() < 2e-3);
        assert!(sky.irradiance(DVec3::NEG_Y, 0.0) < 1e-9);
        // A map bright towards its u = 0.75 column (+x in its frame) alone.
        let mut side = EnvMap::uniform([0.0; 3], 64, 32);
        for (i, t) in side.texels.iter_mut().enumerate() {
            if (40..56).contains(&(i % 64)) {
                *t = [1.0; 3];
            }
        }
        let (east, west) = (
            side.irradiance(DVec3::X, 0.0),
            side.irradiance(DVec3::NEG_X, 0.0),
        );
        assert!(east > 0.1 && west < 1e-9, "{east} {west}");
        // Turned by 180° about +y, the bright side is at −x.
        let turned = side.irradiance(DVec3::NEG_X, 180.0);
        assert!((turned / east - 1.0).abs() < 1e-3, "{turned} {east}");
        // The coarse map (blocks of 4 × 4 texels) gives the same light.
        let coarse = side.coarse(16, 8);
        assert_eq!((coarse.width, coarse.height), (16, 8));
        assert!((coarse.irradiance(DVec3::X, 0.0) / east - 1.0).abs() < 0.02);
    }

    #[test]
    fn the_pdf_integrates_to_one() {
        let mut map = EnvMap::uniform([1.0; 3], 16, 8);
        map.texels[37] = [50.0, 20.0, 5.0];
        let table = map.sampling();
        // Integrate over the sphere by texels: pdf × solid angle of each texel.
        let mut sum = 0.0f64;
        let n = 64;
        for j in 0..n {
            for i in 0..2 * n {
                let u = (i as f32 + 0.5) / (2 * n) as f32;
                let v = (j as f32 + 0.5) / n as f32;
                let d = EnvMap::direction(u, v);
                let dw = (2.0 * PI / (2 * n) as f32) * (PI / n as f32) * (PI * v).sin();
                sum += (map.pdf(&table, d) * dw) as f64;
            }
        }
        assert!((sum - 1.0).abs() < 0.02, "∫pdf = {sum}");
        assert_eq!(*table.marginal.last().unwrap(), 1.0);
    }
}
