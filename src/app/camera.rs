//! The camera controller: fly mode (WASD, Q/E, mouse-look) and orbit mode (around a pivot, pan,
//! zoom). It edits a [`Camera`] in place, so a camera nobody touched stays exactly the file's
//! (and renders like `penumbra render --camera`); the first rotation levels its roll to +Y up.
//!
//! The fly speed follows the distance to what the camera sees (`pick::seen_distance`, a grid of
//! host BVH rays), times a factor the wheel and +/− change; with collision on, a move stops
//! short of the first surface along it (a host ray cast along the move).

use crate::scene::{Bounds, Camera};
use glam::{DQuat, DVec3};

/// Radians of rotation per pixel of mouse movement.
const LOOK_RADIANS_PER_PIXEL: f64 = 0.004;
/// Speed factor while Shift is held.
pub const FAST_FACTOR: f64 = 4.0;
/// Speed (or zoom) factor per wheel notch or +/− press.
const SPEED_STEP: f64 = 1.25;
/// Distance factor per wheel notch in orbit mode.
const ZOOM_STEP: f64 = 0.85;
/// The view may not come closer to straight up or down than this |forward.y|.
const MAX_VERTICAL: f64 = 0.995;
/// Share of the distance to what the camera sees it flies per second at speed factor 1: in a
/// room 4 m across, about 2 m/s; before a wall 1 m away, 0.5 m/s.
const SPEED_PER_SEEN_DISTANCE: f64 = 0.5;
/// With collision on, a move stops this share of the scene's size before a surface.
const COLLISION_MARGIN: f64 = 0.005;

/// The distance to the first surface from a point along a unit direction, if any.
pub type Obstacle<'a> = &'a dyn Fn(DVec3, DVec3) -> Option<f64>;

/// How mouse and keys move the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// Move freely: WASD along the view, mouse-look turns in place.
    #[default]
    Fly,
    /// Turn around a pivot: mouse drags orbit, the wheel zooms; WASD move camera and pivot.
    Orbit,
}

impl Mode {
    /// Name shown to users.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Fly => "fly",
            Mode::Orbit => "orbit",
        }
    }
}

/// The movement keys held down.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Motion {
    /// W.
    pub forward: bool,
    /// S.
    pub back: bool,
    /// A.
    pub left: bool,
    /// D.
    pub right: bool,
    /// E.
    pub up: bool,
    /// Q.
    pub down: bool,
    /// Shift.
    pub fast: bool,
}

impl Motion {
    /// Whether any movement key is held.
    pub fn any(&self) -> bool {
        self.forward || self.back || self.left || self.right || self.up || self.down
    }
}

/// The viewer's camera and how input moves it.
#[derive(Clone, Debug)]
pub struct CameraController {
    /// The camera as it is now.
    pub camera: Camera,
    /// The view R returns to.
    initial: Camera,
    /// Fly or orbit.
    pub mode: Mode,
    /// The point orbit mode turns around.
    pub pivot: DVec3,
    /// Fly speed in scene units per second.
    pub speed: f64,
    /// The user's factor on the speed the seen distance gives (wheel, +/−).
    pub speed_factor: f64,
    /// The last distance to what the camera sees.
    seen: Option<f64>,
    /// Moves stop short of surfaces.
    pub collision: bool,
    /// The scene's size, which scales speeds and limits.
    scene_size: f64,
    /// The scene's center, the default pivot distance reference.
    scene_center: DVec3,
}

impl CameraController {
    /// A controller starting at `camera` in a scene with `bounds`.
    pub fn new(camera: Camera, bounds: &Bounds) -> Self {
        let mut c = Self {
            camera: camera.clone(),
            initial: camera,
            mode: Mode::Fly,
            pivot: DVec3::ZERO,
            speed: 0.0,
            speed_factor: 1.0,
            seen: None,
            collision: false,
            scene_size: bounds.diagonal(),
            scene_center: bounds.center(),
        };
        c.reset();
        c
    }

    /// Back to the initial view, pivot and speed.
    pub fn reset(&mut self) {
        self.camera = self.initial.clone();
        self.speed = 0.25 * self.scene_size;
        self.speed_factor = 1.0;
        self.seen = None;
        self.pivot = self.default_pivot();
    }

