//! Two levels: one bottom-level BVH (BLAS) per mesh, built once and shared by every instance
//! of it, and a top-level BVH (TLAS) over the instances' world boxes, rebuilt when an instance
//! moves. A ray reaching an instance is carried into object space by the instance's
//! `object_from_world` without renormalising its direction, so distances stay in world units and
//! the watertight triangle test runs unchanged on the object-space vertices: a scaled or
//! mirrored instance is as watertight as an identity one. The carried origin's rounding error
//! is bounded and hits closer than it along the ray are ignored (pbrt-v4's rule), so a ray
//! spawned off a surface cannot find that surface again in object space.
//!
//! This is also the host reference of the device's two-level traversal
//! (`traverse_two_level` in kernels/shared/traverse.h): the transform and its error bound are computed
//! here with the kernels' f32 operations in the kernels' order. Hits name the object-space
//! triangle (meshes one after the other, each in its BLAS's order) and the instance, as the
//! device reports them: the device keeps each mesh's triangles and shading data once, in
//! object space, and shading carries a hit to world space through the instance's transform.

use super::wide::{frontier, merge_limit};
use super::{Aabb, Blas, Bvh, Child, Hit, Ray, build_boxes};
use crate::cl::types::{DeviceBvhNode, DeviceHit};
use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;

/// One placed mesh.
#[derive(Clone, Copy, Debug)]
pub struct Instance {
    /// Index of its BLAS.
    pub blas: u32,
    /// World from object transform (f64, as the scene composes it).
    pub world_from_object: DMat4,
    /// Object from world as the device applies it, `p_object = L (p_world - T)`: the rows of L
    /// in f32 with T (the world position of the object's origin) in `.w`.
    pub rows: [[f32; 4]; 3],
    /// Whether the transform mirrors (negative determinant).
    pub mirrored: bool,
}

impl Instance {
    fn new(blas: u32, world_from_object: DMat4) -> Self {
        let linear = glam::DMat3::from_mat4(world_from_object).inverse();
        let origin = world_from_object.w_axis;
        let row = |i: usize| {
            let r = linear.row(i);
            [r.x as f32, r.y as f32, r.z as f32, origin[i] as f32]
        };
        Self {
            blas,
            world_from_object,
            rows: [row(0), row(1), row(2)],
            mirrored: world_from_object.determinant() < 0.0,
        }
    }

    /// World from object as the device applies it for shading, `p_world = M p_object + T`:
    /// the rows of M in f32 (T is in `rows`' `.w`).
    pub fn world_rows(&self) -> [[f32; 4]; 3] {
        let m = self.world_from_object;
        [0, 1, 2].map(|i| {
            let r = m.row(i);
            [r.x as f32, r.y as f32, r.z as f32, 0.0]
        })
    }

    /// An object-space triangle in world space as the device carries it, `M v + T` in f32
    /// (the kernels' `instance_to_world`, operation for operation): a small mesh's triangle
    /// is tested so (`TwoLevel::braid`), and shading finds the same vertices.
    pub fn device_triangle(&self, t: &[Vec3; 3]) -> [Vec3; 3] {
        let m = self.world_rows();
        let at = Vec3::new(self.rows[0][3], self.rows[1][3], self.rows[2][3]);
        let apply = |r: [f32; 4], v: Vec3| r[0] * v.x + r[1] * v.y + r[2] * v.z;
        t.map(|v| Vec3::new(apply(m[0], v), apply(m[1], v), apply(m[2], v)) + at)
    }

    /// An object-space point in world space (f64).
    pub fn to_world(&self, p: Vec3) -> Vec3 {
        self.world_from_object
            .transform_point3(p.as_dvec3())
            .as_vec3()
    }

