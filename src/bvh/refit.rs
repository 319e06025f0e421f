//! Updating a built tree after its triangles moved (skins, morph targets): the boxes are
//! recomputed bottom up with the topology kept, and the tree is rebuilt instead when that has
//! made it too slow to traverse.

use super::sah_split::TRAVERSAL_COST;
use super::{Aabb, Bvh, Child, WideBvh, build};
use crate::cl::types::DeviceBvhNode;
use glam::Vec3;
use rayon::prelude::*;

/// A refit is kept while the SAH cost stays below this multiple of the cost right after the
/// last full build; beyond it the tree is rebuilt.
pub const REFIT_MAX_GROWTH: f32 = 2.0;

/// What [`Bvh::refit_or_rebuild`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Update {
    /// The boxes were refitted; the topology is unchanged.
    Refitted,
    /// The refitted tree had grown too costly and was built again.
    Rebuilt,
}

impl Bvh {
    /// The SAH cost (traversal cost 1, intersection cost 1 per triangle, relative to the root's
    /// area) and the depth of the deepest leaf (root = 0), from the node array.
    pub fn sah_and_depth(&self) -> (f32, u32) {
        (self.sah(), self.deepest_leaf())
    }

    /// The SAH cost of [`Bvh::sah_and_depth`]. Summed in parallel over fixed chunks of nodes, so
    /// the sum is the same at any thread count.
    fn sah(&self) -> f32 {
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        let root_leaf_only = matches!(self.child(0, 1).1, Child::Leaf { count: 0, .. });
        let root_area = child_box(root, 0)
            .union(child_box(root, 1))
            .area()
            .max(f32::MIN_POSITIVE) as f64;
        let chunk_sums: Vec<f64> = self
            .nodes
            .par_chunks(1 << 14)
            .map(|chunk| {
                let mut sum = 0.0;
                for node in chunk {
                    for side in 0..2 {
                        let (lo, hi) = lanes(node, side);
                        // A leaf's cost is its triangle count, an interior node's one step.
                        let weight = if (lo[3].to_bits() as i32) < 0 {
                            hi[3].to_bits() as f64
                        } else {
                            TRAVERSAL_COST as f64
                        };
                        sum += child_box(node, side).area() as f64 * weight;
                    }
                }
                sum
            })
            .collect();
        let step = if root_leaf_only { 0.0 } else { TRAVERSAL_COST };
        (step as f64 + chunk_sums.iter().sum::<f64>() / root_area) as f32
    }

    /// The depth of the deepest leaf of [`Bvh::sah_and_depth`].
    fn deepest_leaf(&self) -> u32 {
        if self.nodes.is_empty() {
            return 0;
        }
        let root_leaf_only = matches!(self.child(0, 1).1, Child::Leaf { count: 0, .. });
        // Children come after their parents, so one forward pass knows every node's depth.
        let mut depths = vec![0u8; self.nodes.len()];
        let mut deepest = 0;
        for (index, node) in self.nodes.iter().enumerate() {
            let depth = depths[index];
            for side in 0..2 {
                let (lo, hi) = lanes(node, side);
                let child = lo[3].to_bits() as i32;
                if child >= 0 {
                    depths[child as usize] = depth + 1;
                } else if hi[3].to_bits() > 0 {
                    deepest = deepest.max(depth as u32 + u32::from(!root_leaf_only));
                }
            }
        }
        deepest
    }

    /// Recomputes every box for `triangles` (in their original order, as given to
    /// [`build`]), keeping the tree's topology; updates `sah_cost`.
    ///
    /// # Panics
    /// When `triangles` is not as long as the list the tree was built over.
    pub fn refit(&mut self, triangles: &[[Vec3; 3]]) {
        assert_eq!(
            triangles.len(),
            self.tri_indices.len(),
            "a refit needs the triangles the tree was built over"
        );
        self.refit_with(|t| triangles[t]);
    }

    /// [`Bvh::refit`] reading triangle `t`'s corners from `corners(t)`: a deformed mesh is
    /// refitted from its vertices and indices, without a list of its triangles (36 bytes a
    /// triangle written and read again each frame).
    pub fn refit_with(&mut self, corners: impl Fn(usize) -> [Vec3; 3] + Sync) {
        let tri_indices = std::mem::take(&mut self.tri_indices);
        self.refit_leaves(|first, count| {
            tri_indices[first..first + count]
                .iter()
                .flat_map(|&t| corners(t as usize))
                .fold(Aabb::EMPTY, Aabb::grow)
        });
        self.tri_indices = tri_indices;
    }

    /// [`Bvh::refit`] from `ordered`, the triangles in the tree's order (`ordered[k]` is
    /// triangle `tri_indices[k]`): each leaf's box from its run of them, no index followed.
    ///
    /// # Panics
    /// When `ordered` is not as long as the list the tree was built over.
    pub fn refit_ordered(&mut self, ordered: &[[Vec3; 3]]) {
        assert_eq!(
            ordered.len(),
            self.tri_indices.len(),
            "a refit needs the triangles the tree was built over"
        );
        self.refit_leaves(|first, count| {
            ordered[first..first + count]
                .iter()
                .flatten()
                .fold(Aabb::EMPTY, |b, &v| b.grow(v))
        });
    }

