//! Intel's Open Image Denoise itself, through the pinned `pyoidn` wheel's Python binding
//! (scripts/install_oidn.sh installs it; scripts/oidn_denoise.py is the script run, embedded
//! here): the reference the comparison test and `bench denoise` hold penumbra's network to.

use super::Quality;
use anyhow::{Context, Result, bail};
use std::io::Write;
use std::process::{Command, Stdio};

/// The script run by `python3 -`.
const SCRIPT: &str = include_str!("../../scripts/oidn_denoise.py");

/// Whether `python3` can import `pyoidn`.
pub fn available() -> bool {
    Command::new("python3")
        .args(["-c", "import pyoidn"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The script's setting that runs `quality`'s weights: OIDN's quality, or `large` for the
/// guides prefiltered at `balanced` (rt_alb, rt_nrm) and then `high` with clean guides.
fn quality_name(quality: Quality) -> &'static str {
    match quality {
        Quality::Full => "high",
        Quality::Small => "fast",
        Quality::Large => "large",
    }
}

/// Runs OIDN's `RT` filter (hdr, albedo, normal; for [`Quality::Large`] after filtering the
/// albedo and the normal, with `cleanAux`) on OIDN's `device` (`cpu` or `cuda`); then,
/// with `runs` > 0, times that many more executions. Returns the denoised image and the times
/// in milliseconds.
pub fn denoise(
    width: usize,
    height: usize,
    quality: Quality,
    device: &str,
    images: [&[[f32; 3]]; 3],
    runs: usize,
) -> Result<(Vec<[f32; 3]>, Vec<f64>)> {
    let dir = scratch_dir()?;
    let mut paths = Vec::new();
    for (name, image) in ["color", "albedo", "normal"].iter().zip(images) {
        let path = dir.join(format!("{name}.f32"));
        std::fs::write(&path, bytemuck::cast_slice::<[f32; 3], u8>(image))?;
        paths.push(path);
    }
    let out = dir.join("output.f32");
    let mut child = Command::new("python3")
        .arg("-")
        .args([width.to_string(), height.to_string()])
        .args([quality_name(quality), device])
        .args(&paths)
        .arg(&out)
        .arg(runs.to_string())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .context("cannot run python3")?;
    child
        .stdin
        .take()
        .context("python3's input")?
        .write_all(SCRIPT.as_bytes())?;
    let result = child.wait_with_output()?;
    if !result.status.success() {
        bail!(
            "Open Image Denoise failed: {}",
            String::from_utf8_lossy(&result.stderr).trim()
        );
    }
    let bytes = std::fs::read(&out)?;
    let image: Vec<[f32; 3]> = bytemuck::pod_collect_to_vec(&bytes);
    let times = if runs > 0 {
        let json: serde_json::Value = serde_json::from_slice(&result.stdout)?;
        json["ms"]
            .as_array()
            .context("no times from the script")?
            .iter()
            .filter_map(|v| v.as_f64())
            .collect()
    } else {
        Vec::new()
    };
    std::fs::remove_dir_all(&dir).ok();
    Ok((image, times))
}

/// A fresh folder under the system's temporary folder.
fn scratch_dir() -> Result<std::path::PathBuf> {
    let dir = std::env::temp_dir().join(format!(
        "penumbra-oidn-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos())
    ));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}
