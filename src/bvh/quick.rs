//! A quick BVH: a linear BVH (LBVH) over the triangles' Morton codes, for trees that must be
//! ready at once and are traced little (the first-view probe's few thousand rays).
//!
//! Each triangle's centroid is quantised to a 1024³ grid over the centroids' box and its
//! 30-bit Morton code sorted together with its index (one `u64` a triangle); a node splits its
//! sorted range where the highest bit in which its first and last codes differ flips, and in
//! the middle when they do not differ (or when the tree would get too deep). No surface areas
//! are evaluated, so the build is a sort and two passes: 16 M triangles in 2.3 s against 17 s
//! for the binned SAH of [`super::build`] (2-core machine, loaded), for a tree of 1.8 times
//! its SAH cost. The closest hit along a ray is the same with either tree (each triangle is
//! tested by the same code; only which of two triangles hit at exactly the same distance is
//! reported may differ).
//!
//! The output has [`super::build`]'s layout: node 0 is the root, a node's interior children lie
//! next to each other after it, and each subtree less its root is contiguous.

use super::build::{Built, finish, write_interior, write_leaf};
use super::{Aabb, Bvh, MAX_DEPTH};
use crate::cl::types::DeviceBvhNode;
use glam::Vec3;
use rayon::prelude::*;

/// Largest leaf.
const LEAF: usize = 4;
/// Ranges of at most this many triangles are built by one task.
const TASK: usize = 1 << 15;

/// The 10 low bits of `v` spread to every third bit.
fn spread(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

fn centroid(t: &[Vec3; 3]) -> Vec3 {
    (t[0] + t[1] + t[2]) / 3.0
}

fn triangle_box(t: &[Vec3; 3]) -> Aabb {
    Aabb::EMPTY.grow(t[0]).grow(t[1]).grow(t[2])
}

/// Builds a quick BVH (see the module docs) over triangles given as three vertices each.
pub fn build_quick(triangles: &[[Vec3; 3]]) -> Bvh {
    quick_over(triangles.len(), &|i| triangles[i]).0
}

/// The quick tree over the `n` triangles `triangle(i)`, and the triangles in its order.
fn quick_over(n: usize, triangle: &(impl Fn(usize) -> [Vec3; 3] + Sync)) -> (Bvh, Vec<[Vec3; 3]>) {
    let (tri_indices, codes) = morton_order(n, triangle);
    let ordered = in_order(&tri_indices, triangle);
    (tree(codes, tri_indices, &ordered), ordered)
}

/// [`build_quick`] of `triangles`, which it takes to return them in BVH order (what tracing the
/// tree needs): they are put in that order once, and the input is freed before the tree is
/// made (its leaves then read the triangles in order), so that the two copies and the tree are
/// never held together.
pub fn build_quick_ordered(triangles: Vec<[Vec3; 3]>) -> (Bvh, Vec<[Vec3; 3]>) {
    let at = |i: usize| triangles[i];
    let (tri_indices, codes) = morton_order(triangles.len(), &at);
    let ordered = in_order(&tri_indices, &at);
    drop(triangles);
    (tree(codes, tri_indices, &ordered), ordered)
}

/// The BLAS of an indexed mesh (object space) over a quick tree: what the renderer traces while
/// the mesh's SAH BLAS ([`super::Blas::of_mesh`]) builds behind it. The triangles are read
/// from the mesh where they are needed (no copy of them in mesh order): the same tree and
/// triangles as [`build_quick_ordered`] of that copy.
pub fn quick_blas(positions: &[Vec3], indices: &[[u32; 3]]) -> super::Blas {
    let (bvh, triangles) = quick_over(indices.len(), &|i| {
        indices[i].map(|v| positions[v as usize])
    });
    super::Blas::copied(bvh, triangles)
}

/// [`quick_blas`] of a shared mesh, which the BLAS keeps and reads its triangles from: the
/// triangles in BVH order the build needs are freed once the tree is made, so that a scene's
/// BLASes hold no copy of them (a 64 M-triangle scene's 2.3 GB).
pub fn quick_blas_shared<M: super::IndexedMesh + 'static>(mesh: &std::sync::Arc<M>) -> super::Blas {
    super::Blas::over_mesh(quick_blas(mesh.positions(), mesh.indices()).bvh, mesh)
}

