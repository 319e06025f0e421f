//! Screenshots: the displayed frame as PNG (exposure, tone curve and sRGB, without the overlay)
//! and the film as EXR (linear radiance), side by side with the same name: on F12, and at the
//! exit with `--screenshot`.

use super::App;
use super::display::display_rgba;
use crate::image_io::{unique_path, write_exr, write_exr_rgba};
use crate::render::tonemap::write_rgba_png;
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The folder F12 saves into, relative to the working directory.
pub const FOLDER: &str = "screenshots";

/// A frame to save.
pub struct Shot<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// What is on screen: RGBA8, sRGB.
    pub rgba: &'a [u8],
    /// The film: linear RGB (premultiplied by `coverage` when there is one).
    pub linear: &'a [[f32; 3]],
    /// With the background cut out, each pixel's coverage: the EXR's A channel.
    pub coverage: Option<&'a [f32]>,
}

/// `YYYYMMDD-HHMMSS` in UTC.
pub fn timestamp(t: SystemTime) -> String {
    let (y, m, d, h, mi, sec) = crate::date::utc(t);
    format!("{y:04}{m:02}{d:02}-{h:02}{mi:02}{sec:02}")
}

/// A PNG path in `dir` named `penumbra-{timestamp}` whose PNG and EXR both do not exist yet.
pub fn next_path(dir: &Path, timestamp: &str) -> PathBuf {
    let mut png = unique_path(dir, "penumbra", timestamp, "png");
    while png.with_extension("exr").exists() {
        let stem = png
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        png = unique_path(dir, &stem, "b", "png");
    }
    png
}

/// Saves into `dir` (created if missing) under a new timestamped name; returns the PNG path.
pub fn save_timestamped(dir: &Path, shot: &Shot) -> Result<PathBuf> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
    let png = next_path(dir, &timestamp(SystemTime::now()));
    save_at(&png, shot)?;
    Ok(png)
}

/// Saves the PNG at `png` and the EXR beside it (same name, `.exr`); returns the EXR path.
pub fn save_at(png: &Path, shot: &Shot) -> Result<PathBuf> {
    write_rgba_png(png, shot.width, shot.height, shot.rgba)?;
    let exr = png.with_extension("exr");
    match shot.coverage {
        Some(a) => write_exr_rgba(&exr, shot.width, shot.height, shot.linear, a)?,
        None => write_exr(&exr, shot.width, shot.height, shot.linear)?,
    }
    Ok(exr)
}

impl App {
    /// Saves the image on screen (PNG, exactly the film: the panel and nothing else around it)
    /// and the film (EXR) into `screenshots/` under a new name.
    pub(super) fn screenshot(&mut self) {
        let film = &self.frame_loop.film;
        if film.pixels.is_empty() || self.display.len() != film.pixels.len() * 4 {
            self.gui.file_error = Some("no frame to save yet".into());
            return;
        }
        let shot = Shot {
            width: film.width,
            height: film.height,
            rgba: &self.display,
            linear: self.shown_denoised().unwrap_or(&film.pixels),
            coverage: film.cutout.then_some(film.coverage.as_slice()),
        };
        match save_timestamped(Path::new(FOLDER), &shot) {
            Ok(png) => {
                println!(
                    "penumbra: saved {} and {} ({}×{})",
                    png.display(),
                    png.with_extension("exr").display(),
                    film.width,
                    film.height
                );
                self.last_screenshot = Some(png);
            }
            Err(e) => self.gui.file_error = Some(format!("{e:#}")),
        }
    }

    /// On exit with `--screenshot`: waits for the running batch and saves the final frame.
    pub(super) fn save_final(&mut self, path: &Path) -> Result<()> {
        if let Err(e) = self.frame_loop.wait() {
            log::warn!("the last batch failed: {e}");
        }
        let film = &self.frame_loop.film;
        if film.pixels.is_empty() {
            bail!("--screenshot {}: no frame was rendered", path.display());
        }
        let v = &self.model.view;
        let rgba = display_rgba(film, v.exposure, v.tone_mapper, v.background);
        let shot = Shot {
            width: film.width,
            height: film.height,
            rgba: &rgba,
            linear: &film.pixels,
            coverage: film.cutout.then_some(film.coverage.as_slice()),
        };
        let exr = save_at(path, &shot)?;
        println!(
            "penumbra: saved {} and {} ({}×{}, {} spp)",
            path.display(),
            exr.display(),
            film.width,
            film.height,
            film.spp
        );
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, UNIX_EPOCH};

    #[test]
    fn timestamps_are_utc_calendar_times() {
        assert_eq!(timestamp(UNIX_EPOCH), "19700101-000000");
        // 2024-02-29 13:45:07 UTC (a leap day).
        let t = UNIX_EPOCH + Duration::from_secs(1_709_214_307);
        assert_eq!(timestamp(t), "20240229-134507");
    }

    #[test]
    fn screenshots_never_overwrite() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join(FOLDER);
        let shot = Shot {
            width: 2,
            height: 1,
            rgba: &[255, 0, 0, 255, 0, 255, 0, 255],
            linear: &[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            coverage: None,
        };
        let a = save_timestamped(&folder, &shot).unwrap();
        let b = save_timestamped(&folder, &shot).unwrap();
        assert_ne!(a, b);
        for p in [&a, &b] {
            assert!(p.exists() && p.with_extension("exr").exists());
            let name = p.file_name().unwrap().to_string_lossy();
            assert!(
                name.starts_with("penumbra-") && name.ends_with(".png"),
                "{name}"
            );
        }
        // A stray EXR with the next name is not overwritten either.
        let ts = "20000101-000000";
        std::fs::write(folder.join(format!("penumbra-{ts}.exr")), b"keep").unwrap();
        let c = next_path(&folder, ts);
        assert!(!c.exists() && !c.with_extension("exr").exists());
        assert_eq!(
            std::fs::read(folder.join(format!("penumbra-{ts}.exr"))).unwrap(),
            b"keep"
        );
    }
}
