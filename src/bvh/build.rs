//! Binned SAH build and its output in the GPU node layout.
//!
//! The builder works on a compact array of primitive boxes (32 bytes a triangle, no allocation
//! per triangle). Large nodes at the top of the tree bin and partition their primitives in
//! parallel (rayon chunks, binned per chunk and reduced; partitioned per chunk and the misplaced
//! runs swapped in parallel), so the top levels scale with cores; below that every subtree is a
//! task that writes its nodes in the final layout into its own block, and the blocks are copied
//! into the node array in parallel. Small nodes use fewer bins, the smallest an exact sweep
//! (docs/architecture.md gives the measured reasons). The layout is depth first with the
//! two children of a node either leaves or next to each other: node 0 is the root, a node's
//! interior children come after it, and each subtree (less its root) is contiguous.

use super::sah_split::{NodeInfo, Prim, Split, decide};
use super::{Aabb, Bvh};
use crate::cl::types::DeviceBvhNode;
use glam::Vec3;
use rayon::prelude::*;

/// Subtrees with more primitives than this are built on another rayon task.
const PARALLEL_THRESHOLD: usize = 4096;

/// Builds a BVH over triangles given as three vertices each.
pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
    build_prims(
        triangles
            .par_iter()
            .enumerate()
            .map(|(i, t)| Prim::new(i, Aabb::EMPTY.grow(t[0]).grow(t[1]).grow(t[2])))
            .collect(),
    )
}

/// Builds a BVH over an indexed mesh's triangles (`indices` into `positions`): the same tree as
/// [`build`] over the triangles written out, without that copy (36 bytes a triangle).
pub fn build_indexed(positions: &[Vec3], indices: &[[u32; 3]]) -> Bvh {
    build_prims(
        indices
            .par_iter()
            .enumerate()
            .map(|(i, t)| {
                let [a, b, c] = t.map(|v| positions[v as usize]);
                Prim::new(i, Aabb::EMPTY.grow(a).grow(b).grow(c))
            })
            .collect(),
    )
}

/// Builds a BVH over boxes (the instances of a top-level tree); `tri_indices` then index
/// `boxes`.
pub fn build_boxes(boxes: &[Aabb]) -> Bvh {
    build_prims(
        boxes
            .par_iter()
            .enumerate()
            .map(|(i, &b)| Prim::new(i, b))
            .collect(),
    )
}

fn build_prims(mut prims: Vec<Prim>) -> Bvh {
    let n = prims.len();
    let info = NodeInfo::of(&prims);
    // Every interior node below the root is written once, straight into `arena`, at a
    // provisional place (see `build_subtree`); `assemble` then packs them into the final
    // layout in place. The arena is allocated zeroed, so its pages cost memory only once
    // written: about the tree's own size, where per-task node lists and a final copy of them
    // cost twice that and left the lists' memory to the allocator.
    let mut arena: Vec<DeviceBvhNode> = bytemuck::zeroed_vec(2 * n.max(1) - 1);
    let root = build_subtree(&mut prims, 0, 0, info, &mut arena[1..], 1);
    let tri_indices = prims.par_iter().map(Prim::index).collect();
    drop(prims);
    finish(root, arena, tri_indices)
}

/// The BVH of the subtree `root` built into `arena` (the root's interior nodes from index 1
/// on, see [`build_subtree`]) over the triangles `tri_indices`: the nodes packed into the
/// final layout, with the tree's SAH cost and depth.
pub(super) fn finish(root: Built, mut arena: Vec<DeviceBvhNode>, tri_indices: Vec<u32>) -> Bvh {
    let nodes = match root {
        Built::Tree { at, len, .. } => {
            // Local indices are final ones: the block moves to the front as it is.
            arena.copy_within(at..at + len, 0);
            arena.truncate(len);
            arena.shrink_to_fit();
            arena
        }
        Built::Top { .. } => assemble(root, arena),
        Built::Leaf {
            bounds,
            first,
            count,
        } => {
            // A root that is a leaf still needs a node: the leaf goes left, an empty leaf right.
            let mut node = DeviceBvhNode::default();
            write_leaf(&mut node, 0, bounds, first, count);
            write_leaf(&mut node, 1, Aabb::EMPTY, 0, 0);
            vec![node]
        }
    };
    let mut bvh = Bvh {
        nodes,
        tri_indices,
        sah_cost: 0.0,
        built_sah_cost: 0.0,
        depth: 0,
    };
    let (sah_cost, depth) = bvh.sah_and_depth();
    bvh.sah_cost = sah_cost;
    bvh.built_sah_cost = sah_cost;
    bvh.depth = depth;
    bvh
}

