//! Which acceleration structure a scene goes to the device in: one flat BVH over every
//! world-space triangle, or two levels (a BLAS per distinct mesh, shared by the nodes that
//! place it, and a TLAS over the instances; see `bvh::instances`).
//!
//! Shading reads the triangles in world space either way (one copy per instance, in the order
//! the traversal reports them), so images agree; two levels store each distinct mesh's BVH and
//! object-space triangles once and make moving an object a TLAS rebuild. The automatic choice
//! (`--bvh auto`) takes two levels when instancing at least halves the triangles the BVH holds
//! (`triangles >= 2 x unique_triangles`), else the flat BVH, which traverses a little faster on
//! a static scene (docs/benchmarks.md has the figures).

use crate::bvh::{Blas, TwoLevel};
use crate::scene::{Object, RenderFrame, Scene};
use glam::{DMat4, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::str::FromStr;

/// `--bvh`: which acceleration structure the device traverses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum BvhChoice {
    /// Two levels when instancing at least halves the triangles, else flat.
    #[default]
    Auto,
    /// One BVH over every world-space triangle.
    Flat,
    /// A BLAS per distinct mesh and a TLAS over the instances.
    TwoLevel,
}

impl FromStr for BvhChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "" | "auto" => Ok(Self::Auto),
            "flat" => Ok(Self::Flat),
            "two-level" | "two_level" => Ok(Self::TwoLevel),
            _ => Err(format!("bvh '{s}' is not 'flat', 'two-level' or 'auto'")),
        }
    }
}

/// A scene's instances: each visible object with triangles, the distinct meshes they use.
pub struct Instancing {
    /// The two levels (render space).
    pub two: TwoLevel,
    /// Index in the flattened triangle list of each triangle in shading order.
    pub order: Vec<u32>,
    /// Material of each object-space triangle, mesh after mesh, in BLAS order.
    pub object_materials: Vec<u32>,
}

/// Counts of a scene's instancing: (triangles over all instances, triangles of the distinct
/// meshes).
pub fn counts(scene: &Scene) -> (usize, usize) {
    let placed = placed(scene);
    let (_, mesh_of) = distinct(&placed);
    let mut seen = vec![false; placed.len()];
    let mut unique = 0;
    for (o, &m) in placed.iter().zip(&mesh_of) {
        if !seen[m as usize] {
            seen[m as usize] = true;
            unique += o.mesh.indices.len();
        }
    }
    (placed.iter().map(|o| o.mesh.indices.len()).sum(), unique)
}

/// The two levels of `scene` in render space `space`, or `None` when the flat BVH is chosen
/// (or must be: flattening `dropped` triangles with absurd vertices, which the instances would
/// keep).
pub fn plan(
    scene: &Scene,
    space: &RenderFrame,
    dropped: usize,
    choice: BvhChoice,
) -> Option<Instancing> {
    if choice == BvhChoice::Flat || dropped > 0 {
        return None;
    }
    let placed = placed(scene);
    let (meshes, mesh_of) = distinct(&placed);
    let unique: usize = meshes.iter().map(|&o| placed[o].mesh.indices.len()).sum();
    let total: usize = placed.iter().map(|o| o.mesh.indices.len()).sum();
    if total == 0 || (choice == BvhChoice::Auto && total < 2 * unique) {
        return None;
    }
    let blases: Vec<Blas> = meshes
        .par_iter()
        .map(|&o| {
            let m = &placed[o].mesh;
            let tris: Vec<[Vec3; 3]> = m
                .indices
                .iter()
                .map(|t| t.map(|i| m.positions[i as usize]))
                .collect();
            Blas::new(&tris)
        })
        .collect();
    let object_materials = meshes
        .iter()
        .zip(&blases)
        .flat_map(|(&o, b)| {
            let m = &placed[o].mesh;
            b.bvh.tri_indices.iter().map(|&k| m.materials[k as usize])
        })
        .collect();
    // Render from object: the render frame's (p - origin) * scale after the node's transform.
    let frame =
        DMat4::from_scale(glam::DVec3::splat(space.scale)) * DMat4::from_translation(-space.origin);
    let instances: Vec<(u32, DMat4)> = placed
        .iter()
        .zip(&mesh_of)
        .map(|(o, &m)| (m, frame * o.world_from_object))
        .collect();
    let two = TwoLevel::from_blases(blases, &instances);
    // Shading order: instance after instance, each in its BLAS's order, as indices into the
    // flattened list (which holds the visible objects' triangles in object order).
    let mut order = Vec::with_capacity(total);
    let mut base = 0u32;
    for (o, inst) in placed.iter().zip(&two.instances) {
        let blas = &two.blases[inst.blas as usize];
        order.extend(blas.bvh.tri_indices.iter().map(|&k| base + k));
        base += o.mesh.indices.len() as u32;
    }
    Some(Instancing {
        two,
        order,
        object_materials,
    })
}

/// The visible objects that have triangles, in object order.
fn placed(scene: &Scene) -> Vec<&Object> {
    scene
        .objects
        .iter()
        .filter(|o| o.visible && !o.mesh.indices.is_empty())
        .collect()
}

/// The distinct meshes among `objects` (the index of the first object using each) and each
/// object's mesh. The importer gives every node its own copy of its mesh, so meshes are told
/// apart by content: triangles, positions and materials.
pub fn distinct(objects: &[&Object]) -> (Vec<usize>, Vec<u32>) {
    let mut index: HashMap<u64, u32> = HashMap::new();
    let mut first = vec![];
    let mesh_of = objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let mut h = std::collections::hash_map::DefaultHasher::new();
            let m = &o.mesh;
            m.indices.hash(&mut h);
            m.materials.hash(&mut h);
            for p in &m.positions {
                p.to_array().map(f32::to_bits).hash(&mut h);
            }
            *index.entry(h.finish()).or_insert_with(|| {
                first.push(i);
                first.len() as u32 - 1
            })
        })
        .collect();
    (first, mesh_of)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choices_parse() {
        assert_eq!("auto".parse(), Ok(BvhChoice::Auto));
        assert_eq!("Two-Level".parse(), Ok(BvhChoice::TwoLevel));
        assert_eq!("flat".parse(), Ok(BvhChoice::Flat));
        assert!("deep".parse::<BvhChoice>().is_err());
    }
}
