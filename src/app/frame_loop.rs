//! The progressive frame loop between the window and the [`Renderer`]. It never waits for the
//! device while the window runs: a batch of samples is started, the window keeps drawing (the
//! overlay, the previous image) and polls; when the batch is done its image is read, the next
//! batch is started at once (so kernel work overlaps the display of this image), and then the
//! image is shown. Changes (camera, lights, scene, settings, window size) are collected and
//! applied together between batches; every one of them resets the accumulation. A sample too
//! long for the budget goes in bands, one per batch (budget.rs), the rest of it split finer
//! when a band runs over the budget; a change abandons the rest of the sample, so input waits
//! for one band at most. With the denoise toggle, the film is denoised on the device between
//! reading it and starting the next batch (`denoise_film`).

use super::budget::{Budget, Level, Plan, levels, pixel_count, scaled};
use super::heat::HeatMap;
use crate::cl::ClError;
use crate::denoise::{Denoiser, Quality};
use crate::render::{Band, KernelChoice, RenderSettings, RenderStats, Renderer, SceneStats};
use crate::scene::{Camera, Light, RenderFrame, Scene};
use std::time::{Duration, Instant};

/// The budget of one batch of kernel work (and of the longest launch) in milliseconds: with the
/// band in flight when input comes, the preview batch after it and the display, the next image
/// is on screen within about 100 ms.
pub const FRAME_BUDGET_MS: f64 = 25.0;

/// What changed since the last batch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changes {
    /// Objects were added, removed, hidden or moved: the BVH is rebuilt.
    pub scene: bool,
    /// Lights changed (no BVH rebuild).
    pub lights: bool,
    /// The camera moved or its field of view changed.
    pub camera: bool,
    /// Bounces, seed or sky changed.
    pub settings: bool,
}

impl Changes {
    /// Everything.
    pub const ALL: Changes = Changes {
        scene: true,
        lights: true,
        camera: true,
        settings: true,
    };

    /// Whether anything changed.
    pub fn any(&self) -> bool {
        self.scene || self.lights || self.camera || self.settings
    }

    /// Adds `other`'s changes.
    pub fn merge(&mut self, other: Changes) {
        self.scene |= other.scene;
        self.lights |= other.lights;
        self.camera |= other.camera;
        self.settings |= other.settings;
    }
}

/// What the next batch renders.
pub struct World<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The lights as rendered (radii applied).
    pub lights: &'a [Light],
    /// The camera.
    pub camera: &'a Camera,
    /// Full-resolution settings (the window's size).
    pub settings: RenderSettings,
    /// Stop at this many samples per pixel.
    pub spp_target: Option<u32>,
    /// Whether the camera is moving (a reduced resolution is allowed).
    pub moving: bool,
}

/// The latest image read from the film.
#[derive(Clone, Debug, Default)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear radiance, rows from the top.
    pub pixels: Vec<[f32; 3]>,
    /// Each pixel's coverage (`Renderer::coverage`) when the renderer counts it; else empty.
    pub coverage: Vec<f32>,
    /// The background is cut out (`RenderSettings::cutout`): `pixels` is premultiplied by
    /// `coverage`.
    pub cutout: bool,
    /// Samples per pixel in it.
    pub spp: u32,
    /// Resolution divisor it was rendered at.
    pub divisor: u32,
    /// Bounces it was rendered with.
    pub bounces: u32,
    /// Whether it is at full quality (full resolution and bounces).
    pub full_quality: bool,
    /// When the earliest change it is the first image of arrived (an input event); taken by
    /// the window when it shows the image, to measure the input's latency.
    pub answers: Option<Instant>,
    /// Counts the views: changes of the camera, scene, lights or settings (not of the level
    /// while the preview climbs back), so exposure can be decided once per view.
    pub view: u64,
    /// With [`FrameLoop::heat_map`] on samples and adaptive sampling, the samples each pixel
    /// took; else empty.
    pub samples: Vec<u32>,
    /// With [`FrameLoop::heat_map`] on error and adaptive sampling, each pixel's error
    /// estimate; else empty.
    pub errors: Vec<f32>,
    /// With [`FrameLoop::denoise`], when this film was worth denoising: its denoised image
    /// (linear, as `pixels`) and the milliseconds the host waited for it; else `None`.
    pub denoised: Option<(Vec<[f32; 3]>, f64)>,
}

