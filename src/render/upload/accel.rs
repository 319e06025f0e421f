//! The acceleration structure of the scene on the device ([`Accel`]) and, with two levels,
//! where the instances' parts sit there ([`InstanceLayout`]): the device instances in TLAS
//! order and the world-space copies of small instances' triangles.

use crate::bvh::{Bvh, PIECE_TRIANGLE, TwoLevel, WideBvh};
use crate::cl::types::*;
use glam::Vec3;

/// The acceleration structure of the scene on the device, with its host reference.
#[derive(Clone, Debug)]
pub enum Accel {
    /// One BVH over the world-space triangles.
    Flat(Bvh),
    /// A BLAS per distinct mesh and a TLAS over the instances (render space).
    TwoLevel(TwoLevel),
}

impl Accel {
    /// "flat" or "two-level".
    pub fn name(&self) -> &'static str {
        match self {
            Accel::Flat(_) => "flat",
            Accel::TwoLevel(_) => "two-level",
        }
    }

    /// Nodes over both levels.
    pub fn node_count(&self) -> usize {
        match self {
            Accel::Flat(b) => b.nodes.len(),
            Accel::TwoLevel(t) => {
                t.tlas.nodes.len() + t.blases.iter().map(|b| b.bvh.nodes.len()).sum::<usize>()
            }
        }
    }

    /// The SAH cost of the flat BVH, or of the TLAS.
    pub fn sah_cost(&self) -> f32 {
        match self {
            Accel::Flat(b) => b.sah_cost,
            Accel::TwoLevel(t) => t.tlas.sah_cost,
        }
    }

    /// The deepest leaf: of the flat BVH, or the TLAS's depth plus the deepest BLAS's.
    pub fn depth(&self) -> u32 {
        match self {
            Accel::Flat(b) => b.depth,
            Accel::TwoLevel(t) => {
                t.tlas.depth + 1 + t.blases.iter().map(|b| b.bvh.depth).max().unwrap_or(0)
            }
        }
    }

    /// Distinct meshes and instances (1 and 0 for the flat BVH).
    pub fn instancing(&self) -> (usize, usize) {
        match self {
            Accel::Flat(_) => (1, 0),
            Accel::TwoLevel(t) => (t.blases.len(), t.instances.len()),
        }
    }
}

/// Where a two-level scene's parts sit on the device, to update instances in place.
#[derive(Clone, Debug, Default)]
pub struct InstanceLayout {
    /// The object each instance places (index in `Scene::objects`).
    pub objects: Vec<u32>,
    /// Each BLAS's root in the binary node array.
    pub roots: Vec<u32>,
    /// Each BLAS's root in the wide node array (empty while the device has no wide nodes).
    pub wide_roots: Vec<u32>,
    /// Each instance's first light (the light index of its first emissive triangle).
    pub light_bases: Vec<i32>,
    /// Each small instance's first world-space triangle copy in the device triangles (see
    /// [`piece_copies`]; `u32::MAX` for an instance that is not small).
    pub copy_bases: Vec<u32>,
    /// Whether the device's tangents hold the meshes' (some mesh has tangents), to be
    /// written again with a deformed mesh's triangles.
    pub mesh_tangents: bool,
    /// Per BLAS, the 4-wide tree on the device (before rebasing) of a mesh deformed in place,
    /// refitted at each pose (the same nodes, so it stays in its range; collapsing the
    /// refitted binary tree again may take more); `None` until its first deformation.
    pub wide_blases: Vec<Option<WideBvh>>,
    /// Per BLAS, a small mesh's object-space device triangles (empty for the others): what a
    /// moved small instance's copies are made from once the triangles live on the device only.
    pub small_meshes: Vec<Vec<DeviceTriangle>>,
}

impl InstanceLayout {
    /// The world-space copies of every small instance's triangles (hidden ones too, so that
    /// showing one writes in place), to follow the meshes' `first` object-space triangles in
    /// the device triangles; keeps where each instance's copies start.
    pub fn piece_copies(&mut self, two: &TwoLevel, first: usize) -> Vec<DeviceTriangle> {
        let mut copies = vec![];
        self.copy_bases = (0..two.instances.len())
            .map(|i| {
                let mesh = &self.small_meshes[two.instances[i].blas as usize];
                if mesh.is_empty() {
                    return u32::MAX;
                }
                let base = (first + copies.len()) as u32;
                copies.extend(piece_copies(two, mesh, i));
                base
            })
            .collect();
        copies
    }

    /// The device instances of `two` in TLAS order, one per TLAS slot (a piece of an
    /// instance: the instance's transforms and its BLAS's roots, or one triangle of a small
    /// mesh), padded to [`TwoLevel::max_pieces`] so that the buffer holds any later TLAS's.
    pub fn gpu_instances(&self, two: &TwoLevel) -> Vec<DeviceInstance> {
        let mut out: Vec<DeviceInstance> = two
            .tlas
            .tri_indices
            .iter()
            .zip(&two.pieces)
            .map(|(&i, &piece)| {
                let inst = &two.instances[i as usize];
                let b = inst.blas as usize;
                // A piece of one triangle names it (among the meshes' triangles) in both.
                let triangle = piece & PIECE_TRIANGLE != 0;
                let (root, wide_root) = if triangle {
                    let k = piece & !PIECE_TRIANGLE;
                    (self.copy_bases[i as usize] + k, two.firsts[b] + k)
                } else {
                    // Any other piece is the whole BLAS. Without the wide nodes on the device
                    // (`NodeForms`), no wide root.
                    (self.roots[b], self.wide_roots.get(b).copied().unwrap_or(0))
                };
                let mut world = inst.world_rows();
                world[0][3] = f32::from_bits(self.light_bases[i as usize] as u32);
                DeviceInstance {
                    row0: inst.rows[0],
                    row1: inst.rows[1],
                    row2: inst.rows[2],
                    world0: world[0],
                    world1: world[1],
                    world2: world[2],
                    root,
                    wide_root,
                    id: i,
                    flags: if inst.mirrored { INSTANCE_MIRRORED } else { 0 }
                        | if triangle { INSTANCE_PIECE_TRIANGLE } else { 0 },
                }
            })
            .collect();
        out.resize(two.max_pieces.max(1), DeviceInstance::default());
        out
    }
}

/// A small instance's triangles in world space, where the two-level traversal tests them as
/// pieces of the TLAS without entering the instance (`TwoLevel::braid`): the vertices as
/// [`crate::bvh::Instance::device_triangle`] carries them (the host reference tests the same
/// values), the payloads of `mesh`, the instance's mesh's object-space device triangles.
pub fn piece_copies(two: &TwoLevel, mesh: &[DeviceTriangle], i: usize) -> Vec<DeviceTriangle> {
    let inst = &two.instances[i];
    let v = |p: Vec3, payload: f32| [p.x, p.y, p.z, payload];
    two.blases[inst.blas as usize]
        .triangles()
        .zip(mesh)
        .map(|(t, o)| {
            let w = inst.device_triangle(&t);
            DeviceTriangle {
                v0: v(w[0], o.v0[3]),
                v1: v(w[1], o.v1[3]),
                v2: v(w[2], o.v2[3]),
            }
        })
        .collect()
}
