//! Adaptive sampling (docs/adaptive-sampling.md): the samples of a render go in steps of
//! [`CHECK_STEP`], and from [`min_samples`] on each step ends with a convergence check on the
//! device (kernels/shared/adaptive.h) after which the pixels whose error is under the threshold,
//! with their neighbours, take no more samples. The host reads how many stay active, and on
//! demand the per-pixel error and sample counts.

use super::{Renderer, film};
use crate::cl::kernels::Launch;
use crate::cl::types::{COUNT_ACTIVE, PIXEL_CONVERGED, PIXEL_SAMPLES};
use crate::cl::{ClError, Stage};

/// Samples between two convergence checks (Cycles' step).
pub const CHECK_STEP: u32 = 16;

/// The samples every pixel takes before its first check: Cycles' automatic minimum
/// max(4, 16 / threshold^0.3), rounded up to a whole number of [`CHECK_STEP`]s (so the checks
/// fall on whole steps: 16 for thresholds from 1 up, 64 at 0.01).
pub fn min_samples(threshold: f32) -> u32 {
    let cycles = (16.0 / threshold.max(f32::MIN_POSITIVE).powf(0.3))
        .ceil()
        .max(4.0);
    (cycles.min(1e6) as u32).div_ceil(CHECK_STEP) * CHECK_STEP
}

/// What adaptive sampling did to the film since the last reset.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AdaptiveStats {
    /// Samples taken, all pixels together.
    pub samples: u64,
    /// Samples taken per pixel, on average.
    pub mean_spp: f64,
    /// Share of the pixels converged at the last check (0 before the first).
    pub converged_share: f64,
    /// The mean over the pixels of their relative error (kernels/shared/adaptive.h's
    /// `pixel_error`): |I − A| over √I, I the mean of all samples and A of the even-numbered.
    pub mean_error: f64,
}

/// A pixel's relative error from its film sum, half sum and state, as the device computes it.
pub fn pixel_error(film: [f32; 4], half: [f32; 4], state: u32) -> f32 {
    let n = (state & PIXEL_SAMPLES) as f32;
    if n == 0.0 || half[3] == 0.0 {
        return f32::INFINITY;
    }
    let (mut diff, mut sum) = (0.0, 0.0);
    for c in 0..3 {
        let i = film[c] / n;
        diff += (i - half[c] / half[3]).abs();
        sum += i;
    }
    diff / (0.0001 + sum.max(0.0).sqrt())
}

impl Renderer {
    /// Enqueues `spp` more samples in steps that end on a multiple of [`CHECK_STEP`], with a
    /// convergence check after each step from [`min_samples`] on.
    pub(super) fn enqueue_adaptive(
        &mut self,
        spp: u32,
        threshold: f32,
    ) -> Result<Vec<(Stage, Launch)>, ClError> {
        let mut launches = Vec::new();
        let mut left = spp;
        while left > 0 {
            if self.active_stale && !self.megakernel {
                // The wavefront sizes its launches to the active pixels: the count of a check
                // still in flight is waited for (a read after it on the in-order queue).
                let counters = self.counters.read(&self.device)?;
                self.active_pixels = Some(counters[COUNT_ACTIVE]);
                self.active_stale = false;
            }
            let n = left.min(CHECK_STEP - self.samples % CHECK_STEP);
            launches.extend(self.enqueue_samples(n)?);
            left -= n;
            launches.extend(self.enqueue_check_if_due(threshold)?);
        }
        Ok(launches)
    }

    /// Enqueues the convergence check when the samples so far end a step from
    /// [`min_samples`] on; nothing otherwise.
    pub(super) fn enqueue_check_if_due(
        &mut self,
        threshold: f32,
    ) -> Result<Vec<(Stage, Launch)>, ClError> {
        if self.samples.is_multiple_of(CHECK_STEP) && self.samples >= min_samples(threshold) {
            self.enqueue_check(threshold)
        } else {
            Ok(Vec::new())
        }
    }

    /// Enqueues the convergence check.
    fn enqueue_check(&mut self, threshold: f32) -> Result<Vec<(Stage, Launch)>, ClError> {
        let (Some(program), Some(f)) = (self.program.as_ref(), self.frame.as_ref()) else {
            return Err(ClError::Device("no scene is loaded".into()));
        };
        let frame = self.settings.gpu_frame(self.light_count);
        let [mark, dilate] = program.converge(
            &self.device,
            &frame,
            &f.film,
            threshold,
            min_samples(threshold),
            &self.counters,
        )?;
        self.adaptive_checked = true;
        self.active_stale = true;
        Ok(vec![(Stage::Converge, mark), (Stage::Converge, dilate)])
    }

