//! Choosing a node's split by the surface area heuristic: the primitives' boxes the builder
//! works on, an exact sweep over the sorted centroids for the smallest nodes, binning for the
//! rest (8 bins up to 256 primitives, else 16; large nodes binned in parallel chunks and the
//! bins reduced), and the partition of the primitives (large nodes in parallel chunks, the
//! misplaced runs swapped in parallel).

use super::Aabb;
use glam::{BVec4A, Vec4};
use rayon::prelude::*;

/// Bins per axis of large nodes.
const BINS: usize = 16;
/// Bins per axis of nodes of at most [`FEW_BINS_MAX`] primitives: 8 there cost 0.2 % of SAH on
/// the 1 M-triangle room and save ~10 % of the build; up to 512 primitives they cost 2.8 %.
const FEW_BINS: usize = 8;
/// Largest node binned with [`FEW_BINS`].
const FEW_BINS_MAX: usize = 256;
/// Nodes binned with two sets of bins (see [`Binning::bin`]) have at least this many primitives.
const TWO_BIN_SETS_MIN: usize = 256;
/// Nodes of at most this many primitives are split by a full SAH sweep over their sorted
/// centroids instead of bins.
const SWEEP_MAX: usize = 4;
/// Largest leaf the SAH may choose.
const MAX_LEAF: usize = 8;
/// Relative cost of one traversal step against one triangle test.
pub(super) const TRAVERSAL_COST: f32 = 1.0;
/// Deepest leaf the builder makes. The kernels' stack holds 64 entries and a traversal pushes
/// at most one entry per level, so the stack cannot overflow; deeper subtrees become leaves.
pub const MAX_DEPTH: u32 = 48;
/// Nodes with at least this many primitives bin and partition them in parallel chunks.
const PARALLEL_SPLIT_THRESHOLD: usize = 1 << 16;
/// Smallest chunk of a parallel binning or partition.
const MIN_CHUNK: usize = 1 << 14;

/// A primitive's box: `min.w` holds the triangle index (u32 bits), `max.w` is 0.
#[derive(Clone, Copy)]
pub(super) struct Prim {
    min: Vec4,
    max: Vec4,
}

impl Prim {
    /// Primitive `index` with box `b` (the index rides in `min.w`).
    pub(super) fn new(index: usize, b: Aabb) -> Self {
        Prim {
            min: b.min.extend(f32::from_bits(index as u32)),
            max: b.max.extend(0.0),
        }
    }

    /// Twice the box centre (`.w` = 0): the builder bins and partitions on `min + max`, which
    /// needs no multiply. The index bits in `min.w` are a denormal float and SIMD arithmetic
    /// on denormals is many times slower, so that lane is cleared first (a mask, no arithmetic).
    fn centroid2(&self) -> Vec4 {
        xyz(self.min) + self.max
    }

    pub(super) fn index(&self) -> u32 {
        self.min.w.to_bits()
    }
}

/// A box in SIMD lanes (`.w` ignored).
#[derive(Clone, Copy)]
pub(super) struct Bounds4 {
    min: Vec4,
    max: Vec4,
}

impl Bounds4 {
    const EMPTY: Bounds4 = Bounds4 {
        min: Vec4::splat(f32::INFINITY),
        max: Vec4::splat(f32::NEG_INFINITY),
    };

    fn grow(&mut self, min: Vec4, max: Vec4) {
        self.min = self.min.min(min);
        self.max = self.max.max(max);
    }

    fn union(self, o: Bounds4) -> Bounds4 {
        Bounds4 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub(super) fn aabb(self) -> Aabb {
        Aabb {
            min: self.min.truncate(),
            max: self.max.truncate(),
        }
    }
}

/// What the builder knows about a node before splitting it: the box of its primitives and the
/// box of their centroids (doubled, as [`Prim::centroid2`] gives them).
#[derive(Clone, Copy)]
pub(super) struct NodeInfo {
    pub(super) bounds: Bounds4,
    centroids: Bounds4,
}

impl NodeInfo {
    const EMPTY: NodeInfo = NodeInfo {
        bounds: Bounds4::EMPTY,
        centroids: Bounds4::EMPTY,
    };

    fn add(&mut self, p: &Prim) {
        self.add_with(p, p.centroid2());
    }

