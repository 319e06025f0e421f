//! The first view of a scene without a camera of its own: robust bounds of what is there, the
//! side its lights illuminate, interiors seen from inside, and the rule that decides whether the
//! scene's own lights light that view (else the viewer adds an environment).
//!
//! Everything here runs on the host with the reference BVH traversal ([`crate::bvh`]) and is
//! deterministic: the same scene gives the same first view. The pieces, one file each:
//! - [`WorldTris`] (`world_tris.rs`): the visible objects' world triangles, read from each
//!   object's vertices;
//! - the [`Probe`] (`probe.rs`): the trees the probe rays are traced through;
//! - [`robust_bounds`] and the fit points (`subject_bounds.rs`): the bulk of the geometry;
//! - [`classify_shell`] and the interior camera (`interior.rs`): rooms seen from inside;
//! - the light test (`light_test.rs`): whether the scene's own lights light the view;
//! - here: the view of an object (the lit side, the fit), [`first_view`] that puts them
//!   together, and the lights added to a view that its own lights leave dark.

mod interior;
mod light_test;
mod probe;
mod subject_bounds;
#[cfg(test)]
mod tests;
mod world_tris;

pub use interior::{
    ENCLOSED_POINTS, EYE_HEIGHT, INTERIOR_HIT_FRACTION, INTERIOR_YFOV, OPEN_SIDE_FRACTION,
    SHELL_RAYS, Shell, classify_model, classify_shell,
};
pub use light_test::{
    MAX_EMITTERS, MAX_SHINY_SKY, MAX_STOPS_BELOW_EMITTERS, METER_PERCENTILE, MIN_LIT_FRACTION,
    MIN_SHINY_SHARE, MIN_SKY_FRACTION, PROBE_COLUMNS, PROBE_ROWS, SKY_RAYS, camera_ray,
    meter_percentile,
};
pub use probe::Probe;
pub use subject_bounds::{FIT_POINTS, SAMPLE_FROM, robust_bounds};
pub use world_tris::WorldTris;

use super::{Bounds, Camera, Light, LightKind, Scene};
use glam::{DVec3, Vec3};
use interior::interior_camera;
use light_test::{LightTest, emitters, light_test};

/// Name of the cameras made here (and by [`Camera::framing`]).
pub const AUTO_CAMERA: &str = "auto";

/// What the first-view analysis found (for messages, the JSON summary and tests).
#[derive(Clone, Debug, PartialEq)]
pub struct FirstView {
    /// The camera to start with.
    pub camera: Camera,
    /// Robust bounds of the visible geometry.
    pub bounds: Bounds,
    /// Whether the camera was put inside (the model is an interior).
    pub interior: bool,
    /// Whether the scene's own lights light the view (the rule of `light_test.rs`).
    pub lit: bool,
    /// The share of probe rays from the camera that hit geometry.
    pub coverage: f64,
    /// The share of subject points with direct light from the scene's lights.
    pub lit_fraction: f64,
    /// L_s: median direct irradiance over π at the subject points.
    pub subject_radiance: f64,
    /// L_e: 90th percentile radiance of the emitters seen directly (0 when none is).
    pub emitter_radiance: f64,
    /// The share of rays from the subject points over their hemispheres that leave the scene:
    /// 0 in a closed room, which an environment cannot light.
    pub sky_fraction: f64,
    /// The [`METER_PERCENTILE`] of the direct irradiance from the scene's lights at the
    /// subject points they light (0 when they light none): what an incident light meter at
    /// the subject reads.
    pub key_irradiance: f64,
    /// The share of what the camera sees (the probe rays that meet something) that is metal
    /// or glass (glass in front of the subject included).
    pub shiny_share: f64,
    /// The share of the hemisphere rays from those points that leave the scene.
    pub shiny_sky: f64,
    /// The unit normals (towards the camera) at the subject points: where an environment's
    /// light is metered.
    pub subject_normals: Vec<DVec3>,
    /// Set when the probe's rays were not traced because each would have taken about this
    /// many triangle tests ([`PROBE_MAX_RAY_COST`]): the view is the bounds' alone.
    pub unprobed_cost: Option<f64>,
}

