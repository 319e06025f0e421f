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
        if !(extent[axis] > 0.0) {
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
