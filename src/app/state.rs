//! What the overlay controls, and how it maps onto the renderer: render settings, the light rig
//! with its light radius, exposure and tone mapping.

use super::exposure::HeldExposure;
use crate::render::RenderSettings;
use crate::render::background::Background;
use crate::render::exposure::ExposureMode;
use crate::render::tonemap::ToneMapper;
use crate::scene::framing::light_near_camera;
use crate::scene::{
    Bounds, Camera, Light, LightKind, LightPreset, Shadows, default_light_radius, preset_lights,
};
use glam::DVec3;

/// How far the camera's subject is: the bounds' middle along the view, or a quarter of the
/// scene's diagonal when that is behind or very near (inside a room).
pub fn subject_distance(camera: &Camera, bounds: &Bounds) -> f64 {
    let size = bounds.diagonal().max(1e-6);
    let along = (bounds.center() - camera.eye).dot(camera.forward);
    if along > 0.1 * size {
        along.min(2.0 * size)
    } else {
        0.25 * size
    }
}

/// Kinds of light the user can add.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NewLight {
    /// A point light (follows the light radius).
    Point,
    /// A spot light pointing down.
    Spot,
    /// A directional (sun) light.
    Directional,
    /// A sphere (area) light: a point light with its own, larger radius.
    Sphere,
}

impl NewLight {
    /// Every kind, for the overlay's buttons.
    pub const ALL: [NewLight; 4] = [
        NewLight::Point,
        NewLight::Spot,
        NewLight::Directional,
        NewLight::Sphere,
    ];

    /// Name shown to users.
    pub fn name(self) -> &'static str {
        match self {
            NewLight::Point => "point",
            NewLight::Spot => "spot",
            NewLight::Directional => "directional",
            NewLight::Sphere => "sphere / area",
        }
    }
}

/// One light of the rig.
#[derive(Clone, Debug, PartialEq)]
pub struct RigLight {
    /// The light; its `radius` is used when `follows_light_radius` is false.
    pub light: Light,
    /// Whether it is rendered.
    pub enabled: bool,
    /// Whether its radius is the global light radius (true for the scene's lights and added
    /// point, spot and directional lights, until the user sets its radius by hand).
    pub follows_light_radius: bool,
}

/// The overlay's render state.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewState {
    /// Bounces after the first hit.
    pub bounces: u32,
    /// Adaptive sampling's noise threshold (`render --noise-threshold`); `None`: off.
    pub noise_threshold: Option<f32>,
    /// With adaptive sampling, the display shows a heat map instead of the image (M cycles).
    pub heat_map: super::heat::HeatMap,
    /// The image is shown denoised (the guide buffers are rendered for it; docs/denoiser.md).
    pub denoise: bool,
    /// Seed of the random sequence.
    pub seed: u32,
    /// Uniform sky radiance.
    pub sky: [f32; 3],
    /// Environment map intensity (a scale on its radiance).
    pub env_intensity: f32,
    /// Environment map rotation about +Y in degrees.
    pub env_rotation: f32,
    /// Thin-lens radius in scene units (0: pinhole, everything sharp).
    pub aperture: f32,
    /// Distance of the plane in focus along the view axis.
    pub focus_distance: f32,
    /// Stop accumulating at this many samples per pixel; `None` renders on and on.
    pub spp_target: Option<u32>,
    /// The light radius (point and spot lights; directional lights get the matching angular
    /// radius) and the hard-shadow switch, which keeps the radius for flipping back.
    pub shadows: Shadows,
    /// Exposure in stops.
    pub exposure: f32,
    /// Automatic exposure (metered on the film) while set; the slider turns it off.
    pub auto_exposure: Option<HeldExposure>,
    /// Whether `exposure` is the first view's incident metering, untouched: a scene opened
    /// later, which the first view did not measure, is metered on the image instead.
    pub incident_exposure: bool,
    /// Tone curve.
    pub tone_mapper: ToneMapper,
    /// What escaped camera rays show.
    pub background: Background,
    /// The lights: the scene's, presets' and the user's.
    pub rig: Vec<RigLight>,
    /// The scene's bounds, which size new lights and the light radius range.
    pub bounds: Bounds,
    /// What the command line set that the overlay does not edit (Russian roulette, strategy).
    base: RenderSettings,
}