/// A subtree as a task returns it.
pub(super) enum Built {
    /// A leaf: triangles `first..first + count` in BVH order.
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    /// A subtree built by one task: `len` nodes in the final layout with its root at local
    /// index 0, written to the arena from index `at` on.
    Tree { bounds: Aabb, at: usize, len: usize },
    /// A node split on the parallel levels.
    Top {
        bounds: Aabb,
        children: Box<[Built; 2]>,
    },
}

impl Built {
    pub(super) fn bounds(&self) -> Aabb {
        match self {
            Built::Leaf { bounds, .. } | Built::Tree { bounds, .. } | Built::Top { bounds, .. } => {
                *bounds
            }
        }
    }

    /// Nodes this subtree takes in the final array.
    fn node_count(&self) -> usize {
        match self {
            Built::Leaf { .. } => 0,
            Built::Tree { len, .. } => *len,
            Built::Top { children, .. } => 1 + children[0].node_count() + children[1].node_count(),
        }
    }
}

/// Builds the subtree over `prims` (triangles `first..` in BVH order): large ones split here
/// and hand their children to rayon, small ones are built by this task alone.
///
/// `space` (arena indices `at..`) has 2m − 2 slots for a subtree of m primitives, a
/// provisional layout that mirrors the final one with room to spare: a split node keeps its
/// first two slots for its children (the final layout puts interior children next to each
/// other) and gives the left child the next 2a − 2 and the right one the 2b − 2 after them; a
/// task's subtree (at most m − 1 nodes) starts at the first slot of its space. In depth-first
/// order every node then lands at or after its final place, so packing moves nodes only
/// towards the front (see `assemble`).
fn build_subtree(
    prims: &mut [Prim],
    first: u32,
    depth: u32,
    info: NodeInfo,
    space: &mut [DeviceBvhNode],
    at: usize,
) -> Built {
    let bounds = info.bounds.aabb();
    let count = prims.len() as u32;
    let Some(split) = decide(prims, info, depth) else {
        return Built::Leaf {
            bounds,
            first,
            count,
        };
    };
    if prims.len() <= PARALLEL_THRESHOLD {
        let mut len = 1;
        emit(prims, first, depth, split, 0, space, &mut len);
        return Built::Tree { bounds, at, len };
    }
    let a = split.at;
    let (left, right) = prims.split_at_mut(a);
    let right_first = first + a as u32;
    let (left_space, right_space) = space[2..].split_at_mut(2 * a - 2);
    let (l, r) = rayon::join(
        || build_subtree(left, first, depth + 1, split.left, left_space, at + 2),
        || {
            let right_at = at + 2 * a;
            build_subtree(
                right,
                right_first,
                depth + 1,
                split.right,
                right_space,
                right_at,
            )
        },
    );
    Built::Top {
        bounds,
        children: Box::new([l, r]),
    }
}

/// Writes the interior node at `slot` (already split by `split`), appending its interior
/// children next to each other at `nodes[*len..]` and then their subtrees, left first.
fn emit(
    prims: &mut [Prim],
    first: u32,
    depth: u32,
    split: Split,
    slot: usize,
    nodes: &mut [DeviceBvhNode],
    len: &mut usize,
) {
    let (left, right) = prims.split_at_mut(split.at);
    let right_first = first + split.at as u32;
    let mut children = [
        (left, first, split.left, None),
        (right, right_first, split.right, None),
    ];
    let mut node = DeviceBvhNode::default();
    for (side, (p, f, info, child)) in children.iter_mut().enumerate() {
        let bounds = info.bounds.aabb();
        match decide(p, *info, depth + 1) {
            Some(s) => {
                write_interior(&mut node, side, bounds, *len as u32);
                *child = Some((s, *len));
                *len += 1;
            }
            None => write_leaf(&mut node, side, bounds, *f, p.len() as u32),
        }
    }
    nodes[slot] = node;
    for (p, f, _, child) in children {
        if let Some((s, index)) = child {
            emit(p, f, depth + 1, s, index, nodes, len);
        }
    }
}

