//! The wavefront loop (after pbrt-v4's wavefront integrator): each wave of paths runs through
//! the [`Stage`]s in launch order, one kernel each, with queues of live paths between them.
//! [`Wave`] has one method per stage; the [`Renderer`] methods here enqueue waves, wait for them
//! and gather their statistics.

use super::Renderer;
pub use crate::cl::Stage;
use crate::cl::kernels::{AdaptiveFilm, AovBuffers, EnvBuffers, Launch, SceneBuffers};
use crate::cl::types::*;
use crate::cl::{Buffer, ClError, Device, Program};

/// Kernel time per stage, in launch order ([`Stage::ALL`]); empty until a frame ran.
#[derive(Clone, Debug, Default)]
pub struct StageTimes(Vec<(&'static str, f64)>);

impl StageTimes {
    /// Adds `ms` to `stage`.
    pub fn add(&mut self, stage: Stage, ms: f64) {
        if self.0.is_empty() {
            self.0 = Stage::ALL.iter().map(|s| (s.name(), 0.0)).collect();
        }
        self.0[stage as usize].1 += ms;
    }

    /// The time of `stage` (0 before any frame).
    pub fn get(&self, stage: Stage) -> f64 {
        self.0.get(stage as usize).map_or(0.0, |t| t.1)
    }

    /// (stage name, milliseconds) in launch order.
    pub fn iter(&self) -> std::slice::Iter<'_, (&'static str, f64)> {
        self.0.iter()
    }

    /// Whether no frame ran since the last reset.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl<'a> IntoIterator for &'a StageTimes {
    type Item = &'a (&'static str, f64);
    type IntoIter = std::slice::Iter<'a, (&'static str, f64)>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

/// A map from stage name to milliseconds, as the JSON summaries print it.
impl serde::Serialize for StageTimes {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, ms) in &self.0 {
            map.serialize_entry(name, ms)?;
        }
        map.end()
    }
}

/// Counters of the work done since the last reset.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    /// Extension (closest-hit) rays traced.
    pub extension_rays: u64,
    /// Shadow (any-hit) rays traced.
    pub shadow_rays: u64,
    /// Samples dropped because they were NaN or infinite.
    pub nonfinite_samples: u64,
    /// Traversal stack overflows (must stay 0).
    pub stack_overflows: u64,
    /// Kernel time per stage in milliseconds, from profiling events, in launch order.
    pub stage_ms: StageTimes,
}

impl RenderStats {
    /// Sum of all stages' kernel time.
    pub fn kernel_ms(&self) -> f64 {
        self.stage_ms.iter().map(|(_, ms)| ms).sum()
    }

    /// Adds `other`'s counts and stage times: the work of two devices' renders.
    pub fn add(&mut self, other: &RenderStats) {
        self.extension_rays += other.extension_rays;
        self.shadow_rays += other.shadow_rays;
        self.nonfinite_samples += other.nonfinite_samples;
        self.stack_overflows += other.stack_overflows;
        for (i, (_, ms)) in other.stage_ms.iter().enumerate() {
            if *ms > 0.0 {
                self.stage_ms.add(Stage::ALL[i], *ms);
            }
        }
    }
}

/// Per-resolution device buffers.
pub(super) struct Frame {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) slots: usize,
    pub(super) film: AdaptiveFilm,
    pub(super) paths: Buffer<DevicePath>,
    pub(super) queues: [Buffer<u32>; 2],
    pub(super) hits: Buffer<DeviceHit>,
    pub(super) shadow_rays: Buffer<DeviceShadowRay>,
    /// Ray cone (width, spread angle) per slot, for texture filtering.
    pub(super) cones: Buffer<[f32; 2]>,
    /// With guide buffers, each slot's record as two float4s (kernels/shared/aovs.h); else one
    /// placeholder element.
    pub(super) aov_paths: Buffer<[f32; 4]>,
}

/// Paths in flight per wave on a GPU, and on other devices.
const WAVE_PATHS_GPU: usize = 1 << 21;
const WAVE_PATHS_CPU: usize = 1 << 16;

