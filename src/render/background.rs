//! What the image shows where the camera ray escapes (`--background`): the environment, nothing
//! (alpha 0), or a flat color. Lighting never changes: the environment still lights the scene;
//! only escaped camera rays are cut out ([`super::RenderSettings::cutout`]) and the film keeps
//! each pixel's coverage (the share of its samples whose camera ray hit, [`super::Renderer::coverage`]).
//!
//! With a cutout the film holds premultiplied radiance (escaped samples add 0). The PNG is made
//! from the straight color (radiance / coverage) with the coverage as alpha (transparent), or
//! composited over the color in linear light (COLOR); the EXR keeps the premultiplied radiance
//! with the coverage as its A channel either way.

use super::tonemap::srgb_encode;
use std::str::FromStr;

/// What escaped camera rays show.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Background {
    /// The environment (map, color or black sky) as it lights the scene.
    #[default]
    Env,
    /// Nothing: alpha 0.
    Transparent,
    /// A flat display color (sRGB-encoded R,G,B in [0, 1]).
    Color([f32; 3]),
}

impl FromStr for Background {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "env" => return Ok(Background::Env),
            "transparent" => return Ok(Background::Transparent),
            _ => {}
        }
        let bad = || format!("'{s}' is not env, transparent or a color R,G,B (0..1) / gray value");
        let parts: Vec<f32> = s
            .split(',')
            .map(|p| p.trim().parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        let c = match parts.as_slice() {
            [v] => [*v; 3],
            [r, g, b] => [*r, *g, *b],
            _ => return Err(bad()),
        };
        if c.iter().any(|v| !(0.0..=1.0).contains(v)) {
            return Err(format!(
                "'{s}': background color values must be within 0..1"
            ));
        }
        Ok(Background::Color(c))
    }
}

impl Background {
    /// Whether escaped camera rays are cut out of the film.
    pub fn cutout(self) -> bool {
        self != Background::Env
    }

    /// Name for summaries and the overlay.
    pub fn name(self) -> String {
        match self {
            Background::Env => "env".into(),
            Background::Transparent => "transparent".into(),
            Background::Color(c) => format!("{},{},{}", c[0], c[1], c[2]),
        }
    }
}

/// The straight (unpremultiplied) color of a premultiplied film: radiance / coverage, black
/// where nothing was hit.
pub fn unpremultiply(image: &[[f32; 3]], coverage: &[f32]) -> Vec<[f32; 3]> {
    image
        .iter()
        .zip(coverage)
        .map(|(p, &a)| if a > 0.0 { p.map(|v| v / a) } else { [0.0; 3] })
        .collect()
}

fn srgb_decode(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Applies `background` to RGBA8 pixels tone-mapped from the straight color: transparent sets
/// alpha to the coverage; a color is blended in behind, in linear light, by 1 − coverage.
pub fn apply(rgba: &mut [u8], coverage: &[f32], background: Background) {
    match background {
        Background::Env => {}
        Background::Transparent => {
            for (px, &a) in rgba.chunks_exact_mut(4).zip(coverage) {
                px[3] = (a.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
            }
        }
        Background::Color(c) => {
            let bg = c.map(srgb_decode);
            for (px, &a) in rgba.chunks_exact_mut(4).zip(coverage) {
                let a = a.clamp(0.0, 1.0);
                for i in 0..3 {
                    let fg = srgb_decode(px[i] as f32 / 255.0);
                    let v = fg * a + bg[i] * (1.0 - a);
                    px[i] = (srgb_encode(v) * 255.0 + 0.5) as u8;
                }
                px[3] = 255;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_env_transparent_and_colors() {
        assert_eq!("env".parse(), Ok(Background::Env));
        assert_eq!("transparent".parse(), Ok(Background::Transparent));
        assert_eq!("1".parse(), Ok(Background::Color([1.0; 3])));
        assert_eq!(
            "0.2, 0.4,0.6".parse(),
            Ok(Background::Color([0.2, 0.4, 0.6]))
        );
        for bad in ["", "blue", "1,2", "0,0,2", "nan", "-0.1"] {
            assert!(bad.parse::<Background>().is_err(), "{bad}");
        }
        assert!(!Background::Env.cutout() && Background::Transparent.cutout());
    }

    #[test]
    fn transparent_sets_alpha_and_colors_fill_uncovered_pixels() {
        let coverage = [1.0, 0.0, 0.5];
        let px = [200, 100, 50, 255, 0, 0, 0, 255, 255, 255, 255, 255];
        let mut t = px;
        apply(&mut t, &coverage, Background::Transparent);
        assert_eq!([t[3], t[7], t[11]], [255, 0, 128]);
        assert_eq!(t[..3], px[..3]);
        let mut c = px;
        apply(&mut c, &coverage, Background::Color([0.0, 1.0, 0.0]));
        // Covered: unchanged; uncovered: the color exactly; half: a linear-light blend.
        assert_eq!(c[..4], px[..4]);
        assert_eq!(c[4..8], [0, 255, 0, 255]);
        assert_eq!(c[9], 255);
        assert!((180..=190).contains(&c[8]), "{}", c[8]);
        let s = unpremultiply(&[[0.5; 3], [0.0; 3]], &[0.5, 0.0]);
        assert_eq!(s, vec![[1.0; 3], [0.0; 3]]);
    }
}