/// The triangles `triangle(i)` for i in `order`.
fn in_order(order: &[u32], triangle: &(impl Fn(usize) -> [Vec3; 3] + Sync)) -> Vec<[Vec3; 3]> {
    if order.len() <= TASK {
        return order.iter().map(|&i| triangle(i as usize)).collect();
    }
    order
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&i| triangle(i as usize))
        .collect()
}

/// The fewest triangles a parallel pass hands one task: a mesh of a few thousand triangles
/// (a scene of many distinct meshes builds them side by side) is one task a pass.
const CHUNK: usize = 1 << 13;

/// The Morton code of centroid `c` in the grid of `min` and `scale` (see [`morton_order`]).
fn morton(c: Vec3, min: Vec3, scale: Vec3) -> u32 {
    let q = ((c - min) * scale).clamp(Vec3::ZERO, Vec3::splat(1023.0));
    spread(q.x as u32) << 2 | spread(q.y as u32) << 1 | spread(q.z as u32)
}

/// Cells per unit along each axis of the grid over the centroids' box `centres` (0 for a flat
/// or empty axis; NaN centroids land in cell 0).
fn grid_scale(centres: &Aabb) -> Vec3 {
    let extent = centres.max - centres.min;
    Vec3::select(
        extent.cmpgt(Vec3::ZERO) & extent.is_finite_mask(),
        Vec3::splat(1023.99) / extent,
        Vec3::ZERO,
    )
}

/// The indices of the `n` triangles `triangle(i)` sorted by their centroids' Morton codes (ties
/// by index), and the sorted codes.
fn morton_order(n: usize, triangle: &(impl Fn(usize) -> [Vec3; 3] + Sync)) -> (Vec<u32>, Vec<u32>) {
    let centroid_of = |i: usize| centroid(&triangle(i));
    if n <= TASK {
        // One task (a small mesh, built beside others): the centroids once, then a radix sort
        // of their codes, stable, so that ties stay in index order as in the sort of (code,
        // index) keys below.
        let centroids: Vec<Vec3> = (0..n).map(centroid_of).collect();
        let centres = centroids.iter().fold(Aabb::EMPTY, |b, &c| b.grow(c));
        let scale = grid_scale(&centres);
        return radix_sort(
            centroids
                .iter()
                .map(|&c| morton(c, centres.min, scale))
                .collect(),
        );
    }
    let centres = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .fold(|| Aabb::EMPTY, |b, i| b.grow(centroid_of(i)))
        .reduce(|| Aabb::EMPTY, Aabb::union);
    let scale = grid_scale(&centres);
    let code = |i: usize| morton(centroid_of(i), centres.min, scale);
    let mut keys: Vec<u64> = (0..n)
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| (code(i) as u64) << 32 | i as u64)
        .collect();
    // Unique keys (the index is part of each), so the order is the same at any thread count.
    keys.par_sort_unstable();
    let tri_indices = keys
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&k| k as u32)
        .collect();
    let codes = keys
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&k| (k >> 32) as u32)
        .collect();
    (tri_indices, codes)
}

/// Digits of [`radix_sort`]: three of 10 bits cover the 30-bit codes.
const DIGIT: u32 = 10;