/// Figures for the overlay, as of the latest finished batch.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    /// Samples per pixel so far.
    pub spp: u32,
    /// Rendering seconds since the last reset (from each batch's start to its end).
    pub seconds: f64,
    /// Pixel samples per second.
    pub samples_per_second: f64,
    /// Rays (extension and shadow) per second.
    pub rays_per_second: f64,
    /// Counters and per-stage kernel times since the last reset.
    pub stats: RenderStats,
    /// The last batch's plan.
    pub plan: Option<Plan>,
    /// The last batch's wall time in milliseconds.
    pub batch_ms: f64,
    /// The last batch's band (from 0) when its sample went in bands.
    pub band: u32,
    /// With adaptive sampling, the share of pixels the last convergence check stopped.
    pub converged_share: Option<f64>,
}

/// A sample (or a batch of samples) in progress, in one band or several.
#[derive(Clone, Copy, Debug)]
struct Sample {
    plan: Plan,
    /// The band the next batch renders.
    next_band: u32,
    /// Wall time of its bands so far.
    ms: f64,
    /// When the changes it shows first arrived.
    answers: Option<Instant>,
    /// The view it shows ([`Film::view`]).
    view: u64,
    /// Whether the camera moved when it was planned.
    moving: bool,
}

struct Batch {
    started: Instant,
    sample: Sample,
}

/// The renderer with its batches in flight and changes waiting.
pub struct FrameLoop {
    /// The renderer.
    pub renderer: Renderer,
    budget: Budget,
    batch: Option<Batch>,
    /// A sample whose next band waits to be started.
    sample: Option<Sample>,
    pending: Changes,
    /// When the earliest of the `pending` changes arrived.
    pending_since: Option<Instant>,
    /// Film size and level as applied to the renderer.
    applied: Option<((u32, u32), Level)>,
    /// The film's level (an index into `levels`) and whether it has an image yet.
    level: Option<(usize, bool)>,
    /// The current view ([`Film::view`]).
    view: u64,
    /// Whether a scene was loaded into the renderer yet.
    loaded: bool,
    /// The latest image.
    pub film: Film,
    /// The heat map whose data each film also reads (adaptive sampling's samples per pixel or
    /// error estimates).
    pub heat_map: HeatMap,
    /// Whether films are denoised (the guide buffers must be rendered: `RenderSettings::aovs`).
    pub denoise: bool,
    /// The denoisers, each network's built on its first use and kept: the camera stopping
    /// and moving again switches between them.
    denoisers: Vec<Denoiser>,
    /// The view, size and network of the last film denoised.
    last_denoised: Option<((u64, u32, u32), Quality)>,
    /// Why denoising failed (then [`FrameLoop::denoise`] is off), for the window to say.
    pub denoise_error: Option<String>,
    /// Figures for the overlay.
    pub progress: Progress,
    /// Figures from the last BVH rebuild.
    pub scene_stats: Option<SceneStats>,
}

impl FrameLoop {
    /// Whether the next step loads the first scene, which builds the kernels.
    pub fn first_load(&self) -> bool {
        !self.loaded
    }

    /// A loop around `renderer` that will load everything on its first step.
    pub fn new(renderer: Renderer) -> Self {
        Self {
            renderer,
            budget: Budget::new(FRAME_BUDGET_MS),
            batch: None,
            sample: None,
            pending: Changes::ALL,
            pending_since: None,
            applied: None,
            level: None,
            view: 0,
            loaded: false,
            film: Film::default(),
            heat_map: HeatMap::Off,
            denoise: false,
            denoisers: Vec::new(),
            last_denoised: None,
            denoise_error: None,
            progress: Progress::default(),
            scene_stats: None,
        }
    }

