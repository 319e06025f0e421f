//! The viewer's animation timeline: which clip plays, the time on it, play and pause (Space),
//! speed, loop, a step of one frame, first and last; and its section of the overlay. Each new
//! time poses the scene and the image restarts; while paused the image accumulates.

use crate::scene::Scene;
use egui::Ui;
use std::time::Instant;

/// The step of "a frame" (◀ ▶): a 30 fps frame.
pub const FRAME_SECONDS: f64 = 1.0 / 30.0;

/// The timeline's state.
#[derive(Clone, Debug)]
pub struct Timeline {
    /// The clip (index in the scene's clips).
    pub clip: usize,
    /// Seconds on the clip's timeline.
    pub time: f64,
    /// Whether time runs.
    pub playing: bool,
    /// Time runs at this multiple of the wall clock.
    pub speed: f64,
    /// At the end, start again (else stop at the end).
    pub looping: bool,
    /// When time last advanced.
    last_tick: Option<Instant>,
    /// The pose last applied (clip, time), or none yet.
    posed: Option<(usize, f64)>,
    /// The last pose's host time (evaluate and deform), ms.
    pub pose_ms: f64,
}

impl Default for Timeline {
    fn default() -> Self {
        Self {
            clip: 0,
            time: 0.0,
            playing: false,
            speed: 1.0,
            looping: true,
            last_tick: None,
            posed: None,
            pose_ms: 0.0,
        }
    }
}

impl Timeline {
    /// A timeline for `scene`: playing its first clip from 0 when it has clips.
    pub fn for_scene(scene: &Scene) -> Self {
        Self {
            playing: !scene.animation.clips.is_empty(),
            ..Self::default()
        }
    }

    /// Play or pause (Space).
    pub fn toggle(&mut self) {
        self.playing = !self.playing;
        self.last_tick = None;
    }

    /// Advances a playing timeline to `now`; a clip that is not looping stops at its end.
    fn tick(&mut self, now: Instant, duration: f64) {
        if !self.playing {
            self.last_tick = None;
            return;
        }
        if let Some(last) = self.last_tick {
            self.time += (now - last).as_secs_f64() * self.speed;
        }
        self.last_tick = Some(now);
        if duration <= 0.0 {
            self.time = 0.0;
        } else if self.looping {
            self.time = self.time.rem_euclid(duration);
        } else if self.time >= duration || self.time < 0.0 {
            self.time = self.time.clamp(0.0, duration);
            self.playing = false;
        }
    }

    /// Advances the time to `now` and poses `scene` when the clip or time differs from the pose
    /// last applied; returns whether it did (the scene changed).
    pub fn update(&mut self, scene: &mut Scene, now: Instant) -> bool {
        let animation = std::sync::Arc::clone(&scene.animation);
        let Some(clip) = animation.clips.get(self.clip) else {
            return false;
        };
        self.tick(now, clip.duration);
        if self.posed == Some((self.clip, self.time)) {
            return false;
        }
        let applied = animation.apply(scene, Some(self.clip), self.time);
        self.pose_ms = applied.evaluate_ms + applied.deform_ms;
        self.posed = Some((self.clip, self.time));
        true
    }

    /// The overlay's "Animation" section (only for a scene with clips).
    pub fn section(&mut self, ui: &mut Ui, scene: &Scene) {
        let clips = &scene.animation.clips;
        if clips.is_empty() {
            return;
        }
        egui::CollapsingHeader::new("Animation")
            .default_open(true)
            .show(ui, |ui| {
                let name = |i: usize| format!("{} ({:.2} s)", clips[i].name, clips[i].duration);
                egui::ComboBox::from_label("clip")
                    .selected_text(name(self.clip.min(clips.len() - 1)))
                    .show_ui(ui, |ui| {
                        for i in 0..clips.len() {
                            if ui.selectable_label(self.clip == i, name(i)).clicked() {
                                self.clip = i;
                                self.time = 0.0;
                            }
                        }
                    });
                let duration = clips[self.clip.min(clips.len() - 1)].duration;
                ui.horizontal(|ui| {
                    if ui.button("⏮").on_hover_text("first").clicked() {
                        self.time = 0.0;
                    }
                    if ui.button("◀").on_hover_text("a frame back").clicked() {
                        self.step(-1.0, duration);
                    }
                    let play = if self.playing {
                        "⏸ pause"
                    } else {
                        "▶ play"
                    };
                    if ui.button(play).on_hover_text("Space").clicked() {
                        self.toggle();
                    }
                    if ui.button("▶|").on_hover_text("a frame on").clicked() {
                        self.step(1.0, duration);
                    }
                    if ui.button("⏭").on_hover_text("last").clicked() {
                        self.time = duration;
                        self.playing = false;
                    }
                });
                ui.add(
                    egui::Slider::new(&mut self.time, 0.0..=duration.max(1e-3))
                        .text("s")
                        .fixed_decimals(3),
                );
                ui.horizontal(|ui| {
                    ui.add(
                        egui::DragValue::new(&mut self.speed)
                            .range(-4.0..=4.0)
                            .speed(0.01)
                            .prefix("speed ×"),
                    );
                    ui.checkbox(&mut self.looping, "loop");
                });
            });
    }

    /// Moves by `frames` frames of [`FRAME_SECONDS`] and pauses.
    fn step(&mut self, frames: f64, duration: f64) {
        self.playing = false;
        let t = self.time + frames * FRAME_SECONDS;
        self.time = if self.looping && duration > 0.0 {
            t.rem_euclid(duration)
        } else {
            t.clamp(0.0, duration)
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn playing_time_follows_the_clock_at_the_speed_and_wraps_or_stops() {
        let mut t = Timeline {
            playing: true,
            speed: 2.0,
            ..Timeline::default()
        };
        let start = Instant::now();
        t.tick(start, 1.0);
        t.tick(start + Duration::from_millis(300), 1.0);
        assert!((t.time - 0.6).abs() < 1e-9);
        t.tick(start + Duration::from_millis(600), 1.0);
        assert!((t.time - 0.2).abs() < 1e-9, "wrapped: {}", t.time);
        t.looping = false;
        t.tick(start + Duration::from_millis(1200), 1.0);
        assert_eq!((t.time, t.playing), (1.0, false));
        // Paused, time stands; a step moves one frame and stays paused.
        t.tick(start + Duration::from_secs(5), 1.0);
        assert_eq!(t.time, 1.0);
        t.step(-1.0, 1.0);
        assert!((t.time - (1.0 - FRAME_SECONDS)).abs() < 1e-12);
        assert!(!t.playing);
    }
}