/// The positions of `codes` (30-bit) in stable sorted order, and the sorted codes: a
/// least-significant-digit radix sort, three passes of 10 bits.
fn radix_sort(codes: Vec<u32>) -> (Vec<u32>, Vec<u32>) {
    const BUCKETS: usize = 1 << DIGIT;
    let n = codes.len();
    let mut counts = vec![[0u32; BUCKETS]; 3];
    for &c in &codes {
        for (d, count) in counts.iter_mut().enumerate() {
            count[(c >> (DIGIT * d as u32)) as usize % BUCKETS] += 1;
        }
    }
    let (mut keys, mut order): (Vec<u32>, Vec<u32>) = (codes, (0..n as u32).collect());
    let (mut keys_to, mut order_to) = (vec![0u32; n], vec![0u32; n]);
    for (d, count) in counts.iter().enumerate() {
        let shift = DIGIT * d as u32;
        if count.iter().any(|&c| c as usize == n) {
            // Every code has the same digit: the pass would leave the order as it is.
            continue;
        }
        let mut next = [0u32; BUCKETS];
        let mut sum = 0;
        for (next, &c) in next.iter_mut().zip(count) {
            *next = sum;
            sum += c;
        }
        for (&k, &i) in keys.iter().zip(&order) {
            let b = (k >> shift) as usize % BUCKETS;
            let at = next[b] as usize;
            keys_to[at] = k;
            order_to[at] = i;
            next[b] += 1;
        }
        std::mem::swap(&mut keys, &mut keys_to);
        std::mem::swap(&mut order, &mut order_to);
    }
    (order, keys)
}

/// The tree over the BVH-order triangles `ordered` with their sorted `codes`.
fn tree(codes: Vec<u32>, tri_indices: Vec<u32>, ordered: &[[Vec3; 3]]) -> Bvh {
    let n = ordered.len();
    if n > LEAF && n <= TASK {
        // One task: the nodes are pushed in their final layout (a placeholder where a slot is
        // taken, filled when its subtree is done), no arena to zero and pack.
        let mut nodes = Vec::with_capacity(n - 1);
        nodes.push(DeviceBvhNode::default());
        let mut len = 1;
        let bounds = emit(&codes, ordered, 0, 0, 0, &mut nodes, &mut len);
        drop(codes);
        return finish(Built::Tree { bounds, at: 0, len }, nodes, tri_indices);
    }
    // As `build`: interior nodes below the root go straight into a zeroed arena (pages cost
    // memory once written), packed into the final layout by `finish`.
    let mut arena: Vec<DeviceBvhNode> = bytemuck::zeroed_vec(2 * n.max(1) - 1);
    let root = build_range(&codes, ordered, 0, 0, &mut arena[1..], 1);
    drop(codes);
    finish(root, arena, tri_indices)
}

/// `⌈log2 n⌉` (0 for n ≤ 1).
fn ceil_log2(n: usize) -> u32 {
    n.next_power_of_two().trailing_zeros()
}

/// Where the sorted range `codes` (more than [`LEAF`] of them) of a node at `depth` splits: at
/// the highest differing bit of its codes while a balanced tree below could still finish
/// within [`MAX_DEPTH`], else in the middle.
fn split_point(codes: &[u32], depth: u32) -> usize {
    let n = codes.len();
    let (a, b) = (codes[0], codes[n - 1]);
    let room = depth + 2 + ceil_log2(n.div_ceil(LEAF)) <= MAX_DEPTH;
    if a == b || !room {
        return n / 2;
    }
    let bit = 31 - (a ^ b).leading_zeros();
    codes.partition_point(|&c| (c >> bit) & 1 == 0)
}

fn leaf_bounds(tris: &[[Vec3; 3]]) -> Aabb {
    tris.iter()
        .fold(Aabb::EMPTY, |b, t| b.union(triangle_box(t)))
}

