//! The probe: the scene's visible world triangles with the trees that the first view's rays
//! are traced through. The rays go through quick BLASes of the distinct meshes under a top
//! level over the visible objects ([`Probe::new`]): the trees the viewer's first image of a
//! large scene traces, which the probe leaves in the scene for the renderer, so that opening
//! builds them once and no tree over every placed triangle is built. Their leaf triangles are
//! tested in world space, so the hits (and the first view) are those of one tree over the
//! world triangles ([`Probe::flat`]).
//!
//! The probe works in the scene's render frame ([`RenderFrame::around`] its robust bounds, the
//! frame the renderer uses): the scene's middle at the origin and its size between 1/2 and 1,
//! so its f32 triangles and rays, and every decision they make, are the same wherever the
//! scene sits and whatever its units (at 10⁵ from the origin, f32 world coordinates moved the
//! shadow rays' start off the surface: the Cornell box's lit fraction fell from 0.83 to 0.61).

use super::super::{Bounds, Mesh, RenderFrame, Scene};
use super::subject_bounds::{fit_points, regular_sample, robust_bounds_windowed};
use super::{WorldTris, luminance};
use crate::bvh::{Blas, Bvh, Ray, TwoLevel, intersect_triangle};
use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// The scene's world triangles with the trees that probe rays are traced through.
pub struct Probe {
    /// How rays find the triangles.
    pub(super) tracer: Tracer,
    /// The visible objects' world triangles in scene order; hits name triangles by their
    /// index here.
    pub(super) tris: WorldTris,
    /// Emitted radiance luminance per material (0 for most).
    pub(super) emission: Vec<f32>,
    /// Whether light passes each material (glass and blended surfaces).
    pub(super) see_through: Vec<bool>,
    /// Whether each material is metal or glass (what reflects or shows its surroundings).
    pub(super) shiny: Vec<bool>,
    /// Whether each material is double-sided (its back faces show).
    pub(super) double_sided: Vec<bool>,
    /// Whether some triangle is opaque.
    pub(super) any_opaque: bool,
    /// Up to [`super::FIT_POINTS`] vertices inside the robust bounds, for fitting the view.
    pub(super) points: Vec<Vec3>,
    /// Robust bounds of the visible geometry, in the render frame.
    pub bounds: Bounds,
    /// The render frame the probe works in: world points map to it by [`RenderFrame::point`].
    pub frame: RenderFrame,
}

/// The trees of a [`Probe`].
pub(super) enum Tracer {
    /// A quick BLAS per distinct mesh ([`crate::bvh::quick_blas`], the trees the viewer's first
    /// image traces) and a top level over the visible objects in world space. Each leaf
    /// triangle is tested in world space, on its vertices in [`Probe::tris`] (instance i is
    /// object i there), so hits are those of one tree over the world triangles, distance for
    /// distance.
    TwoLevel {
        two: TwoLevel,
        /// Each BLAS's mesh.
        meshes: Vec<Arc<Mesh>>,
    },
    /// One quick tree over the world triangles (its triangles in tree order), a second over
    /// the opaque ones alone when some are see-through (`kept`: their indices in
    /// [`Probe::tris`]): scenes with triangles dropped for absurd world vertices, whose
    /// triangles are no longer those of the meshes.
    Flat {
        all: (Bvh, Vec<[Vec3; 3]>),
        opaque: Option<(Bvh, Vec<[Vec3; 3]>, Vec<u32>)>,
    },
}

