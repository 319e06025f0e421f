//! Reading the film back: the image as linear RGB, each pixel's coverage, the raw sums and
//! the guide buffers.

use super::{Renderer, film};
use crate::cl::kernels::AovBuffers;
use crate::cl::types::PIXEL_SAMPLES;
use crate::cl::{ClError, ColorSource, FilmCount, GuideSums};

/// The guide buffers for a denoiser, averaged over each pixel's samples, row by row from the
/// top (docs/aovs.md).
#[derive(Clone, Debug, Default)]
pub struct Aovs {
    /// Albedo of the first surface that is not near-specular (tinted by those before it; an
    /// escaped sample's environment colour clamped to 1), each channel in [0, 1].
    pub albedo: Vec<[f32; 3]>,
    /// World-space shading normal of that surface (0 for escaped samples), not renormalised:
    /// shorter than 1 where the pixel's samples disagree.
    pub normal: Vec<[f32; 3]>,
    /// Distance from the camera along the ray to the first hit, in scene units, over the
    /// samples that hit; `f32::INFINITY` where none did.
    pub depth: Vec<f32>,
}

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

    /// The guide buffers averaged ([`Aovs`]); `None` unless
    /// [`RenderSettings::aovs`](super::RenderSettings::aovs) is on and samples were taken.
    pub fn aovs(&mut self) -> Result<Option<Aovs>, ClError> {
        if !self.pending.is_empty() {
            self.finish()?;
        }
        let Some(b) = self.aov_buffers() else {
            return Ok(None);
        };
        let (albedo, normal, depth) = (
            b.albedo.read(&self.device)?,
            b.normal.read(&self.device)?,
            b.depth.read(&self.device)?,
        );
        let scale = self.space().scale as f32;
        let mean = |s: [f32; 4], n: f32| [s[0] / n, s[1] / n, s[2] / n];
        Ok(Some(Aovs {
            albedo: albedo.iter().map(|a| mean(*a, a[3].max(1.0))).collect(),
            normal: (normal.iter().zip(&albedo))
                .map(|(s, a)| mean(*s, a[3].max(1.0)))
                .collect(),
            depth: depth
                .iter()
                .map(|d| {
                    if d[1] > 0.0 {
                        d[0] / d[1] / scale
                    } else {
                        f32::INFINITY
                    }
                })
                .collect(),
        }))
    }

    /// The guide buffers' sums on the device, for a denoiser that reads them there (layout:
    /// [`AovBuffers`]); `None` unless [`RenderSettings::aovs`](super::RenderSettings::aovs)
    /// is on and the film exists. Wait for the samples first ([`Renderer::finish`]).
    pub fn aov_buffers(&self) -> Option<&AovBuffers> {
        let f = self.frame.as_ref()?;
        (self.settings.aovs && f.aov_paths.len() > 1).then_some(&f.film.aovs)
    }

    /// The film and the guide buffers as a denoiser reads them on the device: each pixel's
    /// colour is its sums over its own sample count, as [`Renderer::image`] divides them (the
    /// film's count, or with the hits counted every pixel's samples, or with adaptive sampling
    /// those its state records); the guides are [`Renderer::aov_buffers`]. `None` where
    /// `aov_buffers` is. Wait for the samples first ([`Renderer::finish`]).
    pub fn denoise_sources(&self) -> Option<(ColorSource<'_>, GuideSums<'_>)> {
        let f = self.frame.as_ref()?;
        let aovs = self.aov_buffers()?;
        let counted = self.settings.cutout || self.settings.count_coverage;
        let count = match (counted, self.settings.noise_threshold) {
            (false, _) => FilmCount::Own,
            (true, None) => FilmCount::Taken(self.samples),
            (true, Some(_)) => FilmCount::State(&f.film.state),
        };
        let guides = GuideSums {
            albedo: &aovs.albedo,
            normal: &aovs.normal,
        };
        Some((ColorSource::Film(&f.film.sum, count), guides))
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
