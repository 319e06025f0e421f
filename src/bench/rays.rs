//! The ray sets `bench trace` times, made on the host so that every device sees the same rays:
//! primary rays through pixel centres, cosine-distributed diffuse rays from the primary hits
//! (the incoherent first bounce) and shadow rays from the primary hits to points on the lights.

use crate::bvh::Ray;
use crate::cl::types::{DeviceCamera, DeviceHit, DeviceRay};
use crate::render::camera::primary_ray;
use glam::Vec3;
use rayon::prelude::*;

/// `DeviceHit::prim` of a miss.
pub const MISS: u32 = u32::MAX;

/// The host form of a device ray.
pub fn to_host(r: &DeviceRay) -> Ray {
    Ray {
        origin: Vec3::new(r.origin[0], r.origin[1], r.origin[2]),
        direction: Vec3::new(r.direction[0], r.direction[1], r.direction[2]),
        tmin: r.origin[3],
        tmax: r.direction[3],
    }
}

fn gpu_ray(origin: Vec3, direction: Vec3, tmax: f32) -> DeviceRay {
    DeviceRay {
        origin: [origin.x, origin.y, origin.z, 0.0],
        direction: [direction.x, direction.y, direction.z, tmax],
    }
}

/// One ray through the centre of every pixel, row by row from the top, as the `generate`
/// kernel forms them (pinhole; no jitter).
pub fn primary_rays(camera: &DeviceCamera, width: u32, height: u32) -> Vec<DeviceRay> {
    (0..width * height)
        .into_par_iter()
        .map(|pixel| {
            let fx = ((pixel % width) as f32 + 0.5) / width as f32;
            let fy = ((pixel / width) as f32 + 0.5) / height as f32;
            let ray = primary_ray(camera, fx, fy);
            gpu_ray(ray.origin, ray.direction.normalize(), f32::INFINITY)
        })
        .collect()
}

/// A point on a surface to start secondary rays from.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// The hit point moved off the surface along `normal`.
    pub origin: Vec3,
    /// The unit geometric normal on the side the primary ray came from.
    pub normal: Vec3,
}

/// The surface points of every hit (misses are left out), offset as the `shade` kernel does.
pub fn surface_points(
    rays: &[DeviceRay],
    hits: &[DeviceHit],
    triangle: &(dyn Fn(&DeviceHit) -> [Vec3; 3] + Sync),
) -> Vec<SurfacePoint> {
    rays.par_iter()
        .zip(hits)
        .filter(|(_, h)| h.prim != MISS)
        .map(|(r, h)| {
            let t = &triangle(h);
            let p = (1.0 - h.u - h.v) * t[0] + h.u * t[1] + h.v * t[2];
            let mut n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or(Vec3::Y);
            if n.dot(to_host(r).direction) > 0.0 {
                n = -n;
            }
            SurfacePoint {
                origin: offset_ray(p, n),
                normal: n,
            }
        })
        .collect()
}

/// Moves `p` off the surface along `n` by a few ulps of its coordinates (Wächter and Binder,
/// Ray Tracing Gems, chapter 6), exactly as the kernels' `offset_ray`.
fn offset_ray(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let mut out = p;
    for k in 0..3 {
        let of_i = (INT_SCALE * n[k]) as i32;
        let shifted = p[k].to_bits() as i32 + if p[k] < 0.0 { -of_i } else { of_i };
        out[k] = if p[k].abs() < ORIGIN {
            p[k] + FLOAT_SCALE * n[k]
        } else {
            f32::from_bits(shifted as u32)
        };
    }
    out
}

/// A 32-bit integer hash (lowbias32, Chris Wellons).
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// A uniform number in [0, 1) for ray `i`, dimension `dim`, from `seed`.
fn uniform(seed: u32, i: u32, dim: u32) -> f32 {
    let h = hash(hash(hash(seed) ^ i) ^ dim.wrapping_mul(0x9e37_79b9));
    (h >> 8) as f32 / 16_777_216.0
}

/// An orthonormal basis around the unit vector `n` (Duff et al. 2017), as (tangent, bitangent).
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// `count` cosine-distributed rays, ray `i` into the hemisphere of point `i % points.len()`
/// (so that the set is as large as the primary set even when some primary rays missed).
pub fn diffuse_rays(points: &[SurfacePoint], count: usize, seed: u32) -> Vec<DeviceRay> {
    assert!(!points.is_empty(), "no surface points");
    (0..count)
        .into_par_iter()
        .map(|i| {
            let s = &points[i % points.len()];
            let (u1, u2) = (uniform(seed, i as u32, 0), uniform(seed, i as u32, 1));
            let r = u1.sqrt();
            let phi = 2.0 * std::f32::consts::PI * u2;
            let (t, b) = basis(s.normal);
            let d = r * phi.cos() * t + r * phi.sin() * b + (1.0 - u1).max(0.0).sqrt() * s.normal;
            gpu_ray(s.origin, d.normalize_or(s.normal), f32::INFINITY)
        })
        .collect()
}