    /// Makes `camera` the current and the initial view (choosing one of the file's cameras).
    pub fn set_initial(&mut self, camera: Camera) {
        self.initial = camera;
        let mode = self.mode;
        self.reset();
        self.mode = mode;
    }

    /// The view's subject: the point straight ahead at the distance of what the camera sees,
    /// else of the scene's center (so switching to orbit mode does not move the view).
    fn default_pivot(&self) -> DVec3 {
        let d = self.seen.unwrap_or_else(|| {
            (self.scene_center - self.camera.eye)
                .length()
                .max(0.05 * self.scene_size)
        });
        self.camera.eye + self.camera.forward * d
    }

    /// The distance to what the camera sees now: the fly speed follows it.
    pub fn set_seen_distance(&mut self, distance: f64) {
        if !(distance.is_finite() && distance > 0.0) {
            return;
        }
        self.seen = Some(distance);
        self.speed = (SPEED_PER_SEEN_DISTANCE * distance * self.speed_factor)
            .clamp(1e-4 * self.scene_size, 1e2 * self.scene_size);
    }

    /// Switches mode; entering orbit mode puts the pivot straight ahead.
    pub fn set_mode(&mut self, mode: Mode) {
        if mode == Mode::Orbit && self.mode != Mode::Orbit {
            self.pivot = self.default_pivot();
        }
        self.mode = mode;
    }

    /// Puts the pivot at `point` (a picked surface point) without moving the camera.
    pub fn set_pivot(&mut self, point: DVec3) {
        self.pivot = point;
    }

    /// The unit right vector.
    fn right(&self) -> DVec3 {
        self.camera
            .forward
            .cross(self.camera.up)
            .try_normalize()
            .unwrap_or(DVec3::X)
    }

    /// Moves by the held keys over `dt` seconds; in orbit mode the pivot moves along. With
    /// collision on, the move stops short of the first surface `obstacle` finds along it.
    /// Returns whether the camera moved.
    pub fn fly(&mut self, motion: &Motion, dt: f64, obstacle: Obstacle) -> bool {
        let axis = |pos: bool, neg: bool| (pos as i32 - neg as i32) as f64;
        let direction = self.camera.forward * axis(motion.forward, motion.back)
            + self.right() * axis(motion.right, motion.left)
            + DVec3::Y * axis(motion.up, motion.down);
        let Some(direction) = direction.try_normalize() else {
            return false;
        };
        let factor = if motion.fast { FAST_FACTOR } else { 1.0 };
        let mut length = self.speed * factor * dt.max(0.0);
        if self.collision
            && let Some(t) = obstacle(self.camera.eye, direction)
        {
            length = length.min((t - COLLISION_MARGIN * self.scene_size).max(0.0));
        }
        let step = direction * length;
        if step == DVec3::ZERO {
            return false;
        }
        self.camera.eye += step;
        if self.mode == Mode::Orbit {
            self.pivot += step;
        }
        true
    }

    /// Mouse-look by a drag of (dx, dy) pixels: turns in place (fly) or around the pivot
    /// (orbit). Returns whether the camera moved.
    pub fn look(&mut self, dx: f64, dy: f64) -> bool {
        let yaw = DQuat::from_axis_angle(DVec3::Y, -dx * LOOK_RADIANS_PER_PIXEL);
        let pitch = DQuat::from_axis_angle(self.right(), -dy * LOOK_RADIANS_PER_PIXEL);
        let mut rotation = yaw * pitch;
        // Refuse the pitch part when it would turn the view past straight up or down.
        if (rotation * self.camera.forward).y.abs() > MAX_VERTICAL {
            rotation = yaw;
        }
        if rotation.angle_between(DQuat::IDENTITY) == 0.0 {
            return false;
        }
        match self.mode {
            Mode::Fly => {
                self.camera.forward = (rotation * self.camera.forward).normalize();
            }
            Mode::Orbit => {
                let offset = rotation * (self.camera.eye - self.pivot);
                self.camera.eye = self.pivot + offset;
                self.camera.forward = (-offset).try_normalize().unwrap_or(self.camera.forward);
            }
        }
        self.level();
        true
    }

