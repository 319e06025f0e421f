//! The defaults that make the first image of any scene readable: the first view (a scene's own
//! camera wins), an environment when the scene's own lights do not light that view and the sky
//! can reach it, and lights inside an interior that nothing lights; and what `--env` names
//! ([`EnvArg`]) and chooses ([`EnvChoice`]).

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
}

/// Decides the first view of `scene` whose own lights are `lights` (without a default rig);
/// `camera` is the camera in use when the scene (or the command line) chose one.
pub fn decide(scene: &Scene, lights: &[Light], camera: Option<&Camera>, aspect: f64) -> FirstImage {
    let view = framing::first_view(scene, lights, camera, aspect);
    // An environment lights only what the sky reaches: never the inside of a closed room, where
    // it would add a light sample and a shadow ray to every path vertex and nothing to the image.
    let reaches = view.environment_reaches();
    let environment = (!view.lit && reaches).then_some(EnvPreset::Studio);
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