impl FirstView {
    /// Whether an environment would show in the view or light it: the camera sees past the
    /// geometry, or at least [`MIN_SKY_FRACTION`] of the subject's hemisphere rays leave.
    pub fn environment_reaches(&self) -> bool {
        self.coverage < 1.0 || self.sky_fraction >= MIN_SKY_FRACTION
    }

    /// Whether the metal and glass in view would reflect a black world: at least
    /// [`MIN_SHINY_SHARE`] of the subject is metal or glass and more than [`MAX_SHINY_SKY`] of
    /// their hemisphere leaves the scene (the scene's own lights and walls do not surround them).
    pub fn shine_needs_environment(&self) -> bool {
        self.shiny_share >= MIN_SHINY_SHARE && self.shiny_sky > MAX_SHINY_SKY
    }
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn area(t: &[Vec3; 3]) -> f32 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// Where each light comes from, seen from `point`, weighted by the irradiance it gives there
/// (unoccluded): (unit direction towards the light, weight).
fn light_directions(probe: &Probe, lights: &[Light], point: DVec3) -> Vec<(DVec3, f64)> {
    let mut out = Vec::new();
    for l in lights {
        let power = l.intensity as f64 * luminance(l.color) as f64;
        match l.kind {
            LightKind::Directional => out.push((-l.direction, power)),
            LightKind::Point | LightKind::Spot { .. } => {
                let to = l.position - point;
                let d2 = to.length_squared().max(1e-12);
                out.push((to / d2.sqrt(), power / d2));
            }
        }
    }
    for (centre, normal, power) in emitters(probe) {
        let to = centre - point;
        let d2 = to.length_squared().max(1e-12);
        let dir = to / d2.sqrt();
        out.push((dir, power * normal.dot(-dir).abs() / d2));
    }
    out
}

/// The view direction (from the subject towards the eye) from which the lights illuminate the
/// visible side: among 16 azimuths × 2 elevations, the one that best faces the light-weighted
/// directions, with smaller preferences for a broad side of the bounds (a fox from the side,
/// not nose-on) and for the glTF front (+Z).
pub fn lit_side(probe: &Probe, lights: &[Light]) -> DVec3 {
    let centre = probe.bounds.center();
    let e = (probe.bounds.max - probe.bounds.min).max(DVec3::ZERO);
    let (side_x, side_z) = (e.y * e.z, e.x * e.y);
    let largest = side_x.max(side_z).max(1e-30);
    let sources = light_directions(probe, lights, centre);
    let total: f64 = sources.iter().map(|s| s.1).sum();
    let front = DVec3::new(0.35, 0.3, 1.0).normalize();
    let mut best = (f64::NEG_INFINITY, front);
    for a in 0..16 {
        for elevation in [0.25f64, 0.5] {
            let az = a as f64 / 16.0 * std::f64::consts::TAU;
            let d = DVec3::new(
                elevation.cos() * az.sin(),
                elevation.sin(),
                elevation.cos() * az.cos(),
            );
            let lit: f64 = if total > 0.0 {
                sources
                    .iter()
                    .map(|(l, w)| w * d.dot(*l).max(0.0))
                    .sum::<f64>()
                    / total
            } else {
                0.0
            };
            // The projected area of the box's sides seen from d, relative to the larger side.
            let broad = (d.x.abs() * side_x + d.z.abs() * side_z) / largest;
            let score = lit + 0.3 * d.dot(front) + 0.4 * broad;
            if score > best.0 {
                best = (score, d);
            }
        }
    }
    best.1
}

/// A subject is mostly flat (a board, a wall of samples) when its bounds' thinnest side is at
/// most this share of the next: it is then seen facing it.
pub const FLAT_RATIO: f64 = 0.2;

/// The direction (subject to eye) that faces a standing, mostly flat subject ([`FLAT_RATIO`],
/// its thin side horizontal): along its thin axis, from the side its punctual lights are on; else, for
/// a board across z, from glTF's front, +Z (Khronos's test boards face it; which side shows
/// more front faces does not tell: ClearCoatTest shows more from behind); else from the only
/// side where an 8 × 8 grid of
/// rays finds surfaces that show (front faces, or double-sided ones: a single-sided board
/// shows nothing from behind), else from +X. A backdrop ([`without_backdrop`]) does not count:
/// the board in front of it decides.
pub fn flat_facing(probe: &Probe, lights: &[Light]) -> Option<DVec3> {
    let b = without_backdrop(probe).unwrap_or(probe.bounds);
    let e = (b.max - b.min).max(DVec3::ZERO);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &k| e[i].total_cmp(&e[k]));
    let (thin, u, v) = (order[0], order[1], order[2]);
    if e[thin] > FLAT_RATIO * e[u] || e[u] <= 0.0 || thin == 1 {
        return None;
    }
    let axis = DVec3::AXES[thin];
    let centre = b.center();
    // Surfaces that show to rays along −s over the board, from side `s`.
    let fronts = |s: f64| {
        let mut n = 0usize;
        for i in 0..8 {
            for k in 0..8 {
                let mut p = centre + axis * (s * e.length());
                p[u] = b.min[u] + (i as f64 + 0.5) / 8.0 * e[u];
                p[v] = b.min[v] + (k as f64 + 0.5) / 8.0 * e[v];
                let d = -axis * s;
                if probe.hit_all(p, d).is_some_and(|prim| probe.shows(prim, d)) {
                    n += 1;
                }
            }
        }
        n
    };
    let (plus, minus) = (fronts(1.0), fronts(-1.0));
    // The punctual lights alone (the first entries): the board's own glowing parts
    // (ClearCoatTest's labels) are no side to face.
    let lit: f64 = light_directions(probe, lights, centre)
        .iter()
        .take(lights.len())
        .map(|(l, w)| w * l.dot(axis))
        .sum();
    let sign = if lit != 0.0 {
        lit.signum()
    } else if thin == 2 || plus > 0 || minus == 0 {
        1.0
    } else {
        -1.0
    };
    Some(axis * sign)
}