impl Probe {
    /// Builds the probe for the visible geometry of `scene`: over quick BLASes of its distinct
    /// meshes and a top level (`Tracer::TwoLevel`), which [`Probe::keep_blases`] leaves in
    /// the scene for the renderer. Glass and blended surfaces
    /// are passed by the rays that light passes; they still count for the bounds and for
    /// telling an interior.
    pub fn new(scene: &Scene) -> Self {
        let t = std::time::Instant::now();
        let frame = RenderFrame::around(&scene.bounds());
        let tris = WorldTris::new(scene.world_objects(&frame));
        log::debug!(
            "probe: world vertices in {:.0} ms",
            t.elapsed().as_secs_f64() * 1e3
        );
        let t = std::time::Instant::now();
        let cpu = crate::cpu_time::process_cpu_seconds().unwrap_or(0.0);
        if tris.objects.iter().any(|o| o.kept.is_some()) {
            // Triangles were dropped: the meshes' triangles are not the world's.
            return Self::with_flat(scene, tris, frame);
        }
        let objects: Vec<&super::super::Object> = scene
            .objects
            .iter()
            .filter(|o| o.visible && !o.mesh.indices.is_empty())
            .collect();
        let (distinct, mesh_of) = super::super::distinct_meshes(&objects);
        let meshes: Vec<Arc<Mesh>> = distinct.iter().map(|&o| objects[o].mesh.clone()).collect();
        // Several meshes at once, each in parallel within (a large mesh's sort and tree).
        let blases: Vec<Blas> = meshes
            .par_iter()
            .map(crate::bvh::quick_blas_shared)
            .collect();
        let frame_from_world =
            DMat4::from_scale(DVec3::splat(frame.scale)) * DMat4::from_translation(-frame.origin);
        let instances: Vec<(u32, DMat4)> = objects
            .iter()
            .zip(&mesh_of)
            .map(|(o, &m)| (m, frame_from_world * o.world_from_object))
            .collect();
        let hidden = vec![false; instances.len()];
        let two = TwoLevel::with_hidden(blases, &instances, hidden, 0);
        log::debug!(
            "probe: quick BLASes and top level in {:.0} ms ({:.2} CPU s)",
            t.elapsed().as_secs_f64() * 1e3,
            crate::cpu_time::process_cpu_seconds().unwrap_or(0.0) - cpu
        );
        Self::with_tracer(scene, Tracer::TwoLevel { two, meshes }, tris, frame)
    }

    /// The probe over one quick tree of the world triangles (`Tracer::Flat`): how the first
    /// view was found before the two levels, and what it falls back to.
    pub fn flat(scene: &Scene) -> Self {
        let frame = RenderFrame::around(&scene.bounds());
        Self::with_flat(scene, WorldTris::new(scene.world_objects(&frame)), frame)
    }

    fn with_flat(scene: &Scene, world: WorldTris, frame: RenderFrame) -> Self {
        let (tris, materials) = world.to_vecs();
        let see_through = see_through_materials(scene);
        let passes = |m: u32| see_through.get(m as usize).copied().unwrap_or(false);
        let ordered = |kept: &[u32]| -> (Bvh, Vec<[Vec3; 3]>) {
            let verts: Vec<[Vec3; 3]> = kept.par_iter().map(|&i| tris[i as usize]).collect();
            let bvh = crate::bvh::build_quick(&verts);
            let verts = bvh
                .tri_indices
                .par_iter()
                .map(|&i| verts[i as usize])
                .collect();
            (bvh, verts)
        };
        let every: Vec<u32> = (0..tris.len() as u32).collect();
        let all = ordered(&every);
        let opaque = materials.par_iter().any(|&m| passes(m)).then(|| {
            let kept: Vec<u32> = every
                .into_par_iter()
                .filter(|&i| !passes(materials[i as usize]))
                .collect();
            let (bvh, verts) = ordered(&kept);
            (bvh, verts, kept)
        });
        drop((tris, materials));
        Self::with_tracer(scene, Tracer::Flat { all, opaque }, world, frame)
    }