    /// [`NodeInfo::add`] with the primitive's [`Prim::centroid2`] already known.
    fn add_with(&mut self, p: &Prim, centroid2: Vec4) {
        self.bounds.grow(p.min, p.max);
        self.centroids.grow(centroid2, centroid2);
    }

    fn union(self, o: NodeInfo) -> NodeInfo {
        NodeInfo {
            bounds: self.bounds.union(o.bounds),
            centroids: self.centroids.union(o.centroids),
        }
    }

    pub(super) fn of(prims: &[Prim]) -> NodeInfo {
        let fold = |prims: &[Prim]| {
            prims.iter().fold(NodeInfo::EMPTY, |mut i, p| {
                i.add(p);
                i
            })
        };
        if prims.len() >= PARALLEL_SPLIT_THRESHOLD {
            prims
                .par_chunks(MIN_CHUNK)
                .map(fold)
                .reduce(|| NodeInfo::EMPTY, NodeInfo::union)
        } else {
            fold(prims)
        }
    }
}

/// A decided split: the first `at` primitives go left.
pub(super) struct Split {
    pub(super) at: usize,
    pub(super) left: NodeInfo,
    pub(super) right: NodeInfo,
}

/// Decides how to split a node, partitioning its primitives; `None` makes it a leaf.
pub(super) fn decide(prims: &mut [Prim], info: NodeInfo, depth: u32) -> Option<Split> {
    let n = prims.len();
    if n <= 1 || depth >= MAX_DEPTH {
        return None;
    }
    let found = if n <= SWEEP_MAX {
        split_sweep(prims, info)
    } else if n <= FEW_BINS_MAX {
        split_binned::<FEW_BINS>(prims, info)
    } else {
        split_binned::<BINS>(prims, info)
    };
    match found {
        Found::Split(split) => Some(split),
        Found::Leaf => None,
        Found::Flat if n <= MAX_LEAF => None,
        // All centroids coincide: split in the middle of the list.
        Found::Flat => {
            let at = n / 2;
            let (l, r) = prims.split_at(at);
            Some(Split {
                at,
                left: NodeInfo::of(l),
                right: NodeInfo::of(r),
            })
        }
    }
}

/// What a split search found.
enum Found {
    /// A split, the primitives already partitioned.
    Split(Split),
    /// No split is cheaper than a leaf of at most [`MAX_LEAF`] primitives.
    Leaf,
    /// The centroids coincide on every axis: no plane separates them.
    Flat,
}

/// `v` with `.w` cleared by a mask: the `.w` lanes of boxes hold index bits, denormal floats
/// that make SIMD arithmetic many times slower.
fn xyz(v: Vec4) -> Vec4 {
    Vec4::select(BVec4A::new(true, true, true, false), v, Vec4::ZERO)
}

/// Half the surface area of a box (`.w` ignored); the SAH only compares ratios.
fn half_area(b: Bounds4) -> f32 {
    let d = xyz(b.max) - xyz(b.min);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// SAH cost of a split relative to its node (with the traversal step), from the sum of
/// half area × primitive count over both sides.
fn relative_cost(weighted_area: f32, info: NodeInfo) -> f32 {
    TRAVERSAL_COST + weighted_area / half_area(info.bounds).max(f32::MIN_POSITIVE)
}

/// The leaf test: a node small enough for a leaf stays one when no split is cheaper.
fn keep_as_leaf(cost: f32, n: usize) -> bool {
    cost >= n as f32 && n <= MAX_LEAF
}

/// Splits a node of at most [`SWEEP_MAX`] primitives by the full SAH: the centroids are sorted
/// on each axis and every split between neighbours is costed.
fn split_sweep(prims: &mut [Prim], info: NodeInfo) -> Found {
    let n = prims.len();
    let extent = info.centroids.max - info.centroids.min;
    if n == 2 {
        // The only split: one primitive a side (the most common node near the leaves).
        if !extent.cmpgt(Vec4::ZERO).any() {
            return Found::Flat;
        }
        let one = |p: &Prim| Bounds4 {
            min: p.min,
            max: p.max,
        };
        let weighted = half_area(one(&prims[0])) + half_area(one(&prims[1]));
        if keep_as_leaf(relative_cost(weighted, info), n) {
            return Found::Leaf;
        }
        let side = |p: &Prim| {
            let mut i = NodeInfo::EMPTY;
            i.add(p);
            i
        };
        return Found::Split(Split {
            at: 1,
            left: side(&prims[0]),
            right: side(&prims[1]),
        });
    }
    let mut centroids = [Vec4::ZERO; SWEEP_MAX];
    for (c, p) in centroids.iter_mut().zip(prims.iter()) {
        *c = p.centroid2();
    }
    let mut orders = [[0u8; SWEEP_MAX]; 3];
    // (axis, primitives on the left, weighted area)
    let mut best: Option<(usize, usize, f32)> = None;
    for (axis, order) in orders.iter_mut().enumerate() {
        // Skip flat axes (and a NaN extent, which no finite input makes).
        if extent[axis].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        // Insertion sort: stable, and fastest on a handful of keys.
        for i in 0..n {
            let key = centroids[i][axis];
            let mut j = i;
            while j > 0 && centroids[order[j - 1] as usize][axis] > key {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = i as u8;
        }
        // Sweep from the right to know every right-hand side, then from the left.
        let mut right = [0.0f32; SWEEP_MAX];
        let mut acc = Bounds4::EMPTY;
        for k in (1..n).rev() {
            let p = &prims[order[k] as usize];
            acc.grow(p.min, p.max);
            right[k] = half_area(acc) * (n - k) as f32;
        }
        let mut acc = Bounds4::EMPTY;
        for k in 1..n {
            let p = &prims[order[k - 1] as usize];
            acc.grow(p.min, p.max);
            let weighted = half_area(acc) * k as f32 + right[k];
            if best.is_none_or(|(_, _, w)| weighted < w) {
                best = Some((axis, k, weighted));
            }
        }
    }
    let Some((axis, at, weighted)) = best else {
        return Found::Flat;
    };
    if keep_as_leaf(relative_cost(weighted, info), n) {
        return Found::Leaf;
    }
    let mut copy = [prims[0]; SWEEP_MAX];
    copy[..n].copy_from_slice(prims);
    for (p, &k) in prims.iter_mut().zip(&orders[axis][..n]) {
        *p = copy[k as usize];
    }
    let (l, r) = prims.split_at(at);
    Found::Split(Split {
        at,
        left: NodeInfo::of(l),
        right: NodeInfo::of(r),
    })
}

/// The bins of all three axes: boxes and primitive counts.
#[derive(Clone, Copy)]
struct Bins<const B: usize> {
    bounds: [[Bounds4; B]; 3],
    counts: [[u32; B]; 3],
}

impl<const B: usize> Bins<B> {
    const EMPTY: Self = Bins {
        bounds: [[Bounds4::EMPTY; B]; 3],
        counts: [[0; B]; 3],
    };

    fn merge(mut self, o: Self) -> Self {
        for axis in 0..3 {
            for i in 0..B {
                self.bounds[axis][i] = self.bounds[axis][i].union(o.bounds[axis][i]);
                self.counts[axis][i] += o.counts[axis][i];
            }
        }
        self
    }
}

/// Where a primitive falls in the bins: `centroid2 * scale - bias` (that is,
/// `(centroid2 - origin) * scale - 0.5`), rounded to the nearest integer and clamped to the bins,
/// is its bin on each axis.
#[derive(Clone, Copy)]
struct Binning {
    scale: Vec4,
    bias: Vec4,
}

impl Binning {
    /// Bins of `B` over the centroid box of `info`; a flat axis gets scale 0 (all in bin 0).
    fn new<const B: usize>(info: NodeInfo) -> Binning {
        let extent = info.centroids.max - info.centroids.min;
        let scale = Vec4::splat(B as f32) / extent;
        let usable = extent.cmpgt(Vec4::ZERO) & scale.cmplt(Vec4::splat(f32::INFINITY));
        let scale = Vec4::select(usable, scale, Vec4::ZERO);
        Binning {
            scale,
            bias: info.centroids.min * scale + 0.5,
        }
    }

    /// The bins, one a lane, of a primitive with [`Prim::centroid2`] `c`. Adding 2^23 (whose
    /// float has no fraction bits left) rounds to the nearest integer and leaves it in the low
    /// bits: that vectorises where a float-to-integer conversion does not. The bins are
    /// monotonic in the centroid, which is all the SAH sweep and the partition need.
    fn bins_of<const B: usize>(self, c: Vec4) -> [u32; 4] {
        let t = (c * self.scale - self.bias)
            .max(Vec4::ZERO)
            .min(Vec4::splat((B - 1) as f32))
            + MAGIC;
        t.to_array().map(|x| x.to_bits() - MAGIC_BITS)
    }

    /// Bins the primitives on all three axes at once.
    fn bin<const B: usize>(self, prims: &[Prim]) -> Bins<B> {
        // Two sets of bins, for even and odd primitives: neighbours often fall in the same
        // bin, and one set would make each update wait for the last one's store.
        let mut even = Bins::<B>::EMPTY;
        let add = |bins: &mut Bins<B>, p: &Prim| {
            let b = self.bins_of::<B>(p.centroid2());
            for (axis, &i) in b[..3].iter().enumerate() {
                bins.bounds[axis][i as usize].grow(p.min, p.max);
                bins.counts[axis][i as usize] += 1;
            }
        };
        if prims.len() < TWO_BIN_SETS_MIN {
            for p in prims {
                add(&mut even, p);
            }
            return even;
        }
        let mut odd = Bins::<B>::EMPTY;
        let mut pairs = prims.chunks_exact(2);
        for pair in &mut pairs {
            add(&mut even, &pair[0]);
            add(&mut odd, &pair[1]);
        }
        for p in pairs.remainder() {
            add(&mut even, p);
        }
        even.merge(odd)
    }
}

/// 2^23: added to a float in [0, 2^23), it leaves the nearest integer in the fraction bits.
const MAGIC_SCALAR: f32 = 8_388_608.0;
const MAGIC: Vec4 = Vec4::splat(MAGIC_SCALAR);
const MAGIC_BITS: u32 = MAGIC_SCALAR.to_bits();

/// Splits a node at the cheapest of `B` bins per axis, partitioning its primitives.
fn split_binned<const B: usize>(prims: &mut [Prim], info: NodeInfo) -> Found {
    let n = prims.len();
    let binning = Binning::new::<B>(info);
    let bins = if n >= PARALLEL_SPLIT_THRESHOLD {
        prims
            .par_chunks(chunk_size(n))
            .map(|c| binning.bin::<B>(c))
            .reduce(|| Bins::EMPTY, Bins::merge)
    } else {
        binning.bin::<B>(prims)
    };
    // (axis, bins on the left, weighted area)
    let mut best: Option<(usize, usize, f32)> = None;
    for axis in 0..3 {
        if binning.scale[axis] == 0.0 {
            continue;
        }
        let (bounds, counts) = (&bins.bounds[axis], &bins.counts[axis]);
        // Sweep from the right to know every right-hand side, then from the left.
        let mut right = [0.0f32; B];
        let mut right_count = [0u32; B];
        let (mut acc, mut count) = (Bounds4::EMPTY, 0);
        for i in (1..B).rev() {
            acc = acc.union(bounds[i]);
            count += counts[i];
            right[i] = half_area(acc) * count as f32;
            right_count[i] = count;
        }
        let (mut acc, mut count) = (Bounds4::EMPTY, 0);
        for i in 1..B {
            acc = acc.union(bounds[i - 1]);
            count += counts[i - 1];
            if count == 0 || right_count[i] == 0 {
                continue;
            }
            let weighted = half_area(acc) * count as f32 + right[i];
            if best.is_none_or(|(_, _, w)| weighted < w) {
                best = Some((axis, i, weighted));
            }
        }
    }
    let Some((axis, split_bin, weighted)) = best else {
        return Found::Flat;
    };
    if keep_as_leaf(relative_cost(weighted, info), n) {
        return Found::Leaf;
    }
    let goes_left = |c: Vec4| (binning.bins_of::<B>(c)[axis] as usize) < split_bin;
    let (at, left, right) = if n >= PARALLEL_SPLIT_THRESHOLD {
        partition_parallel(prims, goes_left)
    } else {
        partition(prims, goes_left)
    };
    debug_assert!(at > 0 && at < n, "the bins counted both sides");
    Found::Split(Split { at, left, right })
}

/// Chunks for the parallel passes: enough for many threads, none tiny, and independent of the
/// thread count so that the tree is too.
fn chunk_size(n: usize) -> usize {
    n.div_ceil(64).max(MIN_CHUNK)
}

/// Moves the primitives whose [`Prim::centroid2`] `goes_left` picks to the front; returns how
/// many there are and what each side holds. Scans from both ends and swaps only the
/// primitives on the wrong side (Hoare's scheme).
fn partition(prims: &mut [Prim], goes_left: impl Fn(Vec4) -> bool) -> (usize, NodeInfo, NodeInfo) {
    let (mut left, mut right) = (NodeInfo::EMPTY, NodeInfo::EMPTY);
    let (mut i, mut j) = (0, prims.len());
    loop {
        // Skip the primitives already on the left, then those already on the right.
        let mut misplaced_left = None;
        while i < j {
            let c = prims[i].centroid2();
            if !goes_left(c) {
                misplaced_left = Some(c);
                break;
            }
            left.add_with(&prims[i], c);
            i += 1;
        }
        let mut misplaced_right = None;
        while i < j {
            let c = prims[j - 1].centroid2();
            if goes_left(c) {
                misplaced_right = Some(c);
                break;
            }
            right.add_with(&prims[j - 1], c);
            j -= 1;
        }
        let (Some(cl), Some(cr)) = (misplaced_left, misplaced_right) else {
            break;
        };
        // prims[i] belongs right and prims[j - 1] left (i < j - 1: each failed its own test).
        prims.swap(i, j - 1);
        left.add_with(&prims[i], cr);
        right.add_with(&prims[j - 1], cl);
        i += 1;
        j -= 1;
    }
    (i, left, right)
}

/// [`partition`] in parallel: each chunk partitions itself, then the right-hand runs that lie
/// in the final left part swap places with the left-hand runs in the final right part.
fn partition_parallel(
    prims: &mut [Prim],
    goes_left: impl Fn(Vec4) -> bool + Sync,
) -> (usize, NodeInfo, NodeInfo) {
    let chunk = chunk_size(prims.len());
    let parts: Vec<(usize, NodeInfo, NodeInfo)> = prims
        .par_chunks_mut(chunk)
        .map(|c| partition(c, &goes_left))
        .collect();
    let at: usize = parts.iter().map(|p| p.0).sum();
    let (mut left, mut right) = (NodeInfo::EMPTY, NodeInfo::EMPTY);
    // Runs out of place: right-hand elements before `at`, left-hand ones from `at` on.
    let (mut wrong_right, mut wrong_left) = (Vec::new(), Vec::new());
    for (k, (count, l, r)) in parts.iter().enumerate() {
        left = left.union(*l);
        right = right.union(*r);
        let start = k * chunk;
        let end = (start + chunk).min(prims.len());
        let mid = start + count;
        if mid < end.min(at) {
            wrong_right.push(mid..end.min(at));
        }
        if mid > start.max(at) {
            wrong_left.push(start.max(at)..mid);
        }
    }
    let (head, tail) = prims.split_at_mut(at);
    let a = carve(head, 0, &wrong_right);
    let b = carve(tail, at, &wrong_left);
    pair_up(a, b)
        .into_par_iter()
        .for_each(|(x, y)| x.swap_with_slice(y));
    (at, left, right)
}

/// The disjoint, ascending `ranges` (indices from `base`) of `slice` as separate slices.
fn carve<'a>(
    mut slice: &'a mut [Prim],
    mut base: usize,
    ranges: &[std::ops::Range<usize>],
) -> Vec<&'a mut [Prim]> {
    let mut out = Vec::with_capacity(ranges.len());
    for r in ranges {
        let (_, rest) = std::mem::take(&mut slice).split_at_mut(r.start - base);
        let (piece, rest) = rest.split_at_mut(r.end - r.start);
        out.push(piece);
        slice = rest;
        base = r.end;
    }
    out
}

/// Pairs two lists of slices holding the same number of elements into pairs of equal length.
fn pair_up<'a>(
    a: Vec<&'a mut [Prim]>,
    b: Vec<&'a mut [Prim]>,
) -> Vec<(&'a mut [Prim], &'a mut [Prim])> {
    let mut out = Vec::new();
    let (mut a, mut b) = (a.into_iter(), b.into_iter());
    let (mut x, mut y): (&mut [Prim], &mut [Prim]) = (&mut [], &mut []);
    loop {
        if x.is_empty() {
            match a.next() {
                Some(s) => x = s,
                None => break,
            }
            continue;
        }
        if y.is_empty() {
            match b.next() {
                Some(s) => y = s,
                None => break,
            }
            continue;
        }
        let n = x.len().min(y.len());
        let (x0, x1) = std::mem::take(&mut x).split_at_mut(n);
        let (y0, y1) = std::mem::take(&mut y).split_at_mut(n);
        out.push((x0, y0));
        x = x1;
        y = y1;
    }
    out
}