/// The bounds of every object but a backdrop: one object whose bounds hold all the others'
/// (a cyclorama behind a board of samples, TransmissionRoughnessTest's), clipped to the
/// probe's bounds; `None` when there is no such object.
fn without_backdrop(probe: &Probe) -> Option<Bounds> {
    let tris = &probe.tris;
    let objects = tris.starts.len().saturating_sub(1);
    if objects < 2 {
        return None;
    }
    let boxes: Vec<Bounds> = (0..objects)
        .map(|o| {
            let mut b = Bounds::default();
            tris.visit(tris.starts[o]..tris.starts[o + 1], |_, v, _| {
                v.iter().for_each(|p| b.grow(p.as_dvec3()))
            });
            b
        })
        .collect();
    let holds = |a: &Bounds, b: &Bounds| {
        b.is_empty() || (a.min.cmple(b.min).all() && a.max.cmpge(b.max).all())
    };
    let backdrop = (0..objects).find(|&o| {
        !boxes[o].is_empty() && (0..objects).all(|k| k == o || holds(&boxes[o], &boxes[k]))
    })?;
    let mut rest = Bounds::default();
    for (k, b) in boxes.iter().enumerate() {
        if k != backdrop && !b.is_empty() {
            rest.grow(b.min.max(probe.bounds.min));
            rest.grow(b.max.min(probe.bounds.max));
        }
    }
    (!rest.is_empty()).then_some(rest)
}