    /// Sets every leaf's box to `leaf(first, count)` (all nodes at once), then every interior
    /// box from its children's; updates `sah_cost`.
    fn refit_leaves(&mut self, leaf: impl Fn(usize, usize) -> Aabb + Sync) {
        self.nodes.par_iter_mut().for_each(|node| {
            for side in 0..2 {
                let (lo, hi) = sides(node, side);
                let index = lo[3].to_bits() as i32;
                if index < 0 {
                    let first = !index as usize;
                    let count = hi[3].to_bits() as usize;
                    set_box(lo, hi, leaf(first, count));
                }
            }
        });
        // Then interior boxes from the back: a node's children come after it.
        for index in (0..self.nodes.len()).rev() {
            for side in 0..2 {
                if let (_, Child::Node(c)) = self.child(index as u32, side) {
                    let n = &self.nodes[c as usize];
                    let b = child_box(n, 0).union(child_box(n, 1));
                    let (lo, hi) = sides(&mut self.nodes[index], side);
                    set_box(lo, hi, b);
                }
            }
        }
        self.sah_cost = self.sah();
    }

    /// Whether refits have taken the SAH cost to [`REFIT_MAX_GROWTH`] times the cost of the
    /// last full build or more: the tree should be built again.
    pub fn needs_rebuild(&self) -> bool {
        self.sah_cost >= REFIT_MAX_GROWTH * self.built_sah_cost
    }

    /// Refits for `triangles`, and builds the tree again when the refit left its SAH cost at
    /// [`REFIT_MAX_GROWTH`] times the cost of the last full build or more.
    pub fn refit_or_rebuild(&mut self, triangles: &[[Vec3; 3]]) -> Update {
        self.refit_or_rebuild_with(triangles.len(), |t| triangles[t])
    }

    /// [`Bvh::refit_or_rebuild`] for the `count` triangles of `corners` (as
    /// [`Bvh::refit_with`]); the list of triangles is made only for a rebuild.
    pub fn refit_or_rebuild_with(
        &mut self,
        count: usize,
        corners: impl Fn(usize) -> [Vec3; 3] + Sync,
    ) -> Update {
        assert_eq!(
            count,
            self.tri_indices.len(),
            "a refit needs the triangles the tree was built over"
        );
        self.refit_with(&corners);
        if !self.needs_rebuild() {
            return Update::Refitted;
        }
        let triangles: Vec<[Vec3; 3]> = (0..count).into_par_iter().map(&corners).collect();
        *self = build(&triangles);
        Update::Rebuilt
    }
}

impl WideBvh {
    /// Recomputes every box for `ordered` (the triangles in BVH order, as its leaves name
    /// them), keeping the tree: leaves' boxes first, all at once, then interior boxes from
    /// the back (a node's children come after it).
    pub fn refit(&mut self, ordered: &[[Vec3; 3]]) {
        self.nodes.par_iter_mut().for_each(|node| {
            for slot in 0..4 {
                if node.count[slot] > 0 {
                    let first = !node.child[slot] as usize;
                    let b = ordered[first..first + node.count[slot] as usize]
                        .iter()
                        .flatten()
                        .fold(Aabb::EMPTY, |b, &v| b.grow(v));
                    super::wide::set_box(node, slot, b);
                }
            }
        });
        for index in (0..self.nodes.len()).rev() {
            for slot in 0..4 {
                let node = &self.nodes[index];
                if node.count[slot] == 0 && node.child[slot] > 0 {
                    let b = self
                        .children(node.child[slot] as u32)
                        .fold(Aabb::EMPTY, |b, (c, _)| b.union(c));
                    super::wide::set_box(&mut self.nodes[index], slot, b);
                }
            }
        }
    }
}

/// The box of child `side` of `node`.
fn child_box(node: &DeviceBvhNode, side: usize) -> Aabb {
    let (lo, hi) = if side == 0 {
        (node.left_min, node.left_max)
    } else {
        (node.right_min, node.right_max)
    };
    Aabb {
        min: Vec3::new(lo[0], lo[1], lo[2]),
        max: Vec3::new(hi[0], hi[1], hi[2]),
    }
}

/// The min and max lanes of child `side`.
fn lanes(node: &DeviceBvhNode, side: usize) -> (&[f32; 4], &[f32; 4]) {
    if side == 0 {
        (&node.left_min, &node.left_max)
    } else {
        (&node.right_min, &node.right_max)
    }
}

/// The min and max lanes of child `side`, to write.
fn sides(node: &mut DeviceBvhNode, side: usize) -> (&mut [f32; 4], &mut [f32; 4]) {
    if side == 0 {
        (&mut node.left_min, &mut node.left_max)
    } else {
        (&mut node.right_min, &mut node.right_max)
    }
}

