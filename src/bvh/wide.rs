//! The 4-wide BVH for SIMD traversal on CPU devices: the binary BVH collapsed so that each node
//! holds up to four children whose boxes are laid out by coordinate (structure of arrays), one
//! `float4` per box plane, so a kernel tests a ray against all four boxes with a few vector
//! operations (kernels/shared/traverse_wide.h). The boxes and leaves are the binary BVH's own, so the
//! same triangles are found; only the order of the tests changes.

use super::traverse::{box_entry, safe_inverse};
use super::{Aabb, Bvh, Child, Hit, Ray, intersect_triangle};
use crate::cl::types::DeviceWideNode;
use glam::Vec3;

/// Children per wide node.
pub const WIDTH: usize = 4;

/// The largest leaf [`WideBvh::collapse_for_cpu`] makes of a small subtree: the CPU kernels test
/// a leaf of three or four triangles in one go, one triangle per `float4` lane.
pub const MERGED_LEAF: u32 = 4;

/// The fewest triangles for which [`WideBvh::collapse_for_cpu`] merges small subtrees: below
/// this the wide nodes fit a core's L2 cache (2 MB: 16 K nodes of 128 bytes, from about 30 K
/// triangles), traversal is bound by arithmetic rather than memory, and the builder's own
/// leaves measured faster (Cornell box 7–10 % slower merged).
pub const MERGE_MIN_TRIANGLES: usize = 65_536;

/// The largest leaf the CPU's wide trees over `triangles` triangles merge small subtrees into
/// ([`WideBvh::collapse_for_cpu`]; 0: none, below [`MERGE_MIN_TRIANGLES`]).
pub fn merge_limit(triangles: usize) -> u32 {
    if triangles >= MERGE_MIN_TRIANGLES {
        MERGED_LEAF
    } else {
        0
    }
}

/// Entries of the wide traversal stack; the kernels use the same size. A visit pushes at most
/// `WIDTH - 1` children and every wide level is at least one binary level, so a binary tree
/// within the builder's depth limit needs at most 3 × 48 entries.
pub const WIDE_STACK_SIZE: usize = (WIDTH - 1) * super::MAX_DEPTH as usize;

/// A collapsed BVH: node 0 is the root; triangles are the binary BVH's, in its order.
#[derive(Clone, Debug)]
pub struct WideBvh {
    /// Nodes. See [`DeviceWideNode`] for the child encoding.
    pub nodes: Vec<DeviceWideNode>,
}

impl WideBvh {
    /// Collapses `bvh`: each wide node takes its binary node's two children and keeps opening
    /// the interior child with the largest surface area until it has four (or only leaves).
    pub fn collapse(bvh: &Bvh) -> Self {
        Self::collapse_merging(bvh, 0)
    }

    /// The wide tree of the CPU megakernel's flat scenes. In large scenes (`merge_limit`)
    /// subtrees of at most [`MERGED_LEAF`] triangles (one range in BVH order) may become
    /// leaves: the binary builder's leaves hold 1–2 triangles, so without merging 44 % of the
    /// 1 M-triangle bunnies' wide nodes have only two children, both leaves, while
    /// traverse_wide.h tests a leaf of three or four triangles in the four lanes of one
    /// `float4` test. Which subtrees become leaves and which binary nodes become wide nodes is
    /// [`WideBvh::collapse_optimal`]'s choice (with [`CollapseCost::CPU`]): on the bunnies 18 %
    /// fewer nodes than merging every small subtree and opening the largest child, for 1.3 %
    /// less expected cost and 1 % fewer visits. The same triangles are tested, in BVH order
    /// within a merged leaf, so the closest hit is the same (short of exact ties in t). Small
    /// scenes get [`WideBvh::collapse`].
    pub fn collapse_for_cpu(bvh: &Bvh) -> Self {
        match merge_limit(bvh.tri_indices.len()) {
            0 => Self::collapse(bvh),
            limit => Self::collapse_optimal(bvh, limit, CollapseCost::CPU),
        }
    }