impl ViewState {
    /// The state the command line asks for (`base` is its validated render settings, `exposure`
    /// automatic, manual or EV100) on a scene with `lights` and `bounds`.
    pub fn new(
        base: RenderSettings,
        spp_target: Option<u32>,
        shadows: Shadows,
        exposure: ExposureMode,
        lights: &[Light],
        bounds: Bounds,
    ) -> Self {
        let mut s = Self {
            bounces: base.bounces,
            noise_threshold: base.noise_threshold,
            heat_map: super::heat::HeatMap::Off,
            denoise: false,
            seed: base.seed,
            sky: base.sky,
            env_intensity: base.env_intensity,
            env_rotation: base.env_rotation,
            aperture: base.lens_radius,
            focus_distance: base.focus_distance,
            spp_target,
            shadows,
            exposure: exposure.stops(None),
            auto_exposure: (exposure == ExposureMode::Auto).then(HeldExposure::default),
            incident_exposure: matches!(exposure, ExposureMode::Incident(_)),
            tone_mapper: ToneMapper::default(),
            background: if base.cutout {
                Background::Transparent
            } else {
                Background::Env
            },
            rig: Vec::new(),
            bounds,
            base,
        };
        s.replace_scene_lights(lights, bounds);
        s
    }

    /// A new scene: its lights replace the rig, the light radius goes back to the scene's
    /// default.
    pub fn replace_scene_lights(&mut self, lights: &[Light], bounds: Bounds) {
        if self.bounds != bounds {
            self.shadows.light_radius = default_light_radius(&bounds);
        }
        self.bounds = bounds;
        self.rig = lights
            .iter()
            .map(|l| RigLight {
                light: l.clone(),
                enabled: true,
                follows_light_radius: true,
            })
            .collect();
    }

    /// The scene's diagonal.
    pub fn diagonal(&self) -> f64 {
        self.bounds.diagonal()
    }

    /// Render settings for a film of `size` pixels.
    pub fn render_settings(&self, size: (u32, u32)) -> RenderSettings {
        RenderSettings {
            width: size.0.max(1),
            height: size.1.max(1),
            bounces: self.bounces,
            noise_threshold: self.noise_threshold,
            seed: self.seed,
            sky: self.sky,
            env_intensity: self.env_intensity.max(0.0),
            env_rotation: self.env_rotation,
            lens_radius: self.aperture.max(0.0),
            focus_distance: self.focus_distance.max(1e-6),
            cutout: self.background.cutout(),
            aovs: self.denoise || self.base.aovs,
            ..self.base.clone()
        }
    }

    /// The radius a rig light renders with.
    pub fn effective_radius(&self, l: &RigLight) -> f32 {
        if l.follows_light_radius {
            self.shadows.radius_for(&l.light.kind, self.diagonal())
        } else if self.shadows.hard {
            0.0
        } else {
            l.light.light_radius
        }
    }

    /// The enabled lights with the radii they render with.
    pub fn lights(&self) -> Vec<Light> {
        self.rig
            .iter()
            .filter(|l| l.enabled)
            .map(|l| Light {
                light_radius: self.effective_radius(l),
                ..l.light.clone()
            })
            .collect()
    }

    /// Whether an enabled light has a radius the hard/soft toggle changes (point, spot and
    /// directional lights; sphere lights keep theirs unless they follow the light radius).
    pub fn has_light_radius(&self) -> bool {
        self.rig
            .iter()
            .any(|l| l.enabled && (l.follows_light_radius || l.light.light_radius > 0.0))
    }

    /// Flips hard shadows (the H key).
    pub fn toggle_hard_shadows(&mut self) {
        self.shadows.hard = !self.shadows.hard;
    }

