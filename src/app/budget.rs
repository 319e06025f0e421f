//! The frame time budget: how much work one batch of kernel work gets so that input is answered
//! within a frame's budget on any device, and how the preview climbs back to full quality.
//!
//! **Quality levels.** [`levels`] lists what a batch may render, from full quality down: the
//! film at the full resolution or divided by 2, 4, 8 or 16 per side, with the full bounces or
//! (from ¼ resolution down) one bounce. While the view moves, the first level whose one sample
//! fits the budget is rendered; when it rests, each new image climbs one level, up to full
//! quality, where as many samples as fit go into a batch.
//!
//! **The cost model.** Milliseconds per pixel-sample-depth (depth = bounces + 2, the most
//! extension rays a path traces), per divisor (a small film pays a larger share of fixed
//! costs), learned from every finished sample's wall time and smoothed; it starts empty for
//! each device and scene. A divisor not measured yet borrows the nearest measured one.
//!
//! **Denoising.** With the viewer's denoise toggle each preview image is also denoised (the
//! small network) before it is shown: milliseconds per pixel of that, per divisor, are learned
//! the same way, and while the view moves a level fits when its sample and its denoising
//! together fit the budget, so the preview lowers its resolution further when the denoising
//! takes time.
//!
//! **Bands.** A sample whose estimate exceeds the budget is split into bands (one launch each,
//! [`crate::render::Band`]) of about the budget, so that new input waits for one band at most.
//! A band that still runs over the budget (the estimate was low, or the device slowed down)
//! has the rest of its sample split as many times finer ([`Plan::split_rest`]).

/// Resolution divisors (1 = full resolution).
pub const DIVISORS: [u32; 5] = [1, 2, 4, 8, 16];

/// Most samples per pixel one batch may hold, so a fast device still shows progress.
pub const MAX_BATCH_SPP: u32 = 256;

/// Most bands one sample is split into.
pub const MAX_BANDS: u32 = 256;

/// Weight of the newest measurement in the running estimate.
const SMOOTHING: f64 = 0.5;

/// The divisor from which the preview also drops to one bounce (a quarter of the resolution:
/// below it the image loses its shapes, above it its light).
const FEW_BOUNCES_FROM: u32 = 4;

/// What a batch renders: a film size and the bounces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    /// Resolution divisor (the film is the image area divided by it, rounded up).
    pub divisor: u32,
    /// Bounces after the first hit.
    pub bounces: u32,
}

/// The quality levels for `bounces` full bounces, best first (see the module docs).
pub fn levels(bounces: u32) -> Vec<Level> {
    let mut out: Vec<Level> = Vec::new();
    for divisor in DIVISORS {
        if divisor < FEW_BOUNCES_FROM {
            out.push(Level { divisor, bounces });
        } else {
            if divisor == FEW_BOUNCES_FROM {
                out.push(Level { divisor, bounces });
            }
            out.push(Level {
                divisor,
                bounces: bounces.min(1),
            });
        }
    }
    out.dedup();
    out
}

/// What the next batch renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    /// The level.
    pub level: Level,
    /// Samples per pixel of the batch (at least 1).
    pub spp: u32,
    /// Bands the batch's one sample is split into (1: one launch; more only with `spp` 1).
    pub bands: u32,
}

impl Plan {
    /// After `done` bands of this plan, the last of which took `band_ms`: the plan for the rest
    /// of the sample, and the index of its next band. A band over `target_ms` splits the rest
    /// into bands ⌈band_ms / target_ms⌉ times finer (band k·m of bands·m starts where band k
    /// of bands did), up to [`MAX_SPLIT_BANDS`] in all; otherwise the plan stands.
    pub fn split_rest(self, done: u32, band_ms: f64, target_ms: f64) -> (Plan, u32) {
        let factor = (band_ms / target_ms).ceil();
        if self.bands <= 1 || done >= self.bands || factor.is_nan() || factor <= 1.0 {
            return (self, done);
        }
        let most = (MAX_SPLIT_BANDS / self.bands).max(1);
        let m = (factor.min(most as f64) as u32).max(1);
        let plan = Plan {
            bands: self.bands * m,
            ..self
        };
        (plan, done * m)
    }
}

/// Most bands a re-planned sample is split into.
pub const MAX_SPLIT_BANDS: u32 = 16 * MAX_BANDS;

/// Measured costs and the budget they are held to.
#[derive(Clone, Debug)]
pub struct Budget {
    /// Target duration of one batch (and the longest launch) in milliseconds.
    pub target_ms: f64,
    /// Smoothed milliseconds per pixel-sample-depth at each divisor of [`DIVISORS`].
    cost: [Option<f64>; DIVISORS.len()],
    /// Smoothed milliseconds per pixel of denoising a preview image, at each divisor.
    denoise: [Option<f64>; DIVISORS.len()],
}

