//! Interiors: whether the model is a room seen from inside, an open box or an object
//! ([`classify_shell`]), and the camera inside a room.

use super::super::Camera;
use super::probe::sphere_directions;
use super::{AUTO_CAMERA, Probe};
use glam::DVec3;

/// Share of the rays from the middle of the bounds that must hit front faces for an interior.
pub const INTERIOR_HIT_FRACTION: f64 = 0.6;
/// Share of escaping rays from which a one-sided opening makes an open box (the Cornell box
/// loses a sixth of its rays through its front; a room loses a few through its windows).
pub const OPEN_SIDE_FRACTION: f64 = 0.08;
/// Rays cast from the middle of the bounds to tell an interior from an object.
pub const SHELL_RAYS: usize = 128;
/// Eye height in metres (glTF's unit) inside a room; models in centimetres or millimetres are
/// recognised by their floor-to-ceiling height.
pub const EYE_HEIGHT: f64 = 1.6;
/// Vertical field of view of an interior view (wider than [`crate::scene::AUTO_YFOV`]).
pub const INTERIOR_YFOV: f64 = 1.15;

/// What the rays from the middle of the bounds say about the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shell {
    /// Most rays hit surfaces that face the middle (walls seen from inside) and the openings
    /// are not all on one side: a room or a building, seen from inside.
    Interior,
    /// A box open on one side (a stage, the Cornell box): seen from that side, along this
    /// unit direction (from the middle outwards).
    OpenSide(DVec3),
    /// Anything else: framed from outside.
    Object,
}

/// Points besides the middle that must be enclosed too (at least this many of the four at a
/// quarter of the bounds' width and depth from the middle): a room encloses every point of
/// it; a hollow object or a group with a gap between its parts encloses its middle alone.
pub const ENCLOSED_POINTS: usize = 3;

/// Classifies the model seen from the middle of its bounds ([`classify_shell`]), and keeps an
/// interior or an open box only when at least [`ENCLOSED_POINTS`] of the four points a quarter
/// of the width and depth away from the middle are enclosed by front faces as well (more than
/// [`INTERIOR_HIT_FRACTION`] of their rays, a quarter less for an open box, which loses more
/// through its opening seen from near it).
pub fn classify_model(probe: &Probe) -> Shell {
    let b = probe.bounds;
    let centre = b.center();
    let shell = classify_shell(probe, centre);
    let need = match shell {
        Shell::Object => return shell,
        Shell::Interior => INTERIOR_HIT_FRACTION,
        Shell::OpenSide(_) => 0.75 * INTERIOR_HIT_FRACTION,
    };
    let e = b.max - b.min;
    let enclosed = [(-1.0, 0.0), (1.0, 0.0), (0.0, -1.0), (0.0, 1.0)]
        .into_iter()
        .filter(|(x, z)| {
            let p = centre + DVec3::new(0.25 * x * e.x, 0.0, 0.25 * z * e.z);
            front_fraction(probe, p).0 >= need
        })
        .count();
    if enclosed >= ENCLOSED_POINTS {
        shell
    } else {
        Shell::Object
    }
}

/// The share of [`SHELL_RAYS`] rays from `point` that hit front faces (surfaces that face the
/// point), the rays that escape and the sum of their directions.
fn front_fraction(probe: &Probe, point: DVec3) -> (f64, usize, DVec3) {
    let (mut front, mut misses) = (0usize, 0usize);
    let mut escape = DVec3::ZERO;
    for d in sphere_directions(SHELL_RAYS) {
        match probe.hit_all(point, d) {
            Some(prim) if probe.normal(prim).dot(d) < 0.0 => front += 1,
            Some(_) => {}
            None => {
                escape += d;
                misses += 1;
            }
        }
    }
    (front as f64 / SHELL_RAYS as f64, misses, escape)
}

/// Classifies the model by [`SHELL_RAYS`] rays from `point`. A surface seen from inside a room
/// faces the point; the shell of a closed object seen from within faces away, so only hits on
/// front faces count. At least [`INTERIOR_HIT_FRACTION`] of the rays must hit front faces; when
/// the rays that escape leave mostly sideways through one side (their mean direction is long and
/// near horizontal), the model is an open box instead.
pub fn classify_shell(probe: &Probe, point: DVec3) -> Shell {
    let (front, misses, escape) = front_fraction(probe, point);
    if front < INTERIOR_HIT_FRACTION {
        return Shell::Object;
    }
    let mean = escape / misses.max(1) as f64;
    let open = misses as f64 >= OPEN_SIDE_FRACTION * SHELL_RAYS as f64;
    if open && mean.length() > 0.6 && mean.normalize().y.abs() < 0.5 {
        Shell::OpenSide(mean.normalize())
    } else {
        Shell::Interior
    }
}

