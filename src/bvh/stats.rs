//! What `penumbra bench bvh` measures: the cost of building and updating the BVH of a scene on
//! the host, without a device.

use super::{TwoLevel, build};
use crate::scene::{Object, Scene};
use glam::{DMat4, DVec3, Vec3};
use serde::Serialize;
use std::time::Instant;

/// Build and update figures of one scene (times are the minimum over the runs).
#[derive(Clone, Debug, Serialize)]
pub struct BvhReport {
    /// Triangles in the BVH (every visible instance flattened into world space).
    pub triangles: usize,
    /// Triangles of the distinct meshes the visible objects use.
    pub unique_triangles: usize,
    /// Visible mesh instances (glTF nodes with a mesh).
    pub instances: usize,
    /// Nodes of the flat BVH.
    pub nodes: usize,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// Gathering the world-space triangles of every instance.
    pub gather_ms: f64,
    /// Building the whole flat BVH (what the renderer uploads today).
    pub full_build_ms: f64,
    /// Moving one instance in the flat BVH: moving its triangles and building the whole tree
    /// again.
    pub flat_move_ms: f64,
    /// Building the host two-level form: one BLAS per distinct mesh and the TLAS.
    pub two_level_build_ms: f64,
    /// Moving one instance in the two-level form: its transform and a new TLAS (host only; the
    /// device does not traverse two levels yet, so nothing is uploaded).
    pub instance_move_ms: f64,
    /// Refitting the whole tree after one instance moved.
    pub refit_ms: f64,
    /// SAH cost of the built tree.
    pub sah_cost: f32,
    /// SAH cost after the refit.
    pub refit_sah_cost: f32,
    /// Timed runs of each measurement.
    pub runs: usize,
}

/// Builds and updates the BVH of `scene` `runs` times (at least once) and reports the fastest
/// of each. The moved instance is the largest visible one, shifted by a tenth of its size.
pub fn report(scene: &Scene, runs: usize) -> BvhReport {
    let runs = runs.max(1);
    let visible: Vec<(usize, &Object)> = scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.visible)
        .collect();
    let t = Instant::now();
    let world = scene.world_triangles();
    let mut tris: Vec<[Vec3; 3]> = world.iter().map(|t| t.v).collect();
    let objects: Vec<u32> = world.iter().map(|t| t.object).collect();
    drop(world);
    let gather_ms = ms(t);

    let mut bvh = build(&tris);
    let mut full_build_ms = f64::INFINITY;
    for _ in 0..runs {
        let t = Instant::now();
        bvh = build(&tris);
        full_build_ms = full_build_ms.min(ms(t));
    }
    let (sah_cost, depth, nodes) = (bvh.sah_cost, bvh.depth, bvh.nodes.len());

    // Move the largest instance by a tenth of its extent along x, back and forth.
    let moved = visible
        .iter()
        .max_by_key(|(_, o)| o.mesh.indices.len())
        .map(|(i, _)| *i as u32);
    let extent = moved.map_or(0.0, |m| {
        let (lo, hi) = tris
            .iter()
            .zip(&objects)
            .filter(|(_, o)| **o == m)
            .flat_map(|(t, _)| *t)
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        (hi - lo).max_element()
    });
    let shift = |tris: &mut [[Vec3; 3]], sign: f32| {
        let d = Vec3::X * extent * 0.1 * sign;
        for (t, o) in tris.iter_mut().zip(&objects) {
            if Some(*o) == moved {
                *t = t.map(|v| v + d);
            }
        }
    };
    let (mut flat_move_ms, mut refit_ms) = (f64::INFINITY, f64::INFINITY);
    let mut refit_sah_cost = sah_cost;
    for run in 0..runs {
        let sign = if run % 2 == 0 { 1.0 } else { -1.0 };
        let t = Instant::now();
        shift(&mut tris, sign);
        let rebuilt = build(&tris);
        flat_move_ms = flat_move_ms.min(ms(t));
        drop(rebuilt);
        let t = Instant::now();
        bvh.refit(&tris);
        refit_ms = refit_ms.min(ms(t));
        refit_sah_cost = bvh.sah_cost;
    }
    drop(bvh);
    drop(tris);

    // The two-level form: one BLAS per distinct mesh, instances placed by their transforms.
    let (meshes, placed) = instances(&visible);
    let mut two_level_build_ms = f64::INFINITY;
    let mut two = TwoLevel::new(&meshes, &placed);
    for _ in 0..runs {
        let t = Instant::now();
        two = TwoLevel::new(&meshes, &placed);
        two_level_build_ms = two_level_build_ms.min(ms(t));
    }
    let mut instance_move_ms = f64::INFINITY;
    if let Some(i) = visible.iter().position(|(i, _)| Some(*i as u32) == moved) {
        let home = placed[i].1;
        for run in 0..runs {
            let d = if run % 2 == 0 { extent * 0.1 } else { 0.0 };
            let t = Instant::now();
            two.set_transform(i, DMat4::from_translation(DVec3::X * d as f64) * home);
            instance_move_ms = instance_move_ms.min(ms(t));
        }
    }
    BvhReport {
        triangles: objects.len(),
        unique_triangles: meshes.iter().map(Vec::len).sum(),
        instances: visible.len(),
        nodes,
        depth,
        gather_ms,
        full_build_ms,
        flat_move_ms,
        two_level_build_ms,
        instance_move_ms,
        refit_ms,
        sah_cost,
        refit_sah_cost,
        runs,
    }
}

