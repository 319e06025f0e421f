//! A bottom-level BVH (BLAS): one mesh's tree in object space and its triangles in tree order,
//! copied or read from the mesh through [`IndexedMesh`], the view of a mesh this module needs
//! (the scene's meshes provide it; `bvh` knows nothing of scenes).

use super::{Aabb, Bvh, Hit, Ray, Update, build, build_indexed};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;

/// An indexed triangle mesh in object space that a [`Blas`] can keep and read its triangles
/// from instead of a copy of them.
pub trait IndexedMesh: std::fmt::Debug + Send + Sync {
    /// Vertex positions.
    fn positions(&self) -> &[Vec3];
    /// Triangles as indices into [`IndexedMesh::positions`].
    fn indices(&self) -> &[[u32; 3]];
}

/// A mesh's BVH and its object-space triangles in BVH order.
#[derive(Clone, Debug)]
pub struct Blas {
    /// The tree.
    pub bvh: Bvh,
    /// Triangles in BVH order (object space); read them with [`Blas::triangle`].
    triangles: BlasTriangles,
}

/// Where a [`Blas`] finds its triangles.
#[derive(Clone, Debug)]
enum BlasTriangles {
    /// Copies in BVH order.
    Copied(Vec<[Vec3; 3]>),
    /// The mesh the tree was built over, read through the tree's `tri_indices`: no copy
    /// (36 B a triangle, 2.3 GB of a 64 M-triangle scene, which only host traversal reads).
    Mesh(Arc<dyn IndexedMesh>),
}

impl Blas {
    /// Builds the BLAS of `triangles` (object space, any order).
    pub fn new(triangles: &[[Vec3; 3]]) -> Self {
        let bvh = build(triangles);
        let triangles = bvh
            .tri_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        Self::copied(bvh, triangles)
    }

    /// A BLAS of `bvh` over its triangles in BVH order.
    pub fn copied(bvh: Bvh, triangles: Vec<[Vec3; 3]>) -> Self {
        debug_assert_eq!(bvh.tri_indices.len(), triangles.len());
        Self {
            bvh,
            triangles: BlasTriangles::Copied(triangles),
        }
    }

    /// A BLAS of `bvh`, built over `mesh`, that reads the mesh's triangles where it needs them.
    pub fn over_mesh<M: IndexedMesh + 'static>(bvh: Bvh, mesh: &Arc<M>) -> Self {
        debug_assert_eq!(bvh.tri_indices.len(), mesh.indices().len());
        Self {
            bvh,
            triangles: BlasTriangles::Mesh(mesh.clone()),
        }
    }

    /// Builds the BLAS of an indexed mesh (object space): the same as [`Blas::new`] over its
    /// triangles, without a copy of them in mesh order.
    pub fn of_mesh(positions: &[Vec3], indices: &[[u32; 3]]) -> Self {
        let bvh = build_indexed(positions, indices);
        let triangles = bvh
            .tri_indices
            .par_iter()
            .map(|&i| indices[i as usize].map(|v| positions[v as usize]))
            .collect();
        Self::copied(bvh, triangles)
    }

    /// [`Blas::of_mesh`] of a shared mesh, which the BLAS keeps and reads its triangles from
    /// (no copy of them in BVH order either): the same tree.
    pub fn of_shared_mesh<M: IndexedMesh + 'static>(mesh: &Arc<M>) -> Self {
        Self::over_mesh(build_indexed(mesh.positions(), mesh.indices()), mesh)
    }

    /// This BLAS's tree refitted over `mesh`, a deformed copy of the mesh the BLAS reads (the
    /// same index list, its vertices moved), in `mesh`'s own space, reading `mesh` from then on;
    /// built anew over it when the refit took the tree's SAH cost to
    /// [`super::REFIT_MAX_GROWTH`] times its last build's or more. `None` when the BLAS does
    /// not read a mesh with `mesh`'s index list (a copied or other mesh).
    pub fn refit_over<M: IndexedMesh + 'static>(&self, mesh: &Arc<M>) -> Option<(Self, Update)> {
        let BlasTriangles::Mesh(old) = &self.triangles else {
            return None;
        };
        // A mesh the BLAS still holds cannot have been deformed in place (`Arc::make_mut`
        // copies a shared mesh).
        if self.reads(mesh) {
            return Some((self.clone(), Update::Refitted));
        }
        let indices = mesh.indices();
        if old.indices() != indices {
            return None;
        }
        let positions = mesh.positions();
        let mut bvh = self.bvh.clone();
        bvh.refit_with(|t| indices[t].map(|v| positions[v as usize]));
        if bvh.needs_rebuild() {
            return Some((Self::of_shared_mesh(mesh), Update::Rebuilt));
        }
        Some((Self::over_mesh(bvh, mesh), Update::Refitted))
    }

    /// Whether the BLAS reads its triangles from `mesh` itself (not a copy of it).
    pub fn reads<M: IndexedMesh + 'static>(&self, mesh: &Arc<M>) -> bool {
        matches!(&self.triangles, BlasTriangles::Mesh(old)
            if std::ptr::addr_eq(Arc::as_ptr(old), Arc::as_ptr(mesh)))
    }

    /// Triangles.
    pub fn len(&self) -> usize {
        self.bvh.tri_indices.len()
    }

    /// Whether the BLAS has no triangles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Triangle `k` in BVH order (object space).
    pub fn triangle(&self, k: usize) -> [Vec3; 3] {
        match &self.triangles {
            BlasTriangles::Copied(t) => t[k],
            BlasTriangles::Mesh(m) => {
                let positions = m.positions();
                m.indices()[self.bvh.tri_indices[k] as usize].map(|v| positions[v as usize])
            }
        }
    }

    /// The triangles in BVH order.
    pub fn triangles(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        (0..self.len()).map(|k| self.triangle(k))
    }

    /// [`Bvh::traverse`] of this BLAS's tree (from its root) over its triangles.
    pub fn traverse(&self, ray: &Ray, any: bool) -> Option<Hit> {
        self.bvh.traverse_by(0, ray, any, |k| self.triangle(k))
    }

    /// The object-space box of the whole mesh.
    pub fn bounds(&self) -> Aabb {
        self.bvh.child(0, 0).0.union(self.bvh.child(0, 1).0)
    }
}