/// A horizontal unit direction at `azimuth` radians (0 = −Z, growing towards +X).
fn horizontal(azimuth: f64) -> DVec3 {
    DVec3::new(azimuth.sin(), 0.0, -azimuth.cos())
}

/// The camera inside a room: among a grid of standing points, the one with the most open space
/// around it at eye height; from there it looks along the longest open direction (averaged over
/// neighbouring directions so that a door does not win), stepped back towards the wall behind.
pub(super) fn interior_camera(probe: &Probe) -> Option<Camera> {
    const AZIMUTHS: usize = 32;
    let b = probe.bounds;
    let size = b.max - b.min;
    let far = probe.scale();
    let metre = probe.frame.scale;
    // Standing points: where a vertical ray finds a floor (the top of the bounds stands in for
    // a missing ceiling: models of flats are often open above).
    let mut spots = Vec::new();
    for i in 0..5 {
        for k in 0..5 {
            let fx = 0.2 + 0.15 * i as f64;
            let fz = 0.2 + 0.15 * k as f64;
            let top = DVec3::new(b.min.x + fx * size.x, b.center().y, b.min.z + fz * size.z);
            if let Some((down, _)) = probe.hit(top, DVec3::NEG_Y, far) {
                let up = probe
                    .hit(top, DVec3::Y, far)
                    .map_or(b.max.y - top.y, |h| h.0);
                spots.push((top.x, top.y - down, top.y + up, top.z));
            }
        }
    }
    // Stand on the lowest floor, not on tables or beds.
    let floor = spots.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
    let mut best: Option<(f64, DVec3, Vec<f64>)> = None;
    for &(x, bottom, ceiling, z) in &spots {
        let height = ceiling - bottom;
        if bottom > floor + 0.05 * height {
            continue;
        }
        // Metres, centimetres or millimetres, whichever makes a room height of it; else 60%.
        // (The probe's render frame is `metre` render units a world unit.)
        let eye_height = [1.0, 100.0, 1000.0]
            .into_iter()
            .find(|unit| (2.0..=5.0).contains(&(height / (unit * metre))))
            .map_or(0.6 * height, |unit| EYE_HEIGHT * unit * metre);
        let eye = DVec3::new(x, bottom + eye_height, z);
        let distances: Vec<f64> = (0..AZIMUTHS)
            .map(|a| {
                let d = horizontal(a as f64 / AZIMUTHS as f64 * std::f64::consts::TAU);
                probe.hit(eye, d, far).map_or(far, |(t, _)| t)
            })
            .collect();
        let nearest = distances.iter().copied().fold(f64::INFINITY, f64::min);
        // Standing inside furniture or at a wall: skip.
        if nearest < 0.08 * height {
            continue;
        }
        let mean = distances.iter().sum::<f64>() / AZIMUTHS as f64;
        let score = mean + nearest;
        if best.as_ref().is_none_or(|(s, _, _)| score > *s) {
            best = Some((score, eye, distances));
        }
    }
    let (_, eye, distances) = best?;
    let n = distances.len();
    let smoothed =
        |a: usize| (distances[(a + n - 1) % n] + 2.0 * distances[a] + distances[(a + 1) % n]) / 4.0;
    let look = (0..n)
        .max_by(|&a, &b| smoothed(a).total_cmp(&smoothed(b)))
        .unwrap_or(0);
    let forward = horizontal(look as f64 / n as f64 * std::f64::consts::TAU);
    let behind = distances[(look + n / 2) % n];
    let eye = eye - forward * (0.6 * behind).min(behind - 0.3 * metre).max(0.0);
    // Look slightly down, at the floor's far half.
    let target = eye + forward * 10.0 - DVec3::Y * 1.2;
    Some(Camera::look_at(AUTO_CAMERA, eye, target, INTERIOR_YFOV))
}
