//! The first view of a scene without a camera of its own: robust bounds of what is there, the
//! side its lights illuminate, interiors seen from inside, and the rule that decides whether the
//! scene's own lights light that view (else the viewer adds an environment).
//!
//! Everything here runs on the host with the reference BVH traversal ([`crate::bvh`]) and is
//! deterministic: the same scene gives the same first view. The probe rays go through quick
//! BLASes of the distinct meshes under a top level over the visible objects ([`Probe::new`]):
//! the trees the viewer's first image of a large scene traces, which the probe leaves in the
//! scene for the renderer, so that opening builds them once and no tree over every placed
//! triangle is built. Their leaf triangles are tested in world space, so the hits (and the
//! first view) are those of one tree over the world triangles ([`Probe::flat`]).
//!
//! # "The scene's own lights light the view"
//!
//! From the chosen camera a grid of [`PROBE_COLUMNS`] × [`PROBE_ROWS`] rays finds the subject
//! points. At each point the direct irradiance E from the scene's punctual lights and emissive
//! triangles is estimated (cosine at the point, inverse square, cone and emitter cosine, one
//! visibility ray per light; the [`MAX_EMITTERS`] most powerful emissive triangles stand for
//! all of them, scaled by their share of the emitted power). With L_s = median(E)/π (the
//! radiance of a white diffuse surface at the median point) and L_e = the 90th percentile of
//! the radiance of emitters the camera sees directly, the lights light the view when
//! - at least [`MIN_LIT_FRACTION`] of the subject points get some direct light, and
//! - L_s ≥ L_e · 2^−[`MAX_STOPS_BELOW_EMITTERS`] (the subject is within the tone curve's reach
//!   once the visible lamps are exposed).
//!
//! Small glowing parts (a car's headlights, a lamp's filament behind glass) fail the first test;
//! a sun or a lamp over the subject passes both.

use super::{Bounds, Camera, Light, LightKind, Mesh, Scene};
use crate::bvh::{Blas, Bvh, Ray, TwoLevel, intersect_triangle};
use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// Columns of the probe grid of camera rays.
pub const PROBE_COLUMNS: usize = 32;
/// Rows of the probe grid of camera rays.
pub const PROBE_ROWS: usize = 24;
/// Emissive triangles evaluated at each subject point (the most powerful ones).
pub const MAX_EMITTERS: usize = 64;
/// The share of subject points that must receive direct light.
pub const MIN_LIT_FRACTION: f64 = 0.25;
/// How far (in stops) the lit subject may lie below the directly seen emitters.
pub const MAX_STOPS_BELOW_EMITTERS: f64 = 10.0;
/// Rays from each subject point over its hemisphere, to find whether the sky reaches it.
pub const SKY_RAYS: usize = 16;
/// The share of those rays that must leave the scene for an environment to light the view: a
/// room with a window lets out a few percent; cracks in a closed model far fewer.
pub const MIN_SKY_FRACTION: f64 = 0.002;
/// Share of the rays from the middle of the bounds that must hit front faces for an interior.
pub const INTERIOR_HIT_FRACTION: f64 = 0.6;
/// Share of escaping rays from which a one-sided opening makes an open box (the Cornell box
/// loses a sixth of its rays through its front; a room loses a few through its windows).
pub const OPEN_SIDE_FRACTION: f64 = 0.08;
/// Rays cast from the middle of the bounds to tell an interior from an object.
pub const SHELL_RAYS: usize = 128;
/// Eye height in metres (glTF's unit) inside a room; models in centimetres or millimetres are
/// recognised by their floor-to-ceiling height.
pub const EYE_HEIGHT: f64 = 1.6;
/// Vertical field of view of an interior view (wider than [`super::AUTO_YFOV`]).
pub const INTERIOR_YFOV: f64 = 1.15;
/// Name of the cameras made here (and by [`Camera::framing`]).
pub const AUTO_CAMERA: &str = "auto";

/// The scene's world triangles with the trees that probe rays are traced through.
pub struct Probe {
    /// How rays find the triangles.
    tracer: Tracer,
    /// The visible objects' world triangles in scene order; hits name triangles by their
    /// index here.
    tris: WorldTris,
    /// Emitted radiance luminance per material (0 for most).
    emission: Vec<f32>,
    /// Whether light passes each material (glass and blended surfaces).
    see_through: Vec<bool>,
    /// Whether some triangle is opaque.
    any_opaque: bool,
    /// Up to [`FIT_POINTS`] vertices inside the robust bounds, for fitting the view.
    points: Vec<Vec3>,
    /// Robust bounds of the visible geometry.
    pub bounds: Bounds,
}

/// The trees of a [`Probe`].
enum Tracer {
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

/// Vertices kept for fitting the view to the subject's silhouette.
pub const FIT_POINTS: usize = 8192;

/// What the first-view analysis found (for messages, the JSON summary and tests).
#[derive(Clone, Debug, PartialEq)]
pub struct FirstView {
    /// The camera to start with.
    pub camera: Camera,
    /// Robust bounds of the visible geometry.
    pub bounds: Bounds,
    /// Whether the camera was put inside (the model is an interior).
    pub interior: bool,
    /// Whether the scene's own lights light the view (the rule in the module docs).
    pub lit: bool,
    /// The share of probe rays from the camera that hit geometry.
    pub coverage: f64,
    /// The share of subject points with direct light from the scene's lights.
    pub lit_fraction: f64,
    /// L_s: median direct irradiance over π at the subject points.
    pub subject_radiance: f64,
    /// L_e: 90th percentile radiance of the emitters seen directly (0 when none is).
    pub emitter_radiance: f64,
    /// The share of rays from the subject points over their hemispheres that leave the scene:
    /// 0 in a closed room, which an environment cannot light.
    pub sky_fraction: f64,
}

impl FirstView {
    /// Whether an environment would show in the view or light it: the camera sees past the
    /// geometry, or at least [`MIN_SKY_FRACTION`] of the subject's hemisphere rays leave.
    pub fn environment_reaches(&self) -> bool {
        self.coverage < 1.0 || self.sky_fraction >= MIN_SKY_FRACTION
    }
}

/// What [`light_test`] finds from a camera (the [`FirstView`] fields of the same names).
struct LightTest {
    lit: bool,
    coverage: f64,
    lit_fraction: f64,
    subject_radiance: f64,
    emitter_radiance: f64,
    sky_fraction: f64,
}

/// The visible objects' world triangles in scene order (as [`Scene::flatten`] keeps them),
/// read from each object's vertices ([`Scene::world_objects`]) instead of a copy of every
/// triangle: a 64 M-triangle scene's copy was 2.3 GB and seconds to write.
#[derive(Clone, Debug)]
pub struct WorldTris {
    objects: Vec<super::WorldObject>,
    /// Each object's first triangle, and the count after the last.
    starts: Vec<usize>,
}

impl WorldTris {
    fn new(objects: Vec<super::WorldObject>) -> Self {
        let mut starts = Vec::with_capacity(objects.len() + 1);
        starts.push(0);
        for o in &objects {
            starts.push(starts.last().copied().unwrap_or(0) + o.len());
        }
        Self { objects, starts }
    }

    /// Triangles in all.
    fn len(&self) -> usize {
        self.starts.last().copied().unwrap_or(0)
    }

    /// (object, kept triangle in it) of triangle `i`.
    fn locate(&self, i: usize) -> (usize, usize) {
        let o = self.starts.partition_point(|&s| s <= i) - 1;
        (o, i - self.starts[o])
    }

    /// Triangle `i`'s vertices.
    fn get(&self, i: usize) -> [Vec3; 3] {
        let (o, k) = self.locate(i);
        let o = &self.objects[o];
        o.vertices(o.triangle(k))
    }

    /// Triangle `i`'s material.
    fn material(&self, i: usize) -> u32 {
        let (o, k) = self.locate(i);
        let o = &self.objects[o];
        o.mesh.materials[o.triangle(k)]
    }

