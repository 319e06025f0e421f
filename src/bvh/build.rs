//! Binned SAH build (multi-threaded with rayon) and flattening into the GPU node layout.

use super::{Aabb, Bvh};
use crate::cl::types::GpuBvhNode;
use glam::Vec3;

/// Number of bins per axis.
const BINS: usize = 16;
/// Largest leaf the SAH may choose.
const MAX_LEAF: usize = 8;
/// Relative cost of one traversal step against one triangle test.
const TRAVERSAL_COST: f32 = 1.0;
/// Deepest leaf the builder makes. The kernels' stack holds 64 entries and a traversal pushes
/// at most one entry per level, so the stack cannot overflow; deeper subtrees become leaves.
pub const MAX_DEPTH: u32 = 48;
/// Subtrees with more primitives than this are built on another rayon task.
const PARALLEL_THRESHOLD: usize = 4096;

enum BuildNode {
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        children: Box<[BuildNode; 2]>,
    },
}

impl BuildNode {
    fn bounds(&self) -> Aabb {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Interior { bounds, .. } => *bounds,
        }
    }
}

#[derive(Clone, Copy)]
struct Prim {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

/// Builds a BVH over triangles given as three vertices each.
pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
    use rayon::prelude::*;
    let mut prims: Vec<Prim> = triangles
        .par_iter()
        .enumerate()
        .map(|(i, t)| {
            let bounds = Aabb::EMPTY.grow(t[0]).grow(t[1]).grow(t[2]);
            Prim {
                bounds,
                centroid: (bounds.min + bounds.max) * 0.5,
                index: i as u32,
            }
        })
        .collect();
    let root = build_node(&mut prims, 0, 0);
    let tri_indices = prims.iter().map(|p| p.index).collect();
    let mut bvh = Bvh {
        nodes: Vec::with_capacity(triangles.len().max(1)),
        tri_indices,
        sah_cost: 0.0,
        depth: 0,
    };
    let root_area = root.bounds().area().max(f32::MIN_POSITIVE);
    bvh.sah_cost = sah_cost(&root, root_area);
    bvh.depth = depth(&root);
    match root {
        BuildNode::Interior { .. } => {
            bvh.nodes.push(GpuBvhNode::default());
            flatten(&root, 0, &mut bvh.nodes);
        }
        leaf @ BuildNode::Leaf { .. } => {
            // A root that is a leaf still needs a node: the leaf goes left, an empty leaf right.
            let empty = BuildNode::Leaf {
                bounds: Aabb::EMPTY,
                first: 0,
                count: 0,
            };
            let mut node = GpuBvhNode::default();
            write_child(&mut node, 0, &leaf, 0);
            write_child(&mut node, 1, &empty, 0);
            bvh.nodes.push(node);
        }
    }
    bvh
}

fn build_node(prims: &mut [Prim], first: u32, depth: u32) -> BuildNode {
    let bounds = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(p.bounds));
    let leaf = BuildNode::Leaf {
        bounds,
        first,
        count: prims.len() as u32,
    };
    if prims.len() <= 1 || depth >= MAX_DEPTH {
        return leaf;
    }
    let split = match find_split(prims, bounds) {
        Some((axis, position, cost)) => {
            if cost >= prims.len() as f32 && prims.len() <= MAX_LEAF {
                return leaf;
            }
            partition(prims, |p| p.centroid[axis] < position)
        }
        None if prims.len() <= MAX_LEAF => return leaf,
        // All centroids coincide: split in the middle of the list.
        None => prims.len() / 2,
    };
    let split = if split == 0 || split == prims.len() {
        prims.len() / 2
    } else {
        split
    };
    let (left, right) = prims.split_at_mut(split);
    let right_first = first + split as u32;
    let (l, r) = if left.len() + right.len() > PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(left, first, depth + 1),
            || build_node(right, right_first, depth + 1),
        )
    } else {
        (
            build_node(left, first, depth + 1),
            build_node(right, right_first, depth + 1),
        )
    };
    BuildNode::Interior {
        bounds,
        children: Box::new([l, r]),
    }
}