    /// Pans by a drag of (dx, dy) pixels on a viewport `height` pixels tall: the point at the
    /// pivot's distance follows the mouse. Camera and pivot move together.
    pub fn pan(&mut self, dx: f64, dy: f64, height: f64) -> bool {
        let distance = (self.pivot - self.camera.eye)
            .length()
            .max(1e-3 * self.scene_size);
        let per_pixel = 2.0 * distance * (self.camera.yfov * 0.5).tan() / height.max(1.0);
        let step = (-dx * self.right() + dy * self.camera.up) * per_pixel;
        if step == DVec3::ZERO {
            return false;
        }
        self.camera.eye += step;
        self.pivot += step;
        true
    }

    /// Wheel `notches` (positive = away from the user): orbit mode moves toward the pivot,
    /// fly mode changes the speed. Returns whether the camera moved.
    pub fn wheel(&mut self, notches: f64) -> bool {
        match self.mode {
            Mode::Fly => {
                self.scale_speed(notches);
                false
            }
            Mode::Orbit => {
                let distance = (self.camera.eye - self.pivot).length();
                let new = (distance * ZOOM_STEP.powf(notches))
                    .clamp(1e-3 * self.scene_size, 1e3 * self.scene_size.max(distance));
                if new == distance {
                    return false;
                }
                self.camera.eye = self.pivot - self.camera.forward * new;
                true
            }
        }
    }

    /// Multiplies the fly speed (and its factor) by 1.25 per step (negative steps slow down).
    pub fn scale_speed(&mut self, steps: f64) {
        let old = self.speed;
        self.speed = (self.speed * SPEED_STEP.powf(steps))
            .clamp(1e-4 * self.scene_size, 1e2 * self.scene_size);
        if old > 0.0 {
            self.speed_factor *= self.speed / old;
        }
    }