    /// Calls `f(i, vertices, material)` for the triangles `range`, in order.
    fn visit(&self, range: std::ops::Range<usize>, mut f: impl FnMut(usize, [Vec3; 3], u32)) {
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
    fn chunks(&self, chunk: usize) -> impl IndexedParallelIterator<Item = std::ops::Range<usize>> {
        let n = self.len();
        (0..n.div_ceil(chunk))
            .into_par_iter()
            .map(move |c| c * chunk..((c + 1) * chunk).min(n))
    }

    /// Every triangle's vertices and material, in order.
    fn to_vecs(&self) -> (Vec<[Vec3; 3]>, Vec<u32>) {
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
    fn soup(tris: &[[Vec3; 3]]) -> Self {
        let mesh = Mesh::soup(tris);
        Self::new(vec![super::WorldObject {
            world: mesh.positions.clone(),
            mesh: Arc::new(mesh),
            kept: None,
            flip: false,
        }])
    }
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn area(t: &[Vec3; 3]) -> f32 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// The key of an `f32` whose unsigned order is [`f32::total_cmp`]'s.
fn order_key(x: f32) -> u32 {
    let b = x.to_bits();
    if b >> 31 == 1 { !b } else { b | 0x8000_0000 }
}

/// The `f32` of an [`order_key`].
fn from_order_key(k: u32) -> f32 {
    f32::from_bits(if k >> 31 == 1 { k & 0x7fff_ffff } else { !k })
}

/// Buckets of a histogram of 16 bits of [`order_key`]s.
const KEY_BUCKETS: usize = 1 << 16;

/// Per histogram h < `count`, the weights `w` summed per bucket of `sort(x, h)` (`None`: not
/// counted) over the triangles of `tris`, where `item(triangle)` gives (w, x); fixed chunks (by
/// the count alone) summed in order, so that the sums do not depend on the thread count.
fn histograms<T>(
    tris: &WorldTris,
    count: usize,
    item: &(impl Fn(&[Vec3; 3]) -> (f32, T) + Sync),
    sort: &(impl Fn(&T, usize) -> Option<usize> + Sync),
) -> Vec<Vec<f64>> {
    let chunk = tris.len().div_ceil(32).max(1 << 18);
    let parts: Vec<Vec<Vec<f64>>> = tris
        .chunks(chunk)
        .map(|range| {
            let mut h = vec![vec![0.0; KEY_BUCKETS]; count];
            tris.visit(range, |_, t, _| {
                let (w, x) = item(&t);
                for (k, h) in h.iter_mut().enumerate() {
                    if let Some(b) = sort(&x, k) {
                        h[b] += w as f64;
                    }
                }
            });
            h
        })
        .collect();
    let mut sum = vec![vec![0.0; KEY_BUCKETS]; count];
    for p in parts {
        for (s, p) in sum.iter_mut().zip(p) {
            s.iter_mut().zip(p).for_each(|(s, w)| *s += w);
        }
    }
    sum
}

/// Per axis, the 5th and 95th percentiles of the triangles' centroids weighted by √area: the
/// first value in ascending ([`f32::total_cmp`]) order at which the running sum of the weights
/// reaches that share of their total, as scanning the sorted (value, weight) pairs gives it.
/// Found without sorting: a histogram of the high 16 bits of the values' [`order_key`]s finds
/// the bucket where the sum crosses, one of the low 16 bits within it the value (all values of
/// a low bucket are the same value). Two passes over the triangles for the six.
fn centroid_percentiles(tris: &WorldTris) -> [[f32; 2]; 3] {
    const QS: [f64; 2] = [0.05, 0.95];
    let keys = |t: &[Vec3; 3]| {
        let c = (t[0] + t[1] + t[2]) / 3.0;
        (
            area(t).sqrt() + 1e-12,
            [order_key(c.x), order_key(c.y), order_key(c.z)],
        )
    };
    let high = histograms(tris, 3, &keys, &|k, axis| Some((k[axis] >> 16) as usize));
    // Where the running sum never reaches the target (a NaN weight): the largest value.
    let largest = |axis: usize| {
        from_order_key(
            tris.chunks(1 << 16)
                .map(|range| {
                    let mut m = 0;
                    tris.visit(range, |_, t, _| m = m.max(keys(&t).1[axis]));
                    m
                })
                .max()
                .unwrap_or(0),
        )
    };
    // Per (axis, q): the running sum before the candidate high bucket, the bucket, the target.
    let next = |axis: usize, from: usize, mut acc: f64, target: f64| {
        for (b, &w) in high[axis].iter().enumerate().skip(from) {
            if w > 0.0 && acc + w >= target {
                return Some((acc, b));
            }
            acc += w;
        }
        None
    };
    let mut out = [[0.0; 2]; 3];
    let mut open: Vec<(usize, usize, f64, usize, f64)> = vec![];
    for axis in 0..3 {
        let total: f64 = high[axis].iter().sum();
        for (k, q) in QS.into_iter().enumerate() {
            let target = q * total;
            match next(axis, 0, 0.0, target) {
                Some((acc, b)) if !target.is_nan() => open.push((axis, k, acc, b, target)),
                _ => out[axis][k] = largest(axis),
            }
        }
    }
    // Rounding (the sums go in another order) may carry a crossing into a later high bucket.
    while !open.is_empty() {
        let low = histograms(tris, open.len(), &keys, &|k, j| {
            let (axis, _, _, b, _) = open[j];
            ((k[axis] >> 16) as usize == b).then_some((k[axis] & 0xffff) as usize)
        });
        let mut still = vec![];
        for (&(axis, k, mut acc, b, target), low) in open.iter().zip(&low) {
            let found = low.iter().enumerate().find_map(|(l, &w)| {
                acc += w;
                (w > 0.0 && acc >= target).then_some(l)
            });
            match found {
                Some(l) => out[axis][k] = from_order_key(((b as u32) << 16) | l as u32),
                None => match next(axis, b + 1, acc, target) {
                    Some((acc, b)) => still.push((axis, k, acc, b, target)),
                    None => out[axis][k] = largest(axis),
                },
            }
        }
        open = still;
    }
    out
}

/// Bounds of the bulk of the geometry. Per axis, the 5th–95th percentile range of the triangle
/// centroids weighted by √area (so that neither a huge ground plane nor a dense small part
/// dominates), widened by half that range on each side, is the window; the bounds of the
/// triangles whose centroids fall in the window, clipped to it, are the result. A stray object
/// far away is left out; a lone object keeps its exact bounds.
pub fn robust_bounds(tris: &WorldTris) -> Bounds {
    robust_bounds_windowed(tris, tris)
}

/// Scenes of more triangles than this place [`robust_bounds`]'s window and pick their fit
/// points from a regular sample of [`SAMPLE`] of their triangles ([`regular_sample`]): at
/// 64 M triangles the four passes over every triangle that the window's percentiles and the
/// fit points take cost 1.5–2.5 s of the opening. The exact bounds and the triangles in the
/// window are still found over all of them.
pub const SAMPLE_FROM: usize = 1 << 22;

/// Triangles in the sample of a scene of more than [`SAMPLE_FROM`].
const SAMPLE: usize = 1 << 20;

/// Every step-th triangle of `tris` from the first, at most [`SAMPLE`] of them, where `tris`
/// has more than [`SAMPLE_FROM`]; else `None` (all of them count).
fn regular_sample(tris: &WorldTris) -> Option<WorldTris> {
    regular_sample_of(tris, SAMPLE_FROM, SAMPLE)
}

/// [`regular_sample`] with its two sizes.
fn regular_sample_of(tris: &WorldTris, from: usize, size: usize) -> Option<WorldTris> {
    let n = tris.len();
    if n <= from {
        return None;
    }
    let step = n.div_ceil(size);
    let picked: Vec<[Vec3; 3]> = (0..n.div_ceil(step))
        .into_par_iter()
        .map(|k| tris.get(k * step))
        .collect();
    Some(WorldTris::soup(&picked))
}

/// [`robust_bounds`] of `tris` with the window's percentiles found over `bulk` (`tris`
/// itself, or a sample of it).
fn robust_bounds_windowed(tris: &WorldTris, bulk: &WorldTris) -> Bounds {
    let union = |mut a: Bounds, b: Bounds| {
        if !b.is_empty() {
            a.grow(b.min);
            a.grow(b.max);
        }
        a
    };
    let exact = tris
        .chunks(1 << 16)
        .map(|range| {
            let mut b = Bounds::default();
            tris.visit(range, |_, t, _| t.iter().for_each(|v| b.grow(v.as_dvec3())));
            b
        })
        .reduce(Bounds::default, union);
    if tris.len() < 8 {
        return exact;
    }
    let centroid = |t: &[Vec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
    let mut lo = Vec3::ZERO;
    let mut hi = Vec3::ZERO;
    for (axis, [a, b]) in centroid_percentiles(bulk).into_iter().enumerate() {
        let margin = 0.5 * (b - a);
        lo[axis] = a - margin;
        hi[axis] = b + margin;
    }
    let bounds = tris
        .chunks(1 << 16)
        .map(|range| {
            let mut bounds = Bounds::default();
            tris.visit(range, |_, t, _| {
                let c = centroid(&t);
                if c.cmpge(lo).all() && c.cmple(hi).all() {
                    for v in t {
                        bounds.grow(v.clamp(lo, hi).as_dvec3());
                    }
                }
            });
            bounds
        })
        .reduce(Bounds::default, union);
    if bounds.is_empty() { exact } else { bounds }
}

/// Every step-th vertex inside `bounds` (all triangles' vertices in order), the step chosen
/// so that at most [`FIT_POINTS`] are kept. Counted in parallel chunks, each chunk then picking
/// the vertices whose rank among all those inside is a multiple of the step.
fn fit_points(all: &WorldTris, bounds: &Bounds) -> Vec<Vec3> {
    const CHUNK: usize = 1 << 16;
    let (lo, hi) = (bounds.min.as_vec3(), bounds.max.as_vec3());
    let inside = |p: &Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
    let counts: Vec<usize> = all
        .chunks(CHUNK)
        .map(|range| {
            let mut n = 0;
            all.visit(range, |_, t, _| n += t.iter().filter(|p| inside(p)).count());
            n
        })
        .collect();
    let step = counts.iter().sum::<usize>().div_ceil(FIT_POINTS).max(1);
    let starts: Vec<usize> = counts
        .iter()
        .scan(0, |acc, &c| {
            *acc += c;
            Some(*acc - c)
        })
        .collect();
    let picked: Vec<Vec<Vec3>> = all
        .chunks(CHUNK)
        .zip(starts)
        .map(|(range, start)| {
            // The chunk's inside vertices from rank `skip` on, every step-th.
            let skip = (step - start % step) % step;
            let (mut rank, mut out) = (0usize, vec![]);
            all.visit(range, |_, t, _| {
                for p in t.into_iter().filter(inside) {
                    if rank >= skip && (rank - skip) % step == 0 {
                        out.push(p);
                    }
                    rank += 1;
                }
            });
            out
        })
        .collect();
    picked.into_iter().flatten().collect()
}

impl Probe {
    /// Builds the probe for the visible geometry of `scene`: over quick BLASes of its distinct
    /// meshes and a top level ([`Tracer::TwoLevel`]), which [`Probe::keep_blases`] leaves in
    /// the scene for the renderer. Glass and blended surfaces
    /// are passed by the rays that light passes; they still count for the bounds and for
    /// telling an interior.
    pub fn new(scene: &Scene) -> Self {
        let t = std::time::Instant::now();
        let tris = WorldTris::new(scene.world_objects(&super::RenderFrame::default()));
        log::debug!(
            "probe: world vertices in {:.0} ms",
            t.elapsed().as_secs_f64() * 1e3
        );
        let t = std::time::Instant::now();
        let cpu = crate::cpu_time::process_cpu_seconds().unwrap_or(0.0);
        if tris.objects.iter().any(|o| o.kept.is_some()) {
            // Triangles were dropped: the meshes' triangles are not the world's.
            return Self::with_flat(scene, tris);
        }
        let objects: Vec<&super::Object> = scene
            .objects
            .iter()
            .filter(|o| o.visible && !o.mesh.indices.is_empty())
            .collect();
        let (distinct, mesh_of) = super::distinct_meshes(&objects);
        let meshes: Vec<Arc<Mesh>> = distinct.iter().map(|&o| objects[o].mesh.clone()).collect();
        // Several meshes at once, each in parallel within (a large mesh's sort and tree).
        let blases: Vec<Blas> = meshes
            .par_iter()
            .map(crate::bvh::quick_blas_shared)
            .collect();
        let instances: Vec<(u32, DMat4)> = objects
            .iter()
            .zip(&mesh_of)
            .map(|(o, &m)| (m, o.world_from_object))
            .collect();
        let hidden = vec![false; instances.len()];
        let two = TwoLevel::with_hidden(blases, &instances, hidden, 0);
        log::debug!(
            "probe: quick BLASes and top level in {:.0} ms ({:.2} CPU s)",
            t.elapsed().as_secs_f64() * 1e3,
            crate::cpu_time::process_cpu_seconds().unwrap_or(0.0) - cpu
        );
        Self::with_tracer(scene, Tracer::TwoLevel { two, meshes }, tris)
    }

    /// The probe over one quick tree of the world triangles ([`Tracer::Flat`]): how the first
    /// view was found before the two levels, and what it falls back to.
    pub fn flat(scene: &Scene) -> Self {
        Self::with_flat(
            scene,
            WorldTris::new(scene.world_objects(&super::RenderFrame::default())),
        )
    }

    fn with_flat(scene: &Scene, world: WorldTris) -> Self {
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
        Self::with_tracer(scene, Tracer::Flat { all, opaque }, world)
    }

    fn with_tracer(scene: &Scene, tracer: Tracer, tris: WorldTris) -> Self {
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
            see_through,
            any_opaque,
            tris,
            points,
            bounds,
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
    fn emission(&self, i: usize) -> f32 {
        self.emission
            .get(self.tris.material(i) as usize)
            .copied()
            .unwrap_or(0.0)
    }

    /// The closest triangle along a ray (with `any`, the first found) between `tmin` and
    /// `tmax`, see-through ones included unless `opaque`: (distance, index in `tris`).
    fn trace(&self, ray: &Ray, any: bool, opaque: bool) -> Option<(f32, usize)> {
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

    /// The closest triangle along a ray, glass included.
    fn hit_all(&self, origin: DVec3, dir: DVec3) -> Option<usize> {
        let ray = Ray {
            origin: origin.as_vec3(),
            direction: dir.as_vec3(),
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        self.trace(&ray, false, false).map(|h| h.1)
    }

    fn hit(&self, origin: DVec3, dir: DVec3, tmax: f64) -> Option<(f64, usize)> {
        let ray = Ray {
            origin: origin.as_vec3(),
            direction: dir.as_vec3(),
            tmin: 0.0,
            tmax: tmax as f32,
        };
        self.trace(&ray, false, true).map(|h| (h.0 as f64, h.1))
    }

    fn visible(&self, from: DVec3, to: DVec3) -> bool {
        let d = to - from;
        let ray = Ray {
            origin: from.as_vec3(),
            direction: d.as_vec3(),
            tmin: 1e-4,
            tmax: 0.999,
        };
        self.trace(&ray, true, true).is_none()
    }

    fn unobstructed(&self, from: DVec3, dir: DVec3) -> bool {
        let ray = Ray {
            origin: from.as_vec3(),
            direction: dir.as_vec3(),
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        self.trace(&ray, true, true).is_none()
    }

    /// The unit geometric normal of a triangle.
    fn normal(&self, prim: usize) -> DVec3 {
        let t = self.tris.get(prim);
        (t[1] - t[0])
            .cross(t[2] - t[0])
            .as_dvec3()
            .normalize_or(DVec3::Y)
    }

    fn scale(&self) -> f64 {
        self.bounds.diagonal().max(1e-6)
    }
}

/// Whether light passes each of `scene`'s materials (transmission or blending).
fn see_through_materials(scene: &Scene) -> Vec<bool> {
    scene
        .materials
        .iter()
        .map(|m| m.transmission > 0.0 || m.alpha == super::AlphaMode::Blend)
        .collect()
}

/// Unit directions spread evenly over the sphere (a Fibonacci lattice).
fn sphere_directions(n: usize) -> impl Iterator<Item = DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n).map(move |i| {
        let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - y * y).max(0.0).sqrt();
        let phi = golden * i as f64;
        DVec3::new(r * phi.cos(), y, r * phi.sin())
    })
}

/// What the rays from the middle of the bounds say about the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shell {
    /// Most rays hit surfaces that face the middle (walls seen from inside) and the openings
    /// are not all on one side: a room or a building, seen from inside.
    Interior,
    /// A box open on one side (a stage, the Cornell box): seen from that side, along this
    /// unit direction (from the middle outwards).
    OpenSide(DVec3),
    /// Anything else: framed from outside.
    Object,
}

/// Classifies the model by [`SHELL_RAYS`] rays from `point`. A surface seen from inside a room
/// faces the point; the shell of a closed object seen from within faces away, so only hits on
/// front faces count. At least [`INTERIOR_HIT_FRACTION`] of the rays must hit front faces; when
/// the rays that escape leave mostly sideways through one side (their mean direction is long and
/// near horizontal), the model is an open box instead.
pub fn classify_shell(probe: &Probe, point: DVec3) -> Shell {
    let (mut front, mut misses) = (0usize, 0usize);
    let mut escape = DVec3::ZERO;
    for d in sphere_directions(SHELL_RAYS) {
        match probe.hit_all(point, d) {
            Some(prim) if probe.normal(prim).dot(d) < 0.0 => front += 1,
            Some(_) => {}
            None => {
                escape += d;
                misses += 1;
            }
        }
    }
    if (front as f64) < INTERIOR_HIT_FRACTION * SHELL_RAYS as f64 {
        return Shell::Object;
    }
    let mean = escape / misses.max(1) as f64;
    let open = misses as f64 >= OPEN_SIDE_FRACTION * SHELL_RAYS as f64;
    if open && mean.length() > 0.6 && mean.normalize().y.abs() < 0.5 {
        Shell::OpenSide(mean.normalize())
    } else {
        Shell::Interior
    }
}

/// A horizontal unit direction at `azimuth` radians (0 = −Z, growing towards +X).
fn horizontal(azimuth: f64) -> DVec3 {
    DVec3::new(azimuth.sin(), 0.0, -azimuth.cos())
}

/// The camera inside a room: among a grid of standing points, the one with the most open space
/// around it at eye height; from there it looks along the longest open direction (averaged over
/// neighbouring directions so that a door does not win), stepped back towards the wall behind.
fn interior_camera(probe: &Probe) -> Option<Camera> {
    const AZIMUTHS: usize = 32;
    let b = probe.bounds;
    let size = b.max - b.min;
    let far = probe.scale();
    // Standing points: where a vertical ray finds a floor (the top of the bounds stands in for
    // a missing ceiling: models of flats are often open above).
    let mut spots = Vec::new();
    for i in 0..5 {
        for k in 0..5 {
            let fx = 0.2 + 0.15 * i as f64;
            let fz = 0.2 + 0.15 * k as f64;
            let top = DVec3::new(b.min.x + fx * size.x, b.center().y, b.min.z + fz * size.z);
            if let Some((down, _)) = probe.hit(top, DVec3::NEG_Y, far) {
                let up = probe
                    .hit(top, DVec3::Y, far)
                    .map_or(b.max.y - top.y, |h| h.0);
                spots.push((top.x, top.y - down, top.y + up, top.z));
            }
        }
    }
    // Stand on the lowest floor, not on tables or beds.
    let floor = spots.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
    let mut best: Option<(f64, DVec3, Vec<f64>)> = None;
    for &(x, bottom, ceiling, z) in &spots {
        let height = ceiling - bottom;
        if bottom > floor + 0.05 * height {
            continue;
        }
        // Metres, centimetres or millimetres, whichever makes a room height of it; else 60%.
        let eye_height = [1.0, 100.0, 1000.0]
            .into_iter()
            .find(|unit| (2.0..=5.0).contains(&(height / unit)))
            .map_or(0.6 * height, |unit| EYE_HEIGHT * unit);
        let eye = DVec3::new(x, bottom + eye_height, z);
        let distances: Vec<f64> = (0..AZIMUTHS)
            .map(|a| {
                let d = horizontal(a as f64 / AZIMUTHS as f64 * std::f64::consts::TAU);
                probe.hit(eye, d, far).map_or(far, |(t, _)| t)
            })
            .collect();
        let nearest = distances.iter().copied().fold(f64::INFINITY, f64::min);
        // Standing inside furniture or at a wall: skip.
        if nearest < 0.08 * height {
            continue;
        }
        let mean = distances.iter().sum::<f64>() / AZIMUTHS as f64;
        let score = mean + nearest;
        if best.as_ref().is_none_or(|(s, _, _)| score > *s) {
            best = Some((score, eye, distances));
        }
    }
    let (_, eye, distances) = best?;
    let n = distances.len();
    let smoothed =
        |a: usize| (distances[(a + n - 1) % n] + 2.0 * distances[a] + distances[(a + 1) % n]) / 4.0;
    let look = (0..n)
        .max_by(|&a, &b| smoothed(a).total_cmp(&smoothed(b)))
        .unwrap_or(0);
    let forward = horizontal(look as f64 / n as f64 * std::f64::consts::TAU);
    let behind = distances[(look + n / 2) % n];
    let eye = eye - forward * (0.6 * behind).min(behind - 0.3).max(0.0);
    // Look slightly down, at the floor's far half.
    let target = eye + forward * 10.0 - DVec3::Y * 1.2;
    Some(Camera::look_at(AUTO_CAMERA, eye, target, INTERIOR_YFOV))
}

/// Where each light comes from, seen from `point`, weighted by the irradiance it gives there
/// (unoccluded): (unit direction towards the light, weight).
fn light_directions(probe: &Probe, lights: &[Light], point: DVec3) -> Vec<(DVec3, f64)> {
    let mut out = Vec::new();
    for l in lights {
        let power = l.intensity as f64 * luminance(l.color) as f64;
        match l.kind {
            LightKind::Directional => out.push((-l.direction, power)),
            LightKind::Point | LightKind::Spot { .. } => {
                let to = l.position - point;
                let d2 = to.length_squared().max(1e-12);
                out.push((to / d2.sqrt(), power / d2));
            }
        }
    }
    for (centre, normal, power) in emitters(probe) {
        let to = centre - point;
        let d2 = to.length_squared().max(1e-12);
        let dir = to / d2.sqrt();
        out.push((dir, power * normal.dot(-dir).abs() / d2));
    }
    out
}

/// The most powerful emissive triangles: (centroid, unit normal, radiance × area), at most
/// [`MAX_EMITTERS`] (the first in scene order among equals), the power scaled up by the share
/// of all emitted power they leave out.
fn emitters(probe: &Probe) -> Vec<(DVec3, DVec3, f64)> {
    // Opaque triangles alone, in scene order: equally powerful emitters keep that order.
    let see_through = |m: u32| probe.see_through.get(m as usize).copied().unwrap_or(false);
    let emission = |m: u32| probe.emission.get(m as usize).copied().unwrap_or(0.0);
    let tris = &probe.tris;
    let mut all: Vec<(usize, f64)> = tris
        .chunks(1 << 16)
        .map(|range| {
            let mut out = vec![];
            tris.visit(range, |i, t, m| {
                if emission(m) > 0.0 && !see_through(m) {
                    let p = emission(m) as f64 * area(&t) as f64;
                    if p > 0.0 {
                        out.push((i, p));
                    }
                }
            });
            out
        })
        .flatten_iter()
        .collect();
    let total: f64 = all.iter().map(|e| e.1).sum();
    all.sort_by(|a, b| b.1.total_cmp(&a.1));
    all.truncate(MAX_EMITTERS);
    let kept: f64 = all.iter().map(|e| e.1).sum();
    let scale = if kept > 0.0 { total / kept } else { 1.0 };
    all.into_iter()
        .map(|(i, p)| {
            let t = probe.tris.get(i);
            let centre = ((t[0] + t[1] + t[2]) / 3.0).as_dvec3();
            (centre, probe.normal(i), p * scale)
        })
        .collect()
}

/// The view direction (from the subject towards the eye) from which the lights illuminate the
/// visible side: among 16 azimuths × 2 elevations, the one that best faces the light-weighted
/// directions, with smaller preferences for a broad side of the bounds (a fox from the side,
/// not nose-on) and for the glTF front (+Z).
pub fn lit_side(probe: &Probe, lights: &[Light]) -> DVec3 {
    let centre = probe.bounds.center();
    let e = (probe.bounds.max - probe.bounds.min).max(DVec3::ZERO);
    let (side_x, side_z) = (e.y * e.z, e.x * e.y);
    let largest = side_x.max(side_z).max(1e-30);
    let sources = light_directions(probe, lights, centre);
    let total: f64 = sources.iter().map(|s| s.1).sum();
    let front = DVec3::new(0.35, 0.3, 1.0).normalize();
    let mut best = (f64::NEG_INFINITY, front);
    for a in 0..16 {
        for elevation in [0.25f64, 0.5] {
            let az = a as f64 / 16.0 * std::f64::consts::TAU;
            let d = DVec3::new(
                elevation.cos() * az.sin(),
                elevation.sin(),
                elevation.cos() * az.cos(),
            );
            let lit: f64 = if total > 0.0 {
                sources
                    .iter()
                    .map(|(l, w)| w * d.dot(*l).max(0.0))
                    .sum::<f64>()
                    / total
            } else {
                0.0
            };
            // The projected area of the box's sides seen from d, relative to the larger side.
            let broad = (d.x.abs() * side_x + d.z.abs() * side_z) / largest;
            let score = lit + 0.3 * d.dot(front) + 0.4 * broad;
            if score > best.0 {
                best = (score, d);
            }
        }
    }
    best.1
}

/// A camera looking at the middle of `bounds` from direction `dir` (unit, subject to eye), at
/// the distance where all `points` fit 90% of the frame of `aspect` (width/height). With the
/// eight corners of the bounds as points the whole box fits; with the subject's vertices its
/// silhouette does, which fills the frame better.
pub fn fit(bounds: &Bounds, points: &[Vec3], dir: DVec3, yfov: f64, aspect: f64) -> Camera {
    let centre = bounds.center();
    let probe = Camera::look_at(AUTO_CAMERA, centre + dir, centre, yfov);
    let right = probe.forward.cross(probe.up).normalize();
    let tan_y = (yfov * 0.5).tan() * 0.9;
    let tan_x = tan_y * aspect.max(1e-3);
    let corners = (0..8).map(|i| {
        DVec3::new(
            if i & 1 == 0 {
                bounds.min.x
            } else {
                bounds.max.x
            },
            if i & 2 == 0 {
                bounds.min.y
            } else {
                bounds.max.y
            },
            if i & 4 == 0 {
                bounds.min.z
            } else {
                bounds.max.z
            },
        )
    });
    let all: Vec<DVec3> = if points.is_empty() {
        corners.collect()
    } else {
        points.iter().map(|p| p.as_dvec3()).collect()
    };
    let mut distance: f64 = 1e-6 * bounds.diagonal();
    for corner in all {
        let p = corner - centre;
        let depth = p.dot(probe.forward);
        distance = distance
            .max(p.dot(right).abs() / tan_x - depth)
            .max(p.dot(probe.up).abs() / tan_y - depth);
    }
    Camera::look_at(AUTO_CAMERA, centre + dir * distance, centre, yfov)
}

/// A primary ray through the pixel at fractions (fx, fy) of the image (0,0 = top left).
fn camera_ray(camera: &Camera, aspect: f64, fx: f64, fy: f64) -> DVec3 {
    let right = camera.forward.cross(camera.up).normalize();
    let h = (camera.yfov * 0.5).tan();
    (camera.forward + right * ((2.0 * fx - 1.0) * h * aspect) + camera.up * ((1.0 - 2.0 * fy) * h))
        .normalize()
}

/// Direct irradiance at `point` (unit normal `n` facing the viewer) from the lights and the
/// emitters, with visibility.
fn irradiance(
    probe: &Probe,
    lights: &[Light],
    emitters: &[(DVec3, DVec3, f64)],
    point: DVec3,
    n: DVec3,
) -> f64 {
    let eps = 1e-4 * probe.scale();
    let origin = point + n * eps;
    let mut e = 0.0;
    for l in lights {
        let power = l.intensity as f64 * luminance(l.color) as f64;
        match l.kind {
            LightKind::Directional => {
                let wi = -l.direction;
                let cos = n.dot(wi);
                if cos > 0.0 && probe.unobstructed(origin, wi) {
                    e += power * cos;
                }
            }
            LightKind::Point | LightKind::Spot { .. } => {
                let to = l.position - origin;
                let d2 = to.length_squared().max(1e-12);
                let wi = to / d2.sqrt();
                let cos = n.dot(wi);
                let cone = match l.kind {
                    LightKind::Spot { inner, outer } => {
                        let c = (-wi).dot(l.direction);
                        let (ci, co) = ((inner as f64).cos(), (outer as f64).cos());
                        ((c - co) / (ci - co).max(1e-6)).clamp(0.0, 1.0)
                    }
                    _ => 1.0,
                };
                if cos > 0.0 && cone > 0.0 && probe.visible(origin, l.position) {
                    e += power * cone * cos / d2;
                }
            }
        }
    }
    for &(centre, normal, power) in emitters {
        let to = centre - origin;
        let d2 = to.length_squared().max(1e-12);
        let wi = to / d2.sqrt();
        let cos = n.dot(wi);
        // Emissive triangles glow on both sides when double-sided; take the facing cosine.
        let cos_e = normal.dot(-wi).abs();
        if cos > 0.0 && probe.visible(origin, centre - wi * eps) {
            e += power * cos * cos_e / d2;
        }
    }
    e
}

/// The rule of the module docs, evaluated from `camera`, and how much sky the subject sees.
fn light_test(probe: &Probe, lights: &[Light], camera: &Camera, aspect: f64) -> LightTest {
    use rayon::prelude::*;
    let emitters = emitters(probe);
    let far = probe.scale() * 100.0 + (camera.eye - probe.bounds.center()).length() * 4.0;
    let sky: Vec<DVec3> = sphere_directions(SKY_RAYS).collect();
    // (direct irradiance and escaping hemisphere rays at a subject point, emitter radiance)
    type Sample = (Option<(f64, usize)>, Option<f64>);
    let samples: Vec<Sample> = (0..PROBE_COLUMNS * PROBE_ROWS)
        .into_par_iter()
        .map(|i| {
            let fx = ((i % PROBE_COLUMNS) as f64 + 0.5) / PROBE_COLUMNS as f64;
            let fy = ((i / PROBE_COLUMNS) as f64 + 0.5) / PROBE_ROWS as f64;
            let d = camera_ray(camera, aspect, fx, fy);
            let Some((t, prim)) = probe.hit(camera.eye, d, far) else {
                return (None, None);
            };
            if probe.emission(prim) > 0.0 {
                return (None, Some(probe.emission(prim) as f64));
            }
            let mut n = probe.normal(prim);
            if n.dot(d) > 0.0 {
                n = -n;
            }
            let point = camera.eye + d * t;
            let origin = point + n * (1e-4 * probe.scale());
            let escaping = sky
                .iter()
                .filter(|&&s| {
                    let s = if s.dot(n) < 0.0 { -s } else { s };
                    probe.hit(origin, s, far).is_none()
                })
                .count();
            (
                Some((irradiance(probe, lights, &emitters, point, n), escaping)),
                None,
            )
        })
        .collect();
    let escaping: usize = samples.iter().filter_map(|s| s.0).map(|(_, k)| k).sum();
    let mut subject: Vec<f64> = samples.iter().filter_map(|s| s.0).map(|(e, _)| e).collect();
    let mut seen: Vec<f64> = samples.iter().filter_map(|s| s.1).collect();
    let coverage = (subject.len() + seen.len()) as f64 / samples.len() as f64;
    if subject.is_empty() {
        return LightTest {
            lit: false,
            coverage,
            lit_fraction: 0.0,
            subject_radiance: 0.0,
            emitter_radiance: 0.0,
            sky_fraction: 0.0,
        };
    }
    let sky_fraction = escaping as f64 / (subject.len() * SKY_RAYS) as f64;
    let lit_fraction = subject.iter().filter(|&&e| e > 0.0).count() as f64 / subject.len() as f64;
    subject.sort_by(f64::total_cmp);
    seen.sort_by(f64::total_cmp);
    let subject_radiance = subject[subject.len() / 2] / std::f64::consts::PI;
    let emitter_radiance = if seen.is_empty() {
        0.0
    } else {
        seen[(seen.len() * 9 / 10).min(seen.len() - 1)]
    };
    let lit = lit_fraction >= MIN_LIT_FRACTION
        && subject_radiance > 0.0
        && subject_radiance >= emitter_radiance * 2f64.powf(-MAX_STOPS_BELOW_EMITTERS);
    LightTest {
        lit,
        coverage,
        lit_fraction,
        subject_radiance,
        emitter_radiance,
        sky_fraction,
    }
}

/// The first view of `scene` lit by `lights` (the scene's own, without a default rig), for an
/// image of `aspect` (width/height). `camera` is the scene's own camera when it has one: it is
/// kept ("a scene's camera wins") and only the light rule is evaluated from it. The probe's
/// quick BLASes stay in the scene for the renderer ([`Probe::keep_blases`]).
pub fn first_view(
    scene: &Scene,
    lights: &[Light],
    camera: Option<&Camera>,
    aspect: f64,
) -> FirstView {
    let _memory = crate::cl::kernels::OpeningMemory::begin();
    let probe = Probe::new(scene);
    let t = std::time::Instant::now();
    let view = first_view_with(&probe, lights, camera, aspect);
    log::debug!("probe: rays in {:.0} ms", t.elapsed().as_secs_f64() * 1e3);
    probe.keep_blases(scene);
    view
}

/// [`first_view`] with a probe already built.
pub fn first_view_with(
    probe: &Probe,
    lights: &[Light],
    camera: Option<&Camera>,
    aspect: f64,
) -> FirstView {
    let bounds = probe.bounds;
    let (camera, interior) = match camera {
        Some(c) => (c.clone(), false),
        None if !probe.any_opaque => (Camera::framing(&bounds, super::AUTO_YFOV), false),
        None => {
            let outside = |dir: DVec3| fit(&bounds, &probe.points, dir, super::AUTO_YFOV, aspect);
            match classify_shell(probe, bounds.center()) {
                Shell::Interior => match interior_camera(probe) {
                    Some(c) => (c, true),
                    None => (outside(lit_side(probe, lights)), false),
                },
                Shell::OpenSide(d) => {
                    // Straight into the opening, a little from above.
                    (outside((d + DVec3::Y * 0.15).normalize()), false)
                }
                Shell::Object => (outside(lit_side(probe, lights)), false),
            }
        }
    };
    let LightTest {
        lit,
        coverage,
        lit_fraction,
        subject_radiance,
        emitter_radiance,
        sky_fraction,
    } = light_test(probe, lights, &camera, aspect);
    FirstView {
        camera,
        bounds,
        interior,
        lit,
        coverage,
        lit_fraction,
        subject_radiance,
        emitter_radiance,
        sky_fraction,
    }
}

/// A light added by the user: a point light above and to the right of the camera, a third of
/// the way to what it looks at, so that it shows in the view and lights the subject with an
/// irradiance of about 1 (`distance` is the camera's distance to its subject).
pub fn light_near_camera(camera: &Camera, distance: f64, name: &str) -> Light {
    let distance = distance.max(1e-6);
    let right = camera.forward.cross(camera.up).normalize_or(DVec3::X);
    let position = camera.eye
        + camera.forward * (0.3 * distance)
        + camera.up * (0.12 * distance)
        + right * (0.12 * distance);
    let to_subject = camera.eye + camera.forward * distance - position;
    let d = to_subject.length();
    Light {
        name: name.into(),
        kind: LightKind::Point,
        position,
        direction: to_subject.normalize_or(DVec3::NEG_Y),
        color: [1.0, 1.0, 1.0],
        intensity: (d * d) as f32,
        light_radius: (0.02 * distance) as f32,
    }
}

/// Lights for an interior the scene's own lights leave dark: a lamp below the ceiling above the
/// camera and a softer one at the camera, both scaled to the room.
pub fn interior_lights(first: &FirstView) -> Vec<Light> {
    let b = first.bounds;
    let height = (b.max.y - b.min.y).max(1e-6);
    let span = (b.max - b.min).length();
    let ahead = first.camera.eye + first.camera.forward.with_y(0.0) * (0.15 * span);
    let ceiling = ahead.with_y(b.max.y - 0.1 * height).clamp(b.min, b.max);
    let mut lamp = light_near_camera(&first.camera, 0.25 * span, "room light");
    lamp.position = ceiling;
    lamp.direction = DVec3::NEG_Y;
    lamp.intensity = (0.25 * span * 0.25 * span) as f32;
    let fill = light_near_camera(&first.camera, 0.15 * span, "camera light");
    vec![lamp, fill]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Mesh, Object};
    use glam::DMat4;

    /// A box from `lo` to `hi` as 12 triangles; `inward` makes the faces look inside.
    fn cuboid(lo: Vec3, hi: Vec3, inward: bool) -> Vec<[Vec3; 3]> {
        let c = |i: usize| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        };
        // Quads as corner indices, counter-clockwise seen from outside.
        let quads = [
            [0, 2, 3, 1], // −Z
            [4, 5, 7, 6], // +Z
            [0, 4, 6, 2], // −X
            [1, 3, 7, 5], // +X
            [0, 1, 5, 4], // −Y
            [2, 6, 7, 3], // +Y
        ];
        let mut out = Vec::new();
        for q in quads {
            let (a, b, cc, d) = (c(q[0]), c(q[1]), c(q[2]), c(q[3]));
            if inward {
                out.push([a, cc, b]);
                out.push([a, d, cc]);
            } else {
                out.push([a, b, cc]);
                out.push([a, cc, d]);
            }
        }
        out
    }

    fn scene_of(parts: &[(Vec<[Vec3; 3]>, Material)]) -> Scene {
        let mut scene = Scene::default();
        for (i, (tris, material)) in parts.iter().enumerate() {
            let mut mesh = Mesh::default();
            for t in tris {
                let base = mesh.positions.len() as u32;
                mesh.positions.extend_from_slice(t);
                mesh.indices.push([base, base + 1, base + 2]);
                mesh.materials.push(i as u32);
            }
            scene.objects.push(Object {
                name: format!("part {i}"),
                world_from_object: DMat4::IDENTITY,
                visible: true,
                mesh: mesh.into(),
            });
            scene.materials.push(material.clone());
        }
        scene
    }

    fn point(position: DVec3, intensity: f32) -> Light {
        Light {
            name: "lamp".into(),
            kind: LightKind::Point,
            position,
            direction: DVec3::NEG_Y,
            color: [1.0; 3],
            intensity,
            light_radius: 0.0,
        }
    }

    /// A finely split unit cube (so percentiles see many triangles) at the origin.
    fn subject() -> Vec<[Vec3; 3]> {
        let mut tris = Vec::new();
        for i in 0..4 {
            for k in 0..4 {
                let lo = Vec3::new(i as f32 * 0.25 - 0.5, -0.5, k as f32 * 0.25 - 0.5);
                tris.extend(cuboid(lo, lo + Vec3::new(0.25, 1.0, 0.25), false));
            }
        }
        tris
    }

    #[test]
    fn robust_bounds_ignore_a_stray_far_object() {
        let mut tris = subject();
        tris.extend(cuboid(Vec3::splat(1000.0), Vec3::splat(1000.1), false));
        let b = robust_bounds(&WorldTris::soup(&tris));
        assert!((b.min - DVec3::splat(-0.5)).length() < 1e-6, "{b:?}");
        assert!((b.max - DVec3::splat(0.5)).length() < 1e-6, "{b:?}");
    }

    /// A large scene's window placed from a regular sample gives the bounds that all the
    /// triangles give: a floor of 20,000 triangles with a far-away speck, sampled down to 500
    /// (and, as a check that the sample matters, the window of the first 500 alone is wrong).
    #[test]
    fn a_sampled_window_gives_the_bounds_of_all_triangles() {
        let mut tris = vec![];
        for i in 0..100 {
            for j in 0..100 {
                let (x, z) = (i as f32 * 0.1, j as f32 * 0.1 + 0.02 * (i % 3) as f32);
                let (a, b) = (Vec3::new(x, 0.0, z), Vec3::new(x + 0.1, 0.0, z));
                let (c, d) = (Vec3::new(x, 0.0, z + 0.1), Vec3::new(x + 0.1, 0.3, z + 0.1));
                tris.push([a, b, c]);
                tris.push([b, d, c]);
            }
        }
        tris.push([
            Vec3::splat(1e6),
            Vec3::splat(1e6) + Vec3::X,
            Vec3::splat(1e6) + Vec3::Y,
        ]);
        let all = WorldTris::soup(&tris);
        assert!(regular_sample_of(&all, all.len(), 500).is_none());
        let sample = regular_sample_of(&all, 1000, 500).unwrap();
        assert!(sample.len() <= 500 && sample.len() >= 450);
        let exact = robust_bounds(&all);
        assert!(exact.max.x < 11.0 && exact.min.x == 0.0);
        assert_eq!(robust_bounds_windowed(&all, &sample), exact);
        let first = WorldTris::soup(&tris[..500]);
        assert_ne!(robust_bounds_windowed(&all, &first), exact);
    }

    /// The percentiles by histograms are those of sorting (value, weight) pairs and scanning
    /// them (how they were found before), ties, signs and zeros of both signs included.
    #[test]
    fn centroid_percentiles_are_those_of_a_sort() {
        fn by_sort(tris: &[[Vec3; 3]], axis: usize, q: f64) -> f32 {
            let mut v: Vec<(f32, f32)> = tris
                .iter()
                .map(|t| (((t[0] + t[1] + t[2]) / 3.0)[axis], area(t).sqrt() + 1e-12))
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let total: f64 = v.iter().map(|v| v.1 as f64).sum();
            let mut acc = 0.0;
            for &(x, w) in &v {
                acc += w as f64;
                if acc >= q * total {
                    return x;
                }
            }
            v.last().unwrap().0
        }
        // A fixed scramble of (triangle, draw) to [0, 1).
        let r = |i: usize, k: usize| ((i * 2654435761 + k * 40503) % 997) as f32 / 997.0;
        for n in [8, 100, 5000] {
            let tris: Vec<[Vec3; 3]> = (0..n)
                .map(|i| {
                    // Centroids on a coarse grid (many ties), some negative, some at ±0.
                    let y = if i % 7 == 0 {
                        -0.0
                    } else {
                        (r(i, 1) * 3.0).floor()
                    };
                    let c = Vec3::new((r(i, 0) * 8.0).floor() - 4.0, y, r(i, 2) * 1e3 - 500.0);
                    let a = Vec3::new((r(i, 3) * 4.0).floor() + 1.0, 0.0, (r(i, 4) * 2.0).floor());
                    let b = Vec3::new(0.0, (r(i, 5) * 4.0).floor() + 1.0, 1.0);
                    [c + a, c + b, c - a - b]
                })
                .collect();
            let soup = WorldTris::soup(&tris);
            for (axis, p) in centroid_percentiles(&soup).into_iter().enumerate() {
                for (k, q) in [0.05, 0.95].into_iter().enumerate() {
                    let expect = by_sort(&tris, axis, q);
                    assert_eq!(p[k].to_bits(), expect.to_bits(), "n {n} axis {axis} q {q}");
                }
            }
        }
    }

    #[test]
    fn a_small_model_fills_the_frame() {
        for size in [0.01f32, 1.0, 300.0] {
            let tris: Vec<[Vec3; 3]> = subject().iter().map(|t| t.map(|v| v * size)).collect();
            let b = robust_bounds(&WorldTris::soup(&tris));
            let cam = fit(&b, &[], DVec3::new(0.3, 0.4, 1.0).normalize(), 0.8, 1.6);
            // Project the corners: the widest one reaches 80–100% of the half-frame.
            let right = cam.forward.cross(cam.up);
            let tan_y = (cam.yfov * 0.5).tan();
            let mut fill = 0.0f64;
            for i in 0..8 {
                let p = DVec3::new(
                    if i & 1 == 0 { b.min.x } else { b.max.x },
                    if i & 2 == 0 { b.min.y } else { b.max.y },
                    if i & 4 == 0 { b.min.z } else { b.max.z },
                ) - cam.eye;
                let z = p.dot(cam.forward);
                assert!(z > 0.0);
                fill = fill
                    .max(p.dot(cam.up).abs() / (z * tan_y))
                    .max(p.dot(right).abs() / (z * tan_y * 1.6));
            }
            assert!((0.8..=0.901).contains(&fill), "size {size}: fill {fill}");
        }
    }

    #[test]
    fn the_view_faces_the_light() {
        let scene = scene_of(&[(subject(), Material::default())]);
        let probe = Probe::new(&scene);
        for light_dir in [DVec3::X, DVec3::NEG_Z, DVec3::new(-1.0, 0.5, 0.2)] {
            let lamp = point(light_dir.normalize() * 5.0, 25.0);
            let d = lit_side(&probe, &[lamp]);
            assert!(
                d.dot(light_dir.normalize()) > 0.6,
                "light from {light_dir}, view from {d}"
            );
        }
    }

    #[test]
    fn a_room_is_seen_from_inside_and_an_object_from_outside() {
        // A 6 × 2.7 × 4 m room with a table in it.
        let mut room = cuboid(Vec3::ZERO, Vec3::new(6.0, 2.7, 4.0), true);
        room.extend(cuboid(
            Vec3::new(2.5, 0.0, 1.5),
            Vec3::new(3.5, 0.75, 2.5),
            false,
        ));
        let scene = scene_of(&[(room, Material::default())]);
        let view = first_view(&scene, &[], None, 1.6);
        assert!(view.interior);
        let eye = view.camera.eye;
        assert!(
            (eye.y - EYE_HEIGHT).abs() < 1e-6 && eye.x > 0.0 && eye.x < 6.0 && eye.z > 0.0,
            "{eye} in {:?}",
            view.bounds
        );
        // It looks along the long (x) side of the room.
        assert!(
            view.camera.forward.x.abs() > 0.9,
            "{:?}",
            view.camera.forward
        );
        // The same box with faces out is a closed object: framed from outside.
        let closed = cuboid(Vec3::ZERO, Vec3::new(6.0, 2.7, 4.0), false);
        let view = first_view(&scene_of(&[(closed, Material::default())]), &[], None, 1.6);
        assert!(!view.interior);
        assert!(view.camera.eye.z > 4.0, "{}", view.camera.eye);
    }

    #[test]
    fn the_sky_reaches_into_a_room_without_a_ceiling_and_not_into_a_closed_one() {
        let camera = Camera::look_at(
            "inside",
            DVec3::new(0.5, 1.4, 1.5),
            DVec3::new(-0.5, 1.0, -2.0),
            0.9,
        );
        let mut room = cuboid(Vec3::new(-3.0, 0.0, -2.0), Vec3::new(3.0, 2.7, 2.0), true);
        let closed = first_view(
            &scene_of(&[(room.clone(), Material::default())]),
            &[],
            Some(&camera),
            1.5,
        );
        assert!(
            closed.coverage == 1.0 && closed.sky_fraction == 0.0,
            "{closed:?}"
        );
        assert!(!closed.environment_reaches());
        room.truncate(10); // the ceiling (+Y) is the last quad
        let open = first_view(
            &scene_of(&[(room, Material::default())]),
            &[],
            Some(&camera),
            1.5,
        );
        assert!(open.sky_fraction > 0.05, "{open:?}");
        assert!(open.environment_reaches());
    }

    #[test]
    fn a_lamp_over_the_subject_lights_the_view_and_a_tiny_glow_does_not() {
        let floor = vec![
            [
                Vec3::new(-5.0, -0.5, -5.0),
                Vec3::new(-5.0, -0.5, 5.0),
                Vec3::new(5.0, -0.5, 5.0),
            ],
            [
                Vec3::new(-5.0, -0.5, -5.0),
                Vec3::new(5.0, -0.5, 5.0),
                Vec3::new(5.0, -0.5, -5.0),
            ],
        ];
        let parts = [
            (subject(), Material::default()),
            (floor, Material::default()),
        ];
        let scene = scene_of(&parts);
        let lamp = point(DVec3::new(1.0, 4.0, 2.0), 20.0);
        let view = first_view(&scene, &[lamp], None, 1.5);
        assert!(view.lit, "{view:?}");
        assert!(view.coverage > 0.3, "{view:?}");
        let view = first_view(&scene, &[], None, 1.5);
        assert!(!view.lit && view.lit_fraction == 0.0, "{view:?}");

        // A small, very bright glowing cube inside a closed housing lights nothing.
        let glow_material = Material {
            emission: [500.0; 3],
            ..Material::default()
        };
        let glow = cuboid(Vec3::new(0.55, 0.2, 0.55), Vec3::new(0.6, 0.25, 0.6), false);
        let housing = cuboid(
            Vec3::new(0.52, 0.17, 0.52),
            Vec3::new(0.63, 0.28, 0.63),
            true,
        );
        let mut parts = parts.to_vec();
        parts.push((glow, glow_material));
        parts.push((
            housing.iter().map(|t| [t[0], t[2], t[1]]).collect(),
            Material::default(),
        ));
        let view = first_view(&scene_of(&parts), &[], None, 1.5);
        assert!(!view.lit, "{view:?}");
    }

    /// A room of shared meshes: a table mesh placed four times (scaled, rotated, mirrored),
    /// a glass pane, a glowing panel and a lamp-lit subject, with the placed objects' meshes
    /// shared as the importer shares them.
    fn instanced_room() -> Scene {
        let mut room = cuboid(Vec3::ZERO, Vec3::new(6.0, 2.7, 4.0), true);
        room.extend(cuboid(
            Vec3::new(0.2, 0.0, 0.2),
            Vec3::new(0.4, 2.0, 0.4),
            false,
        ));
        let table = cuboid(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 0.75, 0.5), false);
        let pane = cuboid(Vec3::new(4.0, 0.5, 3.0), Vec3::new(5.0, 2.0, 3.02), false);
        let panel = cuboid(Vec3::new(2.5, 2.6, 1.5), Vec3::new(3.5, 2.65, 2.5), false);
        let glass = Material {
            transmission: 1.0,
            ..Material::default()
        };
        let glow = Material {
            emission: [4.0; 3],
            ..Material::default()
        };
        let mut scene = scene_of(&[
            (room, Material::default()),
            (pane, glass),
            (panel, glow),
            (table, Material::default()),
        ]);
        let table = scene.objects[3].clone();
        let placements = [
            DMat4::from_translation(DVec3::new(1.5, 0.0, 1.0)),
            DMat4::from_translation(DVec3::new(4.5, 0.0, 1.2))
                * DMat4::from_rotation_y(0.7)
                * DMat4::from_scale(DVec3::new(1.3, 0.8, 0.6)),
            // Mirrored: its triangles' corners swap in world space.
            DMat4::from_translation(DVec3::new(2.0, 0.0, 3.0))
                * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)),
        ];
        scene.objects[3].world_from_object = DMat4::from_translation(DVec3::new(3.0, 0.0, 2.0));
        for (i, m) in placements.into_iter().enumerate() {
            scene.objects.push(Object {
                name: format!("table {i}"),
                world_from_object: m,
                ..table.clone()
            });
        }
        // A hidden one is left out of both.
        scene.objects.push(Object {
            name: "hidden".into(),
            world_from_object: DMat4::from_translation(DVec3::new(3.0, 1.5, 2.0)),
            visible: false,
            ..table
        });
        scene
    }