    /// Adds a light of `kind` where it shows: near `camera`, above and to the right, aimed at
    /// what the camera looks at and scaled to its distance (see [`light_near_camera`]).
    pub fn add_light(&mut self, kind: NewLight, camera: &Camera) {
        let distance = subject_distance(camera, &self.bounds);
        let count = self.rig.len() + 1;
        let mut light = light_near_camera(camera, distance, &format!("{} {count}", kind.name()));
        // Halfway from the middle of the view to its top right corner, whatever the field of
        // view, aimed at the subject with an irradiance of about 1 there.
        let up = camera.up.normalize_or(DVec3::Y);
        let right = camera.forward.cross(up).normalize_or(DVec3::X);
        let ahead = 0.3 * distance;
        let t = (0.5 * camera.yfov).tan();
        light.position = camera.eye + camera.forward * ahead + (up + right) * (0.5 * t * ahead);
        let to_subject = camera.eye + camera.forward * distance - light.position;
        light.direction = to_subject.normalize_or(DVec3::NEG_Y);
        light.intensity = to_subject.length_squared() as f32;
        let follows = kind != NewLight::Sphere;
        match kind {
            NewLight::Point => {}
            NewLight::Spot => {
                light.kind = LightKind::Spot {
                    inner: 0.3,
                    outer: 0.6,
                }
            }
            // A sun from the same side, with an irradiance of about 1 like the others.
            NewLight::Directional => {
                light.kind = LightKind::Directional;
                light.intensity = 1.0;
            }
            NewLight::Sphere => light.light_radius = (0.05 * distance) as f32,
        }
        self.rig.push(RigLight {
            light,
            enabled: true,
            follows_light_radius: follows,
        });
    }

    /// Puts a preset's lights in place of (`replace`) or beside the rig's. Preset lights keep
    /// their own radii (the softbox is meant to be large).
    pub fn apply_preset(&mut self, preset: LightPreset, replace: bool) {
        if replace {
            self.rig.clear();
        }
        self.rig.extend(
            preset_lights(preset, &self.bounds)
                .into_iter()
                .map(|light| RigLight {
                    light,
                    enabled: true,
                    follows_light_radius: false,
                }),
        );
    }

