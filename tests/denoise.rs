//! The denoiser. `render --denoise` on the bundled Cornell box: the EXR holds the raw image and
//! a `denoised` layer much closer to a high-spp reference, the PNG is that layer tone-mapped.
//!
//! penumbra's denoiser against Intel's Open Image Denoise: the same colour, albedo and normal
//! inputs through OIDN 2.5.1's `RT` filter (the pinned pyoidn wheel, scripts/install_oidn.sh)
//! and through penumbra's OpenCL network must agree to PSNR >= 100 dB on the tone-mapped
//! images (the goal asks 40; every correct path agrees to 132-135 dB on PoCL, while a wrong
//! transfer curve in `large`'s albedo prefilter still scored 40-50 dB), for the three networks (`large` after prefiltering the guides, as OIDN's `cleanAux`
//! path does), on three shared scenes. Without pyoidn it skips with a note
//! (fails under CI=true); without PENUMBRA_SCENES it skips.
//!
//! Inputs: a 4-spp render (128 x 128) of each scene with `--aovs`: its colour, and its albedo
//! and normal layers (the renderer's own guide buffers, docs/aovs.md) as the guides; both
//! denoisers see exactly the same ones.

mod common;

use common::{output_dir, penumbra, render_exr, scenes_dir};
use penumbra::cl::{Device, DeviceChoice};
use penumbra::denoise::{Denoiser, Quality, oidn};
use std::path::Path;

const SIZE: usize = 128;
/// The agreement required with Intel's OIDN, in dB (see the file's header).
const AGREE_DB: f64 = 100.0;

/// The tone curve the comparison is made on: Reinhard, then a 2.2 gamma.
fn tone(v: f32) -> f32 {
    let v = v.max(0.0);
    (v / (1.0 + v)).powf(1.0 / 2.2)
}

/// PSNR of two images after the tone curve, peak 1.
fn psnr(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (tone(p[k]) - tone(q[k])) as f64))
        .map(|d| d * d)
        .sum::<f64>()
        / (a.len() * 3) as f64;
    10.0 * (1.0 / mse.max(1e-20)).log10()
}

#[test]
fn the_network_agrees_with_intels_open_image_denoise() {
    let Some(scenes) = scenes_dir() else {
        eprintln!("skipped: PENUMBRA_SCENES is not set");
        return;
    };
    if !oidn::available() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "pyoidn is not installed (scripts/install_oidn.sh) and CI=true"
        );
        eprintln!("skipped: pyoidn is not installed (run scripts/install_oidn.sh)");
        return;
    }
    let device_choice: DeviceChoice = common::test_device().parse().expect("test device");
    let device = Device::open(&device_choice).expect("an OpenCL device");
    let dir = output_dir("denoise");
    let size = SIZE.to_string();
    for scene in [
        "CornellBox/CornellBox.glb",
        "StanfordBunny/bunny.glb",
        "FlightHelmet/FlightHelmet.gltf",
    ] {
        let path = scenes.join(scene);
        let stem = path.file_stem().unwrap().to_string_lossy().to_string();
        let out = dir.join(format!("{stem}_4spp.exr"));
        let args = ["--width", &size, "--height", &size, "--spp", "4", "--aovs"];
        let noisy = render_exr(&path, &out, &args).1;
        let (_, _, channels) = penumbra::image_io::read_exr_channels(&out).unwrap();
        let albedo = layer(&channels, ["albedo.R", "albedo.G", "albedo.B"]);
        let normal = layer(&channels, ["normal.X", "normal.Y", "normal.Z"]);
        for quality in [Quality::Full, Quality::Small, Quality::Large] {
            let (intel, _) =
                oidn::denoise(SIZE, SIZE, quality, "cpu", [&noisy, &albedo, &normal], 0)
                    .expect("Open Image Denoise runs");
            let mut denoiser = Denoiser::new(&device, quality).expect("the denoiser");
            let (ours, _) = denoiser
                .denoise_host(&device, SIZE, SIZE, &noisy, &albedo, &normal)
                .expect("penumbra denoises");
            let agree = psnr(&ours, &intel);
            let change = psnr(&noisy, &intel);
            eprintln!(
                "{stem} {}: penumbra vs OIDN {agree:.1} dB (noisy input vs OIDN {change:.1} dB)",
                quality.name()
            );
            if agree < AGREE_DB {
                for (name, image) in [("penumbra", &ours), ("oidn", &intel)] {
                    let out = dir.join(format!("{stem}_{}_{name}.exr", quality.name()));
                    penumbra::image_io::write_exr(&out, SIZE as u32, SIZE as u32, image).unwrap();
                }
            }
            assert!(
                agree >= AGREE_DB,
                "{stem} {}: penumbra's denoised image is {agree:.1} dB from OIDN's (< {AGREE_DB}); \
                 both written to {}",
                quality.name(),
                dir.display()
            );
            // The denoisers did denoise: their agreement is well above the input's.
            assert!(
                agree > change + 5.0,
                "{stem}: {agree:.1} vs input {change:.1} dB"
            );
        }
    }
}

