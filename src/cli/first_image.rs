//! The defaults that make the first image of any scene readable: the first view (a scene's own
//! camera wins), an environment when the scene's own lights do not light that view, or leave
//! its metal and glass reflecting a black world, and the sky can reach it; lights inside an
//! interior that nothing lights; the light an incident meter reads at the subject (what the
//! exposure is set from); and what `--env` names ([`EnvArg`]) and chooses ([`EnvChoice`]).

/// An environment added to a view its own lights light (for its metal and glass) is a fill:
/// scaled so that a white diffuse surface under it shows this share of what the scene's key
/// light gives it. As much as the key: a glTF viewer adds its environment (radiance about 1)
/// and the scene's lights each at its own level, and IridescenceSuzanne's sun of 3 lux gives a
/// white surface about what its environment does (at one stop below, its metal and glass
/// read a stop darker than the Khronos screenshot shows them).
pub const ENV_FILL: f64 = 1.0;

use crate::scene::framing::{self, FirstView};
use crate::scene::{Camera, EnvMap, EnvPreset, Light, Scene};

/// What `--env` names.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvArg {
    /// No `--env`: decided per scene.
    Auto,
    /// `--env none`: no environment.
    Off,
    /// A bundled environment.
    Preset(EnvPreset),
    /// An image file or a colour (parsed later).
    Other(String),
}

impl EnvArg {
    /// Reads the `--env` value.
    pub fn parse(arg: Option<&str>) -> Self {
        match arg {
            None => EnvArg::Auto,
            Some("none") => EnvArg::Off,
            Some(name) => EnvPreset::from_name(name)
                .map(EnvArg::Preset)
                .unwrap_or_else(|| EnvArg::Other(name.to_string())),
        }
    }
}

/// What `--env` asked for.
pub enum EnvChoice {
    /// A uniform radiance.
    Color([f32; 3]),
    /// An environment image.
    Map(EnvMap),
}

/// The defaults chosen for a scene.
pub struct FirstImage {
    /// The first-view analysis (from the chosen camera).
    pub view: FirstView,
    /// The camera to use when the scene has none of its own (and none was asked for).
    pub camera: Option<Camera>,
    /// The environment the rule asks for (`None`: the scene's lights light the view).
    pub environment: Option<EnvPreset>,
    /// Lights to add: an interior that neither its lights nor the environment reach.
    pub lights: Vec<Light>,
    /// Whether `environment` is a fill beside the scene's own lights (for metal and glass),
    /// scaled by [`ENV_FILL`], rather than the light of a view they leave dark.
    pub fill: bool,
}

impl FirstImage {
    /// The radiance of a white diffuse surface at the subject (an incident meter's reading,
    /// over π): the key irradiance of the scene's lights when they light the view, plus a
    /// white surface's radiance under the environment when it reaches the view
    /// (`env_radiance`: its mean radiance, as it is used). `None` for an interior, whose light
    /// comes mostly by bounces the probe does not follow, and where nothing is measured.
    pub fn white_radiance(&self, env_radiance: f64) -> Option<f64> {
        let v = &self.view;
        let key = if v.lit {
            v.key_irradiance / std::f64::consts::PI
        } else {
            0.0
        };
        let env = if v.environment_reaches() {
            env_radiance
        } else {
            0.0
        };
        let white = key + env;
        (!v.interior && white.is_finite() && white > 0.0).then_some(white)
    }

    /// The factor on the environment's intensity: for a fill, the one that brings a white
    /// surface under it (`env_radiance` at factor 1) to [`ENV_FILL`] of the key light's.
    pub fn env_scale(&self, env_radiance: f64) -> f64 {
        let key = self.view.key_irradiance / std::f64::consts::PI;
        if self.fill && env_radiance > 0.0 && key > 0.0 {
            ENV_FILL * key / env_radiance
        } else {
            1.0
        }
    }
}

/// Decides the first view of `scene` whose own lights are `lights` (without a default rig);
/// `camera` is the camera in use when the scene (or the command line) chose one.
pub fn decide(scene: &Scene, lights: &[Light], camera: Option<&Camera>, aspect: f64) -> FirstImage {
    let view = framing::first_view(scene, lights, camera, aspect);
    // An environment lights only what the sky reaches: never the inside of a closed room, where
    // it would add a light sample and a shadow ray to every path vertex and nothing to the image.
    let reaches = view.environment_reaches();
    // Metal and glass that the scene's own lights and walls do not surround reflect the world:
    // an environment (as a fill) shows what they are. A room lit by its own lamps keeps them.
    let fill = view.lit && reaches && !view.interior && view.shine_needs_environment();
    let environment = ((!view.lit && reaches) || fill).then_some(EnvPreset::Neutral);
    // Inside a room, daylight through the windows is not enough: add a ceiling lamp and a light
    // at the camera unless the scene's own lights reach the view; so too in a closed room
    // without lights of its own. A closed room with lights of its own keeps them alone, lit
    // in part or not at all (a furnace, an emitter turned away): their light is the scene's.
    let own_light = !lights.is_empty() || scene.materials.iter().any(|m| m.is_emissive());
    let dark_and_closed = !reaches && !own_light;
    let added = if !view.lit && (view.interior || dark_and_closed) {
        framing::interior_lights(&view)
    } else {
        Vec::new()
    };
    FirstImage {
        camera: camera.is_none().then(|| view.camera.clone()),
        environment,
        lights: added,
        view,
        fill,
    }
}

/// The environment to use: the one asked for, else the one the first image needs.
pub fn environment(arg: &EnvArg, needed: Option<EnvPreset>) -> Option<EnvChoice> {
    match arg {
        EnvArg::Auto => needed.map(|p| EnvChoice::Map(p.load())),
        EnvArg::Preset(p) => Some(EnvChoice::Map(p.load())),
        EnvArg::Off | EnvArg::Other(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn env_names_parse() {
        assert_eq!(EnvArg::parse(None), EnvArg::Auto);
        assert_eq!(EnvArg::parse(Some("none")), EnvArg::Off);
        assert_eq!(
            EnvArg::parse(Some("outdoor")),
            EnvArg::Preset(EnvPreset::Outdoor)
        );
        assert_eq!(
            EnvArg::parse(Some("sky.hdr")),
            EnvArg::Other("sky.hdr".into())
        );
    }
}