/// One wave's launches: the device state every stage reads, and one method per stage.
struct Wave<'a> {
    device: &'a Device,
    program: &'a Program,
    scene: &'a SceneBuffers,
    env: &'a EnvBuffers,
    camera: &'a DeviceCamera,
    frame: &'a Frame,
    counters: &'a Buffer<u32>,
    stats: &'a Buffer<u64>,
    /// Path slots in this wave.
    slots: usize,
    /// The most paths a bounce's queue holds: the active pixels' slots (all of them without
    /// adaptive sampling). `extend`, `shade` and `connect` are launched over this many.
    live: usize,
    launches: Vec<(Stage, Launch)>,
}

impl Wave<'_> {
    fn push(&mut self, stage: Stage, launch: Launch) {
        self.launches.push((stage, launch));
    }

    fn generate(&mut self, frame: &DeviceFrame) -> Result<(), ClError> {
        let f = self.frame;
        let l = self.program.generate(
            self.device,
            frame,
            self.camera,
            &f.paths,
            &f.queues[0],
            self.counters,
            &f.cones,
            &f.film.state,
            &f.aov_paths,
            self.slots,
        )?;
        self.push(Stage::Generate, l);
        if frame.adaptive != 0 {
            // `generate` queued the active pixels' slots in COUNT_OUT: the first bounce's input.
            self.advance()?;
        }
        Ok(())
    }

    fn extend(&mut self, queue_in: usize) -> Result<(), ClError> {
        let f = self.frame;
        let l = self.program.extend(
            self.device,
            self.scene,
            &f.paths,
            &f.queues[queue_in],
            self.counters,
            &f.hits,
            self.live,
        )?;
        self.push(Stage::Extend, l);
        Ok(())
    }

    fn shade(
        &mut self,
        frame: &DeviceFrame,
        queue_in: usize,
        queue_out: usize,
    ) -> Result<(), ClError> {
        let f = self.frame;
        let l = self.program.shade(
            self.device,
            frame,
            self.env,
            self.scene,
            &f.paths,
            &f.queues[queue_in],
            &f.hits,
            &f.queues[queue_out],
            &f.shadow_rays,
            self.counters,
            &f.cones,
            &f.aov_paths,
            &f.film.rays,
            self.live,
        )?;
        self.push(Stage::Shade, l);
        Ok(())
    }

    fn connect(&mut self) -> Result<(), ClError> {
        let f = self.frame;
        let l = self.program.connect(
            self.device,
            self.scene,
            &f.shadow_rays,
            self.counters,
            &f.paths,
            self.live,
        )?;
        self.push(Stage::Connect, l);
        Ok(())
    }

    fn advance(&mut self) -> Result<(), ClError> {
        let l = self
            .program
            .advance(self.device, self.counters, self.stats)?;
        self.push(Stage::Advance, l);
        Ok(())
    }

    fn accumulate(&mut self, frame: &DeviceFrame) -> Result<(), ClError> {
        let f = self.frame;
        let l = self.program.accumulate(
            self.device,
            frame,
            &f.paths,
            &f.aov_paths,
            &f.film,
            self.counters,
        )?;
        self.push(Stage::Accumulate, l);
        Ok(())
    }
}

/// The most waves [`Renderer::render`] enqueues before it waits for them.
pub const MAX_WAVES_PER_BATCH: u32 = 64;