    /// The probe over quick BLASes and a top level finds, ray for ray, the triangle and
    /// distance that one tree over the world triangles finds (closest and any hit, with and
    /// without glass), and the same first view.
    #[test]
    fn the_two_level_probe_finds_what_one_tree_over_the_world_finds() {
        let scene = instanced_room();
        let two = Probe::new(&scene);
        let flat = Probe::flat(&scene);
        assert!(matches!(two.tracer, Tracer::TwoLevel { .. }));
        assert!(matches!(flat.tracer, Tracer::Flat { .. }));
        assert_eq!(two.tris.to_vecs(), flat.tris.to_vecs());
        let centre = DVec3::new(3.0, 1.2, 2.0);
        let mut hits = 0;
        for (k, d) in sphere_directions(2000).enumerate() {
            // From points all over the room, some inside the tables.
            let o = centre
                + DVec3::new(
                    (k % 7) as f64 - 3.0,
                    (k % 5) as f64 * 0.3 - 0.6,
                    (k % 3) as f64 - 1.0,
                ) * 0.5;
            let ray = Ray {
                origin: o.as_vec3(),
                direction: d.as_vec3(),
                tmin: 0.0,
                tmax: f32::INFINITY,
            };
            for (any, opaque) in [(false, false), (false, true), (true, true)] {
                let (a, b) = (two.trace(&ray, any, opaque), flat.trace(&ray, any, opaque));
                if any {
                    assert_eq!(a.is_some(), b.is_some(), "ray {k}");
                } else {
                    assert_eq!(a, b, "ray {k} opaque {opaque}");
                    hits += a.is_some() as usize;
                }
            }
        }
        assert!(hits > 3000, "{hits}");
        let lamp = point(DVec3::new(3.0, 2.2, 2.0), 5.0);
        for lights in [vec![], vec![lamp]] {
            let a = first_view_with(&two, &lights, None, 1.6);
            let b = first_view_with(&flat, &lights, None, 1.6);
            assert_eq!(format!("{a:?}"), format!("{b:?}"));
        }
        assert!(first_view_with(&two, &[], None, 1.6).interior);
    }