    /// Whether the next step builds kernels: the first load, or a scene change that needs a
    /// kernel variant not built yet (a prediction from the scene's materials).
    pub fn builds_next(&self, scene: &Scene) -> bool {
        !self.loaded || self.pending.scene && self.renderer.would_build_for(scene)
    }

    /// Records changes to apply before the next batch.
    pub fn invalidate(&mut self, changes: Changes) {
        self.invalidate_at(changes, None);
    }

    /// Records changes to apply before the next batch, caused by an input event that arrived
    /// `at` (`None`: not by one, e.g. a held key moving the camera on), whose latency the
    /// first image after it measures.
    pub fn invalidate_at(&mut self, changes: Changes, at: Option<Instant>) {
        if changes.any()
            && let Some(at) = at
        {
            self.pending_since = Some(self.pending_since.map_or(at, |t| t.min(at)));
        }
        self.pending.merge(changes);
    }

    /// When the running batch should be done, by the budget's estimate; `None` when none runs.
    pub fn expected_done(&self) -> Option<Instant> {
        let batch = self.batch.as_ref()?;
        let plan = batch.sample.plan;
        let full = self.renderer.settings();
        let ms = self
            .budget
            .estimate_ms(plan.level, (full.width, full.height))
            .map_or(0.0, |ms| ms * plan.spp as f64 / plan.bands as f64);
        Some(batch.started + Duration::from_secs_f64(ms.min(1e4) * 1e-3))
    }

    /// Whether a batch is running on the device.
    pub fn busy(&self) -> bool {
        self.batch.is_some()
    }

    /// Whether there is nothing left to do: no batch running, no change waiting, and the
    /// samples-per-pixel target reached at full resolution.
    pub fn converged(&self, spp_target: Option<u32>) -> bool {
        self.batch.is_none()
            && self.sample.is_none()
            && !self.renderer.sah_pending()
            && !self.pending.any()
            && self.level.is_some_and(|(i, _)| i == 0)
            && spp_target.is_some_and(|t| self.renderer.samples() >= t)
    }

    /// One step, without waiting: collects a finished batch (returns true when a new image is
    /// in [`FrameLoop::film`]), applies waiting changes and starts the next batch (the next
    /// band of a sample in progress, unless a change abandons it).
    pub fn step(&mut self, world: &World) -> Result<bool, ClError> {
        if self.batch.is_some() && !self.renderer.is_finished()? {
            return Ok(false);
        }
        let new_image = self.collect()?;
        if self.pending.any()
            && let Some(s) = self.sample.take()
            && let Some(t) = s.answers
        {
            // The abandoned sample's input is answered by the next image.
            self.pending_since = Some(self.pending_since.map_or(t, |p| p.min(t)));
        }
        let sample = match self.sample.take() {
            Some(s) => s,
            None => match self.next_sample(world)? {
                Some(s) => s,
                None => return Ok(new_image),
            },
        };
        let plan = sample.plan;
        if plan.bands > 1 {
            self.renderer.start_band(Band {
                index: sample.next_band,
                count: plan.bands,
            })?;
        } else {
            self.renderer.start(plan.spp)?;
        }
        self.batch = Some(Batch {
            started: Instant::now(),
            sample,
        });
        Ok(new_image)
    }