impl Renderer {
    /// Allocates the film and the per-slot buffers for the current size.
    pub(super) fn ensure_frame(&mut self) -> Result<(), ClError> {
        let (w, h) = (self.settings.width, self.settings.height);
        let pixels = (w * h) as usize;
        let wave = if self.device.info.is_gpu {
            WAVE_PATHS_GPU
        } else {
            WAVE_PATHS_CPU
        };
        let slots = pixels * (wave / pixels).max(1);
        let aovs = self.settings.aovs;
        if self.frame.as_ref().is_some_and(|f| {
            f.width == w && f.height == h && f.slots == slots && (f.aov_paths.len() > 1) == aovs
        }) {
            return Ok(());
        }
        self.frame = None; // free the old buffers first
        let device = &self.device;
        let mut film = AdaptiveFilm {
            sum: Buffer::new(device, pixels)?,
            half: Buffer::new(device, pixels)?,
            state: Buffer::new(device, pixels)?,
            rays: Buffer::new(device, pixels)?,
            aovs: AovBuffers::new(device, if aovs { pixels } else { 1 })?,
        };
        film.sum.clear(device)?;
        film.half.clear(device)?;
        film.state.clear(device)?;
        film.rays.clear(device)?;
        self.frame = Some(Frame {
            width: w,
            height: h,
            slots,
            film,
            paths: Buffer::new(device, slots)?,
            queues: [Buffer::new(device, slots)?, Buffer::new(device, slots)?],
            hits: Buffer::new(device, slots)?,
            shadow_rays: Buffer::new(device, slots)?,
            cones: Buffer::new(device, slots)?,
            aov_paths: Buffer::new(device, if aovs { 2 * slots } else { 1 })?,
        });
        self.samples = 0;
        Ok(())
    }

    /// Renders `spp` more samples per pixel into the film and waits for them.
    ///
    /// The samples go in batches of at most `MAX_WAVES_PER_BATCH` waves: every launch holds
    /// an event on the host until the queue finishes, so one batch of any `spp` would grow host
    /// memory with it. Batches are whole waves, so the image is the same as in one batch.
    pub fn render(&mut self, spp: u32) -> Result<(), ClError> {
        self.ensure_frame()?;
        let per_wave = match &self.frame {
            Some(f) => (f.slots / (f.width * f.height) as usize).max(1) as u32,
            None => 1,
        };
        let batch = per_wave.saturating_mul(MAX_WAVES_PER_BATCH);
        let mut left = spp;
        while left > 0 {
            let n = left.min(batch);
            self.start(n)?;
            self.finish()?;
            left -= n;
        }
        Ok(())
    }

    /// Enqueues `spp` more samples per pixel and returns at once, so the host can do other
    /// work (display the last frame) while the device renders; [`Renderer::finish`] waits.
    pub fn start(&mut self, spp: u32) -> Result<(), ClError> {
        let launches = self.enqueue(spp)?;
        self.pending.extend(launches);
        self.device
            .queue
            .flush()
            .map_err(crate::cl::call_err("submitting the frame"))
    }

    /// Enqueues `band` of one more sample per pixel and returns at once, like
    /// [`Renderer::start`]; the sample counts (and adaptive sampling checks) once its last band
    /// is enqueued. The megakernel splits its launch ([`Band`]); the wavefront, whose per-bounce
    /// launches are short already, renders the whole sample at the last band and nothing before.
    pub fn start_band(&mut self, band: super::Band) -> Result<(), ClError> {
        let mut launches = if self.megakernel {
            self.enqueue_megakernel_band(band)?
        } else if band.is_last() {
            self.enqueue_samples(1)?
        } else {
            Vec::new()
        };
        if band.is_last()
            && let Some(threshold) = self.settings.noise_threshold
        {
            launches.extend(self.enqueue_check_if_due(threshold)?);
        }
        self.pending.extend(launches);
        self.device
            .queue
            .flush()
            .map_err(crate::cl::call_err("submitting the frame"))
    }

    /// Whether the work [`Renderer::start`] enqueued is done (true when nothing is pending).
    /// Never waits, so a viewer can keep drawing while the device works; the queue is in
    /// order, so the last launch finishing means all have.
    pub fn is_finished(&self) -> Result<bool, ClError> {
        let Some((_, last)) = self.pending.last() else {
            return Ok(true);
        };
        let status = last
            .event
            .command_execution_status()
            .map_err(crate::cl::call_err("polling the frame"))?;
        // CL_COMPLETE is 0; negative values are errors, which `finish` reports.
        Ok(status.0 <= 0)
    }

