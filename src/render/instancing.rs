//! Which acceleration structure a scene goes to the device in: one flat BVH over every
//! world-space triangle, or two levels (a BLAS per distinct mesh, shared by the nodes that
//! place it, and a TLAS over the instances; see `bvh::instances`).
//!
//! The flat BVH's triangles and shading data are in world space, one copy per placed triangle;
//! two levels keep each distinct mesh's BVH, triangles and shading data once, in object space,
//! and shading carries a hit to world space through its instance's transform, so moving an
//! object is a TLAS rebuild and a few transforms written in place
//! (`Renderer::move_instances`).
//!
//! The automatic choice (`--bvh auto`) takes two levels only for scenes of at least 4 M
//! triangles over all instances that instancing shrinks eightfold (and for any scene of
//! [`HUGE_SCENE`] triangles), on every device, as measured on each. On a GPU (H200) the 1 M
//! rooms of `bench generate` run at 0.82 of the flat BVH's speed on two levels
//! (2026-11-30). On a CPU the flat BVH is walked by the megakernel's vector
//! lanes, which two levels do not have: the same rooms render 1.5–1.7 times as fast flat, for
//! 0.5–0.6 s more building on 2 cores and 100 MB of device memory against 2.5–15
//! (AMD Zen 3, 2026-12-04; until then CPUs took two levels from 1 M
//! triangles shrunk fourfold, when the kernels walked one ray at a time and two levels ran
//! frames 1.2–1.4 times as fast). A flat scene reloads where two levels would move, hide or
//! show an object in place. A small scene is flattened: its flat BVH is built in well under a
//! second and tests no transforms.

use crate::bvh::{Blas, TwoLevel, quick_blas_shared};
use crate::scene::{Mesh, Object, RenderFrame, Scene, distinct_meshes};
use glam::DMat4;
use rayon::prelude::*;
use std::str::FromStr;
use std::sync::Arc;

/// `--bvh auto`'s thresholds for one kind of device: the triangles over all instances from which
/// it considers two levels, and how many times the distinct meshes' triangles the instances
/// must hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AutoRule {
    /// Triangles over all instances from which two levels are considered.
    pub min_triangles: usize,
    /// How many times the distinct meshes' triangles the instances must hold.
    pub min_saving: usize,
    /// Meshes of at most this many triangles become triangle pieces of the top level
    /// ([`TwoLevel::small_mesh`]) in any two-level scene.
    pub small_mesh: usize,
}

/// CPU devices, where the flat BVH is walked in vector lanes and two levels one ray at a time.
pub const AUTO_CPU: AutoRule = AutoRule {
    min_triangles: 4_000_000,
    min_saving: 8,
    small_mesh: crate::bvh::SMALL_MESH,
};

/// GPUs, where two levels trace about a fifth slower than flat.
pub const AUTO_GPU: AutoRule = AutoRule {
    min_triangles: 4_000_000,
    min_saving: 8,
    // On an H200 triangle pieces made two levels slower (bunny room frames 0.81 -> 0.75 of
    // flat, spheres 0.82 -> 0.70; 2026-11-30), while on PoCL they made
    // shadow rays as fast as flat: GPUs keep each small instance whole.
    small_mesh: 0,
};

/// `--bvh`: which acceleration structure the device traverses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum BvhChoice {
    /// Two levels for large, heavily instanced scenes (see the module's rule), else flat.
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

/// A scene's instances: each object with triangles (hidden ones left out of the TLAS), the
/// distinct meshes they use.
pub struct Instancing {
    /// The two levels (render space).
    pub two: TwoLevel,
    /// The object each instance places (index in `Scene::objects`).
    pub objects: Vec<u32>,
    /// An object placing each BLAS's mesh (index in `Scene::objects`).
    pub mesh_objects: Vec<u32>,
    /// Whether the BLASes are quick trees ([`Blases::Quick`] with enough distinct triangles).
    pub quick: bool,
}

/// Distinct triangles from which the viewer opens a two-level scene with quick BLASes
/// ([`crate::render::Renderer::set_quick_first`]): below, the SAH BLASes build in well under a
/// second on 2 cores (1 M triangles: 0.25 s).
pub const QUICK_FIRST_TRIANGLES: usize = 2_000_000;

/// How the BLASes of a two-level plan are made.
pub enum Blases {
    /// Binned SAH trees ([`Blas::of_mesh`]).
    Sah,
    /// Quick trees ([`crate::bvh::quick_blas`]) for a scene of at least `from` distinct
    /// triangles (else SAH trees), traced at once while its SAH trees build behind it.
    Quick {
        /// Distinct triangles from which the trees are quick.
        from: usize,
        /// Quick trees built already (by the first-view probe, [`Scene::take_quick_blases`])
        /// with the meshes they were built from: taken for those meshes, the others built.
        ready: Vec<(Arc<Mesh>, Blas)>,
    },
    /// Trees built already, one per distinct mesh in the plan's order, for the meshes they
    /// were built from (checked: any other mesh gets a SAH tree).
    Built(Vec<(Arc<Mesh>, Blas)>),
}

