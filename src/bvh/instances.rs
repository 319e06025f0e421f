//! Two levels (host side): one bottom-level BVH (BLAS) per mesh, built once and shared by every
//! instance of it, and a top-level BVH (TLAS) over the instances' world boxes, rebuilt when an
//! instance moves. A ray reaching an instance is carried into object space by the instance's
//! `object_from_world` without renormalising its direction, so distances stay in world units and
//! the watertight triangle test runs unchanged on the object-space vertices: a scaled or
//! mirrored instance is as watertight as an identity one. The kernels still traverse one flat
//! BVH; this is the host model and reference the device form will be tested against.

use super::{Aabb, Bvh, Hit, Ray, build, build_boxes};
use glam::{Mat4, Vec3};
use rayon::prelude::*;

/// A mesh's BVH and its object-space triangles in BVH order.
#[derive(Clone, Debug)]
pub struct Blas {
    /// The tree.
    pub bvh: Bvh,
    /// Triangles in BVH order (object space).
    pub triangles: Vec<[Vec3; 3]>,
}

impl Blas {
    /// Builds the BLAS of `triangles` (object space, any order).
    pub fn new(triangles: &[[Vec3; 3]]) -> Self {
        let bvh = build(triangles);
        let triangles = bvh
            .tri_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        Self { bvh, triangles }
    }

    /// The object-space box of the whole mesh.
    pub fn bounds(&self) -> Aabb {
        self.bvh.child(0, 0).0.union(self.bvh.child(0, 1).0)
    }
}

/// One placed mesh.
#[derive(Clone, Copy, Debug)]
pub struct Instance {
    /// Index of its BLAS.
    pub blas: u32,
    /// World from object transform.
    pub world_from_object: Mat4,
    /// Its inverse.
    pub object_from_world: Mat4,
}

/// A hit in a two-level scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceHit {
    /// The instance hit.
    pub instance: u32,
    /// The hit in that instance's BLAS (`prim` in its BVH order; `t` in world units).
    pub hit: Hit,
}

/// BLASes, instances and the TLAS over them.
#[derive(Clone, Debug)]
pub struct TwoLevel {
    /// One per mesh.
    pub blases: Vec<Blas>,
    /// The placed meshes.
    pub instances: Vec<Instance>,
    /// Over the instances' world boxes; its `tri_indices` are instance indices.
    pub tlas: Bvh,
}

impl TwoLevel {
    /// Builds every BLAS (in parallel) and the TLAS over `instances` (mesh index, world from
    /// object).
    pub fn new(meshes: &[Vec<[Vec3; 3]>], instances: &[(u32, Mat4)]) -> Self {
        let blases = meshes.par_iter().map(|m| Blas::new(m)).collect();
        let instances = instances
            .iter()
            .map(|&(blas, m)| Instance {
                blas,
                world_from_object: m,
                object_from_world: m.inverse(),
            })
            .collect();
        let mut two = Self {
            blases,
            instances,
            tlas: build_boxes(&[]),
        };
        two.rebuild_tlas();
        two
    }

    /// Moves instance `i` and rebuilds the TLAS.
    pub fn set_transform(&mut self, i: usize, world_from_object: Mat4) {
        self.instances[i].world_from_object = world_from_object;
        self.instances[i].object_from_world = world_from_object.inverse();
        self.rebuild_tlas();
    }

    /// Builds the TLAS over the instances' current world boxes.
    pub fn rebuild_tlas(&mut self) {
        let boxes: Vec<Aabb> = self
            .instances
            .iter()
            .map(|inst| {
                let b = self.blases[inst.blas as usize].bounds();
                (0..8).fold(Aabb::EMPTY, |acc, corner| {
                    let p = Vec3::select(
                        glam::BVec3::new(corner & 1 != 0, corner & 2 != 0, corner & 4 != 0),
                        b.max,
                        b.min,
                    );
                    acc.grow(inst.world_from_object.transform_point3(p))
                })
            })
            .collect();
        self.tlas = build_boxes(&boxes);
    }

    /// The closest hit along `ray`.
    pub fn intersect(&self, ray: &Ray) -> Option<InstanceHit> {
        self.trace(ray, false)
    }

