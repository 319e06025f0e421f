//! Whether the scene's own lights light the view, and how much sky the subject sees.
//!
//! # "The scene's own lights light the view"
//!
//! From the chosen camera a grid of [`PROBE_COLUMNS`] × [`PROBE_ROWS`] rays finds the subject
//! points. At each point the direct irradiance E from the scene's punctual lights and emissive
//! triangles is estimated (cosine at the point, inverse square, cone and emitter cosine, one
//! visibility ray per light; the [`MAX_EMITTERS`] most powerful emissive triangles stand for
//! all of them, scaled by their share of the emitted power). With L_s = median(E)/π (the
//! radiance of a white diffuse surface at the median point) and L_e = the 90th percentile of
//! the radiance of emitters the camera sees directly, the lights light the view when
//! - at least [`MIN_LIT_FRACTION`] of the subject points get some direct light, and
//! - L_s ≥ L_e · 2^−[`MAX_STOPS_BELOW_EMITTERS`] (the subject is within the tone curve's reach
//!   once the visible lamps are exposed).
//!
//! Small glowing parts (a car's headlights, a lamp's filament behind glass) fail the first test;
//! a sun or a lamp over the subject passes both.

use super::super::{Camera, Light, LightKind};
use super::probe::sphere_directions;
use super::{Probe, area, luminance};
use glam::DVec3;
use rayon::prelude::*;

/// Columns of the probe grid of camera rays.
pub const PROBE_COLUMNS: usize = 32;
/// Rows of the probe grid of camera rays.
pub const PROBE_ROWS: usize = 24;
/// Emissive triangles evaluated at each subject point (the most powerful ones).
pub const MAX_EMITTERS: usize = 64;
/// The share of subject points that must receive direct light.
pub const MIN_LIT_FRACTION: f64 = 0.25;
/// How far (in stops) the lit subject may lie below the directly seen emitters.
pub const MAX_STOPS_BELOW_EMITTERS: f64 = 10.0;
/// Rays from each subject point over its hemisphere, to find whether the sky reaches it.
pub const SKY_RAYS: usize = 16;
/// The share of those rays that must leave the scene for an environment to light the view: a
/// room with a window lets out a few percent; cracks in a closed model far fewer.
pub const MIN_SKY_FRACTION: f64 = 0.002;
/// The share of the hemisphere rays from the metal and glass the camera sees that may leave
/// the scene while its own lights still surround them: above it, what they reflect or show
/// through is mostly the world, black without an environment.
pub const MAX_SHINY_SKY: f64 = 0.25;
/// The share of the subject points that must be metal or glass for [`MAX_SHINY_SKY`] to matter.
pub const MIN_SHINY_SHARE: f64 = 0.05;

/// What [`light_test`] finds from a camera (the [`FirstView`] fields of the same names).
pub(super) struct LightTest {
    pub(super) lit: bool,
    pub(super) coverage: f64,
    pub(super) lit_fraction: f64,
    pub(super) subject_radiance: f64,
    pub(super) emitter_radiance: f64,
    pub(super) sky_fraction: f64,
    pub(super) key_irradiance: f64,
    pub(super) shiny_share: f64,
    pub(super) shiny_sky: f64,
    pub(super) subject_normals: Vec<DVec3>,
}

/// The percentile of the light at the subject points that incident metering shows a white
/// surface under at [`WHITE`](crate::render::exposure::WHITE): the brighter lit quarter of
/// the subject may go above it (into the tone curve's shoulder), little of it clips.
pub const METER_PERCENTILE: f64 = 0.75;

/// The [`METER_PERCENTILE`] value of `values` (sorted ascending), 0 when there are none.
pub fn meter_percentile(values: &[f64]) -> f64 {
    let at = ((values.len() as f64 * METER_PERCENTILE) as usize).min(values.len().max(1) - 1);
    values.get(at).copied().unwrap_or(0.0)
}