    /// The expected cost of a ray that the root's box holds under `cost`: wide node visits
    /// (1 each) and leaf tests, each weighted by its box's area against the root's.
    pub fn expected_cost(&self, cost: CollapseCost) -> f32 {
        let mut total = 0.0f64;
        let mut root = Aabb::EMPTY;
        for node in 0..self.nodes.len() as u32 {
            for (bounds, child) in self.children(node) {
                if node == 0 {
                    root = root.union(bounds);
                }
                total += bounds.area() as f64
                    * match child {
                        Child::Leaf { count, .. } => cost.leaf(count) as f64,
                        Child::Node(_) => 1.0,
                    };
            }
        }
        (1.0 + total / root.area().max(f32::MIN_POSITIVE) as f64) as f32
    }

    /// [`WideBvh::collapse`] with each interior child of at most `limit` triangles (in one
    /// range) made a leaf (`limit` 0: none).
    pub fn collapse_merging(bvh: &Bvh, limit: u32) -> Self {
        Self::assemble(|binary, slots| *slots = frontier(bvh, binary, WIDTH, limit))
    }

    /// The wide nodes from the root's binary node down, `slots_of` giving the children of
    /// the wide node made of a binary node.
    fn assemble(mut slots_of: impl FnMut(u32, &mut Vec<(Aabb, Child)>)) -> Self {
        let mut nodes = vec![DeviceWideNode::default()];
        let mut work = vec![(0u32, 0usize)]; // (binary node, wide node)
        let mut slots = Vec::with_capacity(WIDTH);
        while let Some((binary, wide)) = work.pop() {
            slots.clear();
            slots_of(binary, &mut slots);
            let mut out = DeviceWideNode::default();
            for (i, &(bounds, child)) in slots.iter().enumerate() {
                set_box(&mut out, i, bounds);
                match child {
                    Child::Leaf { first, count } => {
                        out.child[i] = !(first as i32);
                        out.count[i] = count;
                    }
                    Child::Node(n) => {
                        let index = nodes.len();
                        nodes.push(DeviceWideNode::default());
                        out.child[i] = index as i32;
                        work.push((n, index));
                    }
                }
            }
            nodes[wide] = out;
        }
        Self { nodes }
    }

    /// The decoded children of `node` (empty slots left out).
    pub fn children(&self, node: u32) -> impl Iterator<Item = (Aabb, Child)> + '_ {
        let n = &self.nodes[node as usize];
        (0..WIDTH).filter_map(move |i| {
            let child = if n.count[i] > 0 {
                Child::Leaf {
                    first: !n.child[i] as u32,
                    count: n.count[i],
                }
            } else if n.child[i] > 0 {
                Child::Node(n.child[i] as u32)
            } else {
                return None;
            };
            let bounds = Aabb {
                min: Vec3::new(n.min_x[i], n.min_y[i], n.min_z[i]),
                max: Vec3::new(n.max_x[i], n.max_y[i], n.max_z[i]),
            };
            Some((bounds, child))
        })
    }

    /// The closest hit along `ray` among `tris` (in BVH order), visiting children nearest
    /// first as the kernels do: the host reference of kernels/shared/traverse_wide.h.
    pub fn intersect(&self, ray: &Ray, tris: &[[Vec3; 3]]) -> Option<Hit> {
        let inv = safe_inverse(ray.direction);
        let mut tmax = ray.tmax;
        let mut best = None;
        let mut stack = Vec::with_capacity(WIDE_STACK_SIZE);
        let mut node = 0u32;
        loop {
            let mut hit: Vec<(f32, Child)> = self
                .children(node)
                .filter_map(|(b, c)| {
                    box_entry(b.min, b.max, ray.origin, inv, ray.tmin, tmax).map(|d| (d, c))
                })
                .collect();
            hit.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut interior = Vec::new();
            for (d, child) in hit {
                match child {
                    Child::Leaf { first, count } if d < tmax => {
                        for prim in first..first + count {
                            let r = Ray { tmax, ..*ray };
                            if let Some((t, u, v)) = intersect_triangle(&r, &tris[prim as usize]) {
                                tmax = t;
                                best = Some(Hit { t, u, v, prim });
                            }
                        }
                    }
                    Child::Node(n) => interior.push((d, n)),
                    Child::Leaf { .. } => {}
                }
            }
            interior.retain(|&(d, _)| d < tmax);
            if let Some(&(_, nearest)) = interior.first() {
                for &(_, n) in interior[1..].iter().rev() {
                    stack.push(n);
                }
                assert!(stack.len() <= WIDE_STACK_SIZE, "wide stack overflow");
                node = nearest;
            } else {
                match stack.pop() {
                    Some(n) => node = n,
                    None => return best,
                }
            }
        }
    }
}

