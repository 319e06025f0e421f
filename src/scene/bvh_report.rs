//! What `penumbra bench bvh` measures: the cost of building and updating the BVH of a scene on
//! the host, without a device.

use super::{Object, Scene};
use crate::bvh::{Blas, TwoLevel, build};
use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Build and update figures of one scene (times are the minimum over the runs).
#[derive(Clone, Debug, Serialize)]
pub struct BvhReport {
    /// Triangles over all visible instances.
    pub triangles: usize,
    /// Triangles of the distinct meshes the visible objects use.
    pub unique_triangles: usize,
    /// Visible mesh instances (glTF nodes with a mesh).
    pub instances: usize,
    /// Nodes of the flat BVH (`None`: the flat form was not measured).
    pub nodes: Option<usize>,
    /// Depth of the flat BVH's deepest leaf.
    pub depth: Option<u32>,
    /// Gathering the world-space triangles of every instance.
    pub gather_ms: Option<f64>,
    /// Building the whole flat BVH (every placed triangle in one tree).
    pub flat_build_ms: Option<f64>,
    /// Moving one instance in the flat BVH: moving its triangles and building the whole tree
    /// again.
    pub flat_move_ms: Option<f64>,
    /// Refitting the whole flat tree after one instance moved.
    pub refit_ms: Option<f64>,
    /// SAH cost of the flat tree.
    pub sah_cost: Option<f32>,
    /// SAH cost after the refit.
    pub refit_sah_cost: Option<f32>,
    /// A full build, as issue 14 defines it: the host two-level form, every BLAS (one per
    /// distinct mesh) and the TLAS.
    pub full_build_ms: f64,
    /// Nodes of the two-level form (the TLAS and every BLAS).
    pub two_level_nodes: usize,
    /// Moving one instance in the two-level form: its transform and a new TLAS (host only;
    /// `bench trace --bvh two-level` times the move on the device, upload included).
    pub instance_move_ms: f64,
    /// Timed runs of each measurement.
    pub runs: usize,
}

/// Builds and updates the BVH of `scene` `runs` times (at least once) and reports the fastest
/// of each: the flat form when `flat`, and the two-level form. The moved instance is the
/// largest visible one, shifted by a tenth of its size.
pub fn report(scene: &Scene, runs: usize, flat: bool) -> BvhReport {
    let runs = runs.max(1);
    let visible: Vec<(usize, &Object)> = scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.visible)
        .collect();
    let moved = visible
        .iter()
        .max_by_key(|(_, o)| o.mesh.indices.len())
        .map(|(i, _)| *i);
    let extent = moved.map_or(0.0, |m| {
        let o = &scene.objects[m];
        let (lo, hi) = o
            .mesh
            .positions
            .iter()
            .map(|p| o.world_from_object.transform_point3(p.as_dvec3()))
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        (hi - lo).max_element() as f32
    });
    let flat = flat.then(|| flat_report(scene, runs, moved.map(|m| m as u32), extent));

    // The two-level form: one BLAS per distinct mesh, instances placed by their transforms.
    // Each BLAS is built from a transient copy of its mesh's triangles, as the renderer does.
    let objects: Vec<&Object> = visible.iter().map(|(_, o)| *o).collect();
    let (first, mesh_of) = super::distinct_meshes(&objects);
    let placed: Vec<(u32, DMat4)> = objects
        .iter()
        .zip(&mesh_of)
        .map(|(o, &mesh)| (mesh, o.world_from_object))
        .collect();
    let build_two = || {
        let blases = first
            .par_iter()
            .map(|&o| Blas::of_shared_mesh(&objects[o].mesh))
            .collect();
        TwoLevel::from_blases(blases, &placed)
    };
    let mut full_build_ms = f64::INFINITY;
    let mut two = None;
    for _ in 0..runs {
        drop(two.take());
        let t = Instant::now();
        two = Some(build_two());
        full_build_ms = full_build_ms.min(ms(t));
    }
    let mut two = two.expect("built at least once");
    let mut instance_move_ms = f64::INFINITY;
    if let Some(i) = visible.iter().position(|(i, _)| Some(*i) == moved) {
        let home = placed[i].1;
        for run in 0..runs {
            let d = if run % 2 == 0 { extent * 0.1 } else { 0.0 };
            let t = Instant::now();
            two.set_transform(i, DMat4::from_translation(DVec3::X * d as f64) * home);
            instance_move_ms = instance_move_ms.min(ms(t));
        }
    }
    let two_level_nodes =
        two.tlas.nodes.len() + two.blases.iter().map(|b| b.bvh.nodes.len()).sum::<usize>();
    BvhReport {
        triangles: objects.iter().map(|o| o.mesh.indices.len()).sum(),
        unique_triangles: first.iter().map(|&o| objects[o].mesh.indices.len()).sum(),
        instances: visible.len(),
        nodes: flat.as_ref().map(|f| f.nodes),
        depth: flat.as_ref().map(|f| f.depth),
        gather_ms: flat.as_ref().map(|f| f.gather_ms),
        flat_build_ms: flat.as_ref().map(|f| f.flat_build_ms),
        flat_move_ms: flat.as_ref().map(|f| f.flat_move_ms),
        refit_ms: flat.as_ref().map(|f| f.refit_ms),
        sah_cost: flat.as_ref().map(|f| f.sah_cost),
        refit_sah_cost: flat.as_ref().map(|f| f.refit_sah_cost),
        full_build_ms,
        two_level_nodes,
        instance_move_ms,
        runs,
    }
}

