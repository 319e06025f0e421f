//! The environments bundled in the binary: a neutral room made here, and two CC0 Poly Haven
//! HDRIs (`assets/env/`; see the README there). The neutral room is what a scene whose own
//! lights do not light the view is shown in, and the fill for metal and glass they do not
//! surround.

use super::EnvMap;
use glam::Vec3;

/// A bundled environment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvPreset {
    /// A neutral room ([`neutral_room`]): grey walls and floor, three soft lamps.
    Neutral,
    /// A small photo studio: white floor, softboxes.
    Studio,
    /// A meadow under a clear sky.
    Outdoor,
}

impl EnvPreset {
    /// Every preset, for menus.
    pub const ALL: [EnvPreset; 3] = [EnvPreset::Neutral, EnvPreset::Studio, EnvPreset::Outdoor];

    /// The name `--env` takes and the overlay shows.
    pub fn name(self) -> &'static str {
        match self {
            EnvPreset::Neutral => "neutral",
            EnvPreset::Studio => "studio",
            EnvPreset::Outdoor => "outdoor",
        }
    }

    /// The preset called `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The decoded (or, for the neutral room, computed) map.
    pub fn load(self) -> EnvMap {
        let bytes: &[u8] = match self {
            EnvPreset::Neutral => return neutral_room(512, 256),
            EnvPreset::Studio => include_bytes!("../../assets/env/studio.hdr"),
            EnvPreset::Outdoor => include_bytes!("../../assets/env/outdoor.hdr"),
        };
        let image = image::load_from_memory_with_format(bytes, image::ImageFormat::Hdr)
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

/// A lamp of the neutral room: its direction (map frame, +Y up, glTF's front +Z), its angular
/// radius in radians and its radiance.
const NEUTRAL_LAMPS: [([f32; 3], f32, f32); 3] = [
    // The key: above, in front and to the left of a camera on glTF's front.
    ([-0.5, 0.65, 0.6], 0.4, 4.0),
    // A rim behind and to the right.
    ([0.7, 0.3, -0.6], 0.3, 3.0),
    // A side light low on the right.
    ([0.9, 0.1, 0.4], 0.3, 2.0),
];

/// A neutral room of `width` × `height` texels, computed: what a glTF viewer lights a model
/// with (the Khronos Sample Viewer's default is a neutral, calibrated room), so that metal and
/// glass mirror a world that is lit on every side. Grey walls of radiance 0.55 at the horizon
/// rising to 0.8 overhead, a floor of 0.35 (which gives metal a horizon to read its shape
/// by), blended over ±3° of elevation, and three soft round lamps ([`NEUTRAL_LAMPS`]) for
/// highlights and a lit side. Seen directly, the walls show at about half a white surface's
/// brightness under it, so that white labels stand out from them. (The studio HDRI is black
/// above its horizon but for two lamps: a metal sphere in it, seen from glTF's front, reads
/// near black.)
pub fn neutral_room(width: u32, height: u32) -> EnvMap {
    // Each lamp's centre, the cosines of its radius and of 80 % of it (a soft edge: full inside
    // the inner cone, none outside the radius), and its radiance.
    let lamps =
        NEUTRAL_LAMPS.map(|(d, r, l)| (Vec3::from(d).normalize(), r.cos(), (0.8 * r).cos(), l));
    let smooth = |e0: f32, e1: f32, x: f32| {
        let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    let horizon = 3f32.to_radians().sin();
    let texels = (0..width * height)
        .map(|i| {
            let u = ((i % width) as f32 + 0.5) / width as f32;
            let v = ((i / width) as f32 + 0.5) / height as f32;
            let d = EnvMap::direction(u, v);
            let walls = 0.55 + 0.25 * d.y.max(0.0);
            let mut l = 0.35 + (walls - 0.35) * smooth(-horizon, horizon, d.y);
            for (centre, cos_radius, cos_inner, radiance) in lamps {
                l += radiance * smooth(cos_radius, cos_inner, d.dot(centre));
            }
            [l; 3]
        })
        .collect();
    EnvMap {
        name: EnvPreset::Neutral.name().into(),
        width,
        height,
        texels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every direction above the neutral room's horizon is at least the walls' 0.55 (a mirror
    /// shows a lit world whichever way it faces), below it at least the floor's 0.35, and the
    /// lamps are there: the brightest texel is the key's radiance over the walls'.
    #[test]
    fn the_neutral_room_is_lit_on_every_side() {
        let map = neutral_room(128, 64);
        let mut brightest = 0.0f32;
        for (i, t) in map.texels.iter().enumerate() {
            let v = ((i as u32 / map.width) as f32 + 0.5) / map.height as f32;
            let up = EnvMap::direction(0.5, v).y;
            let least = if up > 0.06 { 0.55 } else { 0.35 };
            assert!(
                t[0] >= least - 1e-5 && t[0] == t[1] && t[1] == t[2],
                "{i}: {t:?}"
            );
            brightest = brightest.max(t[0]);
        }
        assert!(brightest > 4.6 && brightest < 4.8, "{brightest}");
    }

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