/// The cost model of [`WideBvh::collapse_optimal`], relative to one wide node visit.
#[derive(Clone, Copy, Debug)]
pub struct CollapseCost {
    /// Testing one triangle of a leaf of one or two (the scalar test).
    pub triangle: f32,
    /// Testing a leaf of three or four triangles (one `float4` test).
    pub leaf4: f32,
}

impl CollapseCost {
    /// The costs the CPU megakernel's trees are collapsed with.
    pub const CPU: CollapseCost = CollapseCost {
        triangle: 0.6,
        leaf4: 1.0,
    };

    /// The cost of testing a leaf of `count` triangles (per unit of its box's area).
    fn leaf(self, count: u32) -> f32 {
        if (3..=4).contains(&count) {
            self.leaf4
        } else {
            self.triangle * count as f32
        }
    }
}

/// What [`WideBvh::collapse_optimal`] knows of a binary node's subtree: its triangles (one
/// range in BVH order when `end - first == count`), its box's area, and the cheapest way to
/// place it in `k + 1` slots of a wide node.
#[derive(Clone, Copy)]
struct Placement {
    first: u32,
    end: u32,
    count: u32,
    /// Cheapest cost (area-weighted, everything below included) in at most `k + 1` slots.
    cost: [f32; WIDTH],
    /// `cost[0]`: whether the subtree is one leaf (else a wide node of its own). `cost[k]`,
    /// `k ≥ 1`: slots given to the left child when the two children share the `k + 1` slots,
    /// 0 when fewer slots are cheapest (`cost[k] == cost[k - 1]`).
    choice: [u8; WIDTH],
    /// Slots given to the left child when the subtree is a wide node of its own.
    split: u8,
}

impl WideBvh {
    /// The binary tree collapsed so that the expected cost of a ray (the surface-area
    /// heuristic over wide node visits and leaf tests, with `cost`) is the least among all
    /// collapses of `bvh` that keep its boxes (dynamic programming over the binary nodes, as
    /// Ylitie, Karras and Laine, "Efficient incoherent ray traversal on GPUs through compressed
    /// wide BVHs", 2017, collapse binary trees into 8-wide ones): each binary subtree is a
    /// leaf (at most `limit` triangles in one range), a wide node of its own, or its children
    /// share its slot's place among the parent's four slots. The triangles stay in BVH order,
    /// so the same triangles are found. The builder's leaves stay leaves.
    pub fn collapse_optimal(bvh: &Bvh, limit: u32, cost: CollapseCost) -> Self {
        let n = bvh.nodes.len();
        if n == 0 {
            return Self {
                nodes: vec![DeviceWideNode::default()],
            };
        }
        let empty = Placement {
            first: 0,
            end: 0,
            count: 0,
            cost: [0.0; WIDTH],
            choice: [0; WIDTH],
            split: 0,
        };
        let mut plan = vec![empty; n];
        // Binary nodes in depth-first order from the root, so that in reverse every node comes
        // after its children (whatever the builder's layout).
        let mut order = Vec::with_capacity(n);
        let mut work = vec![0u32];
        while let Some(node) = work.pop() {
            order.push(node);
            for side in 0..2 {
                if let Child::Node(c) = bvh.child(node, side).1 {
                    work.push(c);
                }
            }
        }
        for &node in order.iter().rev() {
            let sides = [0, 1].map(|side| {
                let (bounds, child) = bvh.child(node, side);
                match child {
                    Child::Leaf { first, count } => {
                        let area = bounds.area();
                        let c = area * cost.leaf(count);
                        Placement {
                            first,
                            end: first + count,
                            count,
                            cost: [c; WIDTH],
                            choice: [1; WIDTH],
                            split: 0,
                        }
                    }
                    Child::Node(c) => plan[c as usize],
                }
            });
            let [l, r] = sides;
            let area = bvh.child(node, 0).0.union(bvh.child(node, 1).0).area();
            let mut p = Placement {
                first: l.first.min(r.first),
                end: l.end.max(r.end),
                count: l.count + r.count,
                cost: [0.0; WIDTH],
                choice: [0; WIDTH],
                split: 0,
            };
            // The two children in at most `k + 1` slots.
            let share = |k: usize| {
                (1..=k)
                    .map(|j| (l.cost[j - 1] + r.cost[k - j], j as u8))
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .unwrap()
            };
            let (children, split) = share(WIDTH - 1);
            p.split = split;
            let interior = area + children;
            let leaf = if p.count <= limit && p.end - p.first == p.count {
                area * cost.leaf(p.count)
            } else {
                f32::INFINITY
            };
            (p.cost[0], p.choice[0]) = if leaf <= interior {
                (leaf, 1)
            } else {
                (interior, 0)
            };
            for k in 1..WIDTH {
                let (c, j) = share(k);
                (p.cost[k], p.choice[k]) = if c < p.cost[k - 1] {
                    (c, j)
                } else {
                    (p.cost[k - 1], 0)
                };
            }
            plan[node as usize] = p;
        }

        Self::assemble(|binary, slots| {
            let j = plan[binary as usize].split as usize;
            place(bvh, &plan, bvh.child(binary, 0), j, slots);
            place(bvh, &plan, bvh.child(binary, 1), WIDTH - j, slots);
        })
    }
}

