//! Robust bounds of the subject (the bulk of the geometry, without a stray far object) and the
//! vertices in them that the view is fitted to. Per axis, percentiles of the triangles'
//! centroids place a window; the triangles in it give the bounds. Large scenes place the
//! window from a regular sample of their triangles. Not [`crate::scene::robust_bounds`], the
//! scene's outlier-proof box of every triangle, which keeps all of an ordinary scene.

use super::super::Bounds;
use super::{WorldTris, area};
use glam::Vec3;
use rayon::prelude::*;

/// Vertices kept for fitting the view to the subject's silhouette.
pub const FIT_POINTS: usize = 8192;

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
pub(super) fn centroid_percentiles(tris: &WorldTris) -> [[f32; 2]; 3] {
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
/// points from a regular sample of `SAMPLE` of their triangles (`regular_sample`): at
/// 64 M triangles the four passes over every triangle that the window's percentiles and the
/// fit points take cost 1.5–2.5 s of the opening. The exact bounds and the triangles in the
/// window are still found over all of them.
pub const SAMPLE_FROM: usize = 1 << 22;

/// Triangles in the sample of a scene of more than [`SAMPLE_FROM`].
const SAMPLE: usize = 1 << 20;

/// Every step-th triangle of `tris` from the first, at most `SAMPLE` of them, where `tris`
/// has more than [`SAMPLE_FROM`]; else `None` (all of them count).
pub(super) fn regular_sample(tris: &WorldTris) -> Option<WorldTris> {
    regular_sample_of(tris, SAMPLE_FROM, SAMPLE)
}

/// `regular_sample` with its two sizes.
pub(super) fn regular_sample_of(tris: &WorldTris, from: usize, size: usize) -> Option<WorldTris> {
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
pub(super) fn robust_bounds_windowed(tris: &WorldTris, bulk: &WorldTris) -> Bounds {
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
    // Clipped on the axes where the window has a width; where every centroid in it sits at
    // one coordinate (coincident triangles, or a floor's height), the triangles keep their
    // own extent, which a window of no width would clip to a point.
    let (mut clip_lo, mut clip_hi) = (Vec3::NEG_INFINITY, Vec3::INFINITY);
    for (axis, [a, b]) in centroid_percentiles(bulk).into_iter().enumerate() {
        let margin = 0.5 * (b - a);
        lo[axis] = a - margin;
        hi[axis] = b + margin;
        if margin > 0.0 {
            (clip_lo[axis], clip_hi[axis]) = (lo[axis], hi[axis]);
        }
    }
    let bounds = tris
        .chunks(1 << 16)
        .map(|range| {
            let mut bounds = Bounds::default();
            tris.visit(range, |_, t, _| {
                let c = centroid(&t);
                if c.cmpge(lo).all() && c.cmple(hi).all() {
                    for v in t {
                        bounds.grow(v.clamp(clip_lo, clip_hi).as_dvec3());
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
pub(super) fn fit_points(all: &WorldTris, bounds: &Bounds) -> Vec<Vec3> {
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