/// A camera looking at the middle of `bounds` from direction `dir` (unit, subject to eye), at
/// the distance where all `points` fit 90% of the frame of `aspect` (width/height). With the
/// eight corners of the bounds as points the whole box fits; with the subject's vertices its
/// silhouette does, which fills the frame better.
pub fn fit(bounds: &Bounds, points: &[Vec3], dir: DVec3, yfov: f64, aspect: f64) -> Camera {
    let centre = bounds.center();
    let probe = Camera::look_at(AUTO_CAMERA, centre + dir, centre, yfov);
    let right = probe.forward.cross(probe.up).normalize();
    let tan_y = (yfov * 0.5).tan() * 0.9;
    let tan_x = tan_y * aspect.max(1e-3);
    let corners = (0..8).map(|i| {
        DVec3::new(
            if i & 1 == 0 {
                bounds.min.x
            } else {
                bounds.max.x
            },
            if i & 2 == 0 {
                bounds.min.y
            } else {
                bounds.max.y
            },
            if i & 4 == 0 {
                bounds.min.z
            } else {
                bounds.max.z
            },
        )
    });
    let all: Vec<DVec3> = if points.is_empty() {
        corners.collect()
    } else {
        points.iter().map(|p| p.as_dvec3()).collect()
    };
    let mut distance: f64 = 1e-6 * bounds.diagonal();
    for corner in all {
        let p = corner - centre;
        let depth = p.dot(probe.forward);
        distance = distance
            .max(p.dot(right).abs() / tan_x - depth)
            .max(p.dot(probe.up).abs() / tan_y - depth);
    }
    Camera::look_at(AUTO_CAMERA, centre + dir * distance, centre, yfov)
}