    /// Chooses the level of the next sample, applies it with the waiting changes and plans the
    /// batch; `None` when the samples-per-pixel target is reached.
    fn next_sample(&mut self, world: &World) -> Result<Option<Sample>, ClError> {
        let full = (world.settings.width, world.settings.height);
        let levels = levels(world.settings.bounces);
        let changed = self.pending.any();
        let current = self.level.map(|(i, shown)| (i, shown && !changed));
        if !self.denoise {
            self.budget.forget_denoise();
        }
        let i = self
            .budget
            .level(&levels, full, world.moving, current)
            .min(levels.len() - 1);
        let level = levels[i];
        let answers = if changed {
            self.view += 1;
            self.pending_since.take()
        } else {
            None
        };
        let reset = self.apply(world, level)?;
        if reset || self.level.is_none_or(|(j, _)| j != i) {
            self.level = Some((i, false));
        }
        let remaining = world
            .spp_target
            .map(|t| t.saturating_sub(self.renderer.samples()));
        if remaining == Some(0) {
            return Ok(None);
        }
        let bands = self.renderer.kernel() == KernelChoice::Megakernel;
        Ok(Some(Sample {
            plan: self.budget.batch(level, full, remaining, bands),
            next_band: 0,
            ms: 0.0,
            answers,
            view: self.view,
            moving: world.moving,
        }))
    }

    /// Waits for the running batch and reads its image (on exit). Returns whether the image
    /// is new.
    pub fn wait(&mut self) -> Result<bool, ClError> {
        self.collect()
    }

    /// Finishes the running batch, if any, and reads the film.
    fn collect(&mut self) -> Result<bool, ClError> {
        let Some(batch) = self.batch.take() else {
            return Ok(false);
        };
        self.renderer.finish()?;
        let ms = batch.started.elapsed().as_secs_f64() * 1e3;
        let mut sample = batch.sample;
        sample.ms += ms;
        sample.next_band += 1;
        self.progress.batch_ms = ms;
        self.progress.band = batch.sample.next_band;
        self.progress.plan = Some(sample.plan);
        if sample.next_band < sample.plan.bands {
            // A band over the budget: the rest of the sample goes in smaller bands.
            (sample.plan, sample.next_band) =
                sample
                    .plan
                    .split_rest(sample.next_band, ms, self.budget.target_ms);
            self.sample = Some(sample);
            return Ok(false);
        }
        let plan = sample.plan;
        let settings = self.renderer.settings().clone();
        let size = (settings.width, settings.height);
        self.budget
            .record(plan.level, pixel_count(size), plan.spp, sample.ms);
        if let Some(level) = self.level.as_mut() {
            level.1 = true;
        }
        let spp = self.renderer.samples();
        // The last film's arrays take the new one in their allocations: a frame allocates no
        // film-sized memory.
        let mut pixels = std::mem::take(&mut self.film.pixels);
        let mut coverage = std::mem::take(&mut self.film.coverage);
        coverage.clear();
        let counted = settings.cutout || settings.count_coverage;
        self.renderer
            .image_into(&mut pixels, counted.then_some(&mut coverage))?;
        let (samples, errors) = self.heat_data()?;
        let full_quality = self.level.is_some_and(|(i, _)| i == 0);
        let denoised = match self.denoise && settings.aovs {
            true => self.denoise_film((sample.view, size.0, size.1), &sample, full_quality),
            false => None,
        };
        self.film = Film {
            width: size.0,
            height: size.1,
            pixels,
            coverage,
            cutout: settings.cutout,
            spp,
            divisor: plan.level.divisor,
            bounces: plan.level.bounces,
            full_quality,
            // An image collected over one never shown answers its input when it is shown.
            answers: sample.answers.or(self.film.answers),
            view: sample.view,
            samples,
            errors,
            denoised,
        };
        let p = &mut self.progress;
        p.seconds += sample.ms * 1e-3;
        p.spp = spp;
        p.stats = self.renderer.stats().clone();
        p.converged_share = self
            .renderer
            .active_pixels()
            .map(|active| 1.0 - f64::from(active) / pixel_count(size).max(1) as f64);
        if p.seconds > 0.0 {
            p.samples_per_second = pixel_count(size) as f64 * spp as f64 / p.seconds;
            p.rays_per_second = (p.stats.extension_rays + p.stats.shadow_rays) as f64 / p.seconds;
        }
        Ok(true)
    }

