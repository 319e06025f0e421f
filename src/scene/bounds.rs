//! Robust scene bounds and the render frame: the f64 translation and power-of-two scale that
//! take world space to the space the device sees, so that the region being rendered keeps full
//! f32 precision wherever the model sits and whatever its units.

use super::{Bounds, Camera, Light, LightKind, Material};
use glam::{DVec3, Vec3};

/// World coordinates beyond this magnitude (or non-finite) are absurd: their triangles are
/// dropped when the scene is flattened (f32 squares of them overflow).
pub const ABSURD_COORDINATE: f64 = 1e30;

/// Whether a world-space point can be rendered at all.
pub fn is_sane(p: DVec3) -> bool {
    p.is_finite() && p.abs().max_element() <= ABSURD_COORDINATE
}

/// Bounds that a few far-away triangles do not blow up: the box of the triangles whose
/// centroids lie within the quartile box of all centroids (per axis, by count) grown by 64
/// times its size (at least the median triangle's) on each side. Every triangle of an ordinary
/// scene passes, so its bounds are exact; a lone object at 10^20 next to a 1-unit scene is left
/// out (it is still rendered, but framing, the light radius and the light table ignore it).
/// Triangles with absurd vertices never count.
pub fn robust_bounds(triangles: &[[DVec3; 3]]) -> Bounds {
    robust_bounds_of(1, &|_| triangles.iter().copied())
}

/// [`robust_bounds`] of the triangles of `parts` parts, `part(k)` yielding part k's in order
/// (called three times per part, parts in parallel), without keeping them: scenes pass their
/// placed triangles transformed on the fly, object by object. The result is that of
/// [`robust_bounds`] over the parts' triangles one after the other.
pub fn robust_bounds_of<I: Iterator<Item = [DVec3; 3]>>(
    parts: usize,
    part: &(dyn Fn(usize) -> I + Sync),
) -> Bounds {
    use rayon::prelude::*;
    let sane = |k: usize| part(k).filter(|t| t.iter().all(|&p| is_sane(p)));
    let counts: Vec<usize> = (0..parts)
        .into_par_iter()
        .map(|k| sane(k).count())
        .collect();
    let count: usize = counts.iter().sum();
    let mut b = Bounds::default();
    if count == 0 {
        return b;
    }
    // Quartiles and the median extent from a regular sample of at most 2^14 triangles:
    // they only place the outlier box, which is 64 scene sizes wide on each side (a quartile
    // of 16 K samples is within about 1 % of the box's width of the true one), and a full sort
    // of every coordinate cost ~0.3 s per call on a 1 M-triangle scene. The sample is every
    // step-th sane triangle of all parts in order (512 KB; 2^16 made this pass the peak of
    // opening a 1 M-triangle room of 20 K distinct triangles, 3 MB).
    let step = count.div_ceil(1 << 14);
    let starts: Vec<usize> = counts
        .iter()
        .scan(0, |acc, &c| {
            *acc += c;
            Some(*acc - c)
        })
        .collect();
    let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
    // Each sampled triangle as its centroid and its largest extent (32 bytes, not 72).
    let sample: Vec<Vec<(DVec3, f64)>> = (0..parts)
        .into_par_iter()
        .map(|k| {
            let skip = (step - starts[k] % step) % step;
            sane(k)
                .skip(skip)
                .step_by(step)
                .map(|t| {
                    let (a, b) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                    (centroid(&t), (b - a).max_element())
                })
                .collect()
        })
        .collect();
    let sampled = || sample.iter().flatten();
    let rank = |len: usize, q: f64| ((len - 1) as f64 * q).round() as usize;
    let quantile = |mut v: Vec<f64>, q: f64| {
        let k = rank(v.len(), q);
        *v.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let (mut lo, mut hi) = (DVec3::ZERO, DVec3::ZERO);
    let mut c: Vec<f64> = Vec::with_capacity(sample.iter().map(Vec::len).sum());
    for axis in 0..3 {
        c.clear();
        c.extend(sampled().map(|s| s.0[axis]));
        // The upper quartile is the smallest of what the lower one's selection left above it.
        let (k, m) = (rank(c.len(), 0.25), rank(c.len(), 0.75));
        let (_, &mut q1, above) = c.select_nth_unstable_by(k, f64::total_cmp);
        lo[axis] = q1;
        hi[axis] = if m == k {
            q1
        } else {
            *above.select_nth_unstable_by(m - k - 1, f64::total_cmp).1
        };
    }
    drop(c);
    let size = (hi - lo)
        .max_element()
        .max(quantile(sampled().map(|s| s.1).collect(), 0.5));
    drop(sample);
    let (lo, hi) = (
        lo - DVec3::splat(64.0 * size),
        hi + DVec3::splat(64.0 * size),
    );
    let grown: Vec<Bounds> = (0..parts)
        .into_par_iter()
        .map(|k| {
            let mut b = Bounds::default();
            for t in sane(k) {
                let c = centroid(&t);
                if c.cmpge(lo).all() && c.cmple(hi).all() {
                    t.iter().for_each(|&p| b.grow(p));
                }
            }
            b
        })
        .collect();
    for g in grown {
        if !g.is_empty() {
            b.grow(g.min);
            b.grow(g.max);
        }
    }
    b
}

/// The map from world space (f64) to render space (f32): `(p - origin) * scale`. `origin`
/// lies on a grid as coarse as the scene, `scale` is a power of two that brings the scene's
/// size to between 1/2 and 1, so moving a scene by a multiple of the grid or scaling it by a
/// power of two gives the device the same numbers, and everything the kernels compute happens
/// at scale 1 near the origin whatever the scene's units and position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderFrame {
    /// World point that becomes the render-space origin.
    pub origin: DVec3,
    /// Render units per world unit (a power of two).
    pub scale: f64,
}