/// The subtree over the sorted `codes` of the BVH-order triangles `tris`, the first of which is
/// triangle `first`, at `depth`; `space` (arena indices `at..`) has 2m − 2 slots for m
/// triangles, laid out as `build`'s subtrees are.
fn build_range(
    codes: &[u32],
    tris: &[[Vec3; 3]],
    first: u32,
    depth: u32,
    space: &mut [DeviceBvhNode],
    at: usize,
) -> Built {
    let count = codes.len();
    if count <= LEAF {
        return Built::Leaf {
            bounds: leaf_bounds(tris),
            first,
            count: count as u32,
        };
    }
    if count <= TASK {
        let mut len = 1;
        let bounds = emit(codes, tris, first, depth, 0, space, &mut len);
        return Built::Tree { bounds, at, len };
    }
    let a = split_point(codes, depth);
    let (left_space, right_space) = space[2..].split_at_mut(2 * a - 2);
    let (l, r) = rayon::join(
        || {
            build_range(
                &codes[..a],
                &tris[..a],
                first,
                depth + 1,
                left_space,
                at + 2,
            )
        },
        || {
            let (c, t) = (&codes[a..], &tris[a..]);
            build_range(c, t, first + a as u32, depth + 1, right_space, at + 2 * a)
        },
    );
    Built::Top {
        bounds: l.bounds().union(r.bounds()),
        children: Box::new([l, r]),
    }
}

/// Writes the interior node at `slot` over `codes` (more than [`LEAF`]; see [`build_range`]),
/// its interior children next to each other at `nodes[*len..]` and then their subtrees, left
/// first; its box.
fn emit(
    codes: &[u32],
    tris: &[[Vec3; 3]],
    first: u32,
    depth: u32,
    slot: usize,
    nodes: &mut (impl Slots + ?Sized),
    len: &mut usize,
) -> Aabb {
    let at = split_point(codes, depth);
    let parts = [
        (&codes[..at], &tris[..at], first),
        (&codes[at..], &tris[at..], first + at as u32),
    ];
    let slots = parts.map(|(c, _, _)| {
        (c.len() > LEAF).then(|| {
            nodes.take(*len);
            *len += 1;
            *len - 1
        })
    });
    let mut node = DeviceBvhNode::default();
    let mut bounds = Aabb::EMPTY;
    for (side, ((c, t, f), s)) in parts.into_iter().zip(slots).enumerate() {
        let b = match s {
            Some(s) => {
                let b = emit(c, t, f, depth + 1, s, nodes, len);
                write_interior(&mut node, side, b, s as u32);
                b
            }
            None => {
                let b = leaf_bounds(t);
                write_leaf(&mut node, side, b, f, c.len() as u32);
                b
            }
        };
        bounds = bounds.union(b);
    }
    nodes.put(slot, node);
    bounds
}

/// Where [`emit`] writes nodes: an arena's slice with room for them all, or a vector that
/// grows as slots are taken.
trait Slots {
    /// Makes room for slot `slot`, the next one.
    fn take(&mut self, slot: usize);
    /// Writes the node of a slot taken.
    fn put(&mut self, slot: usize, node: DeviceBvhNode);
}

impl Slots for [DeviceBvhNode] {
    fn take(&mut self, _: usize) {}

    fn put(&mut self, slot: usize, node: DeviceBvhNode) {
        self[slot] = node;
    }
}

impl Slots for Vec<DeviceBvhNode> {
    fn take(&mut self, slot: usize) {
        debug_assert_eq!(slot, self.len());
        self.push(DeviceBvhNode::default());
    }

    fn put(&mut self, slot: usize, node: DeviceBvhNode) {
        self[slot] = node;
    }
}

#[cfg(test)]
mod tests {
    use super::super::build::tests::{check_tree, random_rays, random_triangles};
    use super::super::{Child, build};
    use super::*;

    fn ordered(bvh: &Bvh, tris: &[[Vec3; 3]]) -> Vec<[Vec3; 3]> {
        bvh.tri_indices.iter().map(|&i| tris[i as usize]).collect()
    }

    /// More triangles than one task builds, so that the parallel levels are assembled too.
    #[test]
    fn every_triangle_is_in_exactly_one_leaf_inside_its_boxes() {
        for n in [0, 1, 3, 5, 100, 3 * TASK + 17] {
            let tris = random_triangles(n, 5 + n as u64);
            let bvh = build_quick(&tris);
            if n > LEAF {
                check_tree(&bvh, &tris);
            } else {
                // One root node: the triangles in a leaf on the left, an empty one on the right.
                assert_eq!(bvh.nodes.len(), 1);
                let count = n as u32;
                assert_eq!(bvh.child(0, 0).1, Child::Leaf { first: 0, count });
                assert_eq!(bvh.child(0, 1).1, Child::Leaf { first: 0, count: 0 });
            }
            assert!(bvh.depth <= MAX_DEPTH);
        }
    }