    /// `ray` in object space, with its tmin raised past the transform's rounding error: the
    /// kernels' `instance_point`, `instance_vector` and `instance_tmin`, operation for operation.
    pub fn to_object(&self, ray: &Ray) -> Ray {
        let [r0, r1, r2] = self.rows;
        let (o, d) = (ray.origin, ray.direction);
        let q = o - Vec3::new(r0[3], r1[3], r2[3]);
        let apply = |r: [f32; 4], v: Vec3| r[0] * v.x + r[1] * v.y + r[2] * v.z;
        let od = Vec3::new(apply(r0, d), apply(r1, d), apply(r2, d));
        let gamma8 = 8.0 * f32::EPSILON * 0.5 / (1.0 - 8.0 * f32::EPSILON * 0.5);
        let a = q.abs();
        let bound = |r: [f32; 4]| r[0].abs() * a.x + r[1].abs() * a.y + r[2].abs() * a.z;
        let err = Vec3::new(bound(r0), bound(r1), bound(r2)) * gamma8;
        let ad = od.abs();
        let len2 = od.x * od.x + od.y * od.y + od.z * od.z;
        let dt = if len2 > 0.0 {
            (ad.x * err.x + ad.y * err.y + ad.z * err.z) / len2
        } else {
            0.0
        };
        Ray {
            origin: Vec3::new(apply(r0, q), apply(r1, q), apply(r2, q)),
            direction: od,
            tmin: ray.tmin.max(dt),
            tmax: ray.tmax,
        }
    }

    /// The world box of the triangles of `bvh` under this instance: the union of the world
    /// boxes ([`Instance::world_box`]) of up to [`FRONTIER`] boxes below the root, opened
    /// largest first. A rotated object's world box grows with its box's corners; its parts'
    /// boxes grow with theirs, which are smaller, so the union hugs the object and fewer rays
    /// enter an instance only to miss it.
    fn bvh_world_box(&self, bvh: &Bvh) -> Aabb {
        frontier(bvh, 0, FRONTIER, 0)
            .into_iter()
            // A leaf of no triangles (a one-leaf tree's other side) has the empty box, whose
            // infinite corners would carry to NaN.
            .filter(|(b, _)| b.min.cmple(b.max).all())
            .fold(Aabb::EMPTY, |all, (b, _)| all.union(self.world_box(b)))
    }

    /// The world box of a BLAS box under this instance, computed in f64 and padded by 2^-20
    /// of its coordinates' magnitude, so that it holds the f32 world triangles and whatever
    /// the device finds through the rounded transform.
    fn world_box(&self, b: Aabb) -> Aabb {
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for corner in 0..8 {
            let p = DVec3::new(
                if corner & 1 != 0 { b.max.x } else { b.min.x } as f64,
                if corner & 2 != 0 { b.max.y } else { b.min.y } as f64,
                if corner & 4 != 0 { b.max.z } else { b.min.z } as f64,
            );
            let w = self.world_from_object.transform_point3(p);
            lo = lo.min(w);
            hi = hi.max(w);
        }
        let pad = lo.abs().max(hi.abs()) * (1.0 / (1u64 << 20) as f64);
        Aabb {
            min: (lo - pad).as_vec3(),
            max: (hi + pad).as_vec3(),
        }
    }
}

/// A hit in a two-level scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceHit {
    /// The instance hit.
    pub instance: u32,
    /// Its TLAS leaf slot (where the device keeps it).
    pub slot: u32,
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
    /// Over the pieces' world boxes, one piece a leaf; its `tri_indices` are the pieces'
    /// instance indices (see [`TwoLevel::rebuild_tlas`]).
    pub tlas: Bvh,
    /// Each TLAS leaf's (slot's) piece of its instance: 0 for the whole BLAS, entered at its
    /// root, or a small mesh's triangle (`PIECE_TRIANGLE | k`, tested in world space; see
    /// `TwoLevel::braid`).
    pub pieces: Vec<u32>,
    /// The most pieces the TLAS may hold: fixed for the scene, so that the device's TLAS and
    /// instance buffers, sized for it, hold any later TLAS.
    pub max_pieces: usize,
    /// Each BLAS's first triangle among the meshes' triangles one after the other.
    pub firsts: Vec<u32>,
    /// Hidden instances are left out of the TLAS (they keep their place among the instances).
    pub hidden: Vec<bool>,
    /// Meshes of at most this many triangles are small: each of their instances' triangles is
    /// a TLAS piece of its own (see `TwoLevel::braid`; 0: none).
    pub small_mesh: usize,
    /// The largest leaf the wide BLASes merge small subtrees into (0: none): as the CPU's flat
    /// BVH does ([`super::WideBvh::collapse_for_cpu`]), by the meshes' triangles
    /// (`merge_limit`), so that both levels' bottoms are walked as fast as the flat tree.
    pub merge: u32,
}

