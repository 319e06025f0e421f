//! A new pose of a flat scene written straight into the device structs it had: each BVH slot's
//! triangle made from its object's posed vertices (placed once an object, as a fresh load
//! places them) into the last pose's lists in place, every chunk that changed marked for the
//! upload, and the BVH refitted from the slots' corners. No list of the scene's triangles in
//! object order is made, and nothing is gathered into BVH order.

use super::host_scene::{Dirty, HostScene, PosedArrays, flat_emitters, render_middle};
use super::structs::gpu_material;
use super::triangles::{device_shape, tangents_of};
use crate::cl::types::*;
use crate::scene::{Material, Placed, RenderFrame, Scene};
use rayon::prelude::*;

/// Elements compared and written together: a run of changed chunks is one write.
pub const CHUNK: usize = 4096;

/// A tree slot's mesh triangle and its corners (object-local vertex indices).
#[derive(Clone, Copy, Debug, Default)]
pub struct SlotCorners {
    triangle: u32,
    corners: [u32; 3],
}

impl HostScene {
    /// [`HostScene::refit_flat`] of a pose that places every triangle of the same objects as
    /// the scene on the device, none dropped: writes the pose's device structs over the last
    /// pose's, refits the BVH from them, and returns which chunks changed, with the host time
    /// of writing and of the refit (ms); `None` when the pose does not fit this form (another
    /// set of objects or triangles, a dropped triangle), leaving the host scene as it was.
    /// After `Some(Err(()))` (the refit passed its cost bound) the tree is spoilt.
    pub(super) fn repose_flat(
        &mut self,
        scene: &Scene,
        space: RenderFrame,
        materials: &[Material],
        tangents: bool,
    ) -> Option<Result<(Dirty, f64, f64), ()>> {
        let t = std::time::Instant::now();
        if self.object_slots.is_empty() {
            let mut counts = vec![0u32; scene.objects.len()];
            for &o in &self.objects {
                *counts.get_mut(o as usize)? += 1;
            }
            self.object_slots = counts;
        }
        // Every visible object has all its triangles in the tree, no hidden one any.
        let counts = &self.object_slots;
        if counts.len() != scene.objects.len()
            || scene.objects.iter().zip(counts).any(|(o, &c)| {
                let placed = if o.visible { o.mesh.indices.len() } else { 0 };
                placed != c as usize
            })
        {
            return None;
        }
        let placed: Vec<Option<Placed>> = (0..scene.objects.len())
            .into_par_iter()
            .map(|i| (counts[i] > 0).then(|| scene.place(i, &space)))
            .collect();
        if placed.iter().flatten().any(|p| p.dropped() > 0) {
            return None;
        }
        // Object o's triangles are flat indices firsts[o].. in object order.
        let firsts: Vec<u32> = counts
            .iter()
            .scan(0, |acc, &c| {
                *acc += c;
                Some(*acc - c)
            })
            .collect();
        let n = self.objects.len();
        if self.vertices.len() != n {
            return None;
        }
        let crate::render::Accel::Flat(bvh) = &mut self.accel else {
            return None;
        };
        let fresh = !self.posed.as_ref().is_some_and(|p| {
            p.triangles.len() == n
                && p.shading.len() == n
                && p.tangents.len() == if tangents { n } else { 0 }
        });
        if fresh {
            self.posed = Some(PosedArrays::filled(n, tangents));
        }
        // Each slot's triangle and corners, read again only when an object's index list or
        // mirroring changed (a pointer chase and a cache miss a triangle at every pose was
        // half the writing's time). The lists are compared whole, not by address: a freed
        // list's memory may hold another one.
        let mirrors: Vec<bool> = placed
            .iter()
            .map(|p| p.as_ref().is_some_and(Placed::mirrors))
            .collect();
        let (_, (kept, kept_mirrors)) = &self.slot_corners;
        let same = kept.len() == scene.objects.len()
            && *kept_mirrors == mirrors
            && scene
                .objects
                .par_iter()
                .zip(kept)
                .all(|(o, k)| o.mesh.indices == *k);
        if !same {
            let (tri_indices, objects) = (&bvh.tri_indices, &self.objects);
            let slots = (0..n)
                .into_par_iter()
                .map(|k| {
                    let o = objects[k] as usize;
                    let triangle = tri_indices[k] - firsts[o];
                    let corners = placed[o]
                        .as_ref()
                        .map_or([0; 3], |p| p.corners(triangle as usize));
                    SlotCorners { triangle, corners }
                })
                .collect();
            let lists = scene
                .objects
                .iter()
                .map(|o| o.mesh.indices.clone())
                .collect();
            self.slot_corners = (slots, (lists, mirrors));
        }
        let posed = self.posed.as_mut()?;
        let emissive: Vec<bool> = materials.iter().map(Material::is_emissive).collect();
        let (slots, objects) = (&self.slot_corners.0, &self.objects);
        let chunks = n.div_ceil(CHUNK);
        let mut tangent_chunks: Vec<&mut [DeviceTriTangents]> = if tangents {
            posed.tangents.chunks_mut(CHUNK).collect()
        } else {
            (0..chunks).map(|_| Default::default()).collect()
        };
        // Each chunk of slots written in place, compared with what it held.
        let flags: Vec<[bool; 3]> = posed
            .triangles
            .par_chunks_mut(CHUNK)
            .zip(posed.shading.par_chunks_mut(CHUNK))
            .zip(self.vertices.par_chunks_mut(CHUNK))
            .zip(tangent_chunks.par_iter_mut())
            .enumerate()
            .map(|(c, (((tris, shading), vertices), tans))| {
                let mut changed = [fresh; 3];
                for j in 0..tris.len() {
                    let k = c * CHUNK + j;
                    let o = objects[k] as usize;
                    let SlotCorners { triangle, corners } = slots[k];
                    let ti = triangle as usize;
                    let Some(p) = &placed[o] else { continue };
                    let (v, normals, smooth) = p.shape_at(corners);
                    let material = p.material(ti);
                    // An emitter keeps its light until the light table is made again.
                    let light = if emissive[material as usize] {
                        tris[j].v1[3].to_bits()
                    } else {
                        u32::MAX
                    };
                    let (tri, sh) = device_shape(&v, &normals, smooth, [material, light, o as u32]);
                    changed[0] |= differs(&tri, &tris[j]);
                    changed[1] |= differs(&sh, &shading[j]);
                    tris[j] = tri;
                    shading[j] = sh;
                    vertices[j] = v;
                    if tangents {
                        let tan = tangents_of(p.tangents(ti));
                        changed[2] |= differs(&tan, &tans[j]);
                        tans[j] = tan;
                    }
                }
                changed
            })
            .collect();
        drop(tangent_chunks);
        let mut dirty = Dirty {
            triangles: flags.iter().map(|f| f[0]).collect(),
            shading: flags.iter().map(|f| f[1]).collect(),
            tangents: if tangents {
                flags.iter().map(|f| f[2]).collect()
            } else {
                vec![]
            },
        };
        self.emissive = flat_emitters(
            &mut posed.triangles,
            &self.vertices,
            materials,
            Some(&mut dirty.triangles),
        );
        let write_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        bvh.refit_ordered(&self.vertices);
        if bvh.needs_rebuild() {
            return Some(Err(()));
        }
        let refit_ms = t.elapsed().as_secs_f64() * 1e3;
        self.space = space;
        self.middle = render_middle(scene, &space);
        self.materials = materials.iter().map(gpu_material).collect();
        Some(Ok((dirty, write_ms, refit_ms)))
    }
}

