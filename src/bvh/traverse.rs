//! Host reference traversal. It follows the kernels' rules step by step (watertight triangle
//! test, slab test with conservative far distances, leaf children tested on the spot, the nearer
//! interior child first) so device results can be compared with it hit for hit.

use super::{Bvh, Child};
use glam::Vec3;

/// A ray with a distance interval (tmin, tmax).
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction (need not be unit length; t is in units of it).
    pub direction: Vec3,
    /// Hits at or before this distance are ignored.
    pub tmin: f32,
    /// Hits at or beyond this distance are ignored.
    pub tmax: f32,
}

/// A ray–triangle hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
    /// Triangle index in BVH order.
    pub prim: u32,
}

/// Per-ray constants of the watertight test (Woop, Benthin, Wald 2013).
struct Shear {
    k: [usize; 3],
    s: Vec3,
}

impl Shear {
    fn new(d: Vec3) -> Self {
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        // A rotation of the axes (as the kernels' prepare_ray): no swap of x and y for a
        // negative z, which would only negate the edge functions and their sum exactly.
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        // As the kernels' prepare_ray: x and y scale by the reciprocal of z, the box test's
        // reciprocal of the dominant axis (`safe_inverse`; only a direction shorter than
        // 1e-20 tells it from 1 / z).
        let iz = safe_inverse(d)[kz];
        Self {
            k: [kx, ky, kz],
            s: Vec3::new(d[kx] * iz, d[ky] * iz, iz),
        }
    }
}

/// The watertight ray–triangle test: returns (t, u, v) with u, v the weights of vertices 1 and 2.
/// Rays through shared edges and vertices hit exactly one of the triangles sharing them.
pub fn intersect_triangle(ray: &Ray, tri: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    intersect_sheared(ray, &Shear::new(ray.direction), tri)
}