impl TwoLevel {
    /// Builds every BLAS (in parallel) and the TLAS over `instances` (mesh index, world from
    /// object).
    pub fn new(meshes: &[Vec<[Vec3; 3]>], instances: &[(u32, DMat4)]) -> Self {
        let blases = meshes.par_iter().map(|m| Blas::new(m)).collect();
        Self::from_blases(blases, instances)
    }

    /// The TLAS over `instances` of prebuilt BLASes.
    pub fn from_blases(blases: Vec<Blas>, instances: &[(u32, DMat4)]) -> Self {
        let shown = vec![false; instances.len()];
        Self::with_hidden(blases, instances, shown, SMALL_MESH)
    }

    /// [`TwoLevel::from_blases`] with `hidden` instances left out of the TLAS and meshes of at
    /// most `small_mesh` triangles small ([`TwoLevel::small_mesh`]).
    pub fn with_hidden(
        blases: Vec<Blas>,
        instances: &[(u32, DMat4)],
        hidden: Vec<bool>,
        small_mesh: usize,
    ) -> Self {
        let instances: Vec<Instance> = instances
            .iter()
            .map(|&(blas, m)| Instance::new(blas, m))
            .collect();
        let mut first = 0u32;
        let firsts = blases
            .iter()
            .map(|b| {
                first += b.len() as u32;
                first - b.len() as u32
            })
            .collect();
        let unique: usize = blases.iter().map(|b| b.len()).sum();
        let mut two = Self {
            merge: merge_limit(unique),
            hidden,
            blases,
            instances,
            tlas: build_boxes(&[]),
            pieces: vec![],
            max_pieces: 0,
            firsts,
            small_mesh,
        };
        two.max_pieces = two.piece_budget();
        two.rebuild_tlas();
        two
    }

    /// The expected triangle tests and node steps of a ray that enters the TLAS's root box:
    /// the TLAS's SAH cost with each leaf costing its piece, a whole BLAS its own SAH cost (also
    /// taken for a piece entered below a BLAS's root, which costs at most that) and a small
    /// mesh's triangle 1. Instances that overlap add up: 256 coincident copies of a mesh cost
    /// 256 of its trees, which is what a ray through them pays.
    pub fn ray_cost(&self) -> f64 {
        if self.tlas.nodes.is_empty() {
            return 0.0;
        }
        let area = |b: Aabb| {
            if b.min.cmple(b.max).all() {
                b.area() as f64
            } else {
                0.0
            }
        };
        let root_area = area(self.tlas.child(0, 0).0.union(self.tlas.child(0, 1).0))
            .max(f32::MIN_POSITIVE as f64);
        let mut cost = 0.0;
        for node in 0..self.tlas.nodes.len() as u32 {
            for side in 0..2 {
                let (b, child) = self.tlas.child(node, side);
                let weight = match child {
                    Child::Node(_) => 1.0,
                    Child::Leaf { first, count } => (first..first + count)
                        .map(|slot| {
                            let piece = self.pieces[slot as usize];
                            if piece & PIECE_TRIANGLE != 0 {
                                1.0
                            } else {
                                let instance = self.tlas.tri_indices[slot as usize] as usize;
                                let blas = self.instances[instance].blas as usize;
                                self.blases[blas].bvh.sah_cost as f64
                            }
                        })
                        .sum(),
                };
                cost += area(b) * weight;
            }
        }
        cost / root_area
    }

    /// Triangles over all instances.
    pub fn triangle_count(&self) -> usize {
        self.instances
            .iter()
            .zip(&self.hidden)
            .filter(|(_, hidden)| !**hidden)
            .map(|(i, _)| self.blases[i.blas as usize].len())
            .sum()
    }