    /// The data of [`FrameLoop::heat_map`] for the film the renderer holds: its samples per pixel
    /// or its error estimates (empty without adaptive sampling).
    fn heat_data(&mut self) -> Result<(Vec<u32>, Vec<f32>), ClError> {
        Ok(match self.heat_map {
            HeatMap::Off => (Vec::new(), Vec::new()),
            HeatMap::Samples => (
                self.renderer.pixel_samples()?.unwrap_or_default(),
                Vec::new(),
            ),
            HeatMap::Error => (
                Vec::new(),
                self.renderer.pixel_errors()?.unwrap_or_default(),
            ),
        })
    }

    /// Reads the heat map's data into the film at once when no batch runs (the image rests, or
    /// its target is reached) and the film lacks it; returns whether it did. While batches run,
    /// the next one's film brings it.
    pub fn read_heat_map(&mut self) -> Result<bool, ClError> {
        let film = &self.film;
        let pixels = film.pixels.len();
        let missing = match self.heat_map {
            HeatMap::Off => false,
            HeatMap::Samples => film.samples.len() != pixels,
            HeatMap::Error => film.errors.len() != pixels,
        };
        let settings = self.renderer.settings();
        let same_film = (settings.width, settings.height) == (film.width, film.height);
        if !missing || pixels == 0 || self.batch.is_some() || !same_film {
            return Ok(false);
        }
        let (samples, errors) = self.heat_data()?;
        if samples.is_empty() && errors.is_empty() {
            return Ok(false);
        }
        self.film.samples = samples;
        self.film.errors = errors;
        Ok(true)
    }

    /// Denoises the film just finished, on the device where it lies, when it is worth it:
    /// every preview image and every image while the camera moves (the small network), and at
    /// full quality the first image of a view, the first after the camera stopped and each one
    /// whose samples per pixel doubled (the full network). A preview's time goes into the
    /// budget, so that the preview lowers its resolution while the denoising takes time. `None`
    /// when not worth it (the last denoised image of the view stays on screen) or on an error,
    /// which turns denoising off and is kept in [`FrameLoop::denoise_error`].
    fn denoise_film(
        &mut self,
        key: (u64, u32, u32),
        sample: &Sample,
        full_quality: bool,
    ) -> Option<(Vec<[f32; 3]>, f64)> {
        let quality = match full_quality && !sample.moving {
            true => Quality::Full,
            false => Quality::Small,
        };
        let worth = quality == Quality::Small
            || self.last_denoised != Some((key, Quality::Full))
            || self.renderer.samples().is_power_of_two();
        if !worth {
            return None;
        }
        let result = (|| {
            if !self.denoisers.iter().any(|d| d.quality() == quality) {
                self.denoisers
                    .push(Denoiser::new(&self.renderer.device, quality)?);
            }
            let denoiser = (self.denoisers.iter_mut())
                .find(|d| d.quality() == quality)
                .expect("built above");
            let start = Instant::now();
            let (pixels, _) = denoiser.denoise_film(&mut self.renderer)?;
            Ok::<_, crate::denoise::DenoiseError>((pixels, start.elapsed().as_secs_f64() * 1e3))
        })();
        match result {
            Ok((pixels, ms)) => {
                self.last_denoised = Some((key, quality));
                if quality == Quality::Small {
                    let level = sample.plan.level;
                    self.budget
                        .record_denoise(level, pixel_count((key.1, key.2)), ms);
                }
                Some((pixels, ms))
            }
            Err(e) => {
                self.denoise_error = Some(e.to_string());
                self.denoise = false;
                self.last_denoised = None;
                None
            }
        }
    }