/// The work of `spp` samples over `pixels` pixels at `bounces` bounces, in pixel-sample-depths.
fn work(pixels: u64, spp: u32, bounces: u32) -> f64 {
    pixels as f64 * spp.max(1) as f64 * (bounces as f64 + 2.0)
}

impl Budget {
    /// A budget of `target_ms` per batch with nothing measured yet.
    pub fn new(target_ms: f64) -> Self {
        Self {
            target_ms,
            cost: [None; DIVISORS.len()],
            denoise: [None; DIVISORS.len()],
        }
    }

    /// Whether nothing was measured yet (a new device or scene).
    pub fn is_empty(&self) -> bool {
        self.cost.iter().all(Option::is_none)
    }

    /// Records that `spp` samples over `pixels` pixels at `level` took `ms`.
    pub fn record(&mut self, level: Level, pixels: u64, spp: u32, ms: f64) {
        let Some(i) = DIVISORS.iter().position(|&d| d == level.divisor) else {
            return;
        };
        let w = work(pixels, spp, level.bounces);
        if w <= 0.0 || !ms.is_finite() || ms < 0.0 {
            return;
        }
        smooth(&mut self.cost[i], ms / w);
    }

    /// Records that denoising a preview image of `pixels` pixels at `level` took `ms`.
    pub fn record_denoise(&mut self, level: Level, pixels: u64, ms: f64) {
        let Some(i) = DIVISORS.iter().position(|&d| d == level.divisor) else {
            return;
        };
        if pixels > 0 && ms.is_finite() && ms >= 0.0 {
            smooth(&mut self.denoise[i], ms / pixels as f64);
        }
    }

    /// Forgets the denoising costs (the toggle is off: previews are not denoised).
    pub fn forget_denoise(&mut self) {
        self.denoise = [None; DIVISORS.len()];
    }

    /// Estimated milliseconds of denoising a preview image at `level` on a `full` sized image,
    /// borrowed as [`Budget::estimate_ms`] borrows; 0 before any measurement.
    pub fn denoise_ms(&self, level: Level, full: (u32, u32)) -> f64 {
        let Some(i) = DIVISORS.iter().position(|&d| d == level.divisor) else {
            return 0.0;
        };
        nearest(&self.denoise, i).map_or(0.0, |cost| {
            cost * pixel_count(scaled(full, level.divisor)) as f64
        })
    }

    /// Estimated milliseconds of one sample per pixel at `level` on a `full` sized image: the
    /// divisor's own measurement, else the nearest measured larger resolution (an optimistic
    /// guess, so smaller divisors get tried), else the nearest smaller one. `None` before any
    /// measurement.
    pub fn estimate_ms(&self, level: Level, full: (u32, u32)) -> Option<f64> {
        let i = DIVISORS.iter().position(|&d| d == level.divisor)?;
        let cost = nearest(&self.cost, i)?;
        let pixels = pixel_count(scaled(full, level.divisor));
        Some(cost * work(pixels, 1, level.bounces))
    }

    /// The level (an index into `levels`) for the next batch on a `full` sized image.
    /// `current` is the level of the film on screen and whether it has an image yet.
    /// Moving: the best level whose one sample, with its denoising, fits (the last when none
    /// does). Resting: one
    /// level better than the current one once it has an image. Before any measurement: the
    /// ¼-resolution level, so the first image of a scene comes quickly and measures the device.
    pub fn level(
        &self,
        levels: &[Level],
        full: (u32, u32),
        moving: bool,
        current: Option<(usize, bool)>,
    ) -> usize {
        let last = levels.len().saturating_sub(1);
        if self.is_empty() {
            return match current {
                Some((i, true)) => i.saturating_sub(1).min(last),
                Some((i, false)) => i.min(last),
                None => levels
                    .iter()
                    .position(|l| l.divisor == FEW_BOUNCES_FROM)
                    .unwrap_or(0),
            };
        }
        if moving {
            return levels
                .iter()
                .position(|&l| {
                    self.estimate_ms(l, full)
                        .is_none_or(|ms| ms + self.denoise_ms(l, full) <= self.target_ms)
                })
                .unwrap_or(last);
        }
        match current {
            Some((i, true)) => i.saturating_sub(1).min(last),
            Some((i, false)) => i.min(last),
            None => 0,
        }
    }

