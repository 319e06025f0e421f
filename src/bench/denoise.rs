//! `penumbra bench denoise`: the denoiser's network time on the device (OpenCL profiling
//! events, a warm-up run discarded) on a synthetic noisy image, the time the host waits from a
//! film on the device to the denoised image in host memory (`render --denoise`'s path) beside
//! the host path's (the images uploaded, denoised, read back), and,
//! where `pyoidn` is installed, Intel's Open Image Denoise on the same input (its CPU device,
//! or CUDA with `--oidn-device cuda`), with the ratio.

use super::{device_json, device_line};
use crate::cl::types::FILM_FRACTION_BITS;
use crate::cl::{Buffer, Device, DeviceChoice};
use crate::date::today;
use crate::denoise::{ColorSource, DenoiseInput, Denoiser, FilmCount, GuideSums, Quality, oidn};
use anyhow::{Result, bail};
use clap::Args;
use std::time::Instant;

/// Samples per pixel of the film the synthetic image is written into.
const FILM_SPP: u32 = 16;

/// Options of `bench denoise`.
#[derive(Args, Debug, Clone)]
pub struct DenoiseArgs {
    /// OpenCL device: gpu, cpu or an index from `penumbra devices` (default: first GPU, else
    /// first CPU; also PENUMBRA_DEVICE).
    #[arg(long)]
    pub device: Option<String>,
    /// Image width (default: 960).
    #[arg(long, default_value_t = 960)]
    pub width: usize,
    /// Image height (default: 600).
    #[arg(long, default_value_t = 600)]
    pub height: usize,
    /// Network: full, small or large (default: full).
    #[arg(long, default_value = "full")]
    pub quality: String,
    /// Timed runs after the warm-up (default: 3).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Open Image Denoise's device for the comparison: cpu, cuda or none (default: cpu).
    #[arg(long, default_value = "cpu")]
    pub oidn_device: String,
}

/// A noisy HDR image with guides: soft shapes and edges, a bright light, per-pixel noise of a
/// few samples per pixel. The network's time does not depend on the content.
pub fn synthetic(width: usize, height: usize) -> [Vec<[f32; 3]>; 3] {
    let (mut c, mut a, mut n) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..height {
        for x in 0..width {
            let (u, v) = (x as f32 / width as f32, y as f32 / height as f32);
            let h = ((y * width + x) as u32).wrapping_mul(2_654_435_761) >> 8;
            let noise = (h & 0xffff) as f32 / 65536.0;
            let inside = (u - 0.5).powi(2) + (v - 0.5).powi(2) < 0.08;
            let albedo = if inside {
                [0.8, 0.3, 0.2]
            } else {
                [0.6, 0.6, 0.6]
            };
            let light = if v < 0.05 && (u - 0.5).abs() < 0.1 {
                20.0
            } else {
                1.0 - 0.7 * v
            };
            let l = light * 4.0 * noise * noise;
            c.push(albedo.map(|k| k * l));
            a.push(albedo);
            let nx = if inside { (u - 0.5) * 3.0 } else { 0.0 };
            n.push([nx, 0.0, (1.0 - nx * nx).max(0.0).sqrt()]);
        }
    }
    [c, a, n]
}

/// A film and its guide sums in host memory, laid out as the renderer keeps them.
struct HostFilm {
    /// Fixed-point colour sums with the count (kernels/shared/film.h).
    sums: Vec<[u64; 4]>,
    /// Albedo sums with the count (kernels/shared/aovs.h).
    albedo: Vec<[f32; 4]>,
    /// Normal sums.
    normal: Vec<[f32; 4]>,
}

/// The synthetic image as the renderer's film and guide buffers hold it after `spp` samples.
fn as_film(images: &[Vec<[f32; 3]>; 3], spp: u32) -> HostFilm {
    let n = spp as f32;
    let one = (1u64 << FILM_FRACTION_BITS) as f64;
    let fixed = |v: f32| (f64::from(v * n) * one).round() as u64;
    let sums = |image: &[[f32; 3]], w: f32| {
        image
            .iter()
            .map(|p| [p[0] * n, p[1] * n, p[2] * n, w])
            .collect()
    };
    HostFilm {
        sums: images[0]
            .iter()
            .map(|c| [fixed(c[0]), fixed(c[1]), fixed(c[2]), u64::from(spp)])
            .collect(),
        albedo: sums(&images[1], n),
        normal: sums(&images[2], 0.0),
    }
}

/// The synthetic image as a film on the device, and the output buffer.
struct DeviceFilm {
    film: Buffer<[u64; 4]>,
    albedo: Buffer<[f32; 4]>,
    normal: Buffer<[f32; 4]>,
    output: Buffer<[f32; 4]>,
}