    /// Whether anything blocks `ray` within its interval.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.trace(ray, true).is_some()
    }

    fn trace(&self, ray: &Ray, any: bool) -> Option<InstanceHit> {
        self.tlas.walk(ray, any, |leaf, r| {
            let instance = self.tlas.tri_indices[leaf as usize];
            let inst = &self.instances[instance as usize];
            let blas = &self.blases[inst.blas as usize];
            // Into object space; the direction keeps its scale so `t` stays a world distance.
            let local = Ray {
                origin: inst.object_from_world.transform_point3(r.origin),
                direction: inst.object_from_world.transform_vector3(r.direction),
                ..*r
            };
            let hit = if any {
                blas.bvh.occluded(&local, &blas.triangles).then_some(Hit {
                    t: r.tmax,
                    u: 0.0,
                    v: 0.0,
                    prim: 0,
                })
            } else {
                blas.bvh.intersect(&local, &blas.triangles)
            };
            hit.map(|hit| (hit.t, InstanceHit { instance, hit }))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::tests::{lcg, random_triangles};
    use super::super::intersect_triangle;
    use super::*;
    use glam::Quat;

    /// A closed cube [-1, 1]³, each face an n×n grid of quads (two triangles each), with shared
    /// corners computed the same way on every face so that edges match exactly.
    fn closed_cube(n: usize) -> Vec<[Vec3; 3]> {
        let c = |i: usize| i as f32 / n as f32 * 2.0 - 1.0;
        let mut tris = vec![];
        for axis in 0..3 {
            for side in [-1.0f32, 1.0] {
                let p = |i: usize, j: usize| {
                    let mut v = Vec3::ZERO;
                    v[axis] = side;
                    v[(axis + 1) % 3] = c(i);
                    v[(axis + 2) % 3] = c(j);
                    v
                };
                for i in 0..n {
                    for j in 0..n {
                        let (a, b, d, e) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                        tris.push([a, b, d]);
                        tris.push([a, d, e]);
                    }
                }
            }
        }
        tris
    }

    /// Identity, moved, non-uniformly scaled, mirrored, and rotated-and-mirrored placements.
    fn placements() -> Vec<Mat4> {
        vec![
            Mat4::IDENTITY,
            Mat4::from_translation(Vec3::new(5.0, -2.0, 3.0)),
            Mat4::from_scale_rotation_translation(
                Vec3::new(0.3, 2.0, 5.0),
                Quat::IDENTITY,
                Vec3::new(-6.0, 1.0, 0.5),
            ),
            Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)) * Mat4::from_translation(Vec3::X * 3.0),
            Mat4::from_scale_rotation_translation(
                Vec3::new(-0.5, 1.5, 0.75),
                Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.7),
                Vec3::new(0.0, 7.0, -4.0),
            ),
        ]
    }

    fn ray(origin: Vec3, direction: Vec3) -> Ray {
        Ray {
            origin,
            direction,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    #[test]
    fn no_ray_leaks_out_of_a_scaled_or_mirrored_closed_mesh() {
        let cube = closed_cube(6);
        let two = TwoLevel::new(
            std::slice::from_ref(&cube),
            &placements().iter().map(|&m| (0, m)).collect::<Vec<_>>(),
        );
        let mut leaks = 0;
        let mut rays = 0;
        for (i, inst) in two.instances.iter().enumerate() {
            let m = inst.world_from_object;
            let centre = m.transform_point3(Vec3::ZERO);
            // Aim at every vertex and edge midpoint (in world space), the hardest directions.
            for t in &cube {
                for k in 0..3 {
                    let targets = [t[k], (t[k] + t[(k + 1) % 3]) * 0.5];
                    for target in targets {
                        let d = m.transform_point3(target) - centre;
                        rays += 1;
                        match two.intersect(&ray(centre, d)) {
                            Some(h) if h.instance == i as u32 => {}
                            _ => leaks += 1,
                        }
                    }
                }
            }
        }
        assert!(rays > 5000);
        assert_eq!(leaks, 0, "rays leaked out of {rays}");
    }

    #[test]
    fn two_levels_find_the_hits_of_the_flattened_scene() {
        let meshes = vec![random_triangles(400, 1), closed_cube(3)];
        let placed: Vec<(u32, Mat4)> = placements()
            .into_iter()
            .enumerate()
            .map(|(i, m)| {
                (
                    (i % 2) as u32,
                    m * Mat4::from_translation(Vec3::splat(i as f32)),
                )
            })
            .collect();
        let two = TwoLevel::new(&meshes, &placed);
        let world: Vec<[Vec3; 3]> = placed
            .iter()
            .flat_map(|&(mesh, m)| {
                meshes[mesh as usize]
                    .iter()
                    .map(move |t| t.map(|v| m.transform_point3(v)))
            })
            .collect();
        let mut s = 5u64;
        let mut checked = 0;
        for _ in 0..2000 {
            // Rays from around the scene towards a random world triangle's centre: each must hit
            // something no farther than that triangle.
            let target = world[(lcg(&mut s) * world.len() as f32) as usize % world.len()];
            let aim = (target[0] + target[1] + target[2]) / 3.0;
            let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 30.0 - 15.0;
            let r = ray(o, aim - o);
            let expect = world
                .iter()
                .filter_map(|t| intersect_triangle(&r, t).map(|h| h.0))
                .fold(f32::INFINITY, f32::min);
            let got = two.intersect(&r).map(|h| h.hit.t);
            let got = got.expect("a ray aimed at a triangle hits");
            assert!(
                (got - expect).abs() <= 1e-4 * expect.max(1.0),
                "{got} vs {expect}"
            );
            assert!(
                got <= 1.0 + 1e-4,
                "nothing nearer than the aimed triangle was missed"
            );
            assert!(two.occluded(&r));
            checked += 1;
        }
        assert_eq!(checked, 2000);
        // A ray pointing away from everything hits nothing.
        assert!(two.intersect(&ray(Vec3::splat(100.0), Vec3::ONE)).is_none());
    }

    #[test]
    fn moving_an_instance_moves_its_hits() {
        let mut two = TwoLevel::new(&[closed_cube(2)], &[(0, Mat4::IDENTITY)]);
        let r = ray(Vec3::new(0.0, 0.0, -10.0), Vec3::Z);
        assert_eq!(two.intersect(&r).map(|h| h.hit.t), Some(9.0));
        two.set_transform(0, Mat4::from_translation(Vec3::new(0.0, 0.0, 4.0)));
        assert_eq!(two.intersect(&r).map(|h| h.hit.t), Some(13.0));
        two.set_transform(0, Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0)));
        assert!(two.intersect(&r).is_none());
    }
}