    /// Samples and bands for a batch at `level`; `remaining` caps the samples when a
    /// samples-per-pixel target is set; `bands` whether the kernels can split a sample.
    pub fn batch(
        &self,
        level: Level,
        full: (u32, u32),
        remaining: Option<u32>,
        bands: bool,
    ) -> Plan {
        let (spp, count) = match self.estimate_ms(level, full) {
            Some(ms) if ms > self.target_ms => {
                let count = (ms / self.target_ms).ceil().min(MAX_BANDS as f64) as u32;
                (1, if bands { count.max(1) } else { 1 })
            }
            Some(ms) if ms > 0.0 => (
                (self.target_ms / ms)
                    .floor()
                    .clamp(1.0, MAX_BATCH_SPP as f64) as u32,
                1,
            ),
            Some(_) => (MAX_BATCH_SPP, 1),
            None => (1, 1),
        };
        let spp = remaining.map_or(spp, |r| spp.min(r).max(1));
        Plan {
            level,
            spp,
            bands: count,
        }
    }
}

/// `cost` folded into a smoothed estimate.
fn smooth(slot: &mut Option<f64>, cost: f64) {
    *slot = Some(match *slot {
        Some(old) => old + SMOOTHING * (cost - old),
        None => cost,
    });
}

/// The cost at divisor index `i`: its own, else the nearest measured larger resolution's (an
/// optimistic guess, so smaller divisors get tried), else the nearest smaller one's.
fn nearest(costs: &[Option<f64>], i: usize) -> Option<f64> {
    costs[i]
        .or_else(|| costs[..i].iter().rev().find_map(|c| *c))
        .or_else(|| costs[i + 1..].iter().find_map(|c| *c))
}

/// The film size for an image size and a divisor (rounded up, at least 1×1).
pub fn scaled(full: (u32, u32), divisor: u32) -> (u32, u32) {
    let d = divisor.max(1);
    (full.0.div_ceil(d).max(1), full.1.div_ceil(d).max(1))
}