/// Finds the cheapest binned split over all three axes: (axis, centroid position, SAH cost
/// relative to this node's area, including the traversal step).
fn find_split(prims: &[Prim], bounds: Aabb) -> Option<(usize, f32, f32)> {
    let centroid_bounds = prims.iter().fold(Aabb::EMPTY, |b, p| b.grow(p.centroid));
    let extent = centroid_bounds.max - centroid_bounds.min;
    let area = bounds.area().max(f32::MIN_POSITIVE);
    let mut best: Option<(usize, f32, f32)> = None;
    for axis in 0..3 {
        // Skip flat axes (and a NaN extent, which no finite input makes).
        if extent[axis].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of = |c: f32| (((c - centroid_bounds.min[axis]) * scale) as usize).min(BINS - 1);
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_counts = [0usize; BINS];
        for p in prims {
            let b = bin_of(p.centroid[axis]);
            bin_bounds[b] = bin_bounds[b].union(p.bounds);
            bin_counts[b] += 1;
        }
        // Sweep from the right to know the cost of every right-hand side.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            acc = acc.union(bin_bounds[i]);
            count += bin_counts[i];
            right_area[i] = acc.area();
            right_count[i] = count;
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for i in 0..BINS - 1 {
            acc = acc.union(bin_bounds[i]);
            count += bin_counts[i];
            if count == 0 || right_count[i + 1] == 0 {
                continue;
            }
            let cost = TRAVERSAL_COST
                + (acc.area() * count as f32 + right_area[i + 1] * right_count[i + 1] as f32)
                    / area;
            if best.is_none_or(|(_, _, c)| cost < c) {
                let position = centroid_bounds.min[axis] + (i + 1) as f32 / scale;
                best = Some((axis, position, cost));
            }
        }
    }
    best
}

/// Moves the elements satisfying `left` to the front; returns how many there are.
fn partition(prims: &mut [Prim], left: impl Fn(&Prim) -> bool) -> usize {
    let mut i = 0;
    for j in 0..prims.len() {
        if left(&prims[j]) {
            prims.swap(i, j);
            i += 1;
        }
    }
    i
}

fn write_child(node: &mut GpuBvhNode, side: usize, child: &BuildNode, index: u32) {
    let b = child.bounds();
    let (reference, count) = match child {
        BuildNode::Leaf { first, count, .. } => (!(*first as i32), *count),
        BuildNode::Interior { .. } => (index as i32, 0),
    };
    let lo = [b.min.x, b.min.y, b.min.z, f32::from_bits(reference as u32)];
    let hi = [b.max.x, b.max.y, b.max.z, f32::from_bits(count)];
    if side == 0 {
        node.left_min = lo;
        node.left_max = hi;
    } else {
        node.right_min = lo;
        node.right_max = hi;
    }
}

/// Writes the interior node `node` at `index`, appending its interior children depth first.
fn flatten(node: &BuildNode, index: usize, nodes: &mut Vec<GpuBvhNode>) {
    let BuildNode::Interior { children, .. } = node else {
        unreachable!("flatten is only called on interior nodes")
    };
    let mut gpu = GpuBvhNode::default();
    let mut pending = Vec::new();
    for (side, child) in children.iter().enumerate() {
        let child_index = if matches!(child, BuildNode::Interior { .. }) {
            nodes.push(GpuBvhNode::default());
            pending.push((child, nodes.len() - 1));
            nodes.len() - 1
        } else {
            0
        };
        write_child(&mut gpu, side, child, child_index as u32);
    }
    nodes[index] = gpu;
    for (child, child_index) in pending {
        flatten(child, child_index, nodes);
    }
}

fn sah_cost(node: &BuildNode, root_area: f32) -> f32 {
    match node {
        BuildNode::Leaf { bounds, count, .. } => bounds.area() / root_area * *count as f32,
        BuildNode::Interior { bounds, children } => {
            bounds.area() / root_area * TRAVERSAL_COST
                + sah_cost(&children[0], root_area)
                + sah_cost(&children[1], root_area)
        }
    }
}