/// A mesh's triangles as vertex positions.
type Triangles = Vec<[Vec3; 3]>;

/// The distinct meshes among `objects` (object-space triangles) and each object's mesh index
/// and transform. The importer gives each node its own copy of the mesh, so meshes are told
/// apart by their content.
fn instances(objects: &[(usize, &Object)]) -> (Vec<Triangles>, Vec<(u32, DMat4)>) {
    let objects: Vec<&Object> = objects.iter().map(|(_, o)| *o).collect();
    let (first, mesh_of) = crate::scene::distinct_meshes(&objects);
    let meshes = first
        .iter()
        .map(|&o| {
            let m = &objects[o].mesh;
            m.indices
                .iter()
                .map(|t| t.map(|i| m.positions[i as usize]))
                .collect()
        })
        .collect();
    let placed = objects
        .iter()
        .zip(mesh_of)
        .map(|(o, mesh)| (mesh, o.world_from_object))
        .collect();
    (meshes, placed)
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_scene_is_measured() {
        let scene = crate::scene::load_or_bundled(None).expect("the bundled scene loads");
        let r = report(&scene, 2);
        assert_eq!(r.triangles, scene.triangle_count());
        assert_eq!(
            r.instances,
            scene.objects.iter().filter(|o| o.visible).count()
        );
        assert!(r.unique_triangles <= r.triangles && r.unique_triangles > 0);
        assert!(r.full_build_ms > 0.0 && r.refit_ms > 0.0);
        assert!(r.sah_cost > 0.0 && r.refit_sah_cost >= r.sah_cost * 0.5);
        assert_eq!(
            r.nodes,
            build(
                &scene
                    .world_triangles()
                    .iter()
                    .map(|t| t.v)
                    .collect::<Vec<_>>()
            )
            .nodes
            .len()
        );
    }

    #[test]
    fn copies_of_one_mesh_count_once() {
        let mut scene = crate::scene::load_or_bundled(None).expect("the bundled scene loads");
        let copy = scene.objects[0].clone();
        let before = report(&scene, 1);
        scene.objects.push(copy);
        let after = report(&scene, 1);
        assert_eq!(after.unique_triangles, before.unique_triangles);
        assert_eq!(after.instances, before.instances + 1);
        assert_eq!(
            after.triangles,
            before.triangles + scene.objects[0].mesh.indices.len()
        );
    }
}
