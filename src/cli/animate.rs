//! `render --time`, `--clip`, `--frames A..B --fps F`: which instants of which clip a render
//! shows, the frames' file names, and a prepared scene brought to each instant (objects,
//! deformed meshes, the file's cameras and lights).

use crate::args::Prepared;
use crate::scene::animation::Applied;
use anyhow::{Result, bail};
use clap::Args;
use std::path::{Path, PathBuf};

/// Frames a second when `--fps` is not given.
pub const DEFAULT_FPS: f64 = 24.0;

/// Animation options of `render`.
#[derive(Args, Debug, Clone, Default)]
pub struct AnimationArgs {
    /// Render the animation at this many seconds into the clip (wrapped over the clip's
    /// length: clips loop) (default: the rest pose, no animation).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_time, conflicts_with = "frames")]
    pub time: Option<f64>,
    /// The clip --time and --frames play, by name or index (default: the first clip).
    #[arg(long)]
    pub clip: Option<String>,
    /// Render frames A to B (inclusive) of the clip, frame n at n / --fps seconds, to -o with
    /// its `#`s replaced by the frame number (out_####.png: out_0001.png …) (default: one
    /// image).
    #[arg(long, value_parser = parse_range)]
    pub frames: Option<(u32, u32)>,
    /// Frames a second of --frames (default: 24).
    #[arg(long, value_parser = crate::args::parse_positive)]
    pub fps: Option<f32>,
    /// Motion blur: the shutter stays open this many seconds from each image's instant, the
    /// samples spread over the poses in between (default: 0, no blur).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_shutter)]
    pub shutter: Option<f64>,
}

/// Poses a shutter interval is rendered at, at most (fewer with fewer samples a pixel): each
/// pose renders its share of the samples into the same film, so the image is the average of
/// the poses at the middles of [`SHUTTER_POSES`] equal parts of the interval. 16 keeps a
/// blurred edge's steps within 1/16 of the way it travels (below the noise of a few hundred
/// samples) for 16 scene updates a frame (the Fox: about 16 ms on 2 cores).
pub const SHUTTER_POSES: u32 = 16;

/// One image to render: its frame number (none for a single image), its instant on the clip's
/// timeline and its file.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// `--frames`' number.
    pub number: Option<u32>,
    /// Seconds into the clip (before wrapping); `None`: the rest pose.
    pub time: Option<f64>,
    /// Where it is written.
    pub output: PathBuf,
}

impl AnimationArgs {
    /// The images to render to `output`: one, or one a frame of `--frames`. Refuses a sequence
    /// whose file name has no `#`.
    pub fn frames(&self, output: &Path) -> Result<Vec<Frame>> {
        let Some((first, last)) = self.frames else {
            if self.fps.is_some() {
                bail!("--fps needs --frames");
            }
            return Ok(vec![Frame {
                number: None,
                time: self.time,
                output: output.to_path_buf(),
            }]);
        };
        let name = output
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !name.contains('#') {
            bail!(
                "{}: a sequence's output needs #s for the frame number (out_####.png)",
                output.display()
            );
        }
        let fps = self.fps.map_or(DEFAULT_FPS, f64::from);
        Ok((first..=last)
            .map(|n| Frame {
                number: Some(n),
                time: Some(f64::from(n) / fps),
                output: output.with_file_name(frame_name(&name, n)),
            })
            .collect())
    }

    /// Whether any option asks for an animated instant.
    pub fn wanted(&self) -> bool {
        self.time.is_some() || self.clip.is_some() || self.frames.is_some() || self.blurs()
    }

    /// Whether the shutter stays open (`--shutter` above 0).
    pub fn blurs(&self) -> bool {
        self.shutter.is_some_and(|s| s > 0.0)
    }

    /// The shutter's poses for an image of `spp` samples a pixel starting at `time`: the
    /// instant of each, and the samples each renders (the first ones one more); one pose at
    /// `time` without a shutter.
    pub fn shutter_poses(&self, time: f64, spp: u32) -> Vec<(f64, u32)> {
        let open = self.shutter.unwrap_or(0.0);
        if !self.blurs() || spp == 0 {
            return vec![(time, spp)];
        }
        let k = SHUTTER_POSES.min(spp);
        (0..k)
            .map(|i| {
                let t = time + open * (f64::from(i) + 0.5) / f64::from(k);
                (t, spp / k + u32::from(i < spp % k))
            })
            .collect()
    }

    /// The clip to play in `prepared`'s scene; `None` when nothing asks for one. Errors when
    /// an instant is asked of a scene without clips or the clip does not exist.
    pub fn clip(&self, prepared: &Prepared) -> Result<Option<usize>> {
        if !self.wanted() {
            return Ok(None);
        }
        let animation = &prepared.scene.animation;
        let source = &prepared.scene.source;
        if animation.clips.is_empty() {
            bail!(
                "{source}: --time, --clip, --frames and --shutter need a scene with animations; it has none"
            );
        }
        match &self.clip {
            Some(name) => animation
                .find_clip(name)
                .map(Some)
                .map_err(|e| anyhow::anyhow!("{source}: --clip: {e}")),
            None => Ok(Some(0)),
        }
    }
}