/// The first view of `scene` lit by `lights` (the scene's own, without a default rig), for an
/// image of `aspect` (width/height). `camera` is the scene's own camera when it has one: it is
/// kept ("a scene's camera wins") and only the light rule is evaluated from it. The probe's
/// quick BLASes stay in the scene for the renderer ([`Probe::keep_blases`]).
pub fn first_view(
    scene: &Scene,
    lights: &[Light],
    camera: Option<&Camera>,
    aspect: f64,
) -> FirstView {
    let _memory = crate::cl::kernels::OpeningMemory::begin();
    let probe = Probe::new(scene);
    let t = std::time::Instant::now();
    let view = first_view_in_frame(&probe, lights, camera, aspect);
    log::debug!("probe: rays in {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
    probe.keep_blases(scene);
    view
}

/// [`first_view_with`] for world-space `lights` and `camera`, traced in the probe's render
/// frame: the view it returns is in world space.
pub fn first_view_in_frame(
    probe: &Probe,
    lights: &[Light],
    camera: Option<&Camera>,
    aspect: f64,
) -> FirstView {
    let frame = probe.frame;
    let lights = frame.lights(lights);
    let camera = camera.map(|c| frame.camera(c));
    let view = first_view_with(probe, &lights, camera.as_ref(), aspect);
    FirstView {
        camera: frame.world_camera(&view.camera),
        bounds: frame.world_bounds(&view.bounds),
        ..view
    }
}

/// [`first_view`] with a probe already built, in the probe's render frame (lights, camera and
/// the view returned).
pub fn first_view_with(
    probe: &Probe,
    lights: &[Light],
    camera: Option<&Camera>,
    aspect: f64,
) -> FirstView {
    let bounds = probe.bounds;
    let cost = probe.ray_cost();
    if cost > PROBE_MAX_RAY_COST {
        return unprobed(probe, camera, aspect, cost);
    }
    let (camera, interior) = match camera {
        Some(c) => (c.clone(), false),
        None if !probe.any_opaque => (Camera::framing(&bounds, super::AUTO_YFOV), false),
        None => {
            let outside = |dir: DVec3| fit(&bounds, &probe.points, dir, super::AUTO_YFOV, aspect);
            let object = || flat_facing(probe, lights).unwrap_or_else(|| lit_side(probe, lights));
            match classify_model(probe) {
                Shell::Interior => match interior_camera(probe) {
                    Some(c) => (c, true),
                    None => (outside(object()), false),
                },
                Shell::OpenSide(d) => {
                    // Straight into the opening, a little from above; a board standing inside
                    // that faces the opening, straight at it, all of it in the frame.
                    match flat_facing(probe, lights).filter(|f| f.dot(d) > 0.5) {
                        Some(dir) => {
                            let board = without_backdrop(probe).unwrap_or(bounds);
                            let corners: Vec<Vec3> = (0..8)
                                .map(|i| {
                                    let pick = |bit: usize, k: usize| {
                                        if i & bit == 0 {
                                            board.min[k]
                                        } else {
                                            board.max[k]
                                        }
                                    };
                                    DVec3::new(pick(1, 0), pick(2, 1), pick(4, 2)).as_vec3()
                                })
                                .collect();
                            (fit(&board, &corners, dir, super::AUTO_YFOV, aspect), false)
                        }
                        None => (outside((d + DVec3::Y * 0.15).normalize()), false),
                    }
                }
                Shell::Object => (outside(object()), false),
            }
        }
    };
    let LightTest {
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
    } = light_test(probe, lights, &camera, aspect);
    FirstView {
        camera,
        bounds,
        interior,
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
        unprobed_cost: None,
    }
}

/// The most triangle tests and node steps one probe ray may be expected to take
/// ([`Probe::ray_cost`]). The probe traces some 40,000 rays at a few nanoseconds a test, so
/// this bounds it to about two seconds; a healthy tree costs tens, while 10⁶ triangles in one
/// place cost 10⁶ (the probe took 110 s on them).
pub const PROBE_MAX_RAY_COST: f64 = 16384.0;

/// The first view without tracing the probe's rays, for a scene whose trees would make them
/// too slow (each about `cost` tests): `camera`, else the robust bounds fitted from the front
/// and a little above; taken as unlit by its own lights, open to the environment, and metered
/// on the image (`unprobed_cost` says so to the caller).
fn unprobed(probe: &Probe, camera: Option<&Camera>, aspect: f64, cost: f64) -> FirstView {
    let dir = DVec3::new(0.35, 0.3, 1.0).normalize();
    let camera = camera.cloned().unwrap_or_else(|| {
        if probe.any_opaque {
            fit(&probe.bounds, &probe.points, dir, super::AUTO_YFOV, aspect)
        } else {
            Camera::framing(&probe.bounds, super::AUTO_YFOV)
        }
    });
    FirstView {
        camera,
        bounds: probe.bounds,
        interior: false,
        lit: false,
        coverage: 0.0,
        lit_fraction: 0.0,
        subject_radiance: 0.0,
        emitter_radiance: 0.0,
        sky_fraction: 1.0,
        key_irradiance: 0.0,
        shiny_share: 0.0,
        shiny_sky: 0.0,
        subject_normals: Vec::new(),
        unprobed_cost: Some(cost),
    }
}

/// A light added by the user: a point light above and to the right of the camera, a third of
/// the way to what it looks at, so that it shows in the view and lights the subject with an
/// irradiance of about 1 (`distance` is the camera's distance to its subject).
pub fn light_near_camera(camera: &Camera, distance: f64, name: &str) -> Light {
    let distance = distance.max(1e-6);
    let right = camera.forward.cross(camera.up).normalize_or(DVec3::X);
    let position = camera.eye
        + camera.forward * (0.3 * distance)
        + camera.up * (0.12 * distance)
        + right * (0.12 * distance);
    let to_subject = camera.eye + camera.forward * distance - position;
    let d = to_subject.length();
    Light {
        name: name.into(),
        kind: LightKind::Point,
        position,
        direction: to_subject.normalize_or(DVec3::NEG_Y),
        color: [1.0, 1.0, 1.0],
        intensity: (d * d) as f32,
        light_radius: (0.02 * distance) as f32,
    }
}

/// Lights for an interior the scene's own lights leave dark: a lamp below the ceiling above the
/// camera and a softer one at the camera, both scaled to the room.
pub fn interior_lights(first: &FirstView) -> Vec<Light> {
    let b = first.bounds;
    let height = (b.max.y - b.min.y).max(1e-6);
    let span = (b.max - b.min).length();
    let ahead = first.camera.eye + first.camera.forward.with_y(0.0) * (0.15 * span);
    let ceiling = ahead.with_y(b.max.y - 0.1 * height).clamp(b.min, b.max);
    let mut lamp = light_near_camera(&first.camera, 0.25 * span, "room light");
    lamp.position = ceiling;
    lamp.direction = DVec3::NEG_Y;
    lamp.intensity = (0.25 * span * 0.25 * span) as f32;
    let fill = light_near_camera(&first.camera, 0.15 * span, "camera light");
    vec![lamp, fill]
}