/// The flat form's figures.
struct FlatReport {
    nodes: usize,
    depth: u32,
    gather_ms: f64,
    flat_build_ms: f64,
    flat_move_ms: f64,
    refit_ms: f64,
    sah_cost: f32,
    refit_sah_cost: f32,
}

/// Flattens `scene`, builds its BVH `runs` times, and moves object `moved` by a tenth of
/// `extent` along x and back (a full rebuild, and a refit).
fn flat_report(scene: &Scene, runs: usize, moved: Option<u32>, extent: f32) -> FlatReport {
    let t = Instant::now();
    let world = scene.world_triangles();
    let mut tris: Vec<[Vec3; 3]> = world.iter().map(|t| t.v).collect();
    let objects: Vec<u32> = world.iter().map(|t| t.object).collect();
    drop(world);
    let gather_ms = ms(t);

    let mut bvh = build(&tris);
    let mut flat_build_ms = f64::INFINITY;
    for _ in 0..runs {
        let t = Instant::now();
        bvh = build(&tris);
        flat_build_ms = flat_build_ms.min(ms(t));
    }
    let (sah_cost, depth, nodes) = (bvh.sah_cost, bvh.depth, bvh.nodes.len());
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
    FlatReport {
        nodes,
        depth,
        gather_ms,
        flat_build_ms,
        flat_move_ms,
        refit_ms,
        sah_cost,
        refit_sah_cost,
    }
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
        let r = report(&scene, 2, true);
        assert_eq!(r.triangles, scene.triangle_count());
        assert_eq!(
            r.instances,
            scene.objects.iter().filter(|o| o.visible).count()
        );
        assert!(r.unique_triangles <= r.triangles && r.unique_triangles > 0);
        let (sah, refit) = (r.sah_cost.unwrap(), r.refit_sah_cost.unwrap());
        assert!(r.flat_build_ms.unwrap() > 0.0 && r.refit_ms.unwrap() > 0.0);
        assert!(sah > 0.0 && refit >= sah * 0.5);
        assert!(r.two_level_nodes > 0 && r.instance_move_ms >= 0.0);
        assert_eq!(report(&scene, 1, false).nodes, None);
        assert_eq!(
            r.nodes.unwrap(),
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
        let before = report(&scene, 1, false);
        scene.objects.push(copy);
        let after = report(&scene, 1, false);
        assert_eq!(after.unique_triangles, before.unique_triangles);
        assert_eq!(after.instances, before.instances + 1);
        assert_eq!(
            after.triangles,
            before.triangles + scene.objects[0].mesh.indices.len()
        );
    }
}
