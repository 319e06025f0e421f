//! The default light rig and the presets the viewer offers.

use super::{Bounds, Light, LightKind, Scene};
use glam::DVec3;

/// Light rigs the viewer can put in place of, or beside, the scene's lights.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightPreset {
    /// Key, fill and rim point lights around the scene.
    ThreePointStudio,
    /// A warm sun (directional light) and a blue sky fill from above.
    SunAndSky,
    /// A large soft light straight above the scene.
    OverheadSoftbox,
}

impl LightPreset {
    /// Every preset, for menus.
    pub const ALL: [LightPreset; 3] = [
        LightPreset::ThreePointStudio,
        LightPreset::SunAndSky,
        LightPreset::OverheadSoftbox,
    ];

    /// Name shown to users.
    pub fn name(self) -> &'static str {
        match self {
            LightPreset::ThreePointStudio => "three-point studio",
            LightPreset::SunAndSky => "sun + sky",
            LightPreset::OverheadSoftbox => "overhead softbox",
        }
    }
}

/// The default soft-shadow radius: 2% of the scene's diagonal.
pub fn default_light_radius(bounds: &Bounds) -> f32 {
    (bounds.diagonal() * 0.02) as f32
}

/// The light radius rule `render`, the benchmarks and the viewer share: how large the lights
/// are, which sets how soft their shadows are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shadows {
    /// Radius of point and spot lights in scene units; directional lights get an angular
    /// radius of 2·light_radius/diagonal radians (at most 0.5).
    pub light_radius: f32,
    /// Hard shadows: every light radius 0 (`light_radius` is kept for switching back).
    pub hard: bool,
}

impl Shadows {
    /// `light_radius`, or without one the default for a scene of `bounds`.
    pub fn new(light_radius: Option<f32>, hard: bool, bounds: &Bounds) -> Self {
        Self {
            light_radius: light_radius.unwrap_or_else(|| default_light_radius(bounds)),
            hard,
        }
    }

    /// The radius point and spot lights render with: 0 with hard shadows.
    pub fn point_radius(self) -> f32 {
        if self.hard { 0.0 } else { self.light_radius }
    }

    /// The radius a light of `kind` renders with in a scene `diagonal` across.
    pub fn radius_for(self, kind: &LightKind, diagonal: f64) -> f32 {
        let radius = self.point_radius();
        match kind {
            LightKind::Directional => (2.0 * radius as f64 / diagonal.max(1e-9)).min(0.5) as f32,
            _ => radius,
        }
    }

    /// `lights` with the radii they render with.
    pub fn apply(self, lights: &[Light], diagonal: f64) -> Vec<Light> {
        lights
            .iter()
            .map(|l| Light {
                light_radius: self.radius_for(&l.kind, diagonal),
                ..l.clone()
            })
            .collect()
    }
}

/// The rig a scene without lights gets: a point key light just above the automatic camera,
/// bright enough for an irradiance of about 1 at the middle of the scene, and a dimmer sun from
/// above-front for shape.
pub fn default_light_rig(bounds: &Bounds) -> Vec<Light> {
    let center = bounds.center();
    let size = bounds.diagonal();
    let camera = super::Camera::framing(bounds, super::AUTO_YFOV);
    let key = camera.eye + camera.up * (0.25 * size);
    let distance = (key - center).length();
    vec![
        Light {
            name: "default key".into(),
            kind: LightKind::Point,
            position: key,
            direction: (center - key).normalize_or(DVec3::NEG_Y),
            color: [1.0, 0.97, 0.92],
            intensity: (distance * distance) as f32,
            light_radius: default_light_radius(bounds),
        },
        Light {
            name: "default sun".into(),
            kind: LightKind::Directional,
            position: center,
            direction: DVec3::new(-0.4, -1.0, -0.5).normalize(),
            color: [1.0, 0.95, 0.85],
            intensity: 0.6,
            light_radius: 0.02,
        },
    ]
}

impl Scene {
    /// Other lighting (an environment, `--env`, or the lamps of a room seen from inside)
    /// replaces the default rig: a scene that only has the rig loses it; a scene with its own
    /// lights keeps them.
    pub fn drop_default_rig(&mut self) {
        if self.default_rig {
            self.lights.clear();
            self.default_rig = false;
        }
    }
}

