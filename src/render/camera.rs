//! Camera rays on the host, formed as the `generate` kernel forms them (pinhole, no jitter):
//! for picking, focusing on what a pixel sees, and the benchmarks' primary rays.

use crate::bvh::Ray;
use crate::cl::types::DeviceCamera;
use glam::Vec3;

/// The ray through the point (fx, fy) of the image, both in [0, 1] from the top left. Its
/// direction is `forward + x·right + y·up`, not normalized (the image centre's has the length of
/// `forward`); `tmin` is 0 and `tmax` infinite.
pub fn primary_ray(camera: &DeviceCamera, fx: f32, fy: f32) -> Ray {
    let v = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    let direction =
        v(camera.forward) + (2.0 * fx - 1.0) * v(camera.right) + (1.0 - 2.0 * fy) * v(camera.up);
    Ray {
        origin: v(camera.origin),
        direction,
        tmin: 0.0,
        tmax: f32::INFINITY,
    }
}