    /// Whether some instance's mesh is small (its triangles are pieces of the TLAS).
    pub fn has_small_meshes(&self) -> bool {
        self.instances
            .iter()
            .any(|i| self.is_small(&self.blases[i.blas as usize]))
    }

    /// Whether `blas` is small (see [`TwoLevel::small_mesh`]).
    pub fn is_small(&self, blas: &Blas) -> bool {
        blas.len() <= self.small_mesh
    }

    /// The most pieces the TLAS may hold, hidden instances' included (so that showing one
    /// fits): a small mesh's triangles each and one for any other instance.
    fn piece_budget(&self) -> usize {
        self.instances
            .iter()
            .map(|i| {
                let b = &self.blases[i.blas as usize];
                if self.is_small(b) { b.len() } else { 1 }
            })
            .sum()
    }

    /// Moves instance `i` and rebuilds the TLAS.
    pub fn set_transform(&mut self, i: usize, world_from_object: DMat4) {
        self.place(i, world_from_object);
        self.rebuild_tlas();
    }

    /// Moves instance `i` without rebuilding the TLAS (call [`TwoLevel::rebuild_tlas`] after
    /// the last move).
    pub fn place(&mut self, i: usize, world_from_object: DMat4) {
        let inst = &mut self.instances[i];
        *inst = Instance::new(inst.blas, world_from_object);
    }

    /// Builds the TLAS over the pieces of the shown instances (`TwoLevel::braid`) at their
    /// current world boxes.
    pub fn rebuild_tlas(&mut self) {
        let pieces = self.braid();
        let boxes: Vec<Aabb> = pieces.iter().map(|p| p.2).collect();
        self.tlas = build_boxes(&boxes);
        split_instance_leaves(&mut self.tlas, &boxes);
        self.pieces = self
            .tlas
            .tri_indices
            .iter()
            .map(|&p| pieces[p as usize].1)
            .collect();
        for p in &mut self.tlas.tri_indices {
            *p = pieces[*p as usize].0;
        }
    }

    /// The pieces of the shown instances (instance, piece, world box). A small mesh's
    /// instance ([`TwoLevel::is_small`]) is one piece per triangle ([`PIECE_TRIANGLE`]), which
    /// the traversal tests in world space, carried there as shading carries it
    /// ([`Instance::device_triangle`]), without entering the instance: a room of a few large
    /// quads would otherwise be one piece whose box holds the whole scene, entered by every
    /// ray. Any other instance is one piece, its whole BLAS (0). No BLAS is opened into pieces
    /// of its subtrees (partial re-braiding; Benthin, Woop, Wald et al., HPG 2017): opening the
    /// bunny room's BLASes measured no faster on PoCL (16 to 1024 more pieces than instances)
    /// and slower on the H200 (256 more; 2026-11-30). Commit 7bfae20 is the last with the
    /// switch, `PENUMBRA_REBRAID`.
    fn braid(&self) -> Vec<(u32, u32, Aabb)> {
        let mut pieces: Vec<(u32, u32, Aabb)> = vec![];
        for i in 0..self.instances.len() as u32 {
            let inst = &self.instances[i as usize];
            let blas = &self.blases[inst.blas as usize];
            if self.hidden[i as usize] {
                continue;
            }
            if !self.is_small(blas) {
                pieces.push((i, 0, inst.bvh_world_box(&blas.bvh)));
                continue;
            }
            for (k, t) in blas.triangles().enumerate() {
                let world = inst.device_triangle(&t);
                let b = world.iter().fold(Aabb::EMPTY, |b, &v| b.grow(v));
                pieces.push((i, PIECE_TRIANGLE | k as u32, b));
            }
        }
        pieces
    }

    /// The closest hit along `ray`.
    pub fn intersect(&self, ray: &Ray) -> Option<InstanceHit> {
        self.trace(ray, false)
    }