/// The lights of a preset, sized to the scene.
pub fn preset_lights(preset: LightPreset, bounds: &Bounds) -> Vec<Light> {
    let center = bounds.center();
    let size = bounds.diagonal();
    let radius = default_light_radius(bounds);
    let point = |name: &str, offset: DVec3, color: [f32; 3], power: f64| Light {
        name: name.into(),
        kind: LightKind::Point,
        position: center + offset * size,
        direction: (-offset).normalize_or(DVec3::NEG_Y),
        color,
        intensity: (power * size * size) as f32,
        light_radius: radius,
    };
    match preset {
        LightPreset::ThreePointStudio => vec![
            point("key", DVec3::new(0.6, 0.5, 0.6), [1.0, 0.96, 0.9], 1.0),
            point("fill", DVec3::new(-0.7, 0.2, 0.5), [0.85, 0.9, 1.0], 0.3),
            point("rim", DVec3::new(0.0, 0.6, -0.8), [1.0, 1.0, 1.0], 0.6),
        ],
        LightPreset::SunAndSky => vec![
            Light {
                name: "sun".into(),
                kind: LightKind::Directional,
                position: center,
                direction: DVec3::new(-0.3, -0.8, -0.5).normalize(),
                color: [1.0, 0.93, 0.8],
                intensity: 3.0,
                light_radius: 0.01,
            },
            Light {
                name: "sky fill".into(),
                kind: LightKind::Directional,
                position: center,
                direction: DVec3::NEG_Y,
                color: [0.5, 0.65, 1.0],
                intensity: 0.5,
                light_radius: 0.5,
            },
        ],
        LightPreset::OverheadSoftbox => vec![Light {
            name: "softbox".into(),
            kind: LightKind::Spot {
                inner: 0.6,
                outer: 1.2,
            },
            position: center + DVec3::Y * (0.6 * size),
            direction: DVec3::NEG_Y,
            color: [1.0, 1.0, 1.0],
            intensity: (1.5 * size * size) as f32,
            light_radius: (0.15 * size) as f32,
        }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Bounds {
        Bounds {
            min: DVec3::ZERO,
            max: DVec3::ONE,
        }
    }

    #[test]
    fn default_rig_scales_with_the_scene() {
        let small = default_light_rig(&unit_box());
        let big = default_light_rig(&Bounds {
            min: DVec3::ZERO,
            max: DVec3::splat(100.0),
        });
        assert_eq!(small.len(), big.len());
        let ratio = big[0].intensity / small[0].intensity;
        assert!((ratio - 10_000.0).abs() < 1.0, "{ratio}");
        assert!(big[0].light_radius > small[0].light_radius);
    }

    #[test]
    fn directional_lights_get_an_angular_radius() {
        let sun = Light {
            name: "sun".into(),
            kind: LightKind::Directional,
            position: glam::DVec3::ZERO,
            direction: glam::DVec3::NEG_Y,
            color: [1.0; 3],
            intensity: 1.0,
            light_radius: 0.0,
        };
        let shadows = Shadows {
            light_radius: 1.0,
            hard: false,
        };
        let l = shadows.apply(&[sun], 100.0);
        assert!((l[0].light_radius - 0.02).abs() < 1e-6);
    }

    #[test]
    fn an_environment_replaces_only_the_default_rig() {
        let rig = default_light_rig(&unit_box());
        let mut lit_by_rig = Scene {
            lights: rig.clone(),
            default_rig: true,
            ..Scene::default()
        };
        lit_by_rig.drop_default_rig();
        assert!(lit_by_rig.lights.is_empty() && !lit_by_rig.default_rig);
        let mut own_lights = Scene {
            lights: rig.clone(),
            ..Scene::default()
        };
        own_lights.drop_default_rig();
        assert_eq!(own_lights.lights, rig);
    }

    #[test]
    fn presets_place_lights_with_positive_power() {
        for preset in LightPreset::ALL {
            let lights = preset_lights(preset, &unit_box());
            assert!(!lights.is_empty(), "{}", preset.name());
            for l in lights {
                assert!(l.intensity > 0.0 && l.direction.is_normalized(), "{l:?}");
            }
        }
    }
}
