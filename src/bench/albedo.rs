//! `penumbra bench albedo`: how faithfully the first image shows base colours. Each scene is
//! opened as with no options (the first view's camera), its own lights taken away and a white
//! environment of radiance 1 put around it; every pixel that shows a material of known base
//! colour (no base colour texture, not metal, glass, emissive, clear-coated or sheen, inside
//! its region: its four neighbours show the same material, found by host rays through the
//! pixel) is tone-mapped under each tone curve at two exposures, incident (a white diffuse
//! surface at radiance 1 shown at [`WHITE`](crate::render::exposure::WHITE)) and metered on the
//! image (the old default), and its mean displayed sRGB colour set beside the base colour's.

use crate::args::CommonArgs;
use crate::render::exposure::{auto_stops, incident_stops, meter_subject};
use crate::render::tonemap::{ToneMapper, srgb_encode};
use crate::scene::framing::{Probe, camera_ray};
use crate::scene::{AlphaMode, EnvMap, Material};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

/// Options of `bench albedo`.
#[derive(Args, Debug, Clone)]
pub struct AlbedoArgs {
    /// The glTF files to measure.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Device, size, samples and the rest, as `render` takes them.
    #[command(flatten)]
    pub common: CommonArgs,
}

/// Whether `m` shows its base colour factor alone under a white light.
fn known_base_colour(m: &Material) -> bool {
    m.textures.base_color.is_none()
        && m.metallic == 0.0
        && m.transmission == 0.0
        && m.emission == [0.0; 3]
        && m.clearcoat == 0.0
        && m.sheen_color == [0.0; 3]
        && !m.unlit
        && m.alpha == AlphaMode::Opaque
}

/// The (tone curve, exposure) pairs compared.
const CASES: [(ToneMapper, bool); 4] = [
    (ToneMapper::PbrNeutral, true),
    (ToneMapper::Aces, true),
    (ToneMapper::PbrNeutral, false),
    (ToneMapper::Aces, false),
];

/// sRGB 8-bit values of a linear colour in [0, 1].
fn srgb8(c: [f32; 3]) -> [f64; 3] {
    c.map(|v| (srgb_encode(v.clamp(0.0, 1.0)) * 255.0) as f64)
}

fn hex(c: [f64; 3]) -> String {
    format!(
        "#{:02x}{:02x}{:02x}",
        c[0].round() as u8,
        c[1].round() as u8,
        c[2].round() as u8
    )
}

/// Measures every scene; prints a Markdown table and the pixel-weighted mean error of each case.
pub fn run(args: &AlbedoArgs) -> Result<()> {
    let settings = args.common.settings((160, 120))?;
    let spp = args.common.sampling.spp.unwrap_or(16);
    let (w, h) = (settings.width as usize, settings.height as usize);
    let aspect = w as f64 / h as f64;
    let white = EnvMap {
        name: "white".into(),
        width: 4,
        height: 2,
        texels: vec![[1.0; 3]; 8],
    };
    let mut renderer = args.common.open_renderer(&settings)?;
    renderer.set_environment(Some(white))?;
    println!(
        "| scene | material | base | neutral, incident | ACES, incident | neutral, metered | \
         ACES, metered | pixels |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut totals = [0.0f64; CASES.len()];
    let mut pixels_all = 0usize;
    for path in &args.scenes {
        let prepared = args.common.prepare(Some(path))?;
        let scene = &prepared.scene;
        renderer
            .load_scene(scene, &[])
            .with_context(|| format!("{}", path.display()))?;
        renderer.set_camera(&prepared.camera)?;
        renderer.render(spp)?;
        let (mut image, mut coverage) = (Vec::new(), Vec::new());
        renderer.image_into(&mut image, Some(&mut coverage))?;
        let metered = meter_subject(&image, Some(&coverage))
            .as_ref()
            .map_or(0.0, auto_stops);
        let exposures = [incident_stops(1.0), metered];
        // What each pixel shows, by a host ray through its centre.
        let probe = Probe::new(scene);
        let cam = &prepared.camera;
        let seen: Vec<Option<u32>> = (0..w * h)
            .map(|i| {
                let (fx, fy) = (
                    ((i % w) as f64 + 0.5) / w as f64,
                    ((i / w) as f64 + 0.5) / h as f64,
                );
                probe.material_seen(cam.eye, camera_ray(cam, aspect, fx, fy))
            })
            .collect();
        let mut sums: Vec<([[f64; 3]; CASES.len()], usize)> =
            vec![([[0.0; 3]; CASES.len()], 0); scene.materials.len()];
        for y in 1..h.saturating_sub(1) {
            for x in 1..w.saturating_sub(1) {
                let i = y * w + x;
                let Some(m) = seen[i] else { continue };
                let inside = [i - 1, i + 1, i - w, i + w]
                    .iter()
                    .all(|&k| seen[k] == Some(m));
                if !inside || !known_base_colour(&scene.materials[m as usize]) {
                    continue;
                }
                let entry = &mut sums[m as usize];
                for (c, (mapper, incident)) in CASES.iter().enumerate() {
                    let stops = exposures[if *incident { 0 } else { 1 }];
                    let shown = mapper.apply(image[i].map(|v| v * 2f32.powf(stops)));
                    for (s, v) in entry.0[c].iter_mut().zip(srgb8(shown)) {
                        *s += v;
                    }
                }
                entry.1 += 1;
            }
        }
        let name = path.file_stem().unwrap_or_default().to_string_lossy();
        for (m, (sum, n)) in sums.iter().enumerate().filter(|(_, s)| s.1 > 0) {
            let material = &scene.materials[m];
            let c = material.base_color;
            let base = srgb8([c[0], c[1], c[2]]);
            let mut row = format!("| {name} | {} | {} |", material.name, hex(base));
            for (k, s) in sum.iter().enumerate() {
                let mean = s.map(|v| v / *n as f64);
                let error = (0..3).map(|j| (mean[j] - base[j]).abs()).sum::<f64>() / 3.0;
                totals[k] += error * *n as f64;
                row += &format!(" {} (Δ {error:.0}) |", hex(mean));
            }
            pixels_all += n;
            println!("{row} {n} |");
        }
    }
    let means: Vec<String> = totals
        .iter()
        .zip(CASES)
        .map(|(t, (mapper, incident))| {
            format!(
                "{} {}: {:.1}",
                mapper.arg_name(),
                if incident { "incident" } else { "metered" },
                t / pixels_all.max(1) as f64
            )
        })
        .collect();
    println!(
        "\nmean |Δ| per channel (8-bit sRGB) over {pixels_all} pixels: {}",
        means.join(", ")
    );
    Ok(())
}