/// `name` with its first run of `#` replaced by `n`, zero-padded to the run's length.
pub fn frame_name(name: &str, n: u32) -> String {
    let start = name.find('#').unwrap_or(name.len());
    let run = name[start..].chars().take_while(|&c| c == '#').count();
    format!("{}{n:0run$}{}", &name[..start], &name[start + run..])
}

/// Brings `prepared` to `time` seconds into `clip` (looping): its scene posed and the camera
/// and lights that the file's animated nodes place moved with it (the camera when it is one of
/// the file's, keeping the field of view chosen).
pub fn pose(prepared: &mut Prepared, clip: usize, time: f64) -> Applied {
    let animation = std::sync::Arc::clone(&prepared.scene.animation);
    let t = animation.clip_time(clip, time, true);
    let applied = animation.apply(&mut prepared.scene, Some(clip), t);
    for &(c, _) in &animation.cameras {
        let posed = &prepared.scene.cameras[c];
        if posed.name == prepared.camera.name {
            prepared.camera.eye = posed.eye;
            prepared.camera.forward = posed.forward;
            prepared.camera.up = posed.up;
        }
    }
    for &(l, _) in &animation.lights {
        let posed = &prepared.scene.lights[l];
        if let Some(light) = prepared.lights.get_mut(l)
            && light.name == posed.name
        {
            light.position = posed.position;
            light.direction = posed.direction;
        }
    }
    applied
}

/// The clips of `prepared`'s scene for the summary: name and duration in seconds.
pub fn clips_json(prepared: &Prepared) -> serde_json::Value {
    prepared
        .scene
        .animation
        .clips
        .iter()
        .map(|c| serde_json::json!({"name": c.name, "duration": c.duration}))
        .collect()
}

/// A time in seconds: any finite number.
fn parse_time(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("'{s}' is not a time in seconds")),
    }
}

/// A shutter interval in seconds: a finite number ≥ 0.
fn parse_shutter(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!(
            "'{s}' is not a shutter interval in seconds (a number >= 0)"
        )),
    }
}

/// `A..B`, frame numbers with A ≤ B.
fn parse_range(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("'{s}' is not a frame range A..B (0..47)");
    let (a, b) = s.trim().split_once("..").ok_or_else(bad)?;
    let (a, b) = (
        a.trim().parse::<u32>().map_err(|_| bad())?,
        b.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if a > b {
        return Err(format!("'{s}': the first frame comes after the last"));
    }
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_names_take_the_number_in_place_of_the_hashes() {
        assert_eq!(frame_name("out_####.png", 7), "out_0007.png");
        assert_eq!(frame_name("f#.exr", 12), "f12.exr");
        assert_eq!(frame_name("a##_b##.png", 3), "a03_b##.png");
    }

    #[test]
    fn ranges_parse_and_a_sequence_needs_hashes() {
        assert_eq!(parse_range("0..47"), Ok((0, 47)));
        assert_eq!(parse_range("5..5"), Ok((5, 5)));
        assert!(parse_range("5..2").is_err());
        assert!(parse_range("5").is_err());
        let args = AnimationArgs {
            frames: Some((2, 4)),
            fps: Some(10.0),
            ..AnimationArgs::default()
        };
        let frames = args.frames(Path::new("dir/out_###.png")).unwrap();
        assert_eq!(frames.len(), 3);
        assert_eq!(frames[0].output, Path::new("dir/out_002.png"));
        assert_eq!(frames[2].time, Some(0.4));
        let err = args.frames(Path::new("out.png")).unwrap_err();
        assert!(err.to_string().contains("needs #s"), "{err}");
    }

    #[test]
    fn a_shutter_spreads_the_samples_over_poses_at_the_middles_of_its_parts() {
        let open = |shutter| AnimationArgs {
            shutter: Some(shutter),
            ..AnimationArgs::default()
        };
        assert_eq!(open(0.0).shutter_poses(1.0, 64), vec![(1.0, 64)]);
        assert!(!open(0.0).wanted());
        let poses = open(0.5).shutter_poses(1.0, 37);
        assert_eq!(poses.len(), SHUTTER_POSES as usize);
        assert_eq!(poses.iter().map(|p| p.1).sum::<u32>(), 37);
        assert_eq!((poses[0].1, poses[15].1), (3, 2));
        assert!((poses[0].0 - (1.0 + 0.5 / 32.0)).abs() < 1e-12);
        assert!((poses[15].0 - (1.5 - 0.5 / 32.0)).abs() < 1e-12);
        // Fewer samples than poses: one sample a pose.
        assert_eq!(open(1.0).shutter_poses(0.0, 4).len(), 4);
        assert!(parse_shutter("-1").is_err() && parse_shutter("nan").is_err());
    }
}
