//! The megakernel (whole paths per work item, CPU devices) against the wavefront (queued
//! stages, GPUs): both must compute the same estimator. Independent renders of the Cornell box
//! (and of a clear-coated floor lit through a thin glass pane) with several seeds give
//! per-block means and their standard errors for each kernel; the means must agree within noise.

mod common;

use common::{Gltf, Prim, render_exr, render_exr_env};
use serde_json::json;
use std::path::Path;

const SIZE: usize = 32;
const BLOCK: usize = 8;
const SEEDS: u32 = 8;

/// Per 8×8 block and channel: the mean over seeds of the block mean, and its variance (of the
/// mean over seeds), from `SEEDS` renders of `kernel`.
fn block_stats(
    kernel: &str,
    scene: &Path,
    extra: &[&str],
    dir: &Path,
    seed0: u32,
) -> (Vec<f64>, Vec<f64>) {
    let blocks = (SIZE / BLOCK) * (SIZE / BLOCK) * 3;
    let mut sum = vec![0.0f64; blocks];
    let mut sum2 = vec![0.0f64; blocks];
    for s in 0..SEEDS {
        let out = dir.join(format!("{kernel}-{s}.exr"));
        let seed = (seed0 + s).to_string();
        let size = SIZE.to_string();
        let mut args = vec![
            "--kernel",
            kernel,
            "--width",
            &size,
            "--height",
            &size,
            "--spp",
            "16",
            "--bounces",
            "6",
            "--seed",
            &seed,
        ];
        args.extend_from_slice(extra);
        let (summary, px) = render_exr(scene, &out, &args);
        assert_eq!(
            summary["kernel"],
            if kernel == "megakernel" {
                "Megakernel"
            } else {
                "Wavefront"
            }
        );
        assert_eq!(summary["nonfinite_samples"], 0);
        for (b, (s1, s2)) in sum.iter_mut().zip(sum2.iter_mut()).enumerate() {
            let (c, blk) = (b % 3, b / 3);
            let (bx, by) = (blk % (SIZE / BLOCK), blk / (SIZE / BLOCK));
            let mut m = 0.0;
            for y in by * BLOCK..(by + 1) * BLOCK {
                for x in bx * BLOCK..(bx + 1) * BLOCK {
                    m += px[y * SIZE + x][c] as f64;
                }
            }
            m /= (BLOCK * BLOCK) as f64;
            *s1 += m;
            *s2 += m * m;
        }
    }
    let n = SEEDS as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / n).collect();
    let var: Vec<f64> = sum2
        .iter()
        .zip(&mean)
        .map(|(s2, m)| (s2 / n - m * m).max(0.0) * n / (n - 1.0) / n)
        .collect();
    (mean, var)
}

/// Asserts that both kernels render `scene` alike within noise, and that the comparison would
/// see a 3% bias.
fn assert_kernels_agree(scene: &Path, extra: &[&str], dir: &Path) {
    let (mw, vw) = block_stats("wavefront", scene, extra, dir, 100);
    let (mm, vm) = block_stats("megakernel", scene, extra, dir, 200);
    let mut z2 = 0.0;
    let mut worst = 0.0f64;
    let mut n = 0;
    for i in 0..mw.len() {
        let se = (vw[i] + vm[i]).sqrt();
        if mw[i] < 1e-4 && mm[i] < 1e-4 {
            continue; // a black block in both
        }
        assert!(se > 0.0, "block {i}: no noise in {} / {}", mw[i], mm[i]);
        let z = (mm[i] - mw[i]) / se;
        worst = worst.max(z.abs());
        z2 += z * z;
        n += 1;
    }
    assert!(n >= 24, "enough lit blocks ({n})");
    // With 8 seeds a side z is t-distributed with ~14 degrees of freedom: |z| > 5 has a
    // probability below 1e-3 per block, and the mean of z² is about 1.2.
    let mean_z2 = z2 / n as f64;
    assert!(worst < 5.0, "a block differs by {worst:.2} standard errors");
    assert!(mean_z2 < 2.5, "mean z² {mean_z2:.2} over {n} blocks");
    // A real difference is seen: a 3% brighter image fails the same test.
    let mut z2_biased = 0.0;
    for i in 0..mw.len() {
        let se = (vw[i] + vm[i]).sqrt();
        if se > 0.0 {
            let z = (mm[i] * 1.03 - mw[i]) / se;
            z2_biased += z * z;
        }
    }
    assert!(z2_biased / n as f64 > 2.5, "the test can see a 3% bias");
}