impl DeviceFilm {
    fn new(device: &Device, images: &[Vec<[f32; 3]>; 3], pixels: usize) -> Result<Self> {
        let host = as_film(images, FILM_SPP);
        Ok(Self {
            film: Buffer::from_slice(device, &host.sums)?,
            albedo: Buffer::from_slice(device, &host.albedo)?,
            normal: Buffer::from_slice(device, &host.normal)?,
            output: Buffer::new(device, pixels)?,
        })
    }

    /// Milliseconds the host waits from the film on the device to the denoised image in host
    /// memory (`render --denoise`'s path).
    fn denoise(
        &self,
        device: &Device,
        denoiser: &mut Denoiser,
        (width, height): (usize, usize),
    ) -> Result<f64> {
        let input = DenoiseInput {
            width,
            height,
            color: ColorSource::Film(&self.film, FilmCount::Own),
            guides: GuideSums {
                albedo: &self.albedo,
                normal: &self.normal,
            },
        };
        let start = Instant::now();
        denoiser.denoise(device, &input, &self.output)?;
        self.output.read(device)?;
        Ok(start.elapsed().as_secs_f64() * 1e3)
    }
}

/// Runs the benchmark and prints a summary and one JSON line.
pub fn run(args: &DenoiseArgs) -> Result<()> {
    let quality: Quality = args.quality.parse().map_err(anyhow::Error::msg)?;
    if args.width == 0 || args.height == 0 || args.runs == 0 {
        bail!("--width, --height and --runs must be at least 1");
    }
    if !["cpu", "cuda", "none"].contains(&args.oidn_device.as_str()) {
        bail!(
            "--oidn-device '{}' is not cpu, cuda or none",
            args.oidn_device
        );
    }
    let device = Device::open(
        &DeviceChoice::from_arg_or_env(args.device.as_deref()).map_err(anyhow::Error::msg)?,
    )?;
    let (w, h) = (args.width, args.height);
    let images = synthetic(w, h);
    let mut denoiser = Denoiser::new(&device, quality)?;
    println!("device: {}", device_line(&device));
    let film = DeviceFilm::new(&device, &images, w * h)?;
    let mut times = Vec::new();
    // Wall times, runs interleaved: the host path (the images uploaded, denoised, read back)
    // and the film's (`render --denoise`).
    let (mut host_ms, mut wait_ms) = (f64::MAX, f64::MAX);
    let mut report = None;
    for run in 0..=args.runs {
        let start = Instant::now();
        let (_, r) = denoiser.denoise_host(&device, w, h, &images[0], &images[1], &images[2])?;
        let host = start.elapsed().as_secs_f64() * 1e3;
        let wait = film.denoise(&device, &mut denoiser, (w, h))?;
        if run > 0 {
            host_ms = host_ms.min(host);
            wait_ms = wait_ms.min(wait);
            times.push((r.kernel_ms, r.conv_ms));
        }
        report = Some(r);
    }
    let report = report.expect("at least one run");
    let best = times
        .iter()
        .cloned()
        .fold((f64::MAX, f64::MAX), |a, b| if b.0 < a.0 { b } else { a });
    let gflops = denoiser.flops(w, h) / (best.1 * 1e-3) / 1e9;
    println!(
        "penumbra {} network, {w}x{h}, {} tile(s) of {}x{}: {:.1} ms (convolutions {:.1} ms, {gflops:.0} GFLOP/s), best of {}",
        quality.name(),
        report.tiling.count(),
        report.tiling.tile_w,
        report.tiling.tile_h,
        best.0,
        best.1,
        args.runs
    );
    println!(
        "from a {FILM_SPP}-spp film on the device to the denoised image in host memory: {wait_ms:.1} ms; \
         from images in host memory (uploaded): {host_ms:.1} ms; best of {}",
        args.runs
    );
    let mut oidn_ms = None;
    if args.oidn_device != "none" {
        if oidn::available() {
            let (_, t) = oidn::denoise(
                w,
                h,
                quality,
                &args.oidn_device,
                [&images[0], &images[1], &images[2]],
                args.runs,
            )?;
            let ms = t.iter().cloned().fold(f64::MAX, f64::min);
            println!(
                "Open Image Denoise 2.5.1 ({} device): {ms:.1} ms, best of {}; penumbra / OIDN = {:.2}",
                args.oidn_device,
                args.runs,
                best.0 / ms
            );
            oidn_ms = Some(ms);
        } else {
            println!("Open Image Denoise: not installed (scripts/install_oidn.sh); no comparison");
        }
    }
    println!(
        "{}",
        serde_json::json!({
            "benchmark": "denoise",
            "date": today(),
            "device": device_json(&device),
            "width": w,
            "height": h,
            "quality": quality.name(),
            "tiles": report.tiling.count(),
            "ms": best.0,
            "conv_ms": best.1,
            "wait_ms": wait_ms,
            "host_path_ms": host_ms,
            "gflops": gflops,
            "oidn_device": args.oidn_device,
            "oidn_ms": oidn_ms,
            "ratio": oidn_ms.map(|o| best.0 / o),
        })
    );
    Ok(())
}
