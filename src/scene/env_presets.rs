//! The environments bundled in the binary (`assets/env/`, CC0 Poly Haven HDRIs; see the README
//! there): what a scene whose own lights do not light the view is shown in.

use super::EnvMap;

/// A bundled environment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvPreset {
    /// A small photo studio: white floor, softboxes.
    Studio,
    /// A meadow under a clear sky.
    Outdoor,
}

impl EnvPreset {
    /// Every preset, for menus.
    pub const ALL: [EnvPreset; 2] = [EnvPreset::Studio, EnvPreset::Outdoor];

    /// The name `--env` takes and the overlay shows.
    pub fn name(self) -> &'static str {
        match self {
            EnvPreset::Studio => "studio",
            EnvPreset::Outdoor => "outdoor",
        }
    }

    /// The preset called `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    fn bytes(self) -> &'static [u8] {
        match self {
            EnvPreset::Studio => include_bytes!("../../assets/env/studio.hdr"),
            EnvPreset::Outdoor => include_bytes!("../../assets/env/outdoor.hdr"),
        }
    }

    /// The decoded map.
    pub fn load(self) -> EnvMap {
        let image = image::load_from_memory_with_format(self.bytes(), image::ImageFormat::Hdr)
            .expect("the bundled environments are valid Radiance files")
            .into_rgb32f();
        let (width, height) = image.dimensions();
        EnvMap {
            name: self.name().into(),
            width,
            height,
            texels: image.pixels().map(|p| p.0).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_environments_decode_and_light() {
        for p in EnvPreset::ALL {
            let map = p.load();
            assert_eq!((map.width, map.height), (512, 256), "{}", p.name());
            let mean = map.sampling().mean_luminance;
            assert!(mean > 0.1 && mean < 10.0, "{}: {mean}", p.name());
            assert!(
                map.texels
                    .iter()
                    .flatten()
                    .all(|v| v.is_finite() && *v >= 0.0)
            );
            assert_eq!(EnvPreset::from_name(p.name()), Some(p));
        }
    }
}