    fn with_tracer(scene: &Scene, tracer: Tracer, tris: WorldTris, frame: RenderFrame) -> Self {
        let t = std::time::Instant::now();
        let cpu = crate::cpu_time::process_cpu_seconds().unwrap_or(0.0);
        let sample = regular_sample(&tris);
        let bulk = sample.as_ref().unwrap_or(&tris);
        let bounds = robust_bounds_windowed(&tris, bulk);
        let points = fit_points(bulk, &bounds);
        drop(sample);
        log::debug!(
            "probe: robust bounds and fit points in {:.0} ms ({:.2} CPU s)",
            t.elapsed().as_secs_f64() * 1e3,
            crate::cpu_time::process_cpu_seconds().unwrap_or(0.0) - cpu
        );
        let see_through = see_through_materials(scene);
        let any_opaque = tris.objects.par_iter().any(|o| {
            (0..o.len()).any(|k| {
                let m = o.mesh.materials[o.triangle(k)];
                !see_through.get(m as usize).copied().unwrap_or(false)
            })
        });
        Self {
            tracer,
            emission: scene
                .materials
                .iter()
                .map(|m| luminance(m.emission))
                .collect(),
            shiny: scene
                .materials
                .iter()
                .map(|m| m.metallic >= 0.5 || m.transmission > 0.0)
                .collect(),
            double_sided: scene.materials.iter().map(|m| m.double_sided).collect(),
            see_through,
            any_opaque,
            tris,
            points,
            bounds,
            frame,
        }
    }

    /// The expected triangle tests and node steps of one probe ray (the trees' SAH cost):
    /// tens in a healthy scene, the triangle count where every triangle lies in one place.
    pub fn ray_cost(&self) -> f64 {
        match &self.tracer {
            Tracer::TwoLevel { two, .. } => two.ray_cost(),
            Tracer::Flat { all, .. } => all.0.sah_cost as f64,
        }
    }

    /// Leaves the quick BLASes in `scene` for the renderer's first load
    /// ([`Scene::keep_quick_blases`]).
    pub fn keep_blases(self, scene: &Scene) {
        if let Tracer::TwoLevel { two, meshes, .. } = self.tracer {
            scene.keep_quick_blases(meshes.into_iter().zip(two.blases).collect());
        }
    }

    /// Triangle `i`'s emitted radiance luminance.
    pub(super) fn emission(&self, i: usize) -> f32 {
        self.emission
            .get(self.tris.material(i) as usize)
            .copied()
            .unwrap_or(0.0)
    }

    /// The closest triangle along a ray (with `any`, the first found) between `tmin` and
    /// `tmax`, see-through ones included unless `opaque`: (distance, index in `tris`).
    pub(super) fn trace(&self, ray: &Ray, any: bool, opaque: bool) -> Option<(f32, usize)> {
        match &self.tracer {
            Tracer::TwoLevel { two, .. } => {
                let passes =
                    |m: u32| opaque && self.see_through.get(m as usize).copied().unwrap_or(false);
                two.tlas.walk(ray, any, |leaf, r| {
                    let instance = two.tlas.tri_indices[leaf as usize] as usize;
                    let inst = &two.instances[instance];
                    let blas = &two.blases[inst.blas as usize];
                    let local = inst.to_object(r);
                    let root = two.pieces[leaf as usize];
                    let object = &self.tris.objects[instance];
                    let start = self.tris.starts[instance];
                    blas.bvh
                        .walk_from(root, &local, any, |k, l| {
                            let ti = blas.bvh.tri_indices[k as usize] as usize;
                            if passes(object.mesh.materials[ti]) {
                                return None;
                            }
                            let world = Ray { tmax: l.tmax, ..*r };
                            intersect_triangle(&world, &object.vertices(ti))
                                .map(|h| (h.0, (h.0, start + ti)))
                        })
                        .map(|h| (h.0, h))
                })
            }
            Tracer::Flat { all, opaque: o } => {
                let (bvh, verts, kept) = match (o, opaque) {
                    (Some((bvh, verts, kept)), true) => (bvh, verts, Some(kept)),
                    _ => (&all.0, &all.1, None),
                };
                bvh.traverse(0, ray, verts, any).map(|h| {
                    let i = bvh.tri_indices[h.prim as usize];
                    (h.t, kept.map_or(i, |k| k[i as usize]) as usize)
                })
            }
        }
    }