    /// Waits for the work [`Renderer::start`] enqueued and gathers its statistics.
    pub fn finish(&mut self) -> Result<(), ClError> {
        self.device
            .queue
            .finish()
            .map_err(crate::cl::call_err("waiting for the frame"))?;
        let launches = std::mem::take(&mut self.pending);
        self.collect(launches)
    }

    /// Enqueues `spp` more samples without waiting, with adaptive sampling's convergence
    /// checks between them.
    fn enqueue(&mut self, spp: u32) -> Result<Vec<(Stage, Launch)>, ClError> {
        match self.settings.noise_threshold {
            Some(threshold) => self.enqueue_adaptive(spp, threshold),
            None => self.enqueue_samples(spp),
        }
    }

    /// Enqueues `spp` more samples by the kernels in use.
    pub(super) fn enqueue_samples(&mut self, spp: u32) -> Result<Vec<(Stage, Launch)>, ClError> {
        if self.megakernel {
            self.enqueue_megakernel(spp)
        } else {
            self.enqueue_wavefront(spp)
        }
    }

    /// Enqueues the stages for `spp` more samples without waiting: per wave, `generate`, then
    /// `extend`, `shade`, `connect` and `advance` for each bounce, then `accumulate`.
    fn enqueue_wavefront(&mut self, spp: u32) -> Result<Vec<(Stage, Launch)>, ClError> {
        self.ensure_frame()?;
        let (Some(program), Some((scene, _)), Some(f)) = (
            self.program.as_ref(),
            self.scene.as_ref(),
            self.frame.as_ref(),
        ) else {
            return Err(ClError::Device("no scene is loaded".into()));
        };
        let pixels = (f.width * f.height) as usize;
        let per_wave = (f.slots / pixels).max(1) as u32;
        // With adaptive sampling `generate` queues only the active pixels' paths, as many as
        // the last convergence check counted (read back before any later wave: see
        // `enqueue_adaptive`); the bounces' launches are sized to them.
        let active = match (self.settings.noise_threshold, self.active_pixels) {
            (Some(_), Some(active)) => (active as usize).min(pixels),
            _ => pixels,
        };
        let mut wave = Wave {
            device: &self.device,
            program,
            scene,
            env: &self.env,
            camera: &self.camera,
            frame: f,
            counters: &self.counters,
            stats: &self.stats_buffer,
            slots: 0,
            live: 0,
            launches: Vec::new(),
        };
        let mut done = 0;
        while done < spp {
            let n = per_wave.min(spp - done);
            wave.slots = pixels * n as usize;
            wave.live = active * n as usize;
            let mut frame = self.settings.gpu_frame(self.light_count);
            frame.samples_in_wave = n;
            frame.first_sample = self.next_sample + done;
            wave.generate(&frame)?;
            for bounce in 0..=self.settings.bounces + 1 {
                frame.bounce = bounce;
                // The queues swap roles every bounce.
                let (qi, qo) = if bounce % 2 == 0 { (0, 1) } else { (1, 0) };
                wave.extend(qi)?;
                wave.shade(&frame, qi, qo)?;
                wave.connect()?;
                wave.advance()?;
            }
            wave.accumulate(&frame)?;
            done += n;
        }
        self.samples += spp;
        self.next_sample += spp;
        Ok(wave.launches)
    }

    /// Reads counters and profiling times after the queue has finished.
    fn collect(&mut self, launches: Vec<(Stage, Launch)>) -> Result<(), ClError> {
        for (stage, l) in &launches {
            self.stats.stage_ms.add(*stage, l.millis());
        }
        let counters = self.counters.read(&self.device)?;
        let stats = self.stats_buffer.read(&self.device)?;
        self.stats.extension_rays = stats[STAT_EXTENSION_RAYS];
        self.stats.shadow_rays = stats[STAT_SHADOW_RAYS];
        self.stats.nonfinite_samples = counters[COUNT_NONFINITE] as u64;
        self.stats.stack_overflows = counters[COUNT_OVERFLOW] as u64;
        if self.adaptive_checked {
            self.active_pixels = Some(counters[COUNT_ACTIVE]);
            self.active_stale = false;
        }
        Ok(())
    }
}
