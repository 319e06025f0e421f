//! The megakernel: on CPU devices a frame is one kernel launch in which each work item traces
//! whole paths for one pixel (kernels/cpu/megakernel.cl). It computes the wavefront's estimator
//! (the same shading function, kernels/shared/path.h) without its queues, path buffers and per-bounce
//! launches, which cost more than they save where there are only a few cores.

use super::Renderer;
use crate::cl::kernels::{Launch, band_items};
use crate::cl::types::DeviceFrame;
use crate::cl::{ClError, Stage};
use std::str::FromStr;
use std::time::Instant;

/// Which kernels render: the wavefront stages or the megakernel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum KernelChoice {
    /// The megakernel on CPU devices (CL_DEVICE_TYPE_CPU), the wavefront elsewhere.
    #[default]
    Auto,
    /// Queued stages per bounce (what GPUs run best).
    Wavefront,
    /// One path per work item, all bounces in one kernel.
    Megakernel,
}

impl FromStr for KernelChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "" | "auto" => Ok(Self::Auto),
            "wavefront" => Ok(Self::Wavefront),
            "megakernel" => Ok(Self::Megakernel),
            _ => Err(format!(
                "kernel '{s}' is not 'wavefront', 'megakernel' or 'auto'"
            )),
        }
    }
}

/// Part of one sample's work: band `index` of `count` contiguous bands of the megakernel's work
/// items (rows of pixels, or of lanes' tiles), so that on a slow device no single launch blocks
/// the queue for longer than a frame's budget and new input waits for one band, not a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Band {
    /// Which band, from 0.
    pub index: u32,
    /// How many bands the sample is split into (at least 1).
    pub count: u32,
}

impl Band {
    /// The whole sample in one launch.
    pub const WHOLE: Band = Band { index: 0, count: 1 };

    /// Whether this is the sample's last band (after which it counts).
    pub fn is_last(&self) -> bool {
        self.index + 1 >= self.count
    }
}

/// Paths one megakernel launch may trace at most, so that its 32-bit ray counters cannot
/// overflow (each path traces at most bounces + 2 extension rays and as many shadow rays).
const MAX_RAYS_PER_LAUNCH: u64 = 1 << 31;

impl Renderer {
    /// Chooses the kernels (resolving `Auto` by the device type); with a scene loaded, builds
    /// the kernels again where the strategy for the new ones differs. Resets the film.
    pub fn set_kernel(&mut self, choice: KernelChoice) -> Result<(), ClError> {
        self.megakernel = super::strategy::runs_megakernel(&self.device_facts, choice);
        if self.scene.is_some() {
            self.ensure_program()?;
        }
        // The loaded scene's node arrays are those of the kernels it was loaded for.
        self.ensure_node_forms()?;
        self.reset()
    }

