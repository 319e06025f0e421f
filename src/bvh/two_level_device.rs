//! The two-level form in the device's layout: the TLAS's nodes in slots reserved at the front
//! of the node arrays (so that a rebuilt TLAS is written over the old one in place), then every
//! BLAS's, rebased, in the binary and the 4-wide forms.

use super::{Blas, TwoLevel, WideBvh};
use crate::cl::types::{DeviceBvhNode, DeviceWideNode};
use rayon::prelude::*;

impl TwoLevel {
    /// Nodes the device reserves for the TLAS at the front of its node arrays (binary and
    /// wide): as many as a TLAS of [`TwoLevel::max_pieces`] leaves can take, so that a rebuilt
    /// TLAS is written over the old one in place and the BLASes behind it stay where they are.
    pub fn tlas_slots(&self) -> usize {
        self.max_pieces.saturating_sub(1).max(1)
    }

    /// The device form: the TLAS's nodes (padded to [`TwoLevel::tlas_slots`]) followed by every
    /// BLAS's (child indices and leaf triangles rebased: BLAS leaves index the object triangles
    /// of all meshes one after the other, TLAS leaves the instances in TLAS order), each BLAS's
    /// root, and each mesh's first object triangle.
    pub fn device_nodes(&self) -> (Vec<DeviceBvhNode>, Vec<u32>, Vec<u32>) {
        let mut nodes = self.device_tlas();
        let roots = self.device_roots();
        let mut firsts = vec![];
        let mut tri_base = 0u32;
        for b in &self.blases {
            debug_assert_eq!(roots[firsts.len()], nodes.len() as u32);
            firsts.push(tri_base);
            nodes.extend(rebased(&b.bvh.nodes, nodes.len() as i32, tri_base));
            tri_base += b.len() as u32;
        }
        (nodes, roots, firsts)
    }

    /// The TLAS's binary nodes in the device's form, padded to [`TwoLevel::tlas_slots`]: each
    /// leaf (one piece, `split_instance_leaves`) has [`crate::cl::types::TLAS_LEAF`] set in
    /// its count.
    pub fn device_tlas(&self) -> Vec<DeviceBvhNode> {
        let mut nodes = self.tlas.nodes.clone();
        for n in &mut nodes {
            for (lo, hi) in [
                (n.left_min, &mut n.left_max),
                (n.right_min, &mut n.right_max),
            ] {
                let count = hi[3].to_bits();
                if (lo[3].to_bits() as i32) < 0 && count > 0 {
                    debug_assert_eq!(count, 1, "a TLAS leaf holds one piece");
                    hi[3] = f32::from_bits(count | crate::cl::types::TLAS_LEAF);
                }
            }
        }
        nodes.resize(self.tlas_slots(), DeviceBvhNode::default());
        nodes
    }

    /// Where [`TwoLevel::device_nodes`] puts each BLAS's root: after the TLAS's slots, the
    /// BLASes one after the other.
    pub fn device_roots(&self) -> Vec<u32> {
        let mut at = self.tlas_slots() as u32;
        self.blases
            .iter()
            .map(|b| {
                at += b.bvh.nodes.len() as u32;
                at - b.bvh.nodes.len() as u32
            })
            .collect()
    }