    /// Whether anything blocks `ray` within its interval.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.trace(ray, true).is_some()
    }

    /// The closest hit as the device reports it: `prim` among the meshes' triangles one after
    /// the other (see [`TwoLevel::firsts`]) and the instance's TLAS slot.
    pub fn device_hit(&self, ray: &Ray) -> Option<DeviceHit> {
        self.intersect(ray).map(|h| {
            let inst = &self.instances[h.instance as usize];
            DeviceHit {
                t: h.hit.t,
                u: h.hit.u,
                v: h.hit.v,
                prim: self.firsts[inst.blas as usize] + h.hit.prim,
                instance: h.slot,
            }
        })
    }

    /// Each instance's first TLAS slot (any of its pieces' slots carries its transforms;
    /// `u32::MAX` for a hidden one).
    pub fn slots(&self) -> Vec<u32> {
        let mut slots = vec![u32::MAX; self.instances.len()];
        for (slot, &i) in self.tlas.tri_indices.iter().enumerate().rev() {
            slots[i as usize] = slot as u32;
        }
        slots
    }

    /// The world-space vertices of triangle `prim` (among the meshes' triangles one after the
    /// other) placed by instance `instance` (its index, not its slot).
    pub fn hit_triangle(&self, prim: u32, instance: u32) -> [Vec3; 3] {
        let inst = &self.instances[instance as usize];
        let b = inst.blas as usize;
        let t = self.blases[b].triangle((prim - self.firsts[b]) as usize);
        t.map(|v| inst.to_world(v))
    }

    fn trace(&self, ray: &Ray, any: bool) -> Option<InstanceHit> {
        self.tlas.walk(ray, any, |leaf, r| {
            let instance = self.tlas.tri_indices[leaf as usize];
            let inst = &self.instances[instance as usize];
            let blas = &self.blases[inst.blas as usize];
            let piece = self.pieces[leaf as usize];
            let hit = if piece & PIECE_TRIANGLE != 0 {
                // A small mesh's triangle, tested in world space (see `braid`).
                let prim = piece & !PIECE_TRIANGLE;
                let world = inst.device_triangle(&blas.triangle(prim as usize));
                super::intersect_triangle(r, &world).map(|(t, u, v)| Hit { t, u, v, prim })
            } else {
                let local = inst.to_object(r);
                blas.traverse(&local, any)
            };
            let hit = hit.map(|h| if any { Hit { t: r.tmax, ..h } } else { h });
            hit.map(|hit| {
                (
                    hit.t,
                    InstanceHit {
                        instance,
                        slot: leaf,
                        hit,
                    },
                )
            })
        })
    }
}

/// Meshes of at most this many triangles are small by default (see [`TwoLevel::small_mesh`]).
pub const SMALL_MESH: usize = 64;

/// How many of a BLAS's boxes bound an instance in the TLAS ([`Instance::bvh_world_box`]).
pub const FRONTIER: usize = 32;

/// A piece's mark for one triangle (its index in the BLAS in the other bits), else a BLAS node.
pub const PIECE_TRIANGLE: u32 = 1 << 31;

/// Splits every TLAS leaf of several pieces into leaves of one, so that a ray tests each
/// piece's box before it is carried into the instance: entering a piece costs a transform and
/// a descent from its BLAS node, where the builder's leaves of up to eight boxes (right for
/// triangles) would enter all of them. A leaf's pieces are split in two along the axis of
/// their boxes' centres where the SAH cost is least, recursively. The TLAS of n pieces then
/// has n - 1 nodes, no more than
/// [`TwoLevel::tlas_slots`] reserves.
fn split_instance_leaves(tlas: &mut Bvh, boxes: &[Aabb]) {
    let mut split = false;
    for node in 0..tlas.nodes.len() as u32 {
        for side in 0..2 {
            if let (b, Child::Leaf { first, count }) = tlas.child(node, side)
                && count > 1
            {
                let index = split_range(tlas, boxes, first, count);
                set_child(&mut tlas.nodes[node as usize], side, b, index as i32, 0);
                split = true;
            }
        }
    }
    if split {
        let (sah, depth) = tlas.sah_and_depth();
        (tlas.sah_cost, tlas.built_sah_cost, tlas.depth) = (sah, sah, depth);
    }
}