    #[test]
    fn the_quick_tree_finds_the_closest_hits_of_the_full_one() {
        let tris = random_triangles(2 * TASK + 5, 21);
        let (quick, full) = (build_quick(&tris), build(&tris));
        assert!(quick.sah_cost > 0.0 && full.sah_cost > 0.0);
        let (q, f) = (ordered(&quick, &tris), ordered(&full, &tris));
        let mut hits = 0;
        for ray in &random_rays(4000, 7) {
            let a = quick.intersect(ray, &q);
            let b = full.intersect(ray, &f);
            assert_eq!(a.map(|h| h.t), b.map(|h| h.t), "{ray:?}");
            assert_eq!(
                a.map(|h| quick.tri_indices[h.prim as usize]),
                b.map(|h| full.tri_indices[h.prim as usize]),
                "{ray:?}"
            );
            assert_eq!(quick.occluded(ray, &q), full.occluded(ray, &f), "{ray:?}");
            hits += a.is_some() as usize;
        }
        assert!(hits > 1000, "{hits}");
    }

    #[test]
    fn a_quick_blas_finds_the_closest_hits_of_the_sah_blas() {
        // An indexed mesh whose vertices are shared by several triangles.
        let soup = random_triangles(3000, 11);
        let positions: Vec<Vec3> = soup.iter().flatten().copied().collect();
        let n = positions.len() as u32;
        let indices: Vec<[u32; 3]> = (0..2 * soup.len() as u32)
            .map(|i| [(7 * i) % n, (7 * i + 1) % n, (7 * i + 2) % n])
            .collect();
        let (quick, sah) = (
            quick_blas(&positions, &indices),
            super::super::Blas::of_mesh(&positions, &indices),
        );
        let mesh_order = sah_order(&sah);
        check_tree(&quick.bvh, &mesh_order);
        let quick_tris: Vec<[Vec3; 3]> = quick.triangles().collect();
        assert_eq!(quick_tris, ordered(&quick.bvh, &mesh_order));
        // The BLASes that read a shared mesh instead of copying its triangles: the same trees,
        // triangles and hits.
        #[derive(Debug)]
        struct Shared(Vec<Vec3>, Vec<[u32; 3]>);
        impl super::super::IndexedMesh for Shared {
            fn positions(&self) -> &[Vec3] {
                &self.0
            }
            fn indices(&self) -> &[[u32; 3]] {
                &self.1
            }
        }
        let mesh = std::sync::Arc::new(Shared(positions.clone(), indices.clone()));
        let (quick_shared, sah_shared) = (
            quick_blas_shared(&mesh),
            super::super::Blas::of_shared_mesh(&mesh),
        );
        assert_eq!(quick_shared.bvh.tri_indices, quick.bvh.tri_indices);
        assert_eq!(sah_shared.bvh.tri_indices, sah.bvh.tri_indices);
        assert!(quick_shared.triangles().eq(quick.triangles()));
        assert!(sah_shared.triangles().eq(sah.triangles()));
        let mut hits = 0;
        for ray in &random_rays(3000, 5) {
            let a = quick.traverse(ray, false);
            let b = sah.traverse(ray, false);
            for (shared, copied) in [(&quick_shared, &quick), (&sah_shared, &sah)] {
                let (s, c) = (shared.traverse(ray, false), copied.traverse(ray, false));
                assert_eq!(
                    s.map(|h| (h.t, h.prim)),
                    c.map(|h| (h.t, h.prim)),
                    "{ray:?}"
                );
                assert_eq!(shared.traverse(ray, true).is_some(), c.is_some(), "{ray:?}");
            }
            assert_eq!(a.map(|h| h.t), b.map(|h| h.t), "{ray:?}");
            assert_eq!(
                a.map(|h| quick.bvh.tri_indices[h.prim as usize]),
                b.map(|h| sah.bvh.tri_indices[h.prim as usize]),
                "{ray:?}"
            );
            hits += a.is_some() as usize;
        }
        assert!(hits > 500, "{hits}");
    }