impl Default for RenderFrame {
    fn default() -> Self {
        Self {
            origin: DVec3::ZERO,
            scale: 1.0,
        }
    }
}

impl RenderFrame {
    /// The frame for a scene of `bounds`, centred on `center` (the scene's middle, or the
    /// viewer's eye after it travelled far) snapped to the scene-sized grid.
    pub fn new(bounds: &Bounds, center: DVec3) -> Self {
        let size = if bounds.is_empty() {
            1.0
        } else {
            (bounds.max - bounds.min).max_element()
        };
        let size = if size.is_finite() && size > 0.0 {
            size
        } else {
            1.0
        };
        let grid = 2f64.powi(size.log2().ceil().clamp(-1000.0, 1000.0) as i32);
        let center = if center.is_finite() {
            center
        } else {
            DVec3::ZERO
        };
        Self {
            origin: (center / grid + 0.5).floor() * grid,
            scale: 1.0 / grid,
        }
    }

    /// The frame for a scene of `bounds` around its middle.
    pub fn around(bounds: &Bounds) -> Self {
        Self::new(bounds, bounds.center())
    }

    /// A world point in render space.
    pub fn point(&self, p: DVec3) -> Vec3 {
        ((p - self.origin) * self.scale).as_vec3()
    }

    /// A render-space point in world space.
    pub fn world_point(&self, p: Vec3) -> DVec3 {
        p.as_dvec3() / self.scale + self.origin
    }

    /// A world length in render units.
    pub fn length(&self, d: f64) -> f32 {
        (d * self.scale) as f32
    }

    /// Whether `eye` has travelled so far from the origin (64 scene sizes) that the frame
    /// should be rebuilt around it.
    pub fn is_far(&self, eye: DVec3) -> bool {
        ((eye - self.origin) * self.scale).abs().max_element() > 64.0
    }

    /// The camera in render space.
    pub fn camera(&self, c: &Camera) -> Camera {
        Camera {
            eye: (c.eye - self.origin) * self.scale,
            ..c.clone()
        }
    }

    /// A render-space camera in world space (inverse of [`RenderFrame::camera`]).
    pub fn world_camera(&self, c: &Camera) -> Camera {
        Camera {
            eye: c.eye / self.scale + self.origin,
            ..c.clone()
        }
    }

    /// Render-space bounds in world space.
    pub fn world_bounds(&self, b: &Bounds) -> Bounds {
        Bounds {
            min: b.min / self.scale + self.origin,
            max: b.max / self.scale + self.origin,
        }
    }

    /// Lights in render space: positions and radii move and scale; point and spot intensities
    /// scale by scale², so the irradiance I / d² they give stays the same (directional
    /// irradiance and angular radii do not change).
    pub fn lights(&self, lights: &[Light]) -> Vec<Light> {
        lights
            .iter()
            .map(|l| {
                let directional = l.kind == LightKind::Directional;
                Light {
                    position: (l.position - self.origin) * self.scale,
                    intensity: if directional {
                        l.intensity
                    } else {
                        (l.intensity as f64 * self.scale * self.scale) as f32
                    },
                    light_radius: if directional {
                        l.light_radius
                    } else {
                        self.length(l.light_radius as f64)
                    },
                    ..l.clone()
                }
            })
            .collect()
    }