    /// The probe's world triangles, read from each object's vertices, are those of
    /// [`Scene::flatten`] one by one (vertices, material, order), mirrored and hidden objects
    /// and a dropped triangle (an absurd vertex) included; reads by index and by range agree.
    #[test]
    fn world_triangles_are_the_flattened_ones() {
        let mut scene = instanced_room();
        let mut far = (*scene.objects[1].mesh).clone();
        far.positions[0] = Vec3::splat(1e38);
        scene.objects[1].mesh = Arc::new(far);
        scene.objects[1].world_from_object = DMat4::from_scale(DVec3::splat(1e10));
        let frame = crate::scene::RenderFrame::default();
        let flat = scene.flatten(&frame);
        assert!(flat.dropped > 0);
        let world = WorldTris::new(scene.world_objects(&frame));
        let (tris, materials) = world.to_vecs();
        assert_eq!(tris.len(), flat.triangles.len());
        for (i, t) in flat.triangles.iter().enumerate() {
            assert_eq!((tris[i], materials[i]), (t.v, t.material), "triangle {i}");
            assert_eq!((world.get(i), world.material(i)), (t.v, t.material));
        }
        let mut seen = vec![];
        world.visit(5..tris.len() - 3, |i, t, _| seen.push((i, t)));
        let expect: Vec<_> = (5..tris.len() - 3).map(|i| (i, tris[i])).collect();
        assert_eq!(seen, expect);
    }