/// Where shadow rays go.
#[derive(Clone, Debug, Default)]
pub struct LightTargets {
    /// Emissive triangles (a uniform point on one).
    pub triangles: Vec<[Vec3; 3]>,
    /// Point and spot light positions.
    pub points: Vec<Vec3>,
    /// Directions towards directional lights (unit).
    pub directions: Vec<Vec3>,
    /// Scene bounds, for random targets when there is no light: (min, max).
    pub bounds: (Vec3, Vec3),
}

impl LightTargets {
    fn count(&self) -> usize {
        self.triangles.len() + self.points.len() + self.directions.len()
    }
}

/// `count` shadow (any-hit) rays, ray `i` from point `i % points.len()` to a light chosen
/// uniformly among the targets (a random point in the scene bounds when there is none), ending
/// just short of the target.
pub fn shadow_rays(
    points: &[SurfacePoint],
    count: usize,
    lights: &LightTargets,
    seed: u32,
) -> Vec<DeviceRay> {
    assert!(!points.is_empty(), "no surface points");
    let targets = lights.count();
    (0..count)
        .into_par_iter()
        .map(|i| {
            let s = &points[i % points.len()];
            let i = i as u32;
            let (u0, u1, u2) = (
                uniform(seed, i, 2),
                uniform(seed, i, 3),
                uniform(seed, i, 4),
            );
            let pick = ((u0 * targets as f32) as usize).min(targets.saturating_sub(1));
            let target = if targets == 0 {
                let (lo, hi) = lights.bounds;
                lo + (hi - lo) * Vec3::new(u0, u1, u2)
            } else if pick < lights.triangles.len() {
                let t = &lights.triangles[pick];
                let su = u1.sqrt();
                t[0] * (1.0 - su) + t[1] * (su * (1.0 - u2)) + t[2] * (su * u2)
            } else if pick < lights.triangles.len() + lights.points.len() {
                lights.points[pick - lights.triangles.len()]
            } else {
                let d = lights.directions[pick - lights.triangles.len() - lights.points.len()];
                return gpu_ray(s.origin, d, f32::INFINITY);
            };
            let d = target - s.origin;
            let dist = d.length();
            if dist > 0.0 {
                gpu_ray(s.origin, d / dist, dist * 0.9999)
            } else {
                gpu_ray(s.origin, s.normal, 0.0)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal() {
        for n in [Vec3::X, Vec3::NEG_Z, Vec3::new(0.3, -0.5, 0.8).normalize()] {
            let (t, b) = basis(n);
            assert!(t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && t.dot(b).abs() < 1e-6);
            assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn diffuse_rays_leave_the_surface_with_a_cosine_mean() {
        let points = vec![SurfacePoint {
            origin: Vec3::ZERO,
            normal: Vec3::Y,
        }];
        let rays = diffuse_rays(&points, 20_000, 7);
        let mean_cos: f32 =
            rays.iter().map(|r| to_host(r).direction.y).sum::<f32>() / rays.len() as f32;
        assert!(rays.iter().all(|r| to_host(r).direction.y >= 0.0));
        // E[cos] under a cosine distribution is 2/3.
        assert!((mean_cos - 2.0 / 3.0).abs() < 0.01, "{mean_cos}");
    }

    #[test]
    fn offset_moves_points_to_the_normal_side() {
        for p in [Vec3::new(5.0, -3.0, 0.0), Vec3::new(-100.0, 0.01, 7.5)] {
            let o = offset_ray(p, Vec3::Y);
            assert!(o.y > p.y && o.x == p.x && o.z == p.z);
        }
    }

    #[test]
    fn shadow_rays_stop_short_of_the_light() {
        let points = [SurfacePoint {
            origin: Vec3::ZERO,
            normal: Vec3::Y,
        }];
        let lights = LightTargets {
            points: vec![Vec3::new(0.0, 2.0, 0.0)],
            ..LightTargets::default()
        };
        let r = to_host(&shadow_rays(&points, 1, &lights, 1)[0]);
        assert!((r.direction - Vec3::Y).length() < 1e-6);
        assert!(r.tmax < 2.0 && r.tmax > 1.99);
    }
}