fn depth(node: &BuildNode) -> u32 {
    match node {
        BuildNode::Leaf { .. } => 0,
        BuildNode::Interior { children, .. } => 1 + depth(&children[0]).max(depth(&children[1])),
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Child, Ray};
    use super::*;

    /// Deterministic pseudo-random numbers in [0, 1).
    pub(crate) fn lcg(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 40) as f32 / (1u64 << 24) as f32
    }

    pub(crate) fn random_triangles(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                let c = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 10.0;
                let mut v = || c + (Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) - 0.5) * 0.8;
                [v(), v(), v()]
            })
            .collect()
    }

    /// Walks the tree checking boxes, collecting the leaf ranges.
    fn check_node(bvh: &Bvh, node: u32, tris: &[[Vec3; 3]], ranges: &mut Vec<(u32, u32)>) {
        for side in 0..2 {
            let (b, child) = bvh.child(node, side);
            match child {
                Child::Node(n) => {
                    assert!(n > node, "children come after their parent");
                    let (cb, _) = bvh.child(n, 0);
                    let (cb2, _) = bvh.child(n, 1);
                    assert!(b.contains(cb.min) && b.contains(cb.max));
                    assert!(b.contains(cb2.min) && b.contains(cb2.max));
                    check_node(bvh, n, tris, ranges);
                }
                Child::Leaf { first, count } => {
                    for p in first..first + count {
                        let original = bvh.tri_indices[p as usize] as usize;
                        for v in tris[original] {
                            assert!(b.contains(v), "a leaf box must hold its triangles");
                        }
                    }
                    ranges.push((first, count));
                }
            }
        }
    }

    #[test]
    fn every_triangle_is_in_exactly_one_leaf_inside_its_boxes() {
        let tris = random_triangles(5000, 7);
        let bvh = build(&tris);
        let mut ranges = vec![];
        check_node(&bvh, 0, &tris, &mut ranges);
        ranges.sort();
        let mut next = 0;
        for (first, count) in ranges {
            assert_eq!(first, next, "leaf ranges tile the triangle list");
            assert!(count >= 1);
            next = first + count;
        }
        assert_eq!(next as usize, tris.len());
        let mut seen = bvh.tri_indices.clone();
        seen.sort();
        assert!(
            seen.iter().enumerate().all(|(i, &t)| i as u32 == t),
            "a permutation"
        );
        assert!(bvh.depth <= MAX_DEPTH);
        assert!(bvh.sah_cost > 0.0 && bvh.sah_cost < tris.len() as f32);
    }

    #[test]
    fn two_triangles_give_the_known_tree() {
        // Two unit triangles far apart on x: the root must split them into two leaves.
        let a = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let b = [
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(11.0, 0.0, 0.0),
            Vec3::new(10.0, 1.0, 0.0),
        ];
        let bvh = build(&[a, b]);
        assert_eq!(bvh.nodes.len(), 1);
        assert_eq!(bvh.tri_indices, vec![0, 1]);
        let (lb, l) = bvh.child(0, 0);
        let (rb, r) = bvh.child(0, 1);
        assert_eq!(l, Child::Leaf { first: 0, count: 1 });
        assert_eq!(r, Child::Leaf { first: 1, count: 1 });
        assert_eq!((lb.min, lb.max), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert_eq!(
            (rb.min, rb.max),
            (Vec3::new(10.0, 0.0, 0.0), Vec3::new(11.0, 1.0, 0.0))
        );
    }

    #[test]
    fn a_single_triangle_gets_a_root_node() {
        let bvh = build(&[[Vec3::ZERO, Vec3::X, Vec3::Y]]);
        assert_eq!(bvh.nodes.len(), 1);
        assert_eq!(bvh.child(0, 0).1, Child::Leaf { first: 0, count: 1 });
        assert_eq!(bvh.child(0, 1).1, Child::Leaf { first: 0, count: 0 });
    }

    #[test]
    fn identical_triangles_still_build_within_the_depth_limit() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let bvh = build(&vec![t; 1000]);
        assert!(bvh.depth <= MAX_DEPTH);
        let mut ranges = vec![];
        check_node(&bvh, 0, &vec![t; 1000], &mut ranges);
        assert_eq!(ranges.iter().map(|r| r.1).sum::<u32>(), 1000);
    }

    fn brute_force(ray: &Ray, tris: &[[Vec3; 3]]) -> Option<f32> {
        let mut best: Option<f32> = None;
        for t in tris {
            let r = Ray {
                tmax: best.unwrap_or(ray.tmax),
                ..*ray
            };
            if let Some((d, _, _)) = super::super::intersect_triangle(&r, t) {
                best = Some(d);
            }
        }
        best
    }

    /// Random, grazing and axis-parallel rays; the BVH must find the same closest distance as
    /// testing every triangle, and any-hit must agree on occlusion.
    #[test]
    fn host_traversal_equals_brute_force() {
        let tris = random_triangles(2000, 11);
        let bvh = build(&tris);
        let ordered: Vec<[Vec3; 3]> = bvh.tri_indices.iter().map(|&i| tris[i as usize]).collect();
        let mut s = 99u64;
        let mut rays = vec![];
        for _ in 0..3000 {
            let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 14.0 - 2.0;
            let d = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) - 0.5;
            rays.push(Ray {
                origin: o,
                direction: d.normalize(),
                tmin: 0.0,
                tmax: f32::INFINITY,
            });
        }
        for i in 0..600 {
            // Axis-parallel rays along each axis in both directions.
            let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 10.0;
            let mut d = Vec3::ZERO;
            d[i % 3] = if i % 2 == 0 { 1.0 } else { -1.0 };
            rays.push(Ray {
                origin: o - d * 20.0,
                direction: d,
                tmin: 0.0,
                tmax: f32::INFINITY,
            });
        }
        for t in tris.iter().take(600) {
            // Grazing rays: in the plane of a triangle, through its edge midpoint.
            let mid = (t[0] + t[1]) * 0.5;
            let d = (t[1] - t[0]).normalize();
            rays.push(Ray {
                origin: mid - d * 5.0,
                direction: d,
                tmin: 0.0,
                tmax: f32::INFINITY,
            });
        }
        for ray in &rays {
            let expect = brute_force(ray, &tris);
            let got = bvh.intersect(ray, &ordered).map(|h| h.t);
            assert_eq!(got, expect, "closest hit differs for {ray:?}");
            assert_eq!(
                bvh.occluded(ray, &ordered),
                expect.is_some(),
                "any hit differs for {ray:?}"
            );
        }
    }
}