    /// Recomputes `up` from +Y so the horizon stays level.
    fn level(&mut self) {
        let right = self
            .camera
            .forward
            .cross(DVec3::Y)
            .try_normalize()
            .unwrap_or_else(|| self.right());
        self.camera.up = right.cross(self.camera.forward).normalize();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene_box() -> Bounds {
        Bounds {
            min: DVec3::splat(-1.0),
            max: DVec3::splat(1.0),
        }
    }

    fn controller() -> CameraController {
        let cam = Camera::look_at("test", DVec3::new(0.0, 0.5, 5.0), DVec3::ZERO, 0.8);
        CameraController::new(cam, &scene_box())
    }

    #[test]
    fn w_moves_along_the_view_direction() {
        let mut c = controller();
        let (eye, forward) = (c.camera.eye, c.camera.forward);
        let held = Motion {
            forward: true,
            ..Motion::default()
        };
        assert!(c.fly(&held, 0.5, &|_, _| None));
        let moved = c.camera.eye - eye;
        assert!((moved.normalize() - forward).length() < 1e-9);
        assert!((moved.length() - 0.5 * c.speed).abs() < 1e-9);
        // Shift is faster; nothing held does nothing.
        let before = c.camera.eye;
        c.fly(
            &Motion {
                back: true,
                fast: true,
                ..Motion::default()
            },
            0.5,
            &|_, _| None,
        );
        assert!(((before - c.camera.eye).length() - 0.5 * c.speed * FAST_FACTOR).abs() < 1e-9);
        assert!(!c.fly(&Motion::default(), 1.0, &|_, _| None));
    }

    #[test]
    fn q_and_e_move_down_and_up() {
        let mut c = controller();
        let y = c.camera.eye.y;
        c.fly(
            &Motion {
                up: true,
                ..Motion::default()
            },
            1.0,
            &|_, _| None,
        );
        assert!((c.camera.eye.y - y - c.speed).abs() < 1e-9);
    }

    #[test]
    fn mouse_look_turns_in_place_and_keeps_the_horizon_level() {
        let mut c = controller();
        let eye = c.camera.eye;
        assert!(c.look(100.0, 30.0));
        assert_eq!(c.camera.eye, eye);
        assert!((c.camera.forward.length() - 1.0).abs() < 1e-9);
        assert!(c.camera.up.dot(c.camera.forward).abs() < 1e-9);
        assert!(c.camera.forward.cross(c.camera.up).y.abs() < 1e-9, "rolled");
        // Looking far up stops short of the pole.
        c.look(0.0, -10_000.0);
        assert!(c.camera.forward.y.abs() <= MAX_VERTICAL + 1e-9);
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_pivot() {
        let mut c = controller();
        c.set_mode(Mode::Orbit);
        let pivot = c.pivot;
        let distance = (c.camera.eye - pivot).length();
        for (dx, dy) in [(50.0, 0.0), (0.0, 40.0), (-120.0, -60.0)] {
            assert!(c.look(dx, dy));
            assert!(((c.camera.eye - pivot).length() - distance).abs() < 1e-9);
            // Still looking at the pivot.
            let to_pivot = (pivot - c.camera.eye).normalize();
            assert!((to_pivot - c.camera.forward).length() < 1e-9);
        }
        // The wheel zooms toward the pivot, panning moves both.
        assert!(c.wheel(1.0));
        assert!((c.camera.eye - pivot).length() < distance);
        let before = (c.camera.eye, c.pivot);
        assert!(c.pan(10.0, 0.0, 100.0));
        assert!(((c.camera.eye - before.0) - (c.pivot - before.1)).length() < 1e-12);
    }

    #[test]
    fn entering_orbit_mode_does_not_move_the_view() {
        let mut c = controller();
        c.look(30.0, 0.0);
        let cam = c.camera.clone();
        c.set_mode(Mode::Orbit);
        assert_eq!(c.camera, cam);
        let to_pivot = (c.pivot - c.camera.eye).normalize();
        assert!((to_pivot - c.camera.forward).length() < 1e-9);
    }

    #[test]
    fn the_wheel_in_fly_mode_changes_speed() {
        let mut c = controller();
        let speed = c.speed;
        assert!(!c.wheel(2.0));
        assert!(c.speed > speed);
        c.scale_speed(-4.0);
        assert!(c.speed < speed);
    }

    #[test]
    fn collision_stops_short_of_a_wall_and_can_be_turned_off() {
        let mut c = controller();
        // A wall across the view 0.5 ahead of the eye.
        let (eye0, normal) = (c.camera.eye, c.camera.forward);
        let plane = move |o: DVec3, d: DVec3| {
            let facing = d.dot(normal);
            (facing > 0.0).then(|| (eye0 + 0.5 * normal - o).dot(normal) / facing)
        };
        let wall: Obstacle = &plane;
        let held = Motion {
            forward: true,
            ..Motion::default()
        };
        c.speed = 10.0;
        c.collision = true;
        let eye = c.camera.eye;
        assert!(c.fly(&held, 1.0, wall));
        let moved = (c.camera.eye - eye).length();
        assert!(moved < 0.5 && moved > 0.4, "{moved}");
        // At the wall: no further.
        assert!(!c.fly(&held, 1.0, wall));
        c.collision = false;
        assert!(c.fly(&held, 1.0, wall));
        assert!((c.camera.eye - eye).length() > 10.0);
    }

    #[test]
    fn the_fly_speed_follows_the_distance_seen_and_the_users_factor() {
        let mut c = controller();
        c.set_seen_distance(2.0);
        assert!((c.speed - 1.0).abs() < 1e-12);
        c.scale_speed(1.0);
        c.set_seen_distance(0.4);
        assert!((c.speed - 0.2 * SPEED_STEP).abs() < 1e-12);
        // The pivot of orbit mode is what the camera sees.
        c.set_mode(Mode::Orbit);
        assert!(((c.pivot - c.camera.eye).length() - 0.4).abs() < 1e-12);
    }

    #[test]
    fn reset_restores_the_initial_view() {
        let mut c = controller();
        let initial = c.camera.clone();
        c.look(40.0, 10.0);
        c.fly(
            &Motion {
                left: true,
                ..Motion::default()
            },
            1.0,
            &|_, _| None,
        );
        c.camera.yfov = 1.2;
        c.scale_speed(3.0);
        assert_ne!(c.camera, initial);
        c.reset();
        assert_eq!(c.camera, initial);
        assert!((c.speed - 0.25 * scene_box().diagonal()).abs() < 1e-12);
        // A chosen file camera becomes what R returns to.
        let other = Camera::look_at("other", DVec3::new(3.0, 0.0, 0.0), DVec3::ZERO, 0.5);
        c.set_initial(other.clone());
        c.look(10.0, 0.0);
        c.reset();
        assert_eq!(c.camera, other);
    }
}