    /// A material in render space: its volume's lengths scale.
    pub fn material(&self, m: &Material) -> Material {
        Material {
            thickness: self.length(m.thickness as f64),
            attenuation_distance: self.length(m.attenuation_distance as f64),
            ..m.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(center: DVec3, size: f64) -> Vec<[DVec3; 3]> {
        let h = 0.5 * size;
        (0..12)
            .map(|i| {
                let s = if i % 2 == 0 { h } else { -h };
                [
                    center + DVec3::new(s, -h, -h),
                    center + DVec3::new(-s, h, -h),
                    center + DVec3::new(h, h, s),
                ]
            })
            .collect()
    }

    #[test]
    fn bounds_by_parts_equal_the_bounds_of_all_triangles() {
        // Enough triangles for a sampled quartile box (step > 1), uneven parts, a far outlier
        // and an absurd triangle.
        let mut parts: Vec<Vec<[DVec3; 3]>> = (0..7)
            .map(|k| {
                (0..(3000 * k * k + 17))
                    .flat_map(|i| cube(DVec3::new(i as f64 * 0.01, k as f64, 0.5), 0.3))
                    .collect()
            })
            .collect();
        parts[3].extend(cube(DVec3::splat(1e20), 1.0));
        parts[5].push([DVec3::splat(f64::NAN); 3]);
        let all: Vec<[DVec3; 3]> = parts.iter().flatten().copied().collect();
        assert!(all.len() > 2 << 16);
        let whole = robust_bounds(&all);
        assert!(whole.max.x < 1e4, "the outlier is left out: {whole:?}");
        let by_parts = robust_bounds_of(parts.len(), &|k| parts[k].iter().copied());
        assert_eq!(by_parts, whole);
    }

    #[test]
    fn a_scenes_remembered_bounds_follow_its_objects() {
        use super::super::{Mesh, Object, Scene};
        let mesh = |center: DVec3| {
            let t = cube(center, 1.0);
            let t: Vec<[glam::Vec3; 3]> = t.iter().map(|t| t.map(|p| p.as_vec3())).collect();
            std::sync::Arc::new(Mesh::soup(&t))
        };
        let object = |m| Object {
            name: "cube".into(),
            world_from_object: glam::DMat4::IDENTITY,
            visible: true,
            mesh: m,
        };
        let mut scene = Scene {
            objects: vec![object(mesh(DVec3::ZERO)), object(mesh(DVec3::X * 3.0))],
            ..Scene::default()
        };
        let fresh = |s: &Scene| {
            let clone = Scene {
                bounds_cache: Default::default(),
                ..s.clone()
            };
            clone.bounds()
        };
        let first = scene.bounds();
        assert_eq!(scene.bounds(), first);
        assert_eq!(first.max.x, 3.5);
        // Moved, hidden, given another mesh: each time the bounds of a fresh computation.
        scene.objects[1].world_from_object = glam::DMat4::from_translation(DVec3::Y * 2.0);
        assert_eq!(scene.bounds(), fresh(&scene));
        assert_eq!(scene.bounds().max.y, 2.5);
        scene.objects[1].visible = false;
        assert_eq!(scene.bounds(), fresh(&scene));
        assert_eq!(scene.bounds().max.x, 0.5);
        scene.objects[0].mesh = mesh(DVec3::Z * -4.0);
        assert_eq!(scene.bounds(), fresh(&scene));
        assert_eq!(scene.bounds().min.z, -4.5);
    }

    #[test]
    fn robust_bounds_are_exact_for_an_ordinary_scene() {
        let t = cube(DVec3::new(1.0, 2.0, 3.0), 2.0);
        let mut exact = Bounds::default();
        t.iter().flatten().for_each(|&p| exact.grow(p));
        assert_eq!(robust_bounds(&t), exact);
    }

    #[test]
    fn a_far_object_and_absurd_vertices_do_not_move_the_bounds() {
        let mut t = Vec::new();
        for i in 0..20 {
            t.extend(cube(DVec3::new(i as f64, 0.0, 0.0), 1.0));
        }
        let expected = robust_bounds(&t);
        t.extend(cube(DVec3::new(1e20, 0.0, 0.0), 1.0));
        t.push([DVec3::splat(f64::NAN), DVec3::ZERO, DVec3::ONE]);
        t.push([DVec3::splat(1e38), DVec3::ZERO, DVec3::ONE]);
        assert_eq!(robust_bounds(&t), expected);
        assert!(expected.max.x < 25.0);
    }

    #[test]
    fn frames_give_the_same_render_space_when_moved_by_the_grid_or_scaled_by_two() {
        let b = Bounds {
            min: DVec3::new(-1.0, 0.0, -1.0),
            max: DVec3::new(1.0, 2.0, 1.0),
        };
        let f = RenderFrame::around(&b);
        assert_eq!(f.scale, 0.5);
        let p = DVec3::new(0.3, 1.7, -0.9);
        let shift = DVec3::new(1e7, -3e6, 1e5);
        let moved = Bounds {
            min: b.min + shift,
            max: b.max + shift,
        };
        assert_eq!(RenderFrame::around(&moved).point(p + shift), f.point(p));
        let scaled = Bounds {
            min: b.min * 1024.0,
            max: b.max * 1024.0,
        };
        assert_eq!(RenderFrame::around(&scaled).point(p * 1024.0), f.point(p));
        assert!((f.world_point(f.point(p)) - p).length() < 1e-6);
        assert!(!f.is_far(DVec3::new(100.0, 0.0, 0.0)));
        assert!(f.is_far(DVec3::new(1000.0, 0.0, 0.0)));
    }
}