/// The most powerful emissive triangles: (centroid, unit normal, radiance × area), at most
/// [`MAX_EMITTERS`] (the first in scene order among equals), the power scaled up by the share
/// of all emitted power they leave out.
pub(super) fn emitters(probe: &Probe) -> Vec<(DVec3, DVec3, f64)> {
    // Opaque triangles alone, in scene order: equally powerful emitters keep that order.
    let see_through = |m: u32| probe.see_through.get(m as usize).copied().unwrap_or(false);
    let emission = |m: u32| probe.emission.get(m as usize).copied().unwrap_or(0.0);
    let tris = &probe.tris;
    let mut all: Vec<(usize, f64)> = tris
        .chunks(1 << 16)
        .map(|range| {
            let mut out = vec![];
            tris.visit(range, |i, t, m| {
                if emission(m) > 0.0 && !see_through(m) {
                    let p = emission(m) as f64 * area(&t) as f64;
                    if p > 0.0 {
                        out.push((i, p));
                    }
                }
            });
            out
        })
        .flatten_iter()
        .collect();
    let total: f64 = all.iter().map(|e| e.1).sum();
    all.sort_by(|a, b| b.1.total_cmp(&a.1));
    all.truncate(MAX_EMITTERS);
    let kept: f64 = all.iter().map(|e| e.1).sum();
    let scale = if kept > 0.0 { total / kept } else { 1.0 };
    all.into_iter()
        .map(|(i, p)| {
            let t = probe.tris.get(i);
            let centre = ((t[0] + t[1] + t[2]) / 3.0).as_dvec3();
            (centre, probe.normal(i), p * scale)
        })
        .collect()
}

/// A primary ray through the pixel at fractions (fx, fy) of the image (0,0 = top left).
pub fn camera_ray(camera: &Camera, aspect: f64, fx: f64, fy: f64) -> DVec3 {
    let right = camera.forward.cross(camera.up).normalize();
    let h = (camera.yfov * 0.5).tan();
    (camera.forward + right * ((2.0 * fx - 1.0) * h * aspect) + camera.up * ((1.0 - 2.0 * fy) * h))
        .normalize()
}

/// Direct irradiance at `point` (unit normal `n` facing the viewer) from the lights and the
/// emitters, with visibility.
fn irradiance(
    probe: &Probe,
    lights: &[Light],
    emitters: &[(DVec3, DVec3, f64)],
    point: DVec3,
    n: DVec3,
) -> f64 {
    let eps = 1e-4 * probe.scale();
    let origin = point + n * eps;
    let mut e = 0.0;
    for l in lights {
        let power = l.intensity as f64 * luminance(l.color) as f64;
        match l.kind {
            LightKind::Directional => {
                let wi = -l.direction;
                let cos = n.dot(wi);
                if cos > 0.0 && probe.unobstructed(origin, wi) {
                    e += power * cos;
                }
            }
            LightKind::Point | LightKind::Spot { .. } => {
                let to = l.position - origin;
                let d2 = to.length_squared().max(1e-12);
                let wi = to / d2.sqrt();
                let cos = n.dot(wi);
                let cone = match l.kind {
                    LightKind::Spot { inner, outer } => {
                        let c = (-wi).dot(l.direction);
                        let (ci, co) = ((inner as f64).cos(), (outer as f64).cos());
                        ((c - co) / (ci - co).max(1e-6)).clamp(0.0, 1.0)
                    }
                    _ => 1.0,
                };
                if cos > 0.0 && cone > 0.0 && probe.visible(origin, l.position) {
                    e += power * cone * cos / d2;
                }
            }
        }
    }
    for &(centre, normal, power) in emitters {
        let to = centre - origin;
        let d2 = to.length_squared().max(1e-12);
        let wi = to / d2.sqrt();
        let cos = n.dot(wi);
        // Emissive triangles glow on both sides when double-sided; take the facing cosine.
        let cos_e = normal.dot(-wi).abs();
        if cos > 0.0 && probe.visible(origin, centre - wi * eps) {
            e += power * cos * cos_e / d2;
        }
    }
    e
}

