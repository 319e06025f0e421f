//! Light selection: the device light list (emissive triangles, punctual lights, the
//! environment map) with its selection table, and the environment's constants.

use super::Renderer;
use super::upload::{HostScene, f4, luminance};
use crate::cl::types::*;
use crate::cl::{Buffer, ClError};
use crate::scene::{Light, LightKind, Scene, srgb_to_linear};
use glam::Vec3;
use rayon::prelude::*;

/// For each material, the mean linear luminance of its emissive texture (1 without one, at least
/// 10⁻³), so that the light table weighs textured emitters by what they emit on average.
pub fn emissive_texture_means(scene: &Scene) -> Vec<f32> {
    scene
        .materials
        .iter()
        .map(|m| {
            let Some(r) = m.textures.emissive.filter(|_| m.is_emissive()) else {
                return 1.0;
            };
            let r = &scene.texture_refs[r as usize];
            let image = &scene.images[r.image as usize];
            let sum: f64 = image
                .rgba
                .par_iter()
                .map(|t| {
                    let c = |v: u8| {
                        if r.srgb {
                            srgb_to_linear(v)
                        } else {
                            v as f32 / 255.0
                        }
                    };
                    luminance([c(t[0]), c(t[1]), c(t[2])]) as f64
                })
                .sum();
            ((sum / image.rgba.len().max(1) as f64) as f32).max(1e-3)
        })
        .collect()
}

/// The light list (emissive triangles first, so a triangle's light index is its position in
/// `HostScene::emissive`, then the punctual lights, then the environment map when
/// `env_luminance` (its mean luminance × intensity) is given) and its cumulative selection
/// table.
///
/// A light's probability is the mean of two tables: one in proportion to its emitted power
/// (4π I for a point light, π r² E for a sun over the scene's disc, π L A for a triangle), one
/// in proportion to an estimate of the irradiance it sends to the middle of the scene (I / d²,
/// E, π L̄ for the environment, L A / d², with d clamped below at 5 % of the diagonal). Power
/// alone made a default-rig sun, whose power grows with the scene's area, 40× less likely than
/// the key light while both lit surfaces about equally, and the rare sun samples showed as
/// speckle; irradiance alone suits a room's lights worse than power (the Cornell box's error
/// grew by a fifth). The mixture is never worse than half of either. Any positive weights keep
/// the estimator unbiased.
pub fn gpu_lights(
    lights: &[Light],
    host: &HostScene,
    env_luminance: Option<f32>,
) -> (Vec<DeviceLight>, Vec<f32>) {
    let mut out = Vec::new();
    // (by irradiance at the middle, by power) per light.
    let mut weights: Vec<(f32, f32)> = Vec::new();
    let (center, diagonal) = host.bounds();
    let disc = std::f32::consts::PI * (0.5 * diagonal) * (0.5 * diagonal);
    let near = (0.05 * diagonal).max(1e-12);
    let inverse_square = |p: Vec3| 1.0 / (p - center).length_squared().max(near * near);
    // Two levels: a triangle light names its instance's slot in the (TLAS-ordered) instances;
    // a hidden instance's lights keep their places in the list but are never chosen.
    let slots = match &host.accel {
        crate::render::Accel::TwoLevel(two) if !host.emissive.is_empty() => two.slots(),
        _ => vec![],
    };
    for e in &host.emissive {
        let (area, centroid) = (e.area, e.centroid);
        let slot = slots.get(e.instance as usize).copied().unwrap_or(0);
        let power = if slot == u32::MAX { 0.0 } else { e.power };
        out.push(DeviceLight {
            position: [0.0, 0.0, 0.0, f32::from_bits(LIGHT_TRIANGLE)],
            intensity: [0.0; 4],
            spot: [f32::from_bits(e.prim), area, f32::from_bits(slot), 0.0],
            extra: [0.0; 4],
        });
        // `power` is π L A (× 2 when double-sided), so power / π is the intensity scale L A.
        weights.push((
            power / std::f32::consts::PI * inverse_square(centroid),
            power,
        ));
    }
    let pi = std::f32::consts::PI;
    for l in lights {
        let color = l.color.map(|c| c * l.intensity);
        let y = luminance(color);
        let (kind, position, irradiance, power) = match l.kind {
            LightKind::Point => (
                LIGHT_POINT,
                l.position,
                y * inverse_square(l.position.as_vec3()),
                y * 4.0 * pi,
            ),
            LightKind::Spot { outer, .. } => (
                LIGHT_SPOT,
                l.position,
                y * inverse_square(l.position.as_vec3()),
                y * 2.0 * pi * (1.0 - outer.cos()).max(0.05),
            ),
            LightKind::Directional => (LIGHT_DIRECTIONAL, l.direction, y, y * disc),
        };
        if !(irradiance > 0.0 && irradiance.is_finite() && power.is_finite()) {
            continue;
        }
        let (cos_inner, cos_outer) = match l.kind {
            LightKind::Spot { inner, outer } => (inner.cos(), outer.cos()),
            _ => (1.0, -1.0),
        };
        let d = l.direction.as_vec3().normalize_or(Vec3::NEG_Y);
        out.push(DeviceLight {
            position: f4(position.as_vec3(), f32::from_bits(kind)),
            intensity: [color[0], color[1], color[2], l.light_radius.max(0.0)],
            spot: f4(d, cos_outer),
            extra: [cos_inner, 0.0, 0.0, 0.0],
        });
        weights.push((irradiance, power));
    }
    if let Some(l) = env_luminance {
        let irradiance = pi * l;
        if irradiance > 0.0 && irradiance.is_finite() {
            out.push(DeviceLight {
                position: [0.0, 0.0, 0.0, f32::from_bits(LIGHT_ENVIRONMENT)],
                ..DeviceLight::default()
            });
            weights.push((irradiance, irradiance * disc));
        }
    }
    let total_irradiance: f32 = weights.iter().map(|w| w.0).sum();
    let total_power: f32 = weights.iter().map(|w| w.1).sum();
    if !(total_irradiance > 0.0 && total_power > 0.0) {
        // Nothing lights the scene (every emitter hidden): no light is sampled.
        return (vec![], vec![]);
    }
    let mut cdf = Vec::with_capacity(weights.len());
    let mut acc = 0.0;
    for (l, w) in out.iter_mut().zip(&weights) {
        let p = 0.5 * (w.0 / total_irradiance + w.1 / total_power);
        l.extra[1] = p;
        acc += p;
        cdf.push(acc);
    }
    if let Some(last) = cdf.last_mut() {
        *last = 1.0;
    }
    (out, cdf)
}