/// Width × height.
pub fn pixel_count(size: (u32, u32)) -> u64 {
    size.0 as u64 * size.1 as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: (u32, u32) = (640, 480);

    fn full(bounces: u32) -> Level {
        Level {
            divisor: 1,
            bounces,
        }
    }

    #[test]
    fn levels_go_down_in_resolution_then_bounces() {
        let l = levels(4);
        let pairs: Vec<_> = l.iter().map(|l| (l.divisor, l.bounces)).collect();
        assert_eq!(pairs, [(1, 4), (2, 4), (4, 4), (4, 1), (8, 1), (16, 1)]);
        // Nothing to drop at one bounce or none.
        assert_eq!(levels(0).len(), 5);
        assert_eq!(levels(1).len(), 5);
    }

    #[test]
    fn the_first_batch_of_a_scene_is_a_quick_quarter_resolution_image() {
        let b = Budget::new(30.0);
        let l = levels(4);
        let i = b.level(&l, FULL, false, None);
        assert_eq!(
            l[i],
            Level {
                divisor: 4,
                bounces: 4
            }
        );
        // Then it climbs, one level per image, measured or not.
        assert_eq!(b.level(&l, FULL, false, Some((i, false))), i);
        assert_eq!(b.level(&l, FULL, false, Some((i, true))), i - 1);
        assert_eq!(
            b.batch(l[i], FULL, None, true),
            Plan {
                level: l[i],
                spp: 1,
                bands: 1
            }
        );
    }

    #[test]
    fn samples_per_batch_follow_the_measured_time() {
        let mut b = Budget::new(30.0);
        // 4 spp took 20 ms: 5 ms per sample, so 6 fit the 30 ms budget.
        b.record(full(4), pixel_count(FULL), 4, 20.0);
        assert_eq!(b.batch(full(4), FULL, None, true).spp, 6);
        // Fewer bounces cost less: 2 bounces are 4/6 of the depth of 4.
        assert_eq!(b.batch(full(2), FULL, None, true).spp, 9);
        // The device slows down: the estimate follows, smoothed.
        b.record(full(4), pixel_count(FULL), 1, 25.0);
        assert_eq!(b.batch(full(4), FULL, None, true).spp, 2);
    }

    #[test]
    fn a_sample_longer_than_the_budget_is_split_into_bands() {
        let mut b = Budget::new(30.0);
        b.record(full(4), pixel_count(FULL), 1, 500.0);
        let p = b.batch(full(4), FULL, None, true);
        assert_eq!((p.spp, p.bands), (1, 17));
        // Kernels that cannot split (the wavefront) get one band.
        assert_eq!(b.batch(full(4), FULL, None, false).bands, 1);
    }

    #[test]
    fn a_band_over_the_budget_splits_the_rest_of_its_sample() {
        let plan = Plan {
            level: full(4),
            spp: 1,
            bands: 4,
        };
        // Band 1 of 4 (the second) took 70 ms of a 30 ms budget: the rest in bands 3 times
        // finer, the next being band 6 of 12, which starts where band 2 of 4 did.
        assert_eq!(
            plan.split_rest(2, 70.0, 30.0),
            (Plan { bands: 12, ..plan }, 6)
        );
        // Within the budget, or a whole sample: the plan stands.
        assert_eq!(plan.split_rest(2, 29.0, 30.0), (plan, 2));
        let whole = Plan { bands: 1, ..plan };
        assert_eq!(whole.split_rest(1, 500.0, 30.0), (whole, 1));
        // Never more than MAX_SPLIT_BANDS; a non-finite time changes nothing.
        let (p, next) = plan.split_rest(1, 1e9, 30.0);
        assert_eq!((p.bands, next), (MAX_SPLIT_BANDS, MAX_SPLIT_BANDS / 4));
        assert_eq!(plan.split_rest(1, f64::NAN, 30.0), (plan, 1));
    }

    #[test]
    fn moving_on_a_slow_device_lowers_the_resolution_then_the_bounces() {
        let mut b = Budget::new(30.0);
        let l = levels(4);
        b.record(full(4), pixel_count(FULL), 1, 400.0);
        // 1/16 of the pixels costs 25 ms: ¼ resolution with every bounce fits.
        let i = b.level(&l, FULL, true, Some((0, true)));
        assert_eq!(
            l[i],
            Level {
                divisor: 4,
                bounces: 4
            }
        );
        // Twice as slow (smoothed): ¼ resolution fits only with one bounce (half the depth).
        b.record(full(4), pixel_count(FULL), 1, 1200.0);
        let i = b.level(&l, FULL, true, Some((0, true)));
        assert_eq!(
            l[i],
            Level {
                divisor: 4,
                bounces: 1
            }
        );
        // Slower than even 1/16 allows: the last level.
        b.record(l[5], pixel_count(scaled(FULL, 16)), 1, 100.0);
        b.record(l[4], pixel_count(scaled(FULL, 8)), 1, 400.0);
        b.record(l[3], pixel_count(scaled(FULL, 4)), 1, 1600.0);
        assert_eq!(b.level(&l, FULL, true, Some((0, true))), 5);
        // At rest it climbs back one level per image, to full quality.
        assert_eq!(b.level(&l, FULL, false, Some((5, true))), 4);
        assert_eq!(b.level(&l, FULL, false, Some((1, true))), 0);
        assert_eq!(b.level(&l, FULL, false, Some((0, true))), 0);
    }

    #[test]
    fn moving_with_the_denoiser_lowers_the_resolution_by_its_time() {
        let mut b = Budget::new(30.0);
        let l = levels(4);
        b.record(full(4), pixel_count(FULL), 1, 400.0);
        // A sample at ¼ resolution takes 25 ms: it fits alone.
        assert_eq!(b.level(&l, FULL, true, Some((0, true))), 2);
        // Denoising that 160 x 120 preview took 12 ms: 37 ms together do not fit; at ¼
        // resolution with one bounce (12.5 ms) and the same denoising they do.
        let quarter = pixel_count(scaled(FULL, 4));
        b.record_denoise(l[2], quarter, 12.0);
        assert!((b.denoise_ms(l[2], FULL) - 12.0).abs() < 1e-9);
        assert_eq!(b.level(&l, FULL, true, Some((0, true))), 3);
        // Denoising three times slower (smoothed: 24 ms): 1/8 resolution, whose denoising
        // is borrowed per pixel (6 ms) beside a 3.1 ms sample.
        b.record_denoise(l[2], quarter, 36.0);
        assert_eq!(b.level(&l, FULL, true, Some((0, true))), 4);
        // The toggle off: the denoising no longer counts.
        b.forget_denoise();
        assert_eq!(b.denoise_ms(l[2], FULL), 0.0);
        assert_eq!(b.level(&l, FULL, true, Some((0, true))), 2);
    }

    #[test]
    fn a_fast_device_moves_at_full_quality() {
        let mut b = Budget::new(30.0);
        b.record(full(4), pixel_count(FULL), 8, 16.0);
        let l = levels(4);
        assert_eq!(b.level(&l, FULL, true, Some((3, true))), 0);
        assert_eq!(b.batch(l[0], FULL, None, true).spp, 15);
    }

    #[test]
    fn the_target_caps_the_batch() {
        let mut b = Budget::new(30.0);
        b.record(full(4), pixel_count(FULL), 1, 1.0);
        assert_eq!(b.batch(full(4), FULL, Some(3), true).spp, 3);
        assert_eq!(b.batch(full(4), FULL, None, true).spp, 30);
        b.record(full(4), pixel_count(FULL), 1, 0.0);
        assert!(b.batch(full(4), FULL, None, true).spp <= MAX_BATCH_SPP);
    }

    #[test]
    fn scaled_sizes_round_up() {
        assert_eq!(scaled((641, 480), 2), (321, 240));
        assert_eq!(scaled((3, 3), 8), (1, 1));
    }
}