    /// Applies waiting changes and `level`; returns whether the film was reset (anything
    /// changed).
    fn apply(&mut self, world: &World, level: Level) -> Result<bool, ClError> {
        let full = (world.settings.width, world.settings.height);
        let divisor = level.divisor;
        let size = scaled(full, divisor);
        let mut pending = std::mem::take(&mut self.pending);
        let mut reset = false;
        // The SAH BLASes behind a quick first image are done: the scene goes to the device
        // again with them and the image restarts (unless the scene is reloaded anyway).
        if self.loaded
            && !pending.scene
            && let Some(stats) = self.renderer.swap_in_sah(world.scene, world.lights)?
        {
            log::info!(
                "SAH BLASes in: built in {:.0} ms, the scene on the device again in {:.0} ms",
                stats.bvh_build_ms,
                stats.upload_ms
            );
            self.scene_stats = Some(stats);
            // The upload reset the film and applied the camera and lights.
            self.progress = Progress::default();
            reset = true;
        }
        if pending.any() {
            log::debug!(
                "applying {pending:?} at {}x{} (1/{divisor})",
                size.0,
                size.1
            );
        }
        if pending.settings || self.applied != Some((size, level)) {
            let settings = RenderSettings {
                width: size.0,
                height: size.1,
                bounces: level.bounces,
                ..world.settings.clone()
            };
            self.renderer.set_settings(&settings)?;
            self.applied = Some((size, level));
            // The camera's aspect follows the film.
            pending.camera = true;
        }
        // Rebase the render space around the eye when the camera travelled far from its origin.
        let far = self.loaded && self.renderer.space().is_far(world.camera.eye);
        // Objects moved, hidden or shown, or a new pose of the animation (a scene change alone:
        // a new file comes with new lights and settings too): `Renderer::update_scene`, as
        // `render --frames` does: moved instances of a two-level scene, a flat BVH refitted
        // with what changed written in place, or a reload; the overlay shows its BVH and
        // upload times.
        let moved = if pending.scene && self.loaded && !far && !pending.lights && !pending.settings
        {
            let animation = &world.scene.animation;
            let deformed = animation.objects.iter().any(|d| d.rig.is_some());
            Some(
                self.renderer
                    .update_scene(world.scene, world.lights, deformed)?,
            )
        } else {
            None
        };
        if let Some(update) = moved {
            if let Some(stats) = self.scene_stats.as_mut() {
                stats.bvh_build_ms = update.bvh_ms;
                stats.upload_ms = update.flatten_ms + update.upload_ms;
                stats.written_bytes = update.bytes;
            }
        } else if pending.scene || !self.loaded || far {
            let mut space = RenderFrame::around(&world.scene.bounds());
            if far || space.is_far(world.camera.eye) {
                space = RenderFrame::new(&world.scene.bounds(), world.camera.eye);
            }
            let stats = self
                .renderer
                .load_scene_in(world.scene, world.lights, space)?;
            if stats.dropped_triangles > 0 && !self.loaded {
                log::warn!(
                    "{} triangles with a non-finite or absurd vertex dropped",
                    stats.dropped_triangles
                );
            }
            log::info!(
                "scene on the device ({}): BVH {:.0} ms, upload {:.0} ms, kernels {:.0} ms{}",
                stats.bvh,
                stats.bvh_build_ms,
                stats.upload_ms,
                stats.kernel_build_ms,
                if self.renderer.sah_pending() {
                    " (quick BLASes; the SAH ones build behind them)"
                } else {
                    ""
                }
            );
            self.scene_stats = Some(stats);
            self.loaded = true;
            // The cost model is per device and scene.
            self.budget = Budget::new(self.budget.target_ms);
        } else if pending.lights {
            self.renderer.set_lights(world.lights)?;
        }
        if pending.camera {
            self.renderer.set_camera(world.camera)?;
        }
        if pending.any() {
            self.progress = Progress::default();
            reset = true;
        }
        Ok(reset)
    }
}
