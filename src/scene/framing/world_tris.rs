//! The visible objects' world triangles in scene order, read from each object's vertices
//! instead of a copy of every triangle: what the probe, the robust bounds and the light test
//! read.

use super::super::{Mesh, WorldObject};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;

/// The visible objects' world triangles in scene order (as [`Scene::flatten`](crate::scene::Scene::flatten) keeps them),
/// read from each object's vertices ([`Scene::world_objects`](crate::scene::Scene::world_objects)) instead of a copy of every
/// triangle: a 64 M-triangle scene's copy was 2.3 GB and seconds to write.
#[derive(Clone, Debug)]
pub struct WorldTris {
    pub(super) objects: Vec<WorldObject>,
    /// Each object's first triangle, and the count after the last.
    pub(super) starts: Vec<usize>,
}

impl WorldTris {
    pub(super) fn new(objects: Vec<WorldObject>) -> Self {
        let mut starts = Vec::with_capacity(objects.len() + 1);
        starts.push(0);
        for o in &objects {
            starts.push(starts.last().copied().unwrap_or(0) + o.len());
        }
        Self { objects, starts }
    }

    /// Triangles in all.
    pub(super) fn len(&self) -> usize {
        self.starts.last().copied().unwrap_or(0)
    }

    /// (object, kept triangle in it) of triangle `i`.
    fn locate(&self, i: usize) -> (usize, usize) {
        let o = self.starts.partition_point(|&s| s <= i) - 1;
        (o, i - self.starts[o])
    }

    /// Triangle `i`'s vertices.
    pub(super) fn get(&self, i: usize) -> [Vec3; 3] {
        let (o, k) = self.locate(i);
        let o = &self.objects[o];
        o.vertices(o.triangle(k))
    }

    /// Triangle `i`'s material.
    pub(super) fn material(&self, i: usize) -> u32 {
        let (o, k) = self.locate(i);
        let o = &self.objects[o];
        o.mesh.materials[o.triangle(k)]
    }

    /// Calls `f(i, vertices, material)` for the triangles `range`, in order.
    pub(super) fn visit(
        &self,
        range: std::ops::Range<usize>,
        mut f: impl FnMut(usize, [Vec3; 3], u32),
    ) {
        if range.is_empty() {
            return;
        }
        let (mut o, mut k) = self.locate(range.start);
        let mut i = range.start;
        while i < range.end {
            let object = &self.objects[o];
            let end = object.len().min(k + range.end - i);
            for k in k..end {
                let ti = object.triangle(k);
                f(i, object.vertices(ti), object.mesh.materials[ti]);
                i += 1;
            }
            o += 1;
            k = 0;
        }
    }

    /// The triangles `0..len` in chunks of `chunk` (the last shorter), in parallel.
    pub(super) fn chunks(
        &self,
        chunk: usize,
    ) -> impl IndexedParallelIterator<Item = std::ops::Range<usize>> {
        let n = self.len();
        (0..n.div_ceil(chunk))
            .into_par_iter()
            .map(move |c| c * chunk..((c + 1) * chunk).min(n))
    }

    /// Every triangle's vertices and material, in order.
    pub(super) fn to_vecs(&self) -> (Vec<[Vec3; 3]>, Vec<u32>) {
        let parts: Vec<(Vec<[Vec3; 3]>, Vec<u32>)> = self
            .chunks(1 << 16)
            .map(|r| {
                let mut out = (Vec::with_capacity(r.len()), Vec::with_capacity(r.len()));
                self.visit(r, |_, t, m| {
                    out.0.push(t);
                    out.1.push(m);
                });
                out
            })
            .collect();
        let (mut tris, mut materials) = (Vec::with_capacity(self.len()), vec![]);
        materials.reserve(self.len());
        for (t, m) in parts {
            tris.extend(t);
            materials.extend(m);
        }
        (tris, materials)
    }

    /// A soup of triangles as one object of material 0.
    pub(super) fn soup(tris: &[[Vec3; 3]]) -> Self {
        let mesh = Mesh::soup(tris);
        Self::new(vec![WorldObject {
            world: mesh.positions.clone(),
            mesh: Arc::new(mesh),
            kept: None,
            flip: false,
        }])
    }
}