/// Appends to `out` the slots of `child` (a box and reference of a binary node's child) in at
/// most `k` slots, as [`WideBvh::collapse_optimal`] planned them.
fn place(
    bvh: &Bvh,
    plan: &[Placement],
    child: (Aabb, Child),
    k: usize,
    out: &mut Vec<(Aabb, Child)>,
) {
    let (bounds, Child::Node(node)) = child else {
        out.push(child);
        return;
    };
    let p = &plan[node as usize];
    let mut k = k - 1;
    while k > 0 && p.choice[k] == 0 {
        k -= 1;
    }
    if k > 0 {
        let j = p.choice[k] as usize;
        place(bvh, plan, bvh.child(node, 0), j, out);
        place(bvh, plan, bvh.child(node, 1), k + 1 - j, out);
    } else if p.choice[0] == 1 {
        out.push((
            bounds,
            Child::Leaf {
                first: p.first,
                count: p.count,
            },
        ));
    } else {
        out.push(child);
    }
}

/// The triangles of the subtree below binary node `node` as one leaf, when they are at most
/// `limit` and form one range in BVH order.
fn subtree_leaf(bvh: &Bvh, node: u32, limit: u32) -> Option<Child> {
    let (mut first, mut end, mut total) = (u32::MAX, 0u32, 0u32);
    let mut work = vec![node];
    while let Some(n) = work.pop() {
        for side in 0..2 {
            match bvh.child(n, side).1 {
                Child::Node(c) => work.push(c),
                Child::Leaf { first: f, count } => {
                    total += count;
                    if total > limit {
                        return None;
                    }
                    first = first.min(f);
                    end = end.max(f + count);
                }
            }
        }
    }
    (end - first == total).then_some(Child::Leaf {
        first,
        count: total,
    })
}

/// Up to `width` boxes below node `binary` of `bvh` that hold all of its triangles: its
/// children, then repeatedly the inner child of largest area replaced by its own two; each
/// interior child of at most `merge` triangles is made a leaf (see
/// [`WideBvh::collapse_for_cpu`]; 0 merges nothing).
pub fn frontier(bvh: &Bvh, binary: u32, width: usize, merge: u32) -> Vec<(Aabb, Child)> {
    let child = |node: u32, side: usize| {
        let (bounds, c) = bvh.child(node, side);
        match c {
            Child::Node(n) if merge > 0 => (bounds, subtree_leaf(bvh, n, merge).unwrap_or(c)),
            _ => (bounds, c),
        }
    };
    let mut slots: Vec<(Aabb, Child)> = (0..2).map(|side| child(binary, side)).collect();
    while slots.len() < width {
        let Some((i, node)) = slots
            .iter()
            .enumerate()
            .filter_map(|(i, s)| match s.1 {
                Child::Node(n) => Some((i, n, s.0.area())),
                Child::Leaf { .. } => None,
            })
            .max_by(|a, b| a.2.total_cmp(&b.2))
            .map(|(i, n, _)| (i, n))
        else {
            break;
        };
        slots.swap_remove(i);
        slots.extend((0..2).map(|side| child(node, side)));
    }
    slots
}