/// Whether two structs' bits differ, compared word by word inline (a `memcmp` call a struct
/// was 5 % of the 1 M-triangle update's profile).
#[inline]
fn differs<T: bytemuck::Pod>(a: &T, b: &T) -> bool {
    let (a, b): (&[u32], &[u32]) = (
        bytemuck::cast_slice(bytemuck::bytes_of(a)),
        bytemuck::cast_slice(bytemuck::bytes_of(b)),
    );
    a.iter().zip(b).fold(false, |d, (x, y)| d | (x != y))
}

/// Whether `a` and `b` differ anywhere, chunk by chunk ([`CHUNK`] elements): all chunks when
/// their lengths differ.
pub(super) fn changed_chunks<T: bytemuck::Pod + Sync>(a: &[T], b: &[T]) -> Vec<bool> {
    if a.len() != b.len() {
        return vec![true; a.len().max(b.len()).div_ceil(CHUNK)];
    }
    a.par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(a, b)| bytemuck::cast_slice::<T, u8>(a) != bytemuck::cast_slice::<T, u8>(b))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Mesh, Object};
    use glam::{DMat4, DVec3, Vec3};
    use std::sync::Arc;

    /// A 24 × 24 grid of smooth triangles bent by a wave of height `wave`, placed twice: as
    /// it is and mirrored (a flipped winding) far to the side.
    fn grid(wave: f32) -> Scene {
        let n = 25;
        let mut mesh = Mesh::default();
        for j in 0..n {
            for i in 0..n {
                let (x, z) = (i as f32 * 0.1, j as f32 * 0.1);
                mesh.positions
                    .push(Vec3::new(x, wave * (3.0 * x).sin() * z, z));
                mesh.normals
                    .push(Vec3::new(-wave * (3.0 * x).cos(), 1.0, wave * x).normalize());
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let v = j * n + i;
                mesh.indices.push([v, v + n, v + 1]);
                mesh.indices.push([v + 1, v + n, v + n + 1]);
            }
        }
        mesh.materials = vec![0; mesh.indices.len()];
        let mesh = Arc::new(mesh);
        let object = |world_from_object| Object {
            name: "grid".into(),
            world_from_object,
            visible: true,
            mesh: Arc::clone(&mesh),
        };
        Scene {
            objects: vec![
                object(DMat4::IDENTITY),
                object(DMat4::from_translation(DVec3::X * 5.0) * DMat4::from_scale(-DVec3::X)),
            ],
            materials: vec![Material::default()],
            ..Scene::default()
        }
    }

    /// A flat scene's device triangles and corner normals as sorted byte strings: the same
    /// structs in any tree order give the same list.
    fn structs(triangles: &[DeviceTriangle], shading: &[DeviceTriShading]) -> Vec<Vec<u8>> {
        let mut v: Vec<Vec<u8>> = triangles
            .iter()
            .zip(shading)
            .map(|(t, s)| [bytemuck::bytes_of(t), bytemuck::bytes_of(s)].concat())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_pose_written_in_place_is_a_fresh_flattening_of_it() {
        let rest = grid(0.0);
        let space = RenderFrame::around(&rest.bounds());
        let (mut host, _) = HostScene::flatten(&rest, &space, &rest.materials);
        for (frame, wave) in [0.3, 0.7, 0.7].into_iter().enumerate() {
            let posed = grid(wave);
            let space = RenderFrame::around(&posed.bounds());
            let Some(Ok((dirty, ..))) = host.repose_flat(&posed, space, &posed.materials, false)
            else {
                panic!("pose {wave} was not written in place");
            };
            // Every chunk moved, save for a pose the same as the last.
            let still = frame == 2;
            assert!(dirty.triangles.iter().all(|&d| d != still), "{frame}");
            assert!(dirty.shading.iter().all(|&d| d != still), "{frame}");
            let (fresh, _) = HostScene::flatten(&posed, &space, &posed.materials);
            let p = host.posed.as_ref().unwrap();
            assert_eq!(
                structs(&p.triangles, &p.shading),
                structs(&fresh.triangles, &fresh.shading),
                "pose {wave}"
            );
            // The refitted tree finds what the fresh one finds.
            for k in 0..200 {
                let x = (k % 20) as f32 * 0.27 - 1.0;
                let z = (k / 20) as f32 * 0.13;
                let ray = crate::bvh::Ray {
                    origin: space.point(DVec3::new(x as f64, 2.0, z as f64)),
                    direction: Vec3::new(0.01, -1.0, 0.02),
                    tmin: 0.0,
                    tmax: f32::INFINITY,
                };
                let hit = |h: &HostScene| h.intersect(&ray).map(|h| (h.t, h.u, h.v));
                assert_eq!(hit(&host), hit(&fresh), "pose {wave}, ray {k}");
            }
        }
        // The first grid mirrored too: its triangles' corners are read swapped.
        let mut mirrored = grid(0.7);
        mirrored.objects[0].world_from_object = DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0));
        let space = RenderFrame::around(&mirrored.bounds());
        let written = host.repose_flat(&mirrored, space, &mirrored.materials, false);
        assert!(matches!(written, Some(Ok(_))));
        let (fresh, _) = HostScene::flatten(&mirrored, &space, &mirrored.materials);
        let p = host.posed.as_ref().unwrap();
        assert_eq!(
            structs(&p.triangles, &p.shading),
            structs(&fresh.triangles, &fresh.shading)
        );
        // Another set of objects is not written in place.
        let mut hidden = grid(0.7);
        hidden.objects[1].visible = false;
        let space = RenderFrame::around(&hidden.bounds());
        assert!(
            host.repose_flat(&hidden, space, &hidden.materials, false)
                .is_none()
        );
    }
}
