//! Honest figures for the overlay: image updates per second (new images presented, not the
//! panel's redraws), the latency of the last input (from its event to the present of the first
//! image rendered after it), and with `--stats-file` one JSON line per presented image for
//! scripts and tests.

use anyhow::{Context, Result};
use std::collections::VecDeque;
use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

/// The span the image rate is counted over.
const RATE_WINDOW: Duration = Duration::from_secs(2);

/// What a presented image was.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ImageLine {
    /// Seconds since the viewer started.
    pub t: f64,
    /// Samples per pixel in it.
    pub spp: u32,
    /// Film size.
    pub width: u32,
    /// Film size.
    pub height: u32,
    /// Resolution divisor of the preview (1: full resolution).
    pub divisor: u32,
    /// Bounces it was rendered with.
    pub bounces: u32,
    /// Exposure shown, in stops.
    pub exposure: f32,
    /// When it is the first image after input: milliseconds from the input event to its
    /// present.
    pub latency_ms: Option<f64>,
    /// The heat map shown instead of the image ("samples per pixel" or "error"), if any.
    pub heat_map: Option<&'static str>,
    /// With adaptive sampling, the share of pixels converged at the last check.
    pub converged_share: Option<f64>,
}

/// Presented images and input latencies.
pub struct ImageStats {
    started: Instant,
    shown: VecDeque<Instant>,
    /// The latency of the last input answered, in milliseconds.
    pub last_latency_ms: Option<f64>,
    file: Option<std::fs::File>,
}

impl ImageStats {
    /// Figures from now on; with `file`, each image is appended to it as a JSON line (the file
    /// is created or truncated).
    pub fn new(file: Option<&Path>) -> Result<Self> {
        let file = file
            .map(|p| {
                std::fs::File::create(p)
                    .with_context(|| format!("--stats-file {}: cannot create it", p.display()))
            })
            .transpose()?;
        Ok(Self {
            started: Instant::now(),
            shown: VecDeque::new(),
            last_latency_ms: None,
            file,
        })
    }

    /// A new image was presented at `now`; `answers` is the input it is the first image after.
    pub fn image_shown(&mut self, now: Instant, answers: Option<Instant>, mut line: ImageLine) {
        self.shown.push_back(now);
        self.forget_before(now);
        line.t = (now - self.started).as_secs_f64();
        if let Some(t) = answers {
            let ms = (now - t).as_secs_f64() * 1e3;
            self.last_latency_ms = Some(ms);
            line.latency_ms = Some(ms);
        }
        if let Some(f) = self.file.as_mut()
            && let Ok(text) = serde_json::to_string(&line)
            && writeln!(f, "{text}").is_err()
        {
            log::warn!("cannot write to the stats file; it is closed");
            self.file = None;
        }
    }

    /// New images per second over the last two seconds (0 when the image rests).
    pub fn images_per_second(&mut self, now: Instant) -> f64 {
        self.forget_before(now);
        self.shown.len() as f64 / RATE_WINDOW.as_secs_f64()
    }

    fn forget_before(&mut self, now: Instant) {
        while self
            .shown
            .front()
            .is_some_and(|&t| now.duration_since(t) > RATE_WINDOW)
        {
            self.shown.pop_front();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line() -> ImageLine {
        ImageLine {
            t: 0.0,
            spp: 1,
            width: 8,
            height: 8,
            divisor: 1,
            bounces: 4,
            exposure: 0.0,
            latency_ms: None,
            heat_map: None,
            converged_share: None,
        }
    }

    #[test]
    fn the_rate_counts_images_not_redraws_and_latency_runs_from_the_input() {
        let dir = std::env::temp_dir().join(format!("penumbra-stats-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("stats.jsonl");
        let mut s = ImageStats::new(Some(&path)).unwrap();
        let t0 = Instant::now();
        for i in 0..10 {
            s.image_shown(t0 + Duration::from_millis(100 * i), None, line());
        }
        let now = t0 + Duration::from_millis(900);
        assert_eq!(s.images_per_second(now), 5.0);
        // Two seconds without an image: the rate is 0, however often the panel redraws.
        assert_eq!(s.images_per_second(now + Duration::from_secs(3)), 0.0);
        let input = now + Duration::from_secs(3);
        s.image_shown(input + Duration::from_millis(80), Some(input), line());
        assert!((s.last_latency_ms.unwrap() - 80.0).abs() < 1e-6);
        drop(s);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 11);
        let last: serde_json::Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
        assert!((last["latency_ms"].as_f64().unwrap() - 80.0).abs() < 1e-6);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