/// Packs the arena of a tree whose top levels were split in parallel into the layout [`emit`]
/// gives: interior children next to each other, then the left subtree, then the right. The
/// split levels are placed first (a few nodes a task); each task's block, less its root, then
/// moves to its final range, blocks in depth-first order (a block's final range starts at or
/// before its provisional one and ends before the next block's, see `build_subtree`), and its
/// child indices are shifted in parallel. The arena is cut to the tree's size.
fn assemble(root: Built, mut arena: Vec<DeviceBvhNode>) -> Vec<DeviceBvhNode> {
    let total = root.node_count();
    let mut tops = Vec::new();
    let mut blocks = Vec::new();
    let mut end = 1;
    place(root, 0, &mut end, &mut tops, &mut blocks);
    // A block's root goes to the slot its parent reserved, which may lie in a range that an
    // earlier block moves into: read them all first.
    let roots: Vec<DeviceBvhNode> = blocks.iter().map(|b| arena[b.at]).collect();
    for b in &blocks {
        arena.copy_within(b.at + 1..b.at + b.len, b.start);
    }
    // Local index i >= 1 lands at start + i - 1.
    let shift = |mut n: DeviceBvhNode, start: usize| {
        let offset = start as u32 - 1;
        for lo in [&mut n.left_min, &mut n.right_min] {
            if (lo[3].to_bits() as i32) >= 0 {
                lo[3] = f32::from_bits(lo[3].to_bits() + offset);
            }
        }
        n
    };
    // The blocks' final ranges, ascending and disjoint.
    let mut jobs = Vec::with_capacity(blocks.len());
    let mut rest = &mut arena[..total];
    let mut base = 0;
    for b in &blocks {
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(b.start - base);
        let (range, tail) = tail.split_at_mut(b.len - 1);
        jobs.push((range, b.start));
        rest = tail;
        base = b.start + b.len - 1;
    }
    jobs.into_par_iter().for_each(|(range, start)| {
        for n in range {
            *n = shift(*n, start);
        }
    });
    for (b, root) in blocks.iter().zip(roots) {
        arena[b.slot] = shift(root, b.start);
    }
    for (slot, node) in tops {
        arena[slot] = node;
    }
    arena.truncate(total);
    arena.shrink_to_fit();
    arena
}

/// A task's block of nodes: in the arena at `at..at + len`; its root goes to `slot`, the rest
/// from `start` on.
struct Block {
    slot: usize,
    start: usize,
    at: usize,
    len: usize,
}

/// Places the split node `node` at `slot` (into `tops`), reserving slots from `end` for its
/// interior children, and notes where the blocks below it go.
fn place(
    node: Built,
    slot: usize,
    end: &mut usize,
    tops: &mut Vec<(usize, DeviceBvhNode)>,
    blocks: &mut Vec<Block>,
) {
    let Built::Top { children, .. } = node else {
        unreachable!("place is only called on split nodes")
    };
    let mut device = DeviceBvhNode::default();
    let mut pending = [None, None];
    for (side, child) in children.iter().enumerate() {
        match child {
            Built::Leaf {
                bounds,
                first,
                count,
            } => write_leaf(&mut device, side, *bounds, *first, *count),
            Built::Tree { .. } | Built::Top { .. } => {
                write_interior(&mut device, side, child.bounds(), *end as u32);
                pending[side] = Some(*end);
                *end += 1;
            }
        }
    }
    tops.push((slot, device));
    let [left, right] = *children;
    for (child, index) in [left, right].into_iter().zip(pending) {
        let Some(index) = index else { continue };
        match child {
            Built::Top { .. } => place(child, index, end, tops, blocks),
            Built::Tree { at, len, .. } => {
                blocks.push(Block {
                    slot: index,
                    start: *end,
                    at,
                    len,
                });
                *end += len - 1;
            }
            Built::Leaf { .. } => unreachable!("leaves reserve no slot"),
        }
    }
}

