//! The frame time budget: how much work (resolution and samples per pixel) one batch of kernel
//! work gets so that the image keeps updating at an interactive rate on any device.
//!
//! The cost of one sample per pixel is measured per resolution divisor (1, 2, 4, 8) in
//! milliseconds per pixel, smoothed over batches. While the camera moves, the largest resolution
//! whose single sample fits the budget is used; when it stops, the full resolution with as many
//! samples as fit (at least one: a device too slow for one full-resolution sample within the
//! budget still makes progress, the frame loop just polls longer).

/// Resolution divisors the viewer may render at while moving (1 = full resolution).
pub const DIVISORS: [u32; 4] = [1, 2, 4, 8];

/// Most samples per pixel one batch may hold, so a fast device still shows progress.
pub const MAX_BATCH_SPP: u32 = 256;

/// Weight of the newest measurement in the running estimate.
const SMOOTHING: f64 = 0.5;

/// What the next batch renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Plan {
    /// Resolution divisor (the film is the window size divided by it, rounded up).
    pub divisor: u32,
    /// Samples per pixel of the batch (at least 1).
    pub spp: u32,
}

/// Measured costs and the budget they are held to.
#[derive(Clone, Debug)]
pub struct Budget {
    /// Target duration of one batch in milliseconds.
    pub target_ms: f64,
    /// Smoothed milliseconds per pixel-sample at each divisor of [`DIVISORS`].
    ms_per_pixel_sample: [Option<f64>; DIVISORS.len()],
}

impl Budget {
    /// A budget of `target_ms` per batch with nothing measured yet.
    pub fn new(target_ms: f64) -> Self {
        Self {
            target_ms,
            ms_per_pixel_sample: [None; DIVISORS.len()],
        }
    }

    /// Records that `spp` samples over `pixels` pixels at `divisor` took `ms`.
    pub fn record(&mut self, divisor: u32, pixels: u64, spp: u32, ms: f64) {
        let Some(i) = DIVISORS.iter().position(|&d| d == divisor) else {
            return;
        };
        let work = pixels as f64 * spp.max(1) as f64;
        if work <= 0.0 || !ms.is_finite() || ms < 0.0 {
            return;
        }
        let cost = ms / work;
        let slot = &mut self.ms_per_pixel_sample[i];
        *slot = Some(match *slot {
            Some(old) => old + SMOOTHING * (cost - old),
            None => cost,
        });
    }

    /// Estimated milliseconds of one sample per pixel over `pixels` pixels at `divisor`: the
    /// divisor's own measurement, else the nearest measured larger resolution (an optimistic
    /// guess, so smaller divisors get tried), else the nearest smaller one. `None` before any
    /// measurement.
    pub fn estimate_ms(&self, divisor: u32, pixels: u64) -> Option<f64> {
        let i = DIVISORS.iter().position(|&d| d == divisor)?;
        let cost = self.ms_per_pixel_sample[i]
            .or_else(|| self.ms_per_pixel_sample[..i].iter().rev().find_map(|c| *c))
            .or_else(|| self.ms_per_pixel_sample[i + 1..].iter().find_map(|c| *c))?;
        Some(cost * pixels as f64)
    }

    /// The plan for the next batch on a `full` sized window; `remaining` caps the samples when
    /// a samples-per-pixel target is set.
    pub fn plan(&self, full: (u32, u32), moving: bool, remaining: Option<u32>) -> Plan {
        let candidates: &[u32] = if moving { &DIVISORS } else { &DIVISORS[..1] };
        // The largest resolution whose one sample fits; the smallest one when none does.
        let divisor = candidates
            .iter()
            .copied()
            .find(|&d| {
                self.estimate_ms(d, pixel_count(scaled(full, d)))
                    .is_none_or(|ms| ms <= self.target_ms)
            })
            .unwrap_or(*candidates.last().unwrap_or(&1));
        let spp = match self.estimate_ms(divisor, pixel_count(scaled(full, divisor))) {
            Some(ms) if ms > 0.0 => (self.target_ms / ms)
                .floor()
                .clamp(1.0, MAX_BATCH_SPP as f64),
            Some(_) => MAX_BATCH_SPP as f64,
            None => 1.0,
        } as u32;
        let spp = match remaining {
            Some(r) => spp.min(r).max(1),
            None => spp,
        };
        Plan { divisor, spp }
    }
}