    /// A BLAS's triangles back in mesh order.
    fn sah_order(b: &super::super::Blas) -> Vec<[Vec3; 3]> {
        let mut tris = vec![[Vec3::ZERO; 3]; b.len()];
        for (k, &i) in b.bvh.tri_indices.iter().enumerate() {
            tris[i as usize] = b.triangle(k);
        }
        tris
    }

    #[test]
    fn the_radix_sort_orders_as_the_sort_of_code_and_index_keys() {
        for (n, spread) in [
            (0, 1),
            (1, 1),
            (7, 3),
            (5000, 1 << 30),
            (5000, 40),
            (3000, 1),
        ] {
            let mut state = 0x9e37_79b9_u32 ^ n as u32;
            let codes: Vec<u32> = (0..n)
                .map(|_| {
                    state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    // Spread over few values (many ties), some with a digit all codes share.
                    (state >> 2) % spread * (1 << 20) / spread.min(1 << 20) + (state >> 31)
                })
                .collect();
            let mut keys: Vec<u64> = codes
                .iter()
                .enumerate()
                .map(|(i, &c)| (c as u64) << 32 | i as u64)
                .collect();
            keys.sort_unstable();
            let (order, sorted) = radix_sort(codes);
            assert_eq!(order, keys.iter().map(|&k| k as u32).collect::<Vec<_>>());
            assert_eq!(
                sorted,
                keys.iter().map(|&k| (k >> 32) as u32).collect::<Vec<_>>()
            );
        }
    }

    /// The BLAS read straight from the mesh is the quick tree of its triangles, bit for bit,
    /// for a mesh one task builds and one built on parallel levels.
    #[test]
    fn a_quick_blas_is_the_quick_tree_of_the_mesh_triangles() {
        for n in [3, 1000, 2 * TASK + 9] {
            let soup = random_triangles(n, 17 + n as u64);
            let positions: Vec<Vec3> = soup.iter().flatten().copied().collect();
            let indices: Vec<[u32; 3]> = (0..n as u32)
                .map(|i| [3 * i + 2, 3 * i, 3 * i + 1])
                .collect();
            let blas = quick_blas(&positions, &indices);
            let mesh: Vec<[Vec3; 3]> = indices
                .iter()
                .map(|t| t.map(|v| positions[v as usize]))
                .collect();
            let (bvh, triangles) = build_quick_ordered(mesh);
            assert!(blas.triangles().eq(triangles.iter().copied()));
            assert_eq!(blas.bvh.tri_indices, bvh.tri_indices);
            assert_eq!(
                bytemuck::cast_slice::<_, u8>(&blas.bvh.nodes),
                bytemuck::cast_slice::<_, u8>(&bvh.nodes)
            );
        }
    }

    #[test]
    fn identical_triangles_still_build_within_the_depth_limit() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let tris = vec![t; 100_000];
        let bvh = build_quick(&tris);
        assert!(bvh.depth <= MAX_DEPTH, "{}", bvh.depth);
        check_tree(&bvh, &tris);
    }

    #[test]
    fn the_tree_does_not_depend_on_the_thread_count() {
        let tris = random_triangles(3 * TASK, 3);
        let many = build_quick(&tris);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let one = pool.install(|| build_quick(&tris));
        assert_eq!(many.tri_indices, one.tri_indices);
        assert_eq!(
            bytemuck::cast_slice::<_, u8>(&many.nodes),
            bytemuck::cast_slice::<_, u8>(&one.nodes)
        );
        assert!(matches!(many.child(0, 0).1, Child::Node(_)));
    }
}