    /// [`TwoLevel::device_nodes`] for the 4-wide form: the collapsed TLAS, then every
    /// collapsed BLAS, rebased alike; and each BLAS's root (where its pieces enter it).
    pub fn device_wide_nodes(&self) -> (Vec<DeviceWideNode>, Vec<u32>) {
        // Every wide node is made of a distinct binary node, so the binary nodes bound the
        // array: reserved at once (address space; only the pages written are touched), it is
        // never moved while it grows.
        let bound =
            self.tlas_slots() + self.blases.iter().map(|b| b.bvh.nodes.len()).sum::<usize>();
        let mut nodes = Vec::with_capacity(bound);
        nodes.extend(WideBvh::collapse(&self.tlas).nodes);
        nodes.resize(self.tlas_slots(), DeviceWideNode::default());
        let mut roots = vec![];
        let mut tri_base = 0i32;
        // The BLASes are collapsed in parallel, a batch of about COLLAPSE_BATCH triangles at a
        // time, and appended in order (in parallel too): only one batch's nodes wait beside the
        // array, so the collapse touches little fresh memory beyond the array itself (a 64
        // M-triangle scene of 3,125 meshes: 5.6 s one BLAS after another).
        const COLLAPSE_BATCH: usize = 1 << 20;
        let mut rest = &self.blases[..];
        while !rest.is_empty() {
            let mut take = 0;
            let mut triangles = 0;
            while take < rest.len() && (take == 0 || triangles < COLLAPSE_BATCH) {
                triangles += rest[take].len();
                take += 1;
            }
            let (batch, after) = rest.split_at(take);
            rest = after;
            let collapsed: Vec<WideBvh> = batch
                .par_iter()
                .map(|b| WideBvh::collapse_merging(&b.bvh, self.merge))
                .collect();
            for (b, wide) in batch.iter().zip(collapsed) {
                let base = nodes.len() as i32;
                roots.push(base as u32);
                nodes.par_extend(wide_rebased(wide.nodes, base, tri_base));
                tri_base += b.len() as i32;
            }
        }
        nodes.shrink_to_fit();
        (nodes, roots)
    }

    /// `blas`'s binary nodes in BLAS `b`'s place in [`TwoLevel::device_nodes`] (from its
    /// root `root`, its triangles from `firsts[b]`): a refit of BLAS `b` that kept its
    /// topology, to be written over the device's nodes in place.
    pub fn device_blas(&self, b: usize, blas: &Blas, root: u32) -> Vec<DeviceBvhNode> {
        rebased(&blas.bvh.nodes, root as i32, self.firsts[b]).collect()
    }

    /// The 4-wide tree of BLAS `b` as [`TwoLevel::device_wide_nodes`] collapses it, before
    /// it is rebased (to be refitted in place after a deformation: [`WideBvh::refit`]).
    pub fn wide_blas(&self, b: usize) -> WideBvh {
        WideBvh::collapse_merging(&self.blases[b].bvh, self.merge)
    }

    /// `wide`, BLAS `b`'s 4-wide tree, rebased as [`TwoLevel::device_wide_nodes`] places it
    /// from `root` on.
    pub fn device_wide_blas(&self, b: usize, wide: &WideBvh, root: u32) -> Vec<DeviceWideNode> {
        wide_rebased(wide.nodes.clone(), root as i32, self.firsts[b] as i32).collect()
    }
}

/// A BLAS's binary nodes with their children moved `base` nodes on and their leaves'
/// triangles `tri_base` on (the device's node array holds the TLAS and every BLAS, its
/// triangle array every mesh's).
fn rebased(
    nodes: &[DeviceBvhNode],
    base: i32,
    tri_base: u32,
) -> impl Iterator<Item = DeviceBvhNode> + '_ {
    nodes.iter().map(move |&n| {
        let mut n = n;
        for (lo, hi) in [
            (&mut n.left_min, n.left_max),
            (&mut n.right_min, n.right_max),
        ] {
            let r = lo[3].to_bits() as i32;
            let r = if r >= 0 {
                r + base
            } else if hi[3].to_bits() > 0 {
                !((!r) + tri_base as i32)
            } else {
                r
            };
            lo[3] = f32::from_bits(r as u32);
        }
        n
    })
}

/// [`rebased`] for a BLAS's 4-wide nodes.
fn wide_rebased(
    nodes: Vec<DeviceWideNode>,
    base: i32,
    tri_base: i32,
) -> impl ParallelIterator<Item = DeviceWideNode> {
    nodes.into_par_iter().map(move |mut n| {
        for i in 0..super::WIDTH {
            if n.count[i] > 0 {
                n.child[i] = !((!n.child[i]) + tri_base);
            } else if n.child[i] > 0 {
                n.child[i] += base;
            }
        }
        n
    })
}