    /// The first view leaves its quick BLASes in the scene, one per distinct visible mesh,
    /// and the renderer's plan takes them for those meshes.
    #[test]
    fn the_first_view_leaves_its_quick_blases_for_the_renderer() {
        let scene = instanced_room();
        first_view(&scene, &[], None, 1.6);
        let kept = scene.take_quick_blases();
        assert_eq!(kept.len(), 4);
        for (mesh, blas) in &kept {
            let fresh = crate::bvh::quick_blas(&mesh.positions, &mesh.indices);
            assert!(blas.triangles().eq(fresh.triangles()));
            assert!(scene.objects.iter().any(|o| Arc::ptr_eq(&o.mesh, mesh)));
        }
        assert!(scene.take_quick_blases().is_empty());
    }

    #[test]
    fn an_added_light_shows_in_view_near_the_camera() {
        let cam = Camera::look_at("c", DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO, 0.8);
        let l = light_near_camera(&cam, 10.0, "added");
        let p = l.position - cam.eye;
        let z = p.dot(cam.forward);
        assert!(z > 0.0 && z < 5.0, "{p}");
        // Inside the field of view.
        assert!(p.dot(cam.up).abs() / z < (0.4f64).tan(), "{p}");
        // Irradiance about 1 at the subject.
        let d2 = (l.position - DVec3::ZERO).length_squared();
        assert!((l.intensity as f64 / d2 - 1.0).abs() < 1e-3);
    }
}