    /// How the megakernel's lanes load their nodes and triangles, `"rows"` or `"gathers"`;
    /// `None` where it does not walk in lanes.
    pub fn lanes_load(&self) -> Option<&'static str> {
        self.walks_in_lanes().then(|| {
            if self.megakernel_has(|f| f.lanes_gathers) {
                "gathers"
            } else {
                "rows"
            }
        })
    }

    /// Whether the megakernel runs with kernels built for a feature `f` picks out.
    fn megakernel_has(&self, f: impl Fn(&crate::cl::KernelFeatures) -> bool) -> bool {
        self.megakernel && self.program.as_ref().is_some_and(|p| f(&p.features))
    }

    /// Whether the megakernel walks its extension rays sixteen at a time in vector lanes
    /// (`KernelFeatures::lanes`, kernels/cpu/traverse_lanes.h) for the loaded scene.
    pub fn walks_in_lanes(&self) -> bool {
        self.megakernel_has(|f| f.lanes)
    }

    /// Whether the megakernel's lanes shade their vertices in batches, in vectors
    /// (`KernelFeatures::lanes_shade`).
    pub fn shades_in_lanes(&self) -> bool {
        self.megakernel_has(|f| f.lanes_shade)
    }

    /// Whether the megakernel's lanes test a small scene's triangles whole instead of walking
    /// its tree (`KernelFeatures::lanes_small`).
    pub fn tests_small_scene_in_lanes(&self) -> bool {
        self.megakernel_has(|f| f.lanes_small)
    }

    /// The kernels in use (never `Auto`).
    pub fn kernel(&self) -> KernelChoice {
        if self.megakernel {
            KernelChoice::Megakernel
        } else {
            KernelChoice::Wavefront
        }
    }

    /// Launches the megakernel once with no samples and waits, so that a driver which compiles
    /// kernels at their first launch (PoCL does, per work-group size) does it now, in the
    /// kernel build time, and not in the first frame. Returns the milliseconds it took.
    pub(super) fn prime_megakernel(&mut self) -> Result<f64, ClError> {
        if !self.megakernel || self.scene.is_none() {
            return Ok(0.0);
        }
        let t = Instant::now();
        self.ensure_frame()?;
        // Over every pixel with no samples: PoCL specialises a kernel for its grid (a grid of 0
        // items compiles a variant the frames never use, and the first frame compiled again).
        let mut frame = self.settings.gpu_frame(self.light_count);
        frame.samples_in_wave = 0;
        self.launch_megakernel(&frame, Band::WHOLE)?;
        // A launch with a global offset (a band of a sample) is another variant for PoCL.
        self.launch_megakernel(&frame, Band { index: 1, count: 2 })?;
        self.device
            .queue
            .finish()
            .map_err(crate::cl::call_err("building the megakernel"))?;
        Ok(t.elapsed().as_secs_f64() * 1e3)
    }

    /// One megakernel launch for `frame` over the work items of `band`, then `advance` to move
    /// its ray counts into the totals.
    fn launch_megakernel(
        &self,
        frame: &DeviceFrame,
        band: Band,
    ) -> Result<[(Stage, Launch); 2], ClError> {
        let (Some(program), Some((scene, _)), Some(f)) = (
            self.program.as_ref(),
            self.scene.as_ref(),
            self.frame.as_ref(),
        ) else {
            return Err(ClError::Device("no scene is loaded".into()));
        };
        let (device, counters) = (&self.device, &self.counters);
        // The small-scene test (kernels built for whole batches of triangles) takes the count
        // here, so that a scene's hidden objects need no other kernels.
        let frame = &DeviceFrame {
            triangles: if program.features.small_scene > 0 || program.features.lanes_small {
                scene.triangles.len() as u32
            } else {
                0
            },
            ..*frame
        };
        let (items, local) = program.megakernel_items(frame);
        let items = band_items(items, local, band.index as usize, band.count as usize);
        let l = program.megakernel(
            device,
            frame,
            &self.camera,
            &self.env,
            scene,
            &f.film,
            counters,
            items,
        )?;
        let a = program.advance(device, counters, &self.stats_buffer)?;
        Ok([(Stage::Megakernel, l), (Stage::Advance, a)])
    }

    /// Enqueues `spp` more samples per pixel as megakernel launches (as few as the ray
    /// counters allow).
    pub(super) fn enqueue_megakernel(&mut self, spp: u32) -> Result<Vec<(Stage, Launch)>, ClError> {
        self.ensure_frame()?;
        let pixels = u64::from(self.settings.width * self.settings.height).max(1);
        let rays_per_sample = 2 * (u64::from(self.settings.bounces) + 2);
        let per_launch = (MAX_RAYS_PER_LAUNCH / (pixels * rays_per_sample)).clamp(1, 1 << 16);
        let mut launches = Vec::new();
        let mut done = 0;
        while done < spp {
            let n = (per_launch as u32).min(spp - done);
            let mut frame = self.settings.gpu_frame(self.light_count);
            frame.samples_in_wave = n;
            frame.first_sample = self.next_sample + done;
            launches.extend(self.launch_megakernel(&frame, Band::WHOLE)?);
            done += n;
        }
        self.samples += spp;
        self.next_sample += spp;
        Ok(launches)
    }

    /// Enqueues `band` of the next sample; the sample counts once its last band is enqueued.
    /// Every band renders the same sample index, so the bands of a sample together give the
    /// film exactly what one whole launch does.
    pub(super) fn enqueue_megakernel_band(
        &mut self,
        band: Band,
    ) -> Result<Vec<(Stage, Launch)>, ClError> {
        self.ensure_frame()?;
        let mut frame = self.settings.gpu_frame(self.light_count);
        frame.first_sample = self.next_sample;
        let launches = self.launch_megakernel(&frame, band)?;
        if band.is_last() {
            self.samples += 1;
            self.next_sample += 1;
        }
        Ok(launches.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_kernel_choices() {
        assert_eq!("auto".parse(), Ok(KernelChoice::Auto));
        assert_eq!("Wavefront".parse(), Ok(KernelChoice::Wavefront));
        assert_eq!("megakernel".parse(), Ok(KernelChoice::Megakernel));
        assert!("fast".parse::<KernelChoice>().is_err());
    }
}