/// A new node over the TLAS leaf items `first .. first + count` (at least two), its leaves of
/// one instance each; returns its index.
fn split_range(tlas: &mut Bvh, boxes: &[Aabb], first: u32, count: u32) -> u32 {
    let centre = |i: &u32| (boxes[*i as usize].min + boxes[*i as usize].max) * 0.5;
    let items = &mut tlas.tri_indices[first as usize..(first + count) as usize];
    // The split of the least SAH cost (the sum of each side's box area times its items: every
    // item is entered at a cost) among the items sorted along each axis by their boxes' centres.
    let mut best = (f32::INFINITY, 0, count / 2);
    for axis in 0..3 {
        items.sort_by(|a, b| centre(a)[axis].total_cmp(&centre(b)[axis]));
        let mut right = vec![0.0f32; count as usize];
        let mut b = Aabb::EMPTY;
        for k in (1..count as usize).rev() {
            b = b.union(boxes[items[k] as usize]);
            right[k] = b.area() * (count as usize - k) as f32;
        }
        let mut b = Aabb::EMPTY;
        for k in 1..count as usize {
            b = b.union(boxes[items[k - 1] as usize]);
            let cost = b.area() * k as f32 + right[k];
            if cost < best.0 {
                best = (cost, axis, k as u32);
            }
        }
    }
    items.sort_by(|a, b| centre(a)[best.1].total_cmp(&centre(b)[best.1]));
    let index = tlas.nodes.len() as u32;
    tlas.nodes.push(DeviceBvhNode::default());
    let half = best.2;
    for (side, (f, c)) in [(first, half), (first + half, count - half)]
        .into_iter()
        .enumerate()
    {
        let b = tlas.tri_indices[f as usize..(f + c) as usize]
            .iter()
            .fold(Aabb::EMPTY, |a, &i| a.union(boxes[i as usize]));
        let (reference, n) = if c == 1 {
            (!(f as i32), 1)
        } else {
            (split_range(tlas, boxes, f, c) as i32, 0)
        };
        set_child(&mut tlas.nodes[index as usize], side, b, reference, n);
    }
    index
}

/// Writes child `side` of a node: its box, its reference (a node index, or `!first` of a leaf)
/// and its leaf count (0 for a node), as the builder lays them out.
fn set_child(node: &mut DeviceBvhNode, side: usize, b: Aabb, reference: i32, count: u32) {
    let lo = [b.min.x, b.min.y, b.min.z, f32::from_bits(reference as u32)];
    let hi = [b.max.x, b.max.y, b.max.z, f32::from_bits(count)];
    if side == 0 {
        (node.left_min, node.left_max) = (lo, hi);
    } else {
        (node.right_min, node.right_max) = (lo, hi);
    }
}