    /// Whether triangle `i` shows to a ray along `d`: it faces the ray, or is double-sided.
    pub(super) fn shows(&self, i: usize, d: DVec3) -> bool {
        self.normal(i).dot(d) < 0.0
            || self
                .double_sided
                .get(self.tris.material(i) as usize)
                .copied()
                .unwrap_or(false)
    }

    /// Whether triangle `i` is metal or glass.
    pub(super) fn shiny(&self, i: usize) -> bool {
        self.shiny
            .get(self.tris.material(i) as usize)
            .copied()
            .unwrap_or(false)
    }

    /// The closest triangle along a ray within `tmax`, see-through ones included unless
    /// `opaque`: (distance, index).
    fn closest(&self, origin: DVec3, dir: DVec3, tmax: f64, opaque: bool) -> Option<(f64, usize)> {
        let ray = Ray {
            origin: origin.as_vec3(),
            direction: dir.as_vec3(),
            tmin: 0.0,
            tmax: tmax as f32,
        };
        self.trace(&ray, false, opaque).map(|h| (h.0 as f64, h.1))
    }

    /// The closest triangle along a ray within `tmax`, glass included: (distance, index).
    pub(super) fn hit_all_at(&self, origin: DVec3, dir: DVec3, tmax: f64) -> Option<(f64, usize)> {
        self.closest(origin, dir, tmax, false)
    }

    /// The material seen along a world-space ray (glass included), if any: how the first
    /// view's camera rays find what a pixel shows.
    pub fn material_seen(&self, origin: DVec3, dir: DVec3) -> Option<u32> {
        let origin = self.frame.point(origin).as_dvec3();
        self.hit_all_at(origin, dir, f64::INFINITY)
            .map(|h| self.tris.material(h.1))
    }

    /// The closest triangle along a ray, glass included.
    pub(super) fn hit_all(&self, origin: DVec3, dir: DVec3) -> Option<usize> {
        self.closest(origin, dir, f64::INFINITY, false).map(|h| h.1)
    }

    /// The closest opaque triangle along a ray within `tmax`: (distance, index).
    pub(super) fn hit(&self, origin: DVec3, dir: DVec3, tmax: f64) -> Option<(f64, usize)> {
        self.closest(origin, dir, tmax, true)
    }

    pub(super) fn visible(&self, from: DVec3, to: DVec3) -> bool {
        let d = to - from;
        let ray = Ray {
            origin: from.as_vec3(),
            direction: d.as_vec3(),
            tmin: 1e-4,
            tmax: 0.999,
        };
        self.trace(&ray, true, true).is_none()
    }

    pub(super) fn unobstructed(&self, from: DVec3, dir: DVec3) -> bool {
        let ray = Ray {
            origin: from.as_vec3(),
            direction: dir.as_vec3(),
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        self.trace(&ray, true, true).is_none()
    }

    /// The unit geometric normal of a triangle.
    pub(super) fn normal(&self, prim: usize) -> DVec3 {
        let t = self.tris.get(prim);
        (t[1] - t[0])
            .cross(t[2] - t[0])
            .as_dvec3()
            .normalize_or(DVec3::Y)
    }

    pub(super) fn scale(&self) -> f64 {
        self.bounds.diagonal().max(1e-6)
    }
}

/// Whether light passes each of `scene`'s materials (transmission or blending).
fn see_through_materials(scene: &Scene) -> Vec<bool> {
    scene
        .materials
        .iter()
        .map(|m| m.transmission > 0.0 || m.alpha == super::super::AlphaMode::Blend)
        .collect()
}

/// Unit directions spread evenly over the sphere (a Fibonacci lattice).
pub(super) fn sphere_directions(n: usize) -> impl Iterator<Item = DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n).map(move |i| {
        let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - y * y).max(0.0).sqrt();
        let phi = golden * i as f64;
        DVec3::new(r * phi.cos(), y, r * phi.sin())
    })
}