#[test]
fn megakernel_and_wavefront_agree_within_noise() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let dir = tempfile::tempdir().unwrap();
    assert_kernels_agree(&scene, &[], dir.path());
}

/// A clear-coated floor and sphere lit by an emissive panel through a smooth thin glass pane
/// (`HAS_CLEARCOAT`, `HAS_THIN_WALLS`): shadow rays pass the pane in both kernels.
fn coated_room_through_a_pane(dir: &Path) -> std::path::PathBuf {
    let mut g = Gltf::default();
    for e in [
        "KHR_materials_clearcoat",
        "KHR_materials_transmission",
        "KHR_materials_volume",
    ] {
        g.use_ext(e);
    }
    let light = g.lambert([0.0; 3], [1.0; 3], 5.0, true);
    g.materials.push(json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.3, 0.2, 1.0], "metallicFactor": 0.0,
                                 "roughnessFactor": 0.6},
        "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0,
                                                   "clearcoatRoughnessFactor": 0.15}}
    }));
    let coated = g.materials.len() - 1;
    g.materials.push(json!({
        "pbrMetallicRoughness": {"baseColorFactor": [0.9, 1.0, 0.8, 1.0], "metallicFactor": 0.0,
                                 "roughnessFactor": 0.0},
        "doubleSided": true,
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                       "KHR_materials_volume": {"thicknessFactor": 0.0}}
    }));
    let pane = g.materials.len() - 1;
    let quad = |y: f32, h: f32, up: bool, m: usize| {
        let p = vec![[-h, y, -h], [h, y, -h], [h, y, h], [-h, y, h]];
        let i = if up {
            vec![0, 2, 1, 0, 3, 2]
        } else {
            vec![0, 1, 2, 0, 2, 3]
        };
        Prim::triangles(p, i, m)
    };
    let (sp, sn, si) = common::sphere(0.15, 12, 24, false);
    let mut ball = Prim::triangles(
        sp.iter().map(|p| [p[0], p[1] + 0.15, p[2]]).collect(),
        si,
        coated,
    );
    ball.normals = sn;
    let mesh = g.mesh(vec![
        quad(0.0, 1.0, true, coated),
        quad(2.0, 0.5, false, light),
        quad(1.0, 3.0, true, pane),
        ball,
    ]);
    g.node(json!({"mesh": mesh}));
    g.cameras
        .push(json!({"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}));
    g.node(json!({"camera": 0, "translation": [0.0, 0.8, 0.4], "rotation": common::LOOK_DOWN}));
    g.write_glb(dir, "coated-room")
}

#[test]
fn kernels_agree_on_a_clear_coat_lit_through_a_thin_wall() {
    let dir = tempfile::tempdir().unwrap();
    let scene = coated_room_through_a_pane(dir.path());
    assert_kernels_agree(&scene, &["--sky", "0,0,0"], dir.path());
}

#[test]
fn the_same_seed_traces_the_same_paths_in_both_kernels() {
    // Both kernels draw the same random numbers for the same (pixel, sample, seed) and shade
    // with the same code, so they trace the same rays.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let dir = tempfile::tempdir().unwrap();
    let args = |k: &'static str| {
        vec![
            "--kernel",
            k,
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "4",
            "--bounces",
            "5",
        ]
    };
    let (a, pa) = render_exr(&scene, &dir.path().join("w.exr"), &args("wavefront"));
    // The megakernel's last rays are traced as the wavefront traces them (not tested against
    // the emitters first: `a_last_ray_is_tested_against_the_emitters_first`).
    let (b, pb) = render_exr_env(
        &scene,
        &dir.path().join("m.exr"),
        &args("megakernel"),
        &[("PENUMBRA_CL_OPTIONS", "-DLAST_RAY_TRACED")],
    );
    let rays = |v: &serde_json::Value| {
        v["rays_per_second"].as_f64().unwrap() * v["seconds"].as_f64().unwrap()
    };
    let (ra, rb) = (rays(&a), rays(&b));
    assert!((ra - rb).abs() <= 1e-6 * ra + 2.0, "{ra} rays against {rb}");
    let (ma, mb) = (common::mean_gray(&pa), common::mean_gray(&pb));
    assert!((ma - mb).abs() <= 1e-3 * ma, "mean {ma} against {mb}");
}

/// Renders the bundled box (32 triangles) as `scene` says, hides its tall block (22 left) and
/// shows it again: no kernels are built after the first, the block is gone from the image and
/// back, the same image again. Returns the kernels' features.
fn hide_and_show_the_tall_block(mut scene: penumbra::scene::Scene) -> penumbra::cl::KernelFeatures {
    use penumbra::render::{RenderSettings, Renderer};
    use penumbra::scene::RenderFrame;
    let choice = common::test_device().parse().unwrap();
    let mut r = Renderer::new(&choice).unwrap();
    r.set_settings(&RenderSettings {
        width: 32,
        height: 32,
        bounces: 2,
        ..Default::default()
    })
    .unwrap();
    let camera = scene.cameras[0].clone();
    let lights = scene.lights.clone();
    let render = |r: &mut Renderer, scene: &penumbra::scene::Scene| {
        let stats = r
            .load_scene_in(scene, &lights, RenderFrame::default())
            .unwrap();
        r.set_camera(&camera).unwrap();
        r.render(16).unwrap();
        (stats, r.image().unwrap())
    };
    let (first, whole) = render(&mut r, &scene);
    assert!(first.kernels_built);
    let features = r.program().unwrap().features;
    let tall = scene
        .objects
        .iter()
        .position(|o| o.name == "TallBlock")
        .expect("the bundled box has a tall block");
    scene.objects[tall].visible = false;
    let (hidden, without) = render(&mut r, &scene);
    assert_eq!(hidden.triangles, first.triangles - 10);
    assert!(!hidden.kernels_built, "hiding an object built kernels");
    assert_eq!(r.program().unwrap().features, features);
    // The tall block stands left of the middle (its top at x 0.12–0.29 of the box's 0.556):
    // with it gone, the back wall shows there, and the image changes.
    let changed = whole
        .iter()
        .zip(&without)
        .filter(|(a, b)| (a[0] - b[0]).abs() + (a[1] - b[1]).abs() + (a[2] - b[2]).abs() > 0.05)
        .count();
    assert!(changed > 32, "only {changed} pixels changed");
    // And back: the same kernels again, the same image as the first (same seed, same samples).
    scene.objects[tall].visible = true;
    let (shown, again) = render(&mut r, &scene);
    assert!(!shown.kernels_built);
    assert_eq!(again, whole);
    features
}

#[test]
fn hiding_an_object_of_a_small_scene_builds_no_kernels() {
    // A small scene the lanes cannot shade in batches (a glossy floor) is tested whole on CPU
    // devices (`SMALL_SCENE`), with kernels built for two batches of sixteen: hiding a block
    // changes the count the frame carries, not the kernels.
    let mut glossy = penumbra::scene::load_or_bundled(None).unwrap();
    glossy.materials[0].specular_factor = 1.0;
    let features = hide_and_show_the_tall_block(glossy);
    let cpu = common::test_device() == "cpu";
    // Where the CPU has vector lanes, they test its triangles whole (`LANES_SMALL`, the count
    // with the frame), sixteen rays at a time.
    let lanes = penumbra::render::strategy::DeviceFacts::of(true).vectors;
    if cpu {
        assert_eq!(
            (features.small_scene, features.lanes, features.lanes_small),
            if lanes {
                (0, true, true)
            } else {
                (32, false, false)
            },
            "{features:?}"
        );
        assert!(!features.lanes_shade, "{features:?}");
    }
    // The Lambertian box: its lanes shade in batches too, and hiding a block builds nothing
    // there either.
    let lambert = penumbra::scene::load_or_bundled(None).unwrap();
    let features = hide_and_show_the_tall_block(lambert);
    if cpu {
        assert_eq!(features.lanes, lanes, "{features:?}");
        assert_eq!(features.lanes_shade, lanes, "{features:?}");
        assert_eq!(features.lanes_small, lanes, "{features:?}");
        assert_eq!(features.small_scene, if lanes { 0 } else { 32 });
    }
}

#[test]
fn the_wavefront_on_a_cpu_compiles_no_lanes() {
    // The kernel strategy (small scenes, lanes) is the megakernel's: the wavefront's kernels
    // are built without it, and switching kernels with a scene loaded builds them for the new
    // ones.
    use penumbra::render::{KernelChoice, Renderer};
    use penumbra::scene::RenderFrame;
    let choice = common::test_device().parse().unwrap();
    let scene = penumbra::scene::load_or_bundled(None).unwrap();
    let mut r = Renderer::new(&choice).unwrap();
    r.set_kernel(KernelChoice::Wavefront).unwrap();
    r.load_scene_in(&scene, &scene.lights, RenderFrame::default())
        .unwrap();
    let strategy = |r: &Renderer| {
        let f = r.program().unwrap().features;
        (f.small_scene, f.lanes, f.lanes_small, f.lanes_shade)
    };
    assert_eq!(strategy(&r), (0, false, false, false));
    r.set_kernel(KernelChoice::Megakernel).unwrap();
    if common::test_device() == "cpu" {
        // The bundled box: 32 Lambertian triangles, tested whole and shaded in batches in
        // lanes, or tested whole one ray at a time.
        let lanes = penumbra::render::strategy::DeviceFacts::of(true).vectors;
        let expected = if lanes {
            (0, true, true, true)
        } else {
            (32, false, false, false)
        };
        assert_eq!(strategy(&r), expected);
    }
    r.set_kernel(KernelChoice::Wavefront).unwrap();
    assert_eq!(strategy(&r), (0, false, false, false));
}

#[test]
fn a_small_scene_tested_whole_in_lanes_makes_the_image_of_its_tree() {
    // A small scene's lanes test its triangles whole (`LANES_SMALL`: the root's four children,
    // then the triangles under those each lane reaches) instead of walking its tree: the same
    // hits, so the image of the tree in lanes (PENUMBRA_LANES_SMALL=0) and of one ray at a
    // time testing it whole (PENUMBRA_LANES=0, `SMALL_SCENE`), bit for bit. The bundled box
    // (closed, Lambertian: shaded in batches) and a sphere of 48 triangles on a floor under the
    // default light rig (open: most rays leave it for the sky, past children they miss).
    let dir = tempfile::tempdir().unwrap();
    let bundled = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let sphere = common::white_sphere_of(dir.path(), true, 3, 8);
    let vectors = penumbra::render::strategy::DeviceFacts::of(true).vectors;
    for (case, scene) in [&bundled, &sphere].into_iter().enumerate() {
        let args = lanes_image_args("5", "6");
        let whole = dir.path().join(format!("whole-{case}.exr"));
        let (a, pa) = render_exr_env(scene, &whole, &args, &[]);
        assert!(
            a["triangles"].as_u64().unwrap() <= penumbra::render::strategy::SMALL_SCENE_MAX as u64
        );
        if common::test_device() == "cpu" {
            assert_eq!(a["lanes_small"], vectors, "{scene:?}: {a}");
        }
        assert!(pa.iter().any(|p| p[0] > 0.0), "{scene:?}: a black image");
        for (what, env) in [
            (
                "the tree in lanes",
                [("PENUMBRA_LANES", "1"), ("PENUMBRA_LANES_SMALL", "0")],
            ),
            (
                "one ray at a time",
                [("PENUMBRA_LANES", "0"), ("PENUMBRA_LANES_SMALL", "1")],
            ),
        ] {
            let out = dir.path().join(format!("{what}-{case}.exr"));
            let (b, pb) = render_exr_env(scene, &out, &args, &env);
            assert_eq!(b["lanes_small"], false, "{scene:?}, {what}: {b}");
            assert_eq!(
                a["extension_rays"], b["extension_rays"],
                "{scene:?}, {what}"
            );
            assert_eq!(a["shadow_rays"], b["shadow_rays"], "{scene:?}, {what}");
            assert!(pa == pb, "{scene:?}: the image differs from {what}'s");
        }
    }
}

#[test]
fn samples_in_one_call_or_many_make_the_same_image() {
    // `render` sizes its calls by time (a pixel's samples back to back in one launch run
    // faster on a CPU); the image must not depend on how the samples were split, in either
    // kernel: each adds a pixel's samples to the film one by one.
    use penumbra::render::{KernelChoice, RenderSettings, Renderer};
    use penumbra::scene::RenderFrame;
    let choice = common::test_device().parse().unwrap();
    let scene = penumbra::scene::load_or_bundled(None).unwrap();
    let image = |kernel: KernelChoice, splits: &[u32]| {
        let mut r = Renderer::new(&choice).unwrap();
        r.set_kernel(kernel).unwrap();
        r.set_settings(&RenderSettings {
            width: 24,
            height: 20,
            bounces: 4,
            ..Default::default()
        })
        .unwrap();
        r.load_scene_in(&scene, &scene.lights, RenderFrame::default())
            .unwrap();
        r.set_camera(&scene.cameras[0]).unwrap();
        for &n in splits {
            r.render(n).unwrap();
        }
        assert_eq!(r.kernel(), kernel);
        r.image().unwrap()
    };
    for kernel in [KernelChoice::Megakernel, KernelChoice::Wavefront] {
        let whole = image(kernel, &[12]);
        assert!(
            whole.iter().any(|p| p[0] + p[1] + p[2] > 0.0),
            "{kernel:?}: a black image"
        );
        assert_eq!(
            image(kernel, &[1; 12]),
            whole,
            "{kernel:?}: twelve calls of one"
        );
        assert_eq!(
            image(kernel, &[5, 7]),
            whole,
            "{kernel:?}: calls of five and seven"
        );
    }
}

#[test]
fn a_sample_rendered_in_bands_makes_the_image_of_whole_launches() {
    // The viewer splits a slow device's sample into bands of work items (one launch each, at
    // a global offset) so that input never waits for a whole sample: the bands must cover
    // every pixel exactly once, each with the sample index of the whole launch, also when the
    // rest of a sample is split finer after a band that ran over its budget.
    use penumbra::render::{Band, KernelChoice, RenderSettings, Renderer};
    use penumbra::scene::RenderFrame;
    let choice = common::test_device().parse().unwrap();
    let scene = penumbra::scene::load_or_bundled(None).unwrap();
    let image = |kernel: KernelChoice, bands: &[Band]| {
        let mut r = Renderer::new(&choice).unwrap();
        r.set_kernel(kernel).unwrap();
        // 37 × 23: the last work-group (and lanes' tile) is partial.
        r.set_settings(&RenderSettings {
            width: 37,
            height: 23,
            bounces: 3,
            ..Default::default()
        })
        .unwrap();
        r.load_scene_in(&scene, &scene.lights, RenderFrame::default())
            .unwrap();
        r.set_camera(&scene.cameras[0]).unwrap();
        for _ in 0..4 {
            for &band in bands {
                r.start_band(band).unwrap();
                r.finish().unwrap();
            }
        }
        assert_eq!(r.samples(), 4);
        r.image().unwrap()
    };
    for kernel in [KernelChoice::Megakernel, KernelChoice::Wavefront] {
        let whole = image(kernel, &[Band::WHOLE]);
        assert!(
            whole.iter().any(|p| p[0] + p[1] + p[2] > 0.0),
            "{kernel:?}: a black image"
        );
        let even =
            |count: u32| -> Vec<Band> { (0..count).map(|index| Band { index, count }).collect() };
        // One band of 3, then the rest in bands 4 times finer: 4..12 of 12.
        let split: Vec<Band> = std::iter::once(Band { index: 0, count: 3 })
            .chain((4..12).map(|index| Band { index, count: 12 }))
            .collect();
        for bands in [even(2), even(3), even(40), split] {
            assert_eq!(image(kernel, &bands), whole, "{kernel:?}: {bands:?}");
        }
    }
}

/// The megakernel's options for the lanes' tests: an image of 37 x 23 (its last work item
/// partial) at `spp` samples and `bounces` bounces.
fn lanes_image_args<'a>(spp: &'a str, bounces: &'a str) -> Vec<&'a str> {
    vec![
        "--kernel",
        "megakernel",
        "--width",
        "37",
        "--height",
        "23",
        "--spp",
        spp,
        "--bounces",
        bounces,
    ]
}

#[test]
fn rays_in_lanes_make_the_image_of_one_ray_at_a_time() {
    // On a CPU with AVX-512 or AVX2 the megakernel starts sixteen paths at a time (a pixel's samples,
    // or a few pixels' below sixteen), their camera rays and first light samples walked as
    // packets (kernels/cpu/traverse_packet.h), and walks the later extension rays sixteen at a
    // time in vector lanes (kernels/cpu/traverse_lanes.h), a work item taking 256 pixels: the same
    // hits, the same samples added in the same order, so the image is the one-ray-at-a-time
    // kernel's bit for bit (but for rays that meet two triangles at exactly the same distance,
    // of which each walk may keep another). A sphere of 34,816 triangles (lanes are for scenes
    // of 32,768 or more: 2 x 128 x 136) on a floor, an image of 37 x 23 (its last work item
    // partial), at 5 samples (three pixels a chunk) and 21 (a pixel's chunks of 16 and 5); lit
    // by the default light rig, and by an emissive panel (light samples that end on a
    // triangle, walked in lanes as any-hit rays, and extension rays that find the light).
    // Every material is Lambertian, so under the panel the lanes shade their vertices in
    // batches, in vectors (kernels/cpu/shade_lanes.h), and with PENUMBRA_LANES_SHADE=0 one by one:
    // the same image both ways; with the background cut out too (camera rays that escape are
    // marked, not lit), and under a sky with light sampling alone (escapes lit by the sky, the
    // last rays traced).
    let dir = tempfile::tempdir().unwrap();
    let (rings, segments) = (128, 136);
    assert!((2 * rings * segments) as usize >= penumbra::render::strategy::LANES_MIN_TRIANGLES);
    let rig = common::white_sphere_of(dir.path(), true, rings, segments);
    let panel = common::white_sphere_under_panel(dir.path(), rings, segments);
    let sky: &[&str] = &["--sky", "0.2,0.3,0.4", "--strategy", "lights"];
    for (case, (scene, spp, extra)) in [
        (&rig, "5", &[][..]),
        (&rig, "21", &[]),
        (&panel, "5", &[]),
        (&panel, "21", &[]),
        (&panel, "5", &["--background", "transparent"]),
        (&panel, "5", sky),
    ]
    .into_iter()
    .enumerate()
    {
        let name = scene.file_stem().unwrap().to_str().unwrap();
        let mut args = lanes_image_args(spp, "4");
        args.extend(extra);
        let one = dir.path().join(format!("one-{case}.exr"));
        let (b, pb) = render_exr_env(scene, &one, &args, &[("PENUMBRA_LANES", "0")]);
        assert_eq!(b["lanes"], false, "PENUMBRA_LANES=0 left lanes on");
        assert_eq!(b["lanes_shade"], false, "lanes_shade without lanes");
        // The lanes load their nodes and triangles as rows (AMD's default) or by gathers, and
        // shade in batches or (PENUMBRA_LANES_SHADE=0) one vertex at a time.
        for (load, shade) in [("rows", "1"), ("gathers", "1"), ("rows", "0")] {
            let out = dir.path().join(format!("lanes-{load}-{shade}-{case}.exr"));
            let (a, pa) = render_exr_env(
                scene,
                &out,
                &args,
                &[
                    ("PENUMBRA_LANES_LOAD", load),
                    ("PENUMBRA_LANES_SHADE", shade),
                ],
            );
            let what = format!("{load}, shading {shade}, {}", extra.join(" "));
            #[cfg(target_arch = "x86_64")]
            if common::test_device() == "cpu"
                && (std::arch::is_x86_feature_detected!("avx512f")
                    || std::arch::is_x86_feature_detected!("avx2"))
            {
                assert_eq!(
                    a["lanes"], true,
                    "a CPU with AVX-512 or AVX2 did not walk in lanes"
                );
                assert_eq!(
                    a["lanes_load"], load,
                    "PENUMBRA_LANES_LOAD={load} not taken"
                );
                // The default light rig's environment map (the sphere without lights) takes
                // the scalar shading.
                assert_eq!(
                    a["lanes_shade"],
                    shade == "1" && scene == &panel,
                    "{name}, {what}: the lanes did not shade as asked"
                );
            }
            assert!(
                pa.iter().any(|p| p[0] > 0.0),
                "{name}, {spp} spp, {what}: a black image"
            );
            assert_eq!(
                a["extension_rays"], b["extension_rays"],
                "{name}, {spp} spp, {what}"
            );
            assert_eq!(
                a["shadow_rays"], b["shadow_rays"],
                "{name}, {spp} spp, {what}"
            );
            // The files too: with the background cut out, their alpha (the camera rays that
            // hit) as well.
            assert!(
                pa == pb && std::fs::read(&out).unwrap() == std::fs::read(&one).unwrap(),
                "{name}, {spp} spp, {what}: the lanes' image differs from one ray at a time's"
            );
        }
    }
}

#[test]
fn a_last_ray_that_can_find_nothing_is_not_traced() {
    // A path's last extension ray only looks for emitters. With a point light, no emissive
    // triangle and a black sky there is none to find: both kernels end the path at its last
    // vertex's light sample instead, and the image is the one with the ray traced. Traced it
    // is under a sky too faint to move a pixel (1e-30): more extension rays, the same image
    // but for the sky's traces in pixels without other light.
    let dir = tempfile::tempdir().unwrap();
    let mut g = common::white_sphere_gltf(true, 24, 32);
    g.lights
        .push(json!({"type": "point", "intensity": 20.0, "color": [1.0, 1.0, 1.0]}));
    g.node(json!({"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [1.0, 3.0, 2.0]}));
    let scene = g.write_glb(dir.path(), "sphere-point");
    for kernel in ["megakernel", "wavefront"] {
        let args = [
            "--kernel",
            kernel,
            "--width",
            "40",
            "--height",
            "30",
            "--spp",
            "4",
            "--bounces",
            "3",
        ];
        let (a, pa) = render_exr(
            &scene,
            &dir.path().join(format!("{kernel}-black.exr")),
            &args,
        );
        let mut faint = args.to_vec();
        faint.extend(["--sky", "1e-30"]);
        let (b, pb) = render_exr(
            &scene,
            &dir.path().join(format!("{kernel}-faint.exr")),
            &faint,
        );
        assert_eq!(a["lights"], 1, "{kernel}: {a}");
        assert_eq!(a["environment"], serde_json::Value::Null, "{kernel}: {a}");
        let (ra, rb) = (
            a["extension_rays"].as_u64().unwrap(),
            b["extension_rays"].as_u64().unwrap(),
        );
        assert!(
            ra < rb,
            "{kernel}: {ra} extension rays under a black sky, {rb} under a faint one"
        );
        assert!(pa.iter().any(|p| p[0] > 0.01), "{kernel}: a black image");
        for (i, (p, q)) in pa.iter().zip(&pb).enumerate() {
            for c in 0..3 {
                assert!(
                    (p[c] - q[c]).abs() <= 1e-6 * p[c].abs() + 1e-25,
                    "{kernel}: pixel {i} channel {c}: {} with the last ray untraced, {} traced",
                    p[c],
                    q[c]
                );
            }
        }
    }
}

#[test]
fn a_last_ray_is_tested_against_the_emitters_first() {
    // A path's last extension ray only looks for emitters. With few emissive triangles, a
    // black sky and no environment map, the megakernel tests it against those triangles
    // first: when it meets none it is not traced, when it meets one only the segment to it is
    // (an any-hit ray), and an unblocked segment shades the emitter's hit. The image is the
    // one with every last ray traced (`-DLAST_RAY_TRACED`) bit for bit, with fewer extension
    // rays and the same light samples; one ray at a time and in lanes. A sphere of 34,816
    // triangles (enough for lanes) on a floor under a one-sided emissive panel.
    let dir = tempfile::tempdir().unwrap();
    let scene = common::white_sphere_under_panel(dir.path(), 128, 136);
    let mut args = lanes_image_args("5", "1");
    args.extend(["--sky", "0,0,0"]);
    for lanes in ["0", "1"] {
        let render = |name: &str, options: &str| {
            render_exr_env(
                &scene,
                &dir.path().join(format!("{name}-{lanes}.exr")),
                &args,
                &[("PENUMBRA_LANES", lanes), ("PENUMBRA_CL_OPTIONS", options)],
            )
        };
        let (a, pa) = render("tested", "");
        let (b, pb) = render("traced", "-DLAST_RAY_TRACED");
        assert_eq!(a["lanes"], b["lanes"], "lanes {lanes}");
        let (ra, rb) = (
            a["extension_rays"].as_u64().unwrap(),
            b["extension_rays"].as_u64().unwrap(),
        );
        // At one bounce many of the 37 x 23 x 5 paths live to their last ray, and most of
        // those miss the panel.
        assert!(
            ra + rb / 10 < rb,
            "lanes {lanes}: {ra} extension rays with the last ones tested, {rb} traced"
        );
        assert_eq!(a["shadow_rays"], b["shadow_rays"], "lanes {lanes}");
        assert!(
            pa.iter().any(|p| p[0] > 0.0),
            "lanes {lanes}: a black image"
        );
        assert!(
            pa == pb,
            "lanes {lanes}: the image differs from the one with every last ray traced"
        );
    }
}