/// A closed cube [-1, 1]³, each face an n×n grid of quads (two triangles each), with shared
/// corners computed the same way on every face so that edges match exactly: the mesh of the
/// leak tests (a ray from inside must hit it, whatever the instance's transform).
pub fn closed_cube(n: usize) -> Vec<[Vec3; 3]> {
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

#[cfg(test)]
mod tests {
    use super::super::build::tests::{lcg, random_triangles};
    use super::super::intersect_triangle;
    use super::*;
    use glam::{DMat4, Mat4, Quat};

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
            &placements()
                .iter()
                .map(|&m| (0, m.as_dmat4()))
                .collect::<Vec<_>>(),
        );
        let mut leaks = 0;
        let mut rays = 0;
        for (i, inst) in two.instances.iter().enumerate() {
            let m = inst.world_from_object.as_mat4();
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
        // A quad is a tree of one leaf (its root's other side is empty): as a small mesh its
        // triangles are pieces (CPU devices), and with no small meshes (GPUs) it is entered.
        let quad = vec![
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        ];
        let meshes = vec![random_triangles(400, 1), closed_cube(3), quad];
        let placed: Vec<(u32, Mat4)> = placements()
            .into_iter()
            .chain(placements().into_iter().take(3))
            .enumerate()
            .map(|(i, m)| {
                (
                    (i % 3) as u32,
                    m * Mat4::from_translation(Vec3::splat(i as f32)),
                )
            })
            .collect();
        let instances: Vec<(u32, DMat4)> = placed
            .iter()
            .map(|&(mesh, m)| (mesh, m.as_dmat4()))
            .collect();
        for small_mesh in [SMALL_MESH, 0] {
            let blases = meshes.iter().map(|m| Blas::new(m)).collect();
            let hidden = vec![false; instances.len()];
            let two = TwoLevel::with_hidden(blases, &instances, hidden, small_mesh);
            finds_the_hits_of_the_flattened_scene(&two, &meshes, &placed);
        }
    }

    fn finds_the_hits_of_the_flattened_scene(
        two: &TwoLevel,
        meshes: &[Vec<[Vec3; 3]>],
        placed: &[(u32, Mat4)],
    ) {
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
    fn every_tlas_leaf_holds_one_instance() {
        // 40 small cubes in rows of four, close together: the builder puts several in a leaf.
        let placed: Vec<(u32, glam::DMat4)> = (0..40)
            .map(|i| {
                let at = Vec3::new((i % 4) as f32 * 0.5 + (i / 4) as f32 * 10.0, 0.0, 0.0);
                let m = Mat4::from_scale_rotation_translation(Vec3::splat(0.2), Quat::IDENTITY, at);
                (0, m.as_dmat4())
            })
            .collect();
        let built = build_boxes_of(&placed);
        assert!(
            (0..built.nodes.len() as u32).any(|n| (0..2)
                .any(|side| matches!(built.child(n, side).1, Child::Leaf { count: 2.., .. }))),
            "the builder alone makes leaves of several instances"
        );
        let two = TwoLevel::new(&[closed_cube(3)], &placed);
        let mut leaves = 0;
        for node in 0..two.tlas.nodes.len() as u32 {
            for side in 0..2 {
                if let (_, Child::Leaf { count, .. }) = two.tlas.child(node, side) {
                    assert_eq!(count, 1, "node {node} side {side}");
                    leaves += 1;
                }
            }
        }
        assert_eq!(
            leaves, 40,
            "a cube of 108 triangles is not small, nor opened"
        );
        assert_eq!(two.tlas.nodes.len(), 39);
        assert!(two.tlas.nodes.len() <= two.tlas_slots());
        let mut slots = two.tlas.tri_indices.clone();
        slots.sort();
        assert_eq!(slots, (0..40).collect::<Vec<u32>>(), "each instance once");
        // Every instance is still found: a ray down onto each cube's centre hits it.
        for (i, (_, m)) in placed.iter().enumerate() {
            let c = m.transform_point3(glam::DVec3::ZERO).as_vec3();
            let hit = two
                .intersect(&ray(c + Vec3::Y * 5.0, -Vec3::Y))
                .expect("a hit");
            assert_eq!(hit.instance, i as u32);
            assert!((hit.hit.t - 4.8).abs() < 1e-5, "{}", hit.hit.t);
        }
    }

    /// The builder's tree over the world boxes of closed cubes placed by `placed`.
    fn build_boxes_of(placed: &[(u32, glam::DMat4)]) -> Bvh {
        let cube = Blas::new(&closed_cube(3));
        let boxes: Vec<Aabb> = placed
            .iter()
            .map(|&(_, m)| Instance::new(0, m).world_box(cube.bounds()))
            .collect();
        build_boxes(&boxes)
    }

    /// A big mesh and a small one (its instances' triangles are TLAS pieces of their own)
    /// placed by every placement, the first of each moved to `moved`.
    fn big_and_small(moved: Option<DMat4>) -> TwoLevel {
        let meshes = vec![random_triangles(3000, 7), closed_cube(2)];
        assert!(meshes[0].len() > SMALL_MESH && meshes[1].len() <= SMALL_MESH);
        let mut placed: Vec<(u32, DMat4)> = placements()
            .into_iter()
            .enumerate()
            .flat_map(|(i, m)| {
                let m = (m * Mat4::from_translation(Vec3::splat(i as f32 * 2.0))).as_dmat4();
                [
                    (0, m),
                    (1, m * DMat4::from_translation(glam::DVec3::X * 12.0)),
                ]
            })
            .collect();
        if let Some(m) = moved {
            placed[0].1 = m;
            placed[1].1 = m;
        }
        TwoLevel::new(&meshes, &placed)
    }

    /// Rays through the scene of [`big_and_small`]: from around it towards random points in it.
    fn rays_through(two: &TwoLevel, n: usize) -> Vec<Ray> {
        let b = two.tlas.child(0, 0).0.union(two.tlas.child(0, 1).0);
        let mut s = 11u64;
        let point = |s: &mut u64| {
            let t = Vec3::new(lcg(s), lcg(s), lcg(s));
            b.min + (b.max - b.min) * (t * 1.4 - 0.2)
        };
        (0..n)
            .map(|_| {
                let (o, aim) = (point(&mut s), point(&mut s));
                ray(o, aim - o)
            })
            .collect()
    }

    #[test]
    fn a_small_instance_is_a_piece_per_triangle_and_no_blas_is_opened() {
        let two = big_and_small(None);
        let pieces =
            |two: &TwoLevel, i: u32| two.tlas.tri_indices.iter().filter(|&&k| k == i).count();
        for i in 0..two.instances.len() as u32 {
            let small = i % 2 == 1;
            assert_eq!(pieces(&two, i), if small { 48 } else { 1 }, "instance {i}");
        }
        assert_eq!(two.pieces.len(), two.max_pieces);
        // Hiding instances leaves room in the TLAS's slots; still every BLAS is entered whole.
        let mut hidden = two.clone();
        (hidden.hidden[1], hidden.hidden[2]) = (true, true);
        hidden.rebuild_tlas();
        assert_eq!(hidden.pieces.len(), two.max_pieces - 49);
        assert!(
            hidden
                .pieces
                .iter()
                .all(|&p| p == 0 || p & PIECE_TRIANGLE != 0),
            "every big piece is a whole BLAS"
        );
        assert!(hidden.tlas.tri_indices.iter().all(|&i| i != 1 && i != 2));
    }

    #[test]
    fn moving_an_instance_moves_all_its_pieces() {
        let to =
            DMat4::from_translation(glam::DVec3::new(3.0, -5.0, 1.0)) * DMat4::from_rotation_y(0.7);
        let mut two = big_and_small(None);
        // Instances 0 and 1 (a big one and a small one of 48 pieces) move as in a scene built
        // so.
        two.place(0, to);
        two.place(1, to);
        two.rebuild_tlas();
        let built = big_and_small(Some(to));
        assert_eq!(two.pieces, built.pieces);
        assert_eq!(two.tlas.tri_indices, built.tlas.tri_indices);
        let mut moved_hits = 0;
        for (k, r) in rays_through(&built, 3000).iter().enumerate() {
            let (a, b) = (two.intersect(r), built.intersect(r));
            assert_eq!(a, b, "ray {k}");
            moved_hits += a.is_some_and(|h| h.instance < 2) as usize;
        }
        assert!(
            moved_hits > 50,
            "rays hit the moved instances ({moved_hits})"
        );
    }

    #[test]
    fn moving_an_instance_moves_its_hits() {
        let mut two = TwoLevel::new(&[closed_cube(2)], &[(0, glam::DMat4::IDENTITY)]);
        let r = ray(Vec3::new(0.0, 0.0, -10.0), Vec3::Z);
        assert_eq!(two.intersect(&r).map(|h| h.hit.t), Some(9.0));
        two.set_transform(
            0,
            glam::DMat4::from_translation(glam::DVec3::new(0.0, 0.0, 4.0)),
        );
        assert_eq!(two.intersect(&r).map(|h| h.hit.t), Some(13.0));
        two.set_transform(
            0,
            glam::DMat4::from_translation(glam::DVec3::new(5.0, 0.0, 0.0)),
        );
        assert!(two.intersect(&r).is_none());
    }
}