    /// Largest light radius the overlay's slider offers.
    pub fn max_light_radius(&self) -> f32 {
        (0.2 * self.diagonal()) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::args::CommonArgs;
    use clap::Parser;

    /// A camera looking at the test bounds from outside.
    fn camera() -> Camera {
        Camera::look_at("c", DVec3::new(0.5, 1.0, 6.0), bounds().center(), 0.8)
    }

    fn state(extra: &[&str], lights: &[Light]) -> ViewState {
        let a = args(extra);
        let base = a.settings((64, 64)).unwrap();
        let shadows = Shadows::new(a.shadows.light_radius, a.shadows.hard_shadows, &bounds());
        ViewState::new(
            base,
            a.sampling.spp,
            shadows,
            a.exposure_mode(),
            lights,
            bounds(),
        )
    }

    fn args(extra: &[&str]) -> CommonArgs {
        #[derive(Parser)]
        struct View {
            #[command(flatten)]
            common: CommonArgs,
        }
        let mut argv = vec!["penumbra"];
        argv.extend_from_slice(extra);
        View::parse_from(argv).common
    }

    fn bounds() -> Bounds {
        Bounds {
            min: DVec3::ZERO,
            max: DVec3::new(1.0, 2.0, 2.0),
        }
    }

    fn point() -> Light {
        Light {
            name: "p".into(),
            kind: LightKind::Point,
            position: DVec3::ONE,
            direction: DVec3::NEG_Y,
            color: [1.0; 3],
            intensity: 5.0,
            light_radius: 0.0,
        }
    }

    fn sun() -> Light {
        Light {
            name: "sun".into(),
            kind: LightKind::Directional,
            ..point()
        }
    }

    #[test]
    fn command_line_options_map_to_render_settings() {
        let s = state(
            &[
                "--bounces",
                "2",
                "--seed",
                "7",
                "--sky",
                "0.5",
                "--spp",
                "9",
                "--aperture",
                "0.01",
                "--focus-distance",
                "2",
            ],
            &[point()],
        );
        let r = s.render_settings((160, 120));
        assert_eq!((r.width, r.height, r.bounces, r.seed), (160, 120, 2, 7));
        assert_eq!(r.sky, [0.5; 3]);
        assert_eq!((r.lens_radius, r.focus_distance), (0.01, 2.0));
        assert_eq!(s.spp_target, Some(9));
    }

    #[test]
    fn environment_edits_reach_the_render_settings() {
        let mut s = state(
            &["--env-intensity", "2", "--env-rotation", "30"],
            &[point()],
        );
        let r = s.render_settings((8, 8));
        assert_eq!((r.env_intensity, r.env_rotation), (2.0, 30.0));
        s.env_intensity = 0.25;
        s.env_rotation = -90.0;
        let r = s.render_settings((8, 8));
        assert_eq!((r.env_intensity, r.env_rotation), (0.25, -90.0));
    }

    #[test]
    fn the_default_light_radius_is_visibly_soft() {
        let s = state(&[], &[point(), sun()]);
        assert_eq!(s.shadows.light_radius, default_light_radius(&bounds()));
        let lights = s.lights();
        assert_eq!(lights[0].light_radius, s.shadows.light_radius);
        // The sun gets the matching angular radius.
        let angular = 2.0 * s.shadows.light_radius as f64 / bounds().diagonal();
        assert!((lights[1].light_radius as f64 - angular).abs() < 1e-6);
    }

    #[test]
    fn the_hard_toggle_gives_radius_zero_and_restores_the_light_radius() {
        let mut s = state(&["--light-radius", "0.1"], &[point()]);
        s.add_light(NewLight::Sphere, &camera());
        let soft = s.lights();
        assert_eq!(soft[0].light_radius, 0.1);
        assert!(soft[1].light_radius > 0.0);
        s.toggle_hard_shadows();
        assert!(s.lights().iter().all(|l| l.light_radius == 0.0));
        s.toggle_hard_shadows();
        assert_eq!(s.lights(), soft);
        // --hard-shadows starts hard but keeps the default light radius for the toggle.
        let mut h = state(&["--hard-shadows"], &[point()]);
        assert_eq!(h.lights()[0].light_radius, 0.0);
        h.toggle_hard_shadows();
        assert_eq!(h.lights()[0].light_radius, default_light_radius(&bounds()));
    }

    #[test]
    fn the_light_radius_follows_the_slider_unless_set_by_hand() {
        let mut s = state(&[], &[point(), point()]);
        s.rig[1].follows_light_radius = false;
        s.rig[1].light.light_radius = 0.3;
        s.shadows.light_radius = 0.05;
        let l = s.lights();
        assert_eq!((l[0].light_radius, l[1].light_radius), (0.05, 0.3));
    }

    #[test]
    fn disabled_lights_are_left_out_and_presets_replace_or_extend() {
        let mut s = state(&[], &[point()]);
        s.apply_preset(LightPreset::ThreePointStudio, false);
        assert_eq!(s.lights().len(), 4);
        s.rig[0].enabled = false;
        assert_eq!(s.lights().len(), 3);
        s.apply_preset(LightPreset::OverheadSoftbox, true);
        assert_eq!(s.rig.len(), 1);
        // The softbox keeps its large radius.
        assert!(s.lights()[0].light_radius > s.shadows.light_radius);
        for kind in NewLight::ALL {
            s.add_light(kind, &camera());
        }
        assert_eq!(s.lights().len(), 5);
        assert!(s.lights().iter().all(|l| l.intensity > 0.0));
    }

    #[test]
    fn added_lights_are_in_view_near_the_camera_and_scaled_to_the_scene() {
        for cam in [
            camera(),
            // Inside the bounds (an interior), looking along +X.
            Camera::look_at(
                "in",
                DVec3::new(0.2, 1.0, 1.0),
                DVec3::new(1.0, 1.0, 1.0),
                1.0,
            ),
        ] {
            let mut s = state(&[], &[]);
            let distance = subject_distance(&cam, &bounds());
            for kind in NewLight::ALL {
                s.add_light(kind, &cam);
            }
            for l in s.lights() {
                let to = l.position - cam.eye;
                // In front of the camera and inside its field of view.
                let ahead = to.dot(cam.forward);
                assert!(ahead > 0.0, "{}: behind the camera", l.name);
                // Within the vertical field of view (and so the wider horizontal one).
                let half = (cam.yfov * 0.5).tan() * ahead;
                let right = cam.forward.cross(cam.up).normalize();
                let (x, y) = (to.dot(right), to.dot(cam.up.normalize()));
                assert!(
                    x.abs() < half && y.abs() < half,
                    "{}: outside the view",
                    l.name
                );
                // Nearer than the subject, not at the top of the bounds.
                assert!(to.length() < distance, "{}: {to:?}", l.name);
                // Spots aim at the subject; about unit irradiance there for every kind.
                if let LightKind::Spot { .. } = l.kind {
                    let aim = (cam.eye + cam.forward * distance - l.position).normalize();
                    assert!(l.direction.dot(aim) > 0.999, "{}", l.name);
                }
                let subject = cam.eye + cam.forward * distance;
                let e = match l.kind {
                    LightKind::Directional => l.intensity as f64,
                    _ => l.intensity as f64 / (subject - l.position).length_squared(),
                };
                assert!((0.5..2.0).contains(&e), "{}: irradiance {e}", l.name);
            }
        }
    }
}