fn intersect_sheared(ray: &Ray, sh: &Shear, tri: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    let [kx, ky, kz] = sh.k;
    let a = tri[0] - ray.origin;
    let b = tri[1] - ray.origin;
    let c = tri[2] - ray.origin;
    let ax = a[kx] - sh.s.x * a[kz];
    let ay = a[ky] - sh.s.y * a[kz];
    let bx = b[kx] - sh.s.x * b[kz];
    let by = b[ky] - sh.s.y * b[kz];
    let cx = c[kx] - sh.s.x * c[kz];
    let cy = c[ky] - sh.s.y * c[kz];
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    // Fall back to double precision on an edge, as the paper does.
    if u == 0.0 || v == 0.0 || w == 0.0 {
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let (az, bz, cz) = (sh.s.z * a[kz], sh.s.z * b[kz], sh.s.z * c[kz]);
    let t = (u * az + v * bz + w * cz) / det;
    if !(t > ray.tmin && t < ray.tmax) {
        return None;
    }
    // pbrt-v4's conservative bound on t's rounding error (as `triangle_t_error` in
    // kernels/shared/traverse.h): a hit closer than its own error could lie behind the origin.
    let t_error = {
        let gamma = |n: f32| (n * 5.960_464_5e-8) / (1.0 - n * 5.960_464_5e-8);
        let max_z = az.abs().max(bz.abs()).max(cz.abs());
        let delta_z = gamma(3.0) * max_z;
        let max_x = ax.abs().max(bx.abs()).max(cx.abs());
        let max_y = ay.abs().max(by.abs()).max(cy.abs());
        let delta_x = gamma(5.0) * (max_x + max_z);
        let delta_y = gamma(5.0) * (max_y + max_z);
        let delta_e = 2.0 * (gamma(2.0) * max_x * max_y + delta_y * max_x + delta_x * max_y);
        let max_e = u.abs().max(v.abs()).max(w.abs());
        3.0 * (gamma(3.0) * max_e * max_z + delta_e * max_z + delta_z * max_e) / det.abs()
    };
    // As on the device, the bound is applied only to hits closer than 1/256 of the farthest
    // vertex: no other hit can come that close to its own error.
    if t < 0.003_906_25 * az.abs().max(bz.abs()).max(cz.abs()) && t <= t_error {
        return None;
    }
    Some((t, v / det, w / det))
}

/// Direction reciprocal that stays finite for axis-parallel rays.
pub(super) fn safe_inverse(d: Vec3) -> Vec3 {
    let fix = |x: f32| {
        if x.abs() > 1e-20 {
            1.0 / x
        } else {
            1.0 / 1e-20f32.copysign(x)
        }
    };
    Vec3::new(fix(d.x), fix(d.y), fix(d.z))
}

/// Slab test; the far distance is scaled up by two ulps so that rounding never loses a hit
/// (Ize 2013). Returns the entry distance.
pub(super) fn box_entry(
    lo: Vec3,
    hi: Vec3,
    origin: Vec3,
    inv: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    let near = t0.min(t1).max_element().max(tmin);
    let far = t0.max(t1).min_element() * (1.0 + 2.0 * f32::EPSILON);
    (near <= far && near < tmax).then_some(near)
}

/// Entries of the traversal stack; the kernels use the same size.
pub const STACK_SIZE: usize = 64;

impl Bvh {
    /// The closest hit along `ray` among `tris` (in BVH order).
    pub fn intersect(&self, ray: &Ray, tris: &[[Vec3; 3]]) -> Option<Hit> {
        self.traverse(0, ray, tris, false)
    }

    /// Whether anything blocks `ray` within its interval.
    pub fn occluded(&self, ray: &Ray, tris: &[[Vec3; 3]]) -> bool {
        self.traverse(0, ray, tris, true).is_some()
    }

    /// The closest hit (or with `any` the first) along `ray` in the subtree below node `root`.
    pub fn traverse(&self, root: u32, ray: &Ray, tris: &[[Vec3; 3]], any: bool) -> Option<Hit> {
        self.traverse_by(root, ray, any, |k| tris[k])
    }

    /// [`Bvh::traverse`] with triangle k (in BVH order) given by `tri(k)`.
    pub fn traverse_by(
        &self,
        root: u32,
        ray: &Ray,
        any: bool,
        tri: impl Fn(usize) -> [Vec3; 3],
    ) -> Option<Hit> {
        let sh = Shear::new(ray.direction);
        self.walk_from(root, ray, any, |prim, r| {
            intersect_sheared(r, &sh, &tri(prim as usize))
                .map(|(t, u, v)| (t, Hit { t, u, v, prim }))
        })
    }

    /// Walks the tree along `ray` as the kernels do, calling `test(item, ray)` for each item
    /// (in BVH order) of every leaf the ray reaches, with `ray.tmax` shortened to the closest hit
    /// so far; `test` returns the distance of its hit and the hit. Returns the closest hit, or
    /// with `any` the first one found.
    pub fn walk<H>(
        &self,
        ray: &Ray,
        any: bool,
        test: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
    ) -> Option<H> {
        self.walk_from(0, ray, any, test)
    }

    /// [`Bvh::walk`] below node `root`.
    pub fn walk_from<H>(
        &self,
        root: u32,
        ray: &Ray,
        any: bool,
        mut test: impl FnMut(u32, &Ray) -> Option<(f32, H)>,
    ) -> Option<H> {
        let inv = safe_inverse(ray.direction);
        let mut tmax = ray.tmax;
        let mut best = None;
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0;
        let mut node = root;
        loop {
            let mut near = [None, None];
            for (side, slot) in near.iter_mut().enumerate() {
                let (bounds, child) = self.child(node, side);
                let Some(d) = box_entry(bounds.min, bounds.max, ray.origin, inv, ray.tmin, tmax)
                else {
                    continue;
                };
                match child {
                    Child::Leaf { first, count } => {
                        for item in first..first + count {
                            let r = Ray { tmax, ..*ray };
                            if let Some((t, hit)) = test(item, &r) {
                                tmax = t;
                                best = Some(hit);
                                if any {
                                    return best;
                                }
                            }
                        }
                    }
                    Child::Node(index) => *slot = Some((d, index)),
                }
            }
            node = match near {
                [Some((dl, l)), Some((dr, r))] => {
                    let (first, second) = if dl <= dr { (l, r) } else { (r, l) };
                    assert!(sp < STACK_SIZE, "BVH deeper than the traversal stack");
                    stack[sp] = second;
                    sp += 1;
                    first
                }
                [Some((_, n)), None] | [None, Some((_, n))] => n,
                [None, None] => {
                    if sp == 0 {
                        return best;
                    }
                    sp -= 1;
                    stack[sp]
                }
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: Vec3, d: Vec3) -> Ray {
        Ray {
            origin: o,
            direction: d,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    #[test]
    fn hits_a_triangle_with_correct_barycentrics() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let (t, u, v) =
            intersect_triangle(&ray(Vec3::new(0.25, 0.5, 1.0), -Vec3::Z), &tri).unwrap();
        assert!((t - 1.0).abs() < 1e-6);
        assert!((u - 0.25).abs() < 1e-6 && (v - 0.5).abs() < 1e-6, "{u} {v}");
    }

    #[test]
    fn misses_outside_and_behind() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(intersect_triangle(&ray(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z), &tri).is_none());
        assert!(intersect_triangle(&ray(Vec3::new(0.2, 0.2, 1.0), Vec3::Z), &tri).is_none());
    }

    #[test]
    fn no_ray_slips_through_a_shared_edge() {
        // Two triangles sharing the diagonal of the unit square; rays exactly on the diagonal.
        let a = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)];
        let b = [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        for i in 1..100 {
            let x = i as f32 / 100.0;
            let r = ray(Vec3::new(x, x, 1.0), Vec3::new(0.0, 0.0, -1.0));
            let hits = [&a, &b]
                .iter()
                .filter(|t| intersect_triangle(&r, t).is_some())
                .count();
            assert!(hits >= 1, "the ray at {x} slipped through the edge");
        }
    }
}