impl Renderer {
    /// The light list and selection table for the current lights and environment.
    pub(super) fn light_table(&self, host: &HostScene) -> (Vec<DeviceLight>, Vec<f32>) {
        let env_luminance = self
            .environment
            .as_ref()
            .map(|(_, t)| t.mean_luminance * self.settings.env_intensity);
        gpu_lights(&host.space.lights(&self.lights), host, env_luminance)
    }

    /// Fills the environment constants from the settings and the light list.
    pub(super) fn update_env_info(&mut self, lights: &[DeviceLight]) {
        let Some((map, table)) = self.environment.as_ref() else {
            self.env.info = DeviceEnvironment::default();
            return;
        };
        let light = lights
            .iter()
            .position(|l| l.position[3].to_bits() == LIGHT_ENVIRONMENT);
        let (sin, cos) = self.settings.env_rotation.to_radians().sin_cos();
        self.env.info = DeviceEnvironment {
            scale: [
                self.settings.env_intensity,
                table.norm,
                light.map_or(0.0, |i| lights[i].extra[1]),
                0.0,
            ],
            rotation: [cos, sin, 0.0, 0.0],
            width: map.width,
            height: map.height,
            light: light.map_or(u32::MAX, |i| i as u32),
            pad: 0,
        };
    }

    /// Rebuilds the light table on the device (after lights, environment or its intensity
    /// changed).
    pub(super) fn upload_lights(&mut self) -> Result<(), ClError> {
        let Some((_, host)) = self.scene.as_ref() else {
            return Ok(());
        };
        let (glights, cdf) = self.light_table(host);
        let Some((buffers, _)) = self.scene.as_mut() else {
            return Ok(());
        };
        buffers.lights = Buffer::from_slice(&self.device, &glights)?;
        buffers.light_cdf = Buffer::from_slice(&self.device, &cdf)?;
        self.light_count = glights.len() as u32;
        self.update_env_info(&glights);
        Ok(())
    }
}