/// Mean of (x − r)² / (r² + 0.01) over pixels and channels (`bench converge`'s relMSE).
fn relmse(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .flat_map(|(p, r)| (0..3).map(move |k| (p[k] as f64, r[k] as f64)))
        .map(|(x, r)| (x - r) * (x - r) / (r * r + 0.01))
        .sum();
    sum / (image.len() * 3) as f64
}

/// The channels `names` of `channels` as RGB pixels.
fn layer(channels: &[(String, Vec<f32>)], names: [&str; 3]) -> Vec<[f32; 3]> {
    let plane = |name: &str| {
        let found = channels.iter().find(|(n, _)| n == name);
        &found.unwrap_or_else(|| panic!("no channel {name}")).1
    };
    let [r, g, b] = names.map(plane);
    (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect()
}

/// The bundled Cornell box at 4 spp is grainy; `render --denoise` keeps that raw image as the
/// EXR's RGB and adds `denoised.R/G/B`, smooth walls with sharp edges: its relMSE against a
/// 1024-spp reference is at least 3× lower than the raw one's, with either network. A PNG
/// is the denoised layer, exposed and tone-mapped as the raw image would be.
#[test]
fn render_denoise_writes_the_raw_and_the_denoised_image() {
    let dir = output_dir("render_denoise");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let size = ["--width", "96", "--height", "96"];
    let args = |extra: &[&'static str]| [&size[..], extra].concat();
    let (_, reference) = render_exr(
        &scene,
        &dir.join("reference.exr"),
        &args(&["--spp", "1024"]),
    );
    for (network, gain) in [("full", 3.0), ("small", 3.0)] {
        let out = dir.join(format!("denoised_{network}.exr"));
        let extra = ["--spp", "4", "--denoise", "--denoiser", network];
        let (summary, raw) = render_exr(&scene, &out, &args(&extra));
        assert_eq!(summary["denoise"], true);
        assert_eq!(summary["denoiser"], network);
        assert!(summary["denoise_ms"].as_f64().unwrap() > 0.0, "{summary}");
        assert_eq!(summary["denoise_tiling"]["tiles"], 1, "{summary}");
        let (w, h, channels) = penumbra::image_io::read_exr_channels(&out).unwrap();
        assert_eq!((w, h), (96, 96));
        assert_eq!(layer(&channels, ["R", "G", "B"]), raw);
        // Without --aovs the guide buffers are used, not written.
        assert!(!channels.iter().any(|(n, _)| n.starts_with("albedo")));
        let denoised = layer(&channels, ["denoised.R", "denoised.G", "denoised.B"]);
        let (before, after) = (relmse(&raw, &reference), relmse(&denoised, &reference));
        eprintln!("{network}: relMSE raw {before:.4}, denoised {after:.4}");
        assert!(
            after * gain <= before,
            "{network}: denoised relMSE {after:.4} is not {gain}× under the raw {before:.4} ({})",
            out.display()
        );

        let png = dir.join(format!("denoised_{network}.png"));
        let line = [
            &[
                "render",
                scene.to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
            ][..],
            &args(&extra)[..],
            &["--exposure", "0.5"][..],
        ]
        .concat();
        let o = penumbra(&line);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let shown = image::open(&png).unwrap().to_rgba8();
        let want = penumbra::render::tonemap::to_rgba8(
            &denoised,
            0.5,
            penumbra::render::tonemap::ToneMapper::PbrNeutral,
        );
        let off = (shown.as_raw().iter().zip(&want))
            .filter(|(a, b)| a.abs_diff(**b) > 1)
            .count();
        assert_eq!(
            off, 0,
            "{network}: the PNG is not the denoised layer tone-mapped"
        );
    }
}

/// The device path (`Denoiser::denoise_film`: the network's input made from the film's
/// fixed-point sums and the guide sums where they lie) gives the host path's image
/// (`Renderer::image` and `Renderer::aovs` read back, then `Denoiser::denoise_host`) to f32
/// rounding, on the bundled box seen from further back (the sky around it) at 48 x 32, for
/// each way a pixel's count is known: the film's
/// own count (8 spp; and with adaptive sampling, 48 spp at most, where pixels took different
/// numbers of samples); the hits counted with the background cut out (every pixel's samples);
/// and both, where the count is the one adaptive sampling's state records.
#[test]
fn the_film_denoised_on_the_device_is_the_host_paths_image() {
    use penumbra::render::{RenderSettings, Renderer};
    use penumbra::scene::RenderFrame;
    let choice = common::test_device().parse().unwrap();
    let scene = penumbra::scene::load_or_bundled(None).unwrap();
    let mut r = Renderer::new(&choice).unwrap();
    let mut denoiser = Denoiser::new(&r.device, Quality::Small).expect("the denoiser");
    let mut camera = scene.cameras[0].clone();
    camera.eye -= camera.forward * 1.5;
    let base = RenderSettings {
        width: 48,
        height: 32,
        aovs: true,
        ..Default::default()
    };
    let modes = [
        ("own count", base.clone()),
        (
            "cut out",
            RenderSettings {
                cutout: true,
                ..base.clone()
            },
        ),
        (
            "adaptive",
            RenderSettings {
                noise_threshold: Some(1.0),
                ..base.clone()
            },
        ),
        (
            "adaptive, cut out",
            RenderSettings {
                cutout: true,
                noise_threshold: Some(1.0),
                ..base.clone()
            },
        ),
    ];
    for (name, settings) in modes {
        r.set_settings(&settings).unwrap();
        r.load_scene_in(&scene, &scene.lights, RenderFrame::default())
            .unwrap();
        r.set_camera(&camera).unwrap();
        // Adaptive sampling checks after 16 samples, then every 16.
        let calls = if settings.noise_threshold.is_some() {
            3
        } else {
            1
        };
        for _ in 0..calls {
            r.render(if calls > 1 { 16 } else { 8 }).unwrap();
        }
        if settings.noise_threshold.is_some() {
            let taken = r.pixel_samples().unwrap().unwrap();
            let (lo, hi) = (taken.iter().min().unwrap(), taken.iter().max().unwrap());
            assert!(lo < hi, "{name}: every pixel took {lo} samples");
        }
        let image = r.image().unwrap();
        if settings.cutout {
            // Pixels where some samples missed: their count is not the film's.
            let partial = r.coverage().unwrap().iter().filter(|&&c| c < 1.0).count();
            assert!(partial > 100, "{name}: {partial} pixels show the sky");
        }
        let aovs = r.aovs().unwrap().unwrap();
        let (host, _) = denoiser
            .denoise_host(&r.device, 48, 32, &image, &aovs.albedo, &aovs.normal)
            .unwrap();
        let (device, _) = denoiser.denoise_film(&mut r).unwrap();
        let worst = (host.iter().zip(&device))
            .flat_map(|(h, d)| (0..3).map(move |k| (h[k] - d[k]).abs() / (1e-3 + h[k].abs())))
            .fold(0.0f32, f32::max);
        eprintln!("{name}: largest relative difference {worst:.2e}");
        assert!(
            worst < 1e-4,
            "{name}: the device path differs by {worst:.2e}"
        );
        // Not the raw image: the network ran.
        assert!(psnr(&device, &image) < 60.0, "{name}");
    }
}