/// The two levels of `scene` in render space `space`, or `None` when the flat BVH is chosen
/// (or must be: flattening drops triangles with absurd world vertices, which the instances
/// would keep).
pub fn plan(
    scene: &Scene,
    space: &RenderFrame,
    choice: BvhChoice,
    rule: AutoRule,
    how: Blases,
) -> Option<Instancing> {
    if choice == BvhChoice::Flat {
        return None;
    }
    let objects = instanced_objects(scene);
    let placed: Vec<&Object> = objects
        .iter()
        .map(|&i| &scene.objects[i as usize])
        .collect();
    let (meshes, mesh_of) = distinct_meshes(&placed);
    let unique: usize = meshes.iter().map(|&o| placed[o].mesh.indices.len()).sum();
    let total: usize = placed
        .iter()
        .filter(|o| o.visible)
        .map(|o| o.mesh.indices.len())
        .sum();
    let auto_flat = !auto_takes_two_levels(total, unique, rule);
    if total == 0 || (choice == BvhChoice::Auto && auto_flat) || scene.absurd_triangles() > 0 {
        return None;
    }
    let quick = matches!(how, Blases::Quick { from, .. } if unique >= from);
    let sah = |o: usize| Blas::of_shared_mesh(&placed[o].mesh);
    let blases: Vec<Blas> = match how {
        Blases::Quick { ready, .. } if quick => {
            let mut ready: std::collections::HashMap<*const Mesh, Blas> = ready
                .into_iter()
                .map(|(m, b)| (Arc::as_ptr(&m), b))
                .collect();
            let mut taken: Vec<Option<Blas>> = meshes
                .iter()
                .map(|&o| ready.remove(&Arc::as_ptr(&placed[o].mesh)))
                .collect();
            drop(ready);
            taken
                .par_iter_mut()
                .zip(&meshes)
                .map(|(b, &o)| {
                    b.take()
                        .unwrap_or_else(|| quick_blas_shared(&placed[o].mesh))
                })
                .collect()
        }
        Blases::Sah | Blases::Quick { .. } => meshes.par_iter().map(|&o| sah(o)).collect(),
        Blases::Built(built) => {
            let mut built = built.into_iter();
            meshes
                .iter()
                .map(|&o| match built.next() {
                    Some((mesh, blas)) if Arc::ptr_eq(&mesh, &placed[o].mesh) => blas,
                    _ => sah(o),
                })
                .collect()
        }
    };
    let frame = render_from_world(space);
    let instances: Vec<(u32, DMat4)> = placed
        .iter()
        .zip(&mesh_of)
        .map(|(o, &m)| (m, frame * o.world_from_object))
        .collect();
    let hidden = placed.iter().map(|o| !o.visible).collect();
    Some(Instancing {
        two: TwoLevel::with_hidden(blases, &instances, hidden, rule.small_mesh),
        mesh_objects: meshes.iter().map(|&o| objects[o]).collect(),
        objects,
        quick,
    })
}

/// Whether `--bvh auto` takes two levels for `total` triangles over all instances of meshes of
/// `unique` triangles under `rule` (see the module's rules).
pub fn auto_takes_two_levels(total: usize, unique: usize, rule: AutoRule) -> bool {
    total >= rule.min_triangles && (total >= rule.min_saving * unique || total >= HUGE_SCENE)
}

/// Triangles over all instances from which `--bvh auto` takes two levels on any device, however
/// little instancing saves: the flat form's host build needs about 280 bytes a triangle
/// (64 M triangles: 18 GB, against the 150 a distinct triangle that issue 14 allows) and
/// 34 s for 16 M distinct triangles on the 2-core machine, against 108 bytes and a few
/// seconds for two levels (2026-12-01).
pub const HUGE_SCENE: usize = 16_000_000;

/// The render frame's map, (p - origin) * scale, as a matrix: render from object is this times
/// the node's world from object.
pub fn render_from_world(space: &RenderFrame) -> DMat4 {
    DMat4::from_scale(glam::DVec3::splat(space.scale)) * DMat4::from_translation(-space.origin)
}

/// The indices of the objects that have triangles, visible or hidden: the instances, in object
/// order (hidden ones are left out of the TLAS, so that hiding or showing one is an update).
pub fn instanced_objects(scene: &Scene) -> Vec<u32> {
    (0..scene.objects.len() as u32)
        .filter(|&i| !scene.objects[i as usize].mesh.indices.is_empty())
        .collect()
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

    #[test]
    fn auto_takes_two_levels_for_large_heavily_instanced_scenes() {
        for rule in [AUTO_CPU, AUTO_GPU] {
            // The rooms of `bench generate`: 7 bunnies and 49 icospheres, 1 M triangles each:
            // flat (on a CPU its lanes walk them 1.5-1.7 times as fast as two levels).
            for (total, unique) in [(1_008_336, 144_060), (1_003_534, 20_494)] {
                assert!(!auto_takes_two_levels(total, unique, rule));
            }
            // 4 M triangles of one 144 k mesh, and 16 M: two levels.
            assert!(auto_takes_two_levels(4_000_000, 144_000, rule));
            assert!(auto_takes_two_levels(16_000_000, 144_000, rule));
            // Small, or hardly instanced: flat.
            assert!(!auto_takes_two_levels(4_000_000, 600_000, rule));
            assert!(!auto_takes_two_levels(500_000, 10_000, rule));
            assert!(!auto_takes_two_levels(4_000_000, 2_000_000, rule));
            assert!(!auto_takes_two_levels(0, 0, rule));
            // Huge, even with no instancing at all: two levels (the flat build's memory).
            assert!(auto_takes_two_levels(64_000_014, 64_000_014, rule));
            assert!(auto_takes_two_levels(HUGE_SCENE, HUGE_SCENE, rule));
            assert!(!auto_takes_two_levels(HUGE_SCENE - 1, HUGE_SCENE - 1, rule));
        }
    }
}