    /// Pixels the last convergence check left active; `None` before the first check (or
    /// without adaptive sampling). 0: the image has converged, more samples add nothing.
    pub fn active_pixels(&self) -> Option<u32> {
        self.active_pixels
    }

    /// Reads adaptive sampling's pixel states into `state_readback`; false without adaptive
    /// sampling or a frame.
    pub(super) fn read_states(&mut self) -> Result<bool, ClError> {
        if !self.pending.is_empty() {
            self.finish()?;
        }
        match (&self.frame, self.settings.noise_threshold) {
            (Some(f), Some(_)) => {
                f.film
                    .state
                    .read_into(&self.device, &mut self.state_readback)?;
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// What adaptive sampling did since the last reset; `None` without it.
    pub fn adaptive_stats(&mut self) -> Result<Option<AdaptiveStats>, ClError> {
        let errors = match self.pixel_errors()? {
            Some(e) => e,
            None => return Ok(None),
        };
        let pixels = self.state_readback.len().max(1) as f64;
        let samples: u64 = self
            .state_readback
            .iter()
            .map(|s| u64::from(s & PIXEL_SAMPLES))
            .sum();
        let converged = self
            .state_readback
            .iter()
            .filter(|s| *s & PIXEL_CONVERGED != 0)
            .count();
        let finite: Vec<f64> = errors
            .iter()
            .filter(|e| e.is_finite())
            .map(|e| f64::from(*e))
            .collect();
        Ok(Some(AdaptiveStats {
            samples,
            mean_spp: samples as f64 / pixels,
            converged_share: converged as f64 / pixels,
            mean_error: finite.iter().sum::<f64>() / finite.len().max(1) as f64,
        }))
    }

    /// The samples each pixel took, row by row from the top; `None` without adaptive sampling.
    pub fn pixel_samples(&mut self) -> Result<Option<Vec<u32>>, ClError> {
        if !self.read_states()? {
            return Ok(None);
        }
        Ok(Some(
            self.state_readback
                .iter()
                .map(|s| s & PIXEL_SAMPLES)
                .collect(),
        ))
    }

    /// Each pixel's relative error, row by row from the top; `None` without adaptive
    /// sampling. Also leaves the film and the states in their readback buffers.
    pub fn pixel_errors(&mut self) -> Result<Option<Vec<f32>>, ClError> {
        if !self.read_states()? {
            return Ok(None);
        }
        let Some(f) = self.frame.as_ref() else {
            return Ok(None);
        };
        let half = f.film.half.read(&self.device)?;
        f.film.sum.read_into(&self.device, &mut self.readback)?;
        Ok(Some(
            self.readback
                .iter()
                .zip(&half)
                .zip(&self.state_readback)
                .map(|((film, half), state)| pixel_error(film::as_float(*film), *half, *state))
                .collect(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_minimum_is_cycles_rounded_up_to_whole_steps() {
        // 16 / 0.01^0.3 = 63.7; 16 / 0.1^0.3 = 31.9; 16 / 0.05^0.3 = 39.3.
        assert_eq!(min_samples(0.01), 64);
        assert_eq!(min_samples(0.1), 32);
        assert_eq!(min_samples(0.05), 48);
        assert_eq!(min_samples(1.0), 16);
        assert_eq!(min_samples(100.0), 16);
    }

    #[test]
    fn the_error_compares_the_half_with_the_whole() {
        // Four samples of 1 and 3 alternating: mean 2; the even ones (1, 1) have mean 1.
        let film = [8.0, 8.0, 8.0, 4.0];
        let half = [2.0, 2.0, 2.0, 2.0];
        let e = pixel_error(film, half, 4);
        assert!((e - 3.0 / (0.0001 + 6f32.sqrt())).abs() < 1e-6, "{e}");
        // Equal halves: no error; no samples: no estimate.
        assert_eq!(
            pixel_error([4.0, 4.0, 4.0, 2.0], [2.0, 2.0, 2.0, 1.0], 2),
            0.0
        );
        assert!(pixel_error([0.0; 4], [0.0; 4], 0).is_infinite());
    }
}