/// The film size for a window size and a divisor (rounded up, at least 1×1).
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

    #[test]
    fn the_first_batch_is_one_full_sample() {
        let b = Budget::new(30.0);
        assert_eq!(b.plan(FULL, false, None), Plan { divisor: 1, spp: 1 });
        assert_eq!(b.plan(FULL, true, None).spp, 1);
    }

    #[test]
    fn samples_per_batch_follow_the_measured_time() {
        let mut b = Budget::new(30.0);
        // 4 spp took 20 ms: 5 ms per sample, so 6 fit the 30 ms budget.
        b.record(1, pixel_count(FULL), 4, 20.0);
        assert_eq!(b.plan(FULL, false, None).spp, 6);
        // The device slows down (more bounces): the estimate follows, smoothed.
        b.record(1, pixel_count(FULL), 1, 25.0);
        assert_eq!(b.plan(FULL, false, None).spp, 2);
        for _ in 0..10 {
            b.record(1, pixel_count(FULL), 1, 25.0);
        }
        assert_eq!(b.plan(FULL, false, None).spp, 1);
    }

    #[test]
    fn a_slow_device_still_renders_one_sample_at_full_resolution() {
        let mut b = Budget::new(30.0);
        b.record(1, pixel_count(FULL), 1, 500.0);
        assert_eq!(b.plan(FULL, false, None), Plan { divisor: 1, spp: 1 });
    }

    #[test]
    fn moving_on_a_slow_device_lowers_the_resolution() {
        let mut b = Budget::new(30.0);
        b.record(1, pixel_count(FULL), 1, 400.0);
        // 1/16 of the pixels costs 25 ms: divisor 4 is the largest that fits.
        let p = b.plan(FULL, true, None);
        assert_eq!(p, Plan { divisor: 4, spp: 1 });
        // Slower than even 1/8 of the resolution allows: the smallest one, one sample.
        b.record(1, pixel_count(FULL), 1, 10_000.0);
        b.record(1, pixel_count(FULL), 1, 10_000.0);
        b.record(1, pixel_count(FULL), 1, 10_000.0);
        b.record(4, pixel_count(scaled(FULL, 4)), 1, 600.0);
        b.record(8, pixel_count(scaled(FULL, 8)), 1, 150.0);
        assert_eq!(b.plan(FULL, true, None), Plan { divisor: 8, spp: 1 });
        // Standing still goes back to the full resolution.
        assert_eq!(b.plan(FULL, false, None).divisor, 1);
    }

    #[test]
    fn a_fast_device_moves_at_full_resolution() {
        let mut b = Budget::new(30.0);
        b.record(1, pixel_count(FULL), 8, 16.0);
        assert_eq!(
            b.plan(FULL, true, None),
            Plan {
                divisor: 1,
                spp: 15
            }
        );
    }

    #[test]
    fn the_target_caps_the_batch() {
        let mut b = Budget::new(30.0);
        b.record(1, pixel_count(FULL), 1, 1.0);
        assert_eq!(b.plan(FULL, false, Some(3)).spp, 3);
        assert_eq!(b.plan(FULL, false, None).spp, 30);
        b.record(1, pixel_count(FULL), 1, 0.0);
        assert!(b.plan(FULL, false, None).spp <= MAX_BATCH_SPP);
    }

    #[test]
    fn scaled_sizes_round_up() {
        assert_eq!(scaled((641, 480), 2), (321, 240));
        assert_eq!(scaled((3, 3), 8), (1, 1));
    }
}
