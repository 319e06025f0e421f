//! Reading the film back: the image as linear RGB, each pixel's coverage, the raw sums.

use super::{Renderer, film};
use crate::cl::ClError;
use crate::cl::types::PIXEL_SAMPLES;

impl Renderer {
    /// The film as linear RGB (the mean of the samples), row by row from the top.
    pub fn image(&mut self) -> Result<Vec<[f32; 3]>, ClError> {
        let mut image = Vec::new();
        self.image_into(&mut image, None)?;
        Ok(image)
    }

    /// [`Renderer::image`] into `image`, and [`Renderer::coverage`] into `coverage`, from one
    /// read of the film: their allocations and the renderer's readback buffer are reused, so
    /// the viewer's frames allocate no film-sized memory.
    pub fn image_into(
        &mut self,
        image: &mut Vec<[f32; 3]>,
        coverage: Option<&mut Vec<f32>>,
    ) -> Result<(), ClError> {
        let read = self.read_film()?;
        let n = (self.settings.width * self.settings.height) as usize;
        if !read {
            image.clear();
            image.resize(n, [0.0; 3]);
            if let Some(coverage) = coverage {
                coverage.clear();
                coverage.resize(n, 1.0);
            }
            return Ok(());
        }
        let counted = self.settings.cutout || self.settings.count_coverage;
        // With adaptive sampling each pixel took its own number of samples.
        let adaptive = counted && self.read_states()?;
        let samples = f64::from(self.samples);
        let states = &self.state_readback;
        let taken = |i: usize| {
            if adaptive {
                f64::from(states[i] & PIXEL_SAMPLES)
            } else {
                samples
            }
        };
        film::image_into(&self.readback, counted, taken, image, coverage);
        Ok(())
    }

    /// Each pixel's coverage: the share of its samples whose camera ray hit the scene, with
    /// [`RenderSettings::cutout`](super::RenderSettings::cutout) or
    /// [`RenderSettings::count_coverage`](super::RenderSettings::count_coverage) (else all 1); with the
    /// image, [`Renderer::image_into`] reads it from the same read of the film.
    pub fn coverage(&mut self) -> Result<Vec<f32>, ClError> {
        let (mut image, mut coverage) = (Vec::new(), Vec::new());
        self.image_into(&mut image, Some(&mut coverage))?;
        Ok(coverage)
    }

    /// The film's raw pixels: each pixel's fixed-point sums and count, exact (a shard's data).
    pub fn film(&mut self) -> Result<Vec<film::FilmPixel>, ClError> {
        let n = (self.settings.width * self.settings.height) as usize;
        if !self.read_film()? {
            return Ok(vec![[0; 4]; n]);
        }
        Ok(self.readback.clone())
    }

    /// Finishes the pending launches and reads the film into [`Renderer::readback`]; false
    /// when no frame exists yet.
    fn read_film(&mut self) -> Result<bool, ClError> {
        if !self.pending.is_empty() {
            self.finish()?;
        }
        let Some(f) = self.frame.as_ref() else {
            return Ok(false);
        };
        f.film.sum.read_into(&self.device, &mut self.readback)?;
        Ok(true)
    }
}