fn write_child(node: &mut DeviceBvhNode, side: usize, b: Aabb, reference: i32, count: u32) {
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

pub(super) fn write_leaf(node: &mut DeviceBvhNode, side: usize, b: Aabb, first: u32, count: u32) {
    write_child(node, side, b, !(first as i32), count);
}

pub(super) fn write_interior(node: &mut DeviceBvhNode, side: usize, b: Aabb, index: u32) {
    write_child(node, side, b, index as i32, 0);
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::{Child, MAX_DEPTH, Ray};
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

    /// Checks that every triangle sits in exactly one leaf inside all the boxes above it, that
    /// the leaves tile the triangle list and that the depth limit holds.
    pub(crate) fn check_tree(bvh: &Bvh, tris: &[[Vec3; 3]]) {
        let mut ranges = vec![];
        check_node(bvh, 0, tris, &mut ranges);
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
    }

    #[test]
    fn every_triangle_is_in_exactly_one_leaf_inside_its_boxes() {
        // The large soups go through the parallel binning and partition.
        for (n, seed) in [(5000, 7), (200_000, 8)] {
            let tris = random_triangles(n, seed);
            let bvh = build(&tris);
            check_tree(&bvh, &tris);
            assert!(bvh.sah_cost > 0.0 && bvh.sah_cost < tris.len() as f32);
            assert_eq!(bvh.sah_cost, bvh.built_sah_cost);
        }
    }

    #[test]
    fn the_tree_does_not_depend_on_the_thread_count() {
        let tris = random_triangles(150_000, 21);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| build(&tris));
        let four = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap()
            .install(|| build(&tris));
        // Leaf references are NaN bits as floats: compare bytes.
        let bytes = |b: &Bvh| bytemuck::cast_slice::<_, u8>(&b.nodes).to_vec();
        assert!(bytes(&one) == bytes(&four), "the same nodes");
        assert!(one.tri_indices == four.tri_indices, "the same order");
    }

    #[test]
    fn an_indexed_mesh_builds_the_tree_of_its_triangles() {
        // Triangles sharing vertices: a grid of quads, some vertices used by six triangles.
        let side = 300;
        let mut s = 5;
        let positions: Vec<Vec3> = (0..side * side)
            .map(|i| {
                let (x, z) = ((i % side) as f32, (i / side) as f32);
                Vec3::new(x, lcg(&mut s) * 3.0, z)
            })
            .collect();
        let mut indices = vec![];
        for z in 0..side as u32 - 1 {
            for x in 0..side as u32 - 1 {
                let i = z * side as u32 + x;
                indices.push([i, i + 1, i + side as u32]);
                indices.push([i + 1, i + side as u32 + 1, i + side as u32]);
            }
        }
        let tris: Vec<[Vec3; 3]> = indices
            .iter()
            .map(|t| t.map(|i| positions[i as usize]))
            .collect();
        let (a, b) = (build(&tris), build_indexed(&positions, &indices));
        let bytes = |b: &Bvh| bytemuck::cast_slice::<_, u8>(&b.nodes).to_vec();
        assert!(bytes(&a) == bytes(&b), "the same nodes");
        assert!(a.tri_indices == b.tri_indices, "the same order");
        check_tree(&b, &tris);
    }

    #[test]
    fn the_sah_cost_matches_a_recursive_sum() {
        fn cost(bvh: &Bvh, node: u32, root_area: f32) -> f32 {
            (0..2)
                .map(|side| match bvh.child(node, side) {
                    (b, Child::Node(n)) => b.area() / root_area + cost(bvh, n, root_area),
                    (b, Child::Leaf { count, .. }) => b.area() / root_area * count as f32,
                })
                .sum()
        }
        let tris = random_triangles(3000, 4);
        let bvh = build(&tris);
        let (l, _) = bvh.child(0, 0);
        let (r, _) = bvh.child(0, 1);
        let expect = 1.0 + cost(&bvh, 0, l.union(r).area());
        assert!((bvh.sah_cost - expect).abs() < 1e-3 * expect, "{expect}");
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

    /// Random rays from around the soups of [`random_triangles`], and axis-parallel ones.
    pub(crate) fn random_rays(n: usize, seed: u64) -> Vec<Ray> {
        let mut s = seed;
        let mut rays = vec![];
        for _ in 0..n {
            let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 14.0 - 2.0;
            let d = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) - 0.5;
            rays.push(Ray {
                origin: o,
                direction: d.normalize(),
                tmin: 0.0,
                tmax: f32::INFINITY,
            });
        }
        for i in 0..n / 5 {
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
        rays
    }

    /// Random, grazing and axis-parallel rays; the BVH must find the same closest distance as
    /// testing every triangle, and any-hit must agree on occlusion.
    #[test]
    fn host_traversal_equals_brute_force() {
        let tris = random_triangles(2000, 11);
        let bvh = build(&tris);
        let ordered: Vec<[Vec3; 3]> = bvh.tri_indices.iter().map(|&i| tris[i as usize]).collect();
        let mut rays = random_rays(3000, 99);
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