/// Writes box `b` into slot `slot` of a wide node.
pub(super) fn set_box(node: &mut DeviceWideNode, slot: usize, b: Aabb) {
    node.min_x[slot] = b.min.x;
    node.min_y[slot] = b.min.y;
    node.min_z[slot] = b.min.z;
    node.max_x[slot] = b.max.x;
    node.max_y[slot] = b.max.y;
    node.max_z[slot] = b.max.z;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_triangles(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut s = seed;
        let mut rnd = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(rnd(), rnd(), rnd()) * 10.0;
                let mut v = || c + (Vec3::new(rnd(), rnd(), rnd()) - 0.5) * 0.8;
                [v(), v(), v()]
            })
            .collect()
    }

    /// Triangles in BVH order.
    fn ordered(bvh: &Bvh, tris: &[[Vec3; 3]]) -> Vec<[Vec3; 3]> {
        bvh.tri_indices.iter().map(|&i| tris[i as usize]).collect()
    }

    #[test]
    fn every_triangle_is_in_exactly_one_leaf_inside_its_box() {
        let tris = random_triangles(5000, 3);
        let bvh = crate::bvh::build(&tris);
        let wide = WideBvh::collapse(&bvh);
        check_leaves(&bvh, &tris, &wide);
        // Four-wide nodes: about a third as many as the binary tree's.
        assert!(
            wide.nodes.len() * 2 < bvh.nodes.len(),
            "{}",
            wide.nodes.len()
        );
    }

    #[test]
    fn merged_small_subtrees_are_leaves_of_at_most_four_triangles() {
        let tris = random_triangles(5000, 3);
        let bvh = crate::bvh::build(&tris);
        let merged = WideBvh::collapse_merging(&bvh, MERGED_LEAF);
        check_leaves(&bvh, &tris, &merged);
        let leaves = leaf_sizes(&merged);
        let mean = leaves.iter().sum::<u32>() as f32 / leaves.len() as f32;
        let plain = WideBvh::collapse(&bvh);
        // The builder's own leaves may be larger; merging makes none larger than MERGED_LEAF.
        let builder_max = leaf_sizes(&plain).into_iter().max().unwrap();
        assert!(
            leaves.iter().all(|&c| c <= MERGED_LEAF.max(builder_max)),
            "leaf sizes"
        );
        assert!(
            merged.nodes.len() < plain.nodes.len() * 3 / 4,
            "{} merged nodes against {}",
            merged.nodes.len(),
            plain.nodes.len()
        );
        assert!(mean > 2.0, "mean leaf {mean}");
        // Small scenes stay as built.
        assert_eq!(WideBvh::collapse_for_cpu(&bvh).nodes, plain.nodes);
    }

    #[test]
    fn the_optimal_collapse_costs_no_more_than_the_greedy_one() {
        let tris = random_triangles(20_000, 7);
        let bvh = crate::bvh::build(&tris);
        for cost in [
            CollapseCost::CPU,
            CollapseCost {
                triangle: 0.3,
                leaf4: 2.0,
            },
        ] {
            let greedy = WideBvh::collapse_merging(&bvh, MERGED_LEAF);
            let optimal = WideBvh::collapse_optimal(&bvh, MERGED_LEAF, cost);
            check_leaves(&bvh, &tris, &optimal);
            let builder_max = leaf_sizes(&WideBvh::collapse(&bvh))
                .into_iter()
                .max()
                .unwrap();
            assert!(
                leaf_sizes(&optimal)
                    .iter()
                    .all(|&c| c <= MERGED_LEAF.max(builder_max)),
                "leaf sizes"
            );
            let (g, o) = (greedy.expected_cost(cost), optimal.expected_cost(cost));
            assert!(o <= g * 1.0001, "{o} against greedy {g}");
            // Merging nothing: still no worse than the plain collapse.
            let plain = WideBvh::collapse(&bvh).expected_cost(cost);
            let unmerged = WideBvh::collapse_optimal(&bvh, 0, cost);
            check_leaves(&bvh, &tris, &unmerged);
            assert!(unmerged.expected_cost(cost) <= plain * 1.0001);
        }
        // A quick (unordered) build collapses too.
        let quick = crate::bvh::build_quick(&tris);
        let optimal = WideBvh::collapse_optimal(&quick, MERGED_LEAF, CollapseCost::CPU);
        check_leaves(&quick, &tris, &optimal);
    }

    fn leaf_sizes(wide: &WideBvh) -> Vec<u32> {
        (0..wide.nodes.len() as u32)
            .flat_map(|n| wide.children(n).collect::<Vec<_>>())
            .filter_map(|(_, c)| match c {
                Child::Leaf { count, .. } => Some(count),
                Child::Node(_) => None,
            })
            .collect()
    }

    /// Every triangle in exactly one leaf whose box holds it; every node reached once.
    fn check_leaves(bvh: &Bvh, tris: &[[Vec3; 3]], wide: &WideBvh) {
        let ordered = ordered(bvh, tris);
        let mut seen = vec![0u32; tris.len()];
        let mut reached = vec![false; wide.nodes.len()];
        reached[0] = true;
        for node in 0..wide.nodes.len() as u32 {
            let children: Vec<_> = wide.children(node).collect();
            assert!(
                children.len() >= 2 && children.len() <= WIDTH,
                "node {node}"
            );
            for (bounds, child) in children {
                match child {
                    Child::Leaf { first, count } => {
                        for p in first..first + count {
                            seen[p as usize] += 1;
                            for v in ordered[p as usize] {
                                assert!(bounds.contains(v), "triangle {p} outside its box");
                            }
                        }
                    }
                    Child::Node(n) => {
                        assert!(!reached[n as usize], "node {n} has two parents");
                        reached[n as usize] = true;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "each triangle once");
        assert!(reached.iter().all(|&r| r), "every node reachable");
    }

    #[test]
    fn wide_traversal_finds_the_binary_traversals_hits() {
        let tris = random_triangles(3000, 9);
        let bvh = crate::bvh::build(&tris);
        let wide = WideBvh::collapse(&bvh);
        let merged = WideBvh::collapse_merging(&bvh, MERGED_LEAF);
        let optimal = WideBvh::collapse_optimal(&bvh, MERGED_LEAF, CollapseCost::CPU);
        let ordered = ordered(&bvh, &tris);
        let mut s = 5u64;
        let mut rnd = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut hits = 0;
        for i in 0..4000 {
            let origin = Vec3::new(rnd(), rnd(), rnd()) * 14.0 - 2.0;
            let mut direction = (Vec3::new(rnd(), rnd(), rnd()) - 0.5).normalize();
            if i % 10 == 0 {
                direction = Vec3::Y; // axis-parallel
            }
            let ray = Ray {
                origin,
                direction,
                tmin: 0.0,
                tmax: if i % 7 == 0 { 2.0 } else { f32::INFINITY },
            };
            let a = bvh.intersect(&ray, &ordered);
            let b = wide.intersect(&ray, &ordered);
            assert_eq!(a.map(|h| h.t), b.map(|h| h.t), "ray {i}");
            let c = merged.intersect(&ray, &ordered);
            assert_eq!(a.map(|h| h.t), c.map(|h| h.t), "ray {i}, merged leaves");
            let d = optimal.intersect(&ray, &ordered);
            assert_eq!(a.map(|h| h.t), d.map(|h| h.t), "ray {i}, optimal collapse");
            hits += a.is_some() as usize;
        }
        assert!(hits > 400, "the rays hit something ({hits})");
    }

    #[test]
    fn a_single_leaf_tree_collapses_to_one_node() {
        let tris = random_triangles(2, 1);
        let bvh = crate::bvh::build(&tris);
        let wide = WideBvh::collapse(&bvh);
        assert_eq!(wide.nodes.len(), 1);
        let ordered = ordered(&bvh, &tris);
        let c = (ordered[0][0] + ordered[0][1] + ordered[0][2]) / 3.0;
        let ray = Ray {
            origin: c + Vec3::Z * 20.0,
            direction: -Vec3::Z,
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        assert_eq!(
            wide.intersect(&ray, &ordered).map(|h| h.t),
            bvh.intersect(&ray, &ordered).map(|h| h.t)
        );
    }
}
