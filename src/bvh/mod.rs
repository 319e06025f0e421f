//! The bounding volume hierarchy: built on the host (binned SAH, rayon), flattened into one
//! array of [`DeviceBvhNode`]s with children referenced by index, and traversed on the host by the
//! same rules the kernels use (the reference the device is tested against).

mod blas;
mod build;
mod instances;
mod quick;
mod refit;
mod sah_split;
mod traverse;
mod two_level_device;
mod wide;

pub use blas::{Blas, IndexedMesh};
pub use build::{build, build_boxes, build_indexed};
pub use instances::{Instance, InstanceHit, PIECE_TRIANGLE, SMALL_MESH, TwoLevel, closed_cube};
pub use quick::{build_quick, build_quick_ordered, quick_blas, quick_blas_shared};
pub use refit::{REFIT_MAX_GROWTH, Update};
pub use sah_split::MAX_DEPTH;
pub use traverse::{Hit, Ray, STACK_SIZE, intersect_triangle};
pub use wide::{CollapseCost, MERGE_MIN_TRIANGLES, MERGED_LEAF, WIDE_STACK_SIZE, WIDTH, WideBvh};

use crate::cl::types::DeviceBvhNode;
use glam::Vec3;

/// Axis-aligned box in f32.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (grows from anything).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The union of two boxes.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Grows the box to hold a point.
    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Surface area (0 for an empty box).
    pub fn area(self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// Whether `p` lies inside (inclusive).
    pub fn contains(self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// A flattened BVH over a triangle list.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// Nodes; node 0 is the root. See [`DeviceBvhNode`] for the child encoding.
    pub nodes: Vec<DeviceBvhNode>,
    /// Original triangle index of each triangle in BVH order.
    pub tri_indices: Vec<u32>,
    /// The SAH cost of the tree (traversal cost 1, intersection cost 1 per triangle).
    pub sah_cost: f32,
    /// The SAH cost right after the last full build (refits compare against it).
    pub built_sah_cost: f32,
    /// The depth of the deepest leaf (root = 0).
    pub depth: u32,
}

/// A child reference decoded from a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Child {
    /// An interior node.
    Node(u32),
    /// A leaf: triangles `first..first + count` in BVH order.
    Leaf {
        /// First triangle.
        first: u32,
        /// Count.
        count: u32,
    },
}

impl Bvh {
    /// The most triangles in one leaf (0 for an empty tree).
    pub fn largest_leaf(&self) -> u32 {
        self.nodes
            .iter()
            .flat_map(|n| [n.left_max[3], n.right_max[3]])
            .map(f32::to_bits)
            .max()
            .unwrap_or(0)
    }

    /// The box and reference of the left (0) or right (1) child of `node`.
    pub fn child(&self, node: u32, side: usize) -> (Aabb, Child) {
        let n = &self.nodes[node as usize];
        let (lo, hi) = if side == 0 {
            (n.left_min, n.left_max)
        } else {
            (n.right_min, n.right_max)
        };
        let index = lo[3].to_bits() as i32;
        let child = if index >= 0 {
            Child::Node(index as u32)
        } else {
            Child::Leaf {
                first: !index as u32,
                count: hi[3].to_bits(),
            }
        };
        (
            Aabb {
                min: Vec3::new(lo[0], lo[1], lo[2]),
                max: Vec3::new(hi[0], hi[1], hi[2]),
            },
            child,
        )
    }
}