/// Writes a box into a child's lanes, keeping the `.w` references.
fn set_box(lo: &mut [f32; 4], hi: &mut [f32; 4], b: Aabb) {
    lo[..3].copy_from_slice(&b.min.to_array());
    hi[..3].copy_from_slice(&b.max.to_array());
}

#[cfg(test)]
mod tests {
    use super::super::build::tests::random_triangles;
    use super::*;

    #[test]
    fn refitting_an_unchanged_mesh_gives_the_built_tree() {
        for n in [1, 2, 7, 5000, 70_000] {
            let tris = random_triangles(n, 3);
            let built = build(&tris);
            let mut refitted = built.clone();
            refitted.refit(&tris);
            // Leaf references are NaN bits as floats: compare bytes.
            let same = refitted
                .nodes
                .iter()
                .zip(&built.nodes)
                .position(|(a, b)| bytemuck::bytes_of(a) != bytemuck::bytes_of(b));
            assert_eq!(same, None, "the first differing node of {n} triangles");
            assert_eq!(refitted.sah_cost, built.sah_cost);
            assert_eq!(refitted.tri_indices, built.tri_indices);
        }
    }

    #[test]
    fn a_refit_after_moving_vertices_holds_every_triangle() {
        let tris = random_triangles(3000, 5);
        let mut bvh = build(&tris);
        // A wave that moves every vertex by up to 0.3 along y and z.
        let moved: Vec<[Vec3; 3]> = tris
            .iter()
            .map(|t| t.map(|v| v + Vec3::new(0.0, (v.x * 1.7).sin(), (v.x * 0.9).cos()) * 0.3))
            .collect();
        assert_eq!(bvh.refit_or_rebuild(&moved), Update::Refitted);
        super::super::build::tests::check_tree(&bvh, &moved);
        // Closest hits through the refitted tree equal those of a fresh build.
        let fresh = build(&moved);
        let order = |b: &Bvh| -> Vec<[Vec3; 3]> {
            b.tri_indices.iter().map(|&i| moved[i as usize]).collect()
        };
        let (a, b) = (order(&bvh), order(&fresh));
        for ray in super::super::build::tests::random_rays(500, 17) {
            let x = bvh.intersect(&ray, &a).map(|h| h.t);
            let y = fresh.intersect(&ray, &b).map(|h| h.t);
            assert_eq!(x, y, "{ray:?}");
        }
    }

    #[test]
    fn a_refitted_wide_tree_holds_every_moved_triangle_and_finds_the_same_hits() {
        let tris = random_triangles(5000, 7);
        let bvh = build(&tris);
        let order = |t: &[[Vec3; 3]]| -> Vec<[Vec3; 3]> {
            bvh.tri_indices.iter().map(|&i| t[i as usize]).collect()
        };
        let mut wide = WideBvh::collapse_for_cpu(&bvh);
        let mut same = wide.clone();
        same.refit(&order(&tris));
        assert!(same.nodes.iter().zip(&wide.nodes).all(|(a, b)| a == b));
        let moved_flat: Vec<[Vec3; 3]> = tris
            .iter()
            .map(|t| t.map(|v| v + Vec3::new((v.y * 2.3).sin(), 0.0, (v.x * 1.1).cos()) * 0.4))
            .collect();
        let moved = order(&moved_flat);
        wide.refit(&moved);
        // Every leaf's box holds its triangles, every node's box its children's.
        for node in 0..wide.nodes.len() as u32 {
            for (b, child) in wide.children(node) {
                let inner = match child {
                    Child::Leaf { first, count } => moved[first as usize..(first + count) as usize]
                        .iter()
                        .flatten()
                        .fold(Aabb::EMPTY, |b, &v| b.grow(v)),
                    Child::Node(n) => wide.children(n).fold(Aabb::EMPTY, |b, (c, _)| b.union(c)),
                };
                assert_eq!(b.union(inner), b, "node {node}");
            }
        }
        let fresh = build(&moved_flat);
        let fresh_order: Vec<[Vec3; 3]> = fresh
            .tri_indices
            .iter()
            .map(|&i| moved_flat[i as usize])
            .collect();
        for ray in super::super::build::tests::random_rays(500, 3) {
            let x = wide.intersect(&ray, &moved).map(|h| h.t);
            let y = fresh.intersect(&ray, &fresh_order).map(|h| h.t);
            assert_eq!(x, y, "{ray:?}");
        }
    }

    #[test]
    fn a_scrambled_mesh_is_rebuilt() {
        let tris = random_triangles(4000, 9);
        let mut bvh = build(&tris);
        // Every triangle swaps places with one far away: the old topology no longer fits.
        let scrambled: Vec<[Vec3; 3]> = (0..tris.len())
            .map(|i| tris[(i * 2311 + 17) % tris.len()])
            .collect();
        assert_eq!(bvh.refit_or_rebuild(&scrambled), Update::Rebuilt);
        assert!(bvh.sah_cost < 2.0 * build(&tris).sah_cost);
        super::super::build::tests::check_tree(&bvh, &scrambled);
    }
}