/// The rule of this module's docs, evaluated from `camera`, and how much sky the subject sees.
pub(super) fn light_test(
    probe: &Probe,
    lights: &[Light],
    camera: &Camera,
    aspect: f64,
) -> LightTest {
    let emitters = emitters(probe);
    let far = probe.scale() * 100.0 + (camera.eye - probe.bounds.center()).length() * 4.0;
    let sky: Vec<DVec3> = sphere_directions(SKY_RAYS).collect();
    // Hemisphere rays from `point` (normal `n`) that leave the scene.
    let escaping = |point: DVec3, n: DVec3| {
        let origin = point + n * (1e-4 * probe.scale());
        sky.iter()
            .filter(|&&s| {
                let s = if s.dot(n) < 0.0 { -s } else { s };
                probe.hit(origin, s, far).is_none()
            })
            .count()
    };
    // The normal of `prim` facing against `d`.
    let facing = |prim: usize, d: DVec3| {
        let n = probe.normal(prim);
        if n.dot(d) > 0.0 { -n } else { n }
    };
    // (direct irradiance, escaping hemisphere rays and normal at a subject point, emitter
    // radiance, escaping hemisphere rays at the metal or glass the camera sees first)
    type Sample = (Option<(f64, usize, DVec3)>, Option<f64>, Option<usize>);
    let samples: Vec<Sample> = (0..PROBE_COLUMNS * PROBE_ROWS)
        .into_par_iter()
        .map(|i| {
            let fx = ((i % PROBE_COLUMNS) as f64 + 0.5) / PROBE_COLUMNS as f64;
            let fy = ((i / PROBE_COLUMNS) as f64 + 0.5) / PROBE_ROWS as f64;
            let d = camera_ray(camera, aspect, fx, fy);
            // Glass in front of the subject is what the camera sees there.
            let shiny = probe.hit_all_at(camera.eye, d, far).and_then(|(t, prim)| {
                probe
                    .shiny(prim)
                    .then(|| escaping(camera.eye + d * t, facing(prim, d)))
            });
            let Some((t, prim)) = probe.hit(camera.eye, d, far) else {
                return (None, None, shiny);
            };
            if probe.emission(prim) > 0.0 {
                return (None, Some(probe.emission(prim) as f64), shiny);
            }
            let n = facing(prim, d);
            let point = camera.eye + d * t;
            (
                Some((
                    irradiance(probe, lights, &emitters, point, n),
                    escaping(point, n),
                    n,
                )),
                None,
                shiny,
            )
        })
        .collect();
    let escaping: usize = samples.iter().filter_map(|s| s.0).map(|(_, k, _)| k).sum();
    let mut subject: Vec<f64> = samples
        .iter()
        .filter_map(|s| s.0)
        .map(|(e, ..)| e)
        .collect();
    let subject_normals: Vec<DVec3> = samples.iter().filter_map(|s| s.0).map(|s| s.2).collect();
    let mut seen: Vec<f64> = samples.iter().filter_map(|s| s.1).collect();
    let coverage = (subject.len() + seen.len()) as f64 / samples.len() as f64;
    let shiny: Vec<usize> = samples.iter().filter_map(|s| s.2).collect();
    // Over every sample that meets something: glass with nothing behind it is seen too (over
    // the opaque points alone, two glass spheres on nothing made a share of 2).
    let seen_any = samples
        .iter()
        .filter(|s| s.0.is_some() || s.1.is_some() || s.2.is_some())
        .count();
    let shiny_share = shiny.len() as f64 / seen_any.max(1) as f64;
    let shiny_sky = shiny.iter().sum::<usize>() as f64 / (shiny.len().max(1) * SKY_RAYS) as f64;
    if subject.is_empty() {
        return LightTest {
            lit: false,
            coverage,
            lit_fraction: 0.0,
            subject_radiance: 0.0,
            emitter_radiance: 0.0,
            sky_fraction: 0.0,
            key_irradiance: 0.0,
            shiny_share,
            shiny_sky,
            subject_normals,
        };
    }
    let sky_fraction = escaping as f64 / (subject.len() * SKY_RAYS) as f64;
    let lit_fraction = subject.iter().filter(|&&e| e > 0.0).count() as f64 / subject.len() as f64;
    subject.sort_by(f64::total_cmp);
    seen.sort_by(f64::total_cmp);
    let subject_radiance = subject[subject.len() / 2] / std::f64::consts::PI;
    let lit_points = &subject[subject.partition_point(|&e| e <= 0.0)..];
    let key_irradiance = meter_percentile(lit_points);
    let emitter_radiance = if seen.is_empty() {
        0.0
    } else {
        seen[(seen.len() * 9 / 10).min(seen.len() - 1)]
    };
    let lit = lit_fraction >= MIN_LIT_FRACTION
        && subject_radiance > 0.0
        && subject_radiance >= emitter_radiance * 2f64.powf(-MAX_STOPS_BELOW_EMITTERS);
    LightTest {
        lit,
        coverage,
        lit_fraction,
        subject_radiance,
        emitter_radiance,
        sky_fraction,
        key_irradiance,
        shiny_share,
        shiny_sky,
        subject_normals,
    }
}
