//! Keyboard and mouse: window events become camera moves (fly, look, pan, orbit, zoom) and the
//! viewer's actions (pick, focus, hard shadows, heat maps, screenshot, overlay, quit).

use super::camera::{Mode, Motion};
use super::frame_loop::Changes;
use super::heat::HeatMap;
use super::{App, pick};
use glam::DVec3;
use std::time::Instant;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{KeyCode, PhysicalKey};

/// Mouse and key state between events.
#[derive(Default)]
pub(super) struct Input {
    pub motion: Motion,
    pub cursor: Option<(f64, f64)>,
    pub look: bool,
    pub pan: bool,
    pub shift: bool,
    pub ctrl: bool,
    /// A button pressed while the overlay is shown, handled after egui's next pass.
    pub press: Option<MouseButton>,
    /// When the earliest input not yet turned into a change arrived (for its latency).
    pub event_at: Option<Instant>,
}

impl App {
    /// Handles a keyboard or mouse event. `typing`: egui has the keyboard (key releases still
    /// count); `wheel_free`: the wheel is not egui's.
    pub(super) fn input_event(&mut self, event: WindowEvent, typing: bool, wheel_free: bool) {
        let acts = match &event {
            WindowEvent::KeyboardInput { event, .. } => {
                event.state == ElementState::Pressed && !event.repeat
            }
            WindowEvent::CursorMoved { .. } => self.input.look || self.input.pan,
            WindowEvent::MouseInput { .. } | WindowEvent::MouseWheel { .. } => true,
            _ => false,
        };
        if acts && self.input.event_at.is_none() {
            self.input.event_at = Some(Instant::now());
        }
        match event {
            WindowEvent::ModifiersChanged(m) => {
                self.input.shift = m.state().shift_key();
                self.input.ctrl = m.state().control_key();
                self.input.motion.fast = self.input.shift;
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    let pressed = event.state == ElementState::Pressed;
                    // Releases always count so no key stays stuck.
                    if !pressed || !typing {
                        self.key(code, pressed, event.repeat);
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let pressed = state == ElementState::Pressed;
                if pressed && self.overlay {
                    // egui learns where the pointer is only when it runs: decide in the next
                    // frame whether the press was on the overlay or on the image.
                    self.input.press = Some(button);
                } else if pressed {
                    self.press(button);
                } else if matches!(button, MouseButton::Right | MouseButton::Middle) {
                    self.input.look = false;
                    self.input.pan = false;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let now = (position.x, position.y);
                if let Some(last) = self.input.cursor {
                    let (dx, dy) = (now.0 - last.0, now.1 - last.1);
                    let moved = if self.input.pan {
                        self.model.camera.pan(dx, dy, self.size.1 as f64)
                    } else if self.input.look {
                        self.model.camera.look(dx, dy)
                    } else {
                        false
                    };
                    if moved {
                        self.camera_moved();
                    }
                }
                self.input.cursor = Some(now);
            }
            WindowEvent::CursorLeft { .. } => self.input.cursor = None,
            // Releases that happen elsewhere never arrive: nothing stays held.
            WindowEvent::Focused(false) => {
                self.input.motion = Motion::default();
                self.input.look = false;
                self.input.pan = false;
            }
            WindowEvent::MouseWheel { delta, .. } if wheel_free => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                if self.model.camera.wheel(notches) {
                    self.camera_moved();
                }
            }
            _ => {}
        }
    }

    /// A mouse button pressed on the image: pick, look or pan.
    pub(super) fn press(&mut self, button: MouseButton) {
        match button {
            MouseButton::Left => self.pick(),
            MouseButton::Right if self.input.shift => self.input.pan = true,
            MouseButton::Right => self.input.look = true,
            MouseButton::Middle => self.input.pan = true,
            _ => {}
        }
    }

    pub(super) fn camera_moved(&mut self) {
        self.last_motion = Some(Instant::now());
        let at = self.change_time();
        self.frame_loop.invalidate_at(
            Changes {
                camera: true,
                ..Changes::default()
            },
            at,
        );
    }

    fn key(&mut self, code: KeyCode, pressed: bool, repeat: bool) {
        let ctrl = self.input.ctrl;
        let m = &mut self.input.motion;
        match code {
            KeyCode::KeyW => m.forward = pressed,
            KeyCode::KeyS => m.back = pressed,
            KeyCode::KeyA => m.left = pressed,
            KeyCode::KeyD => m.right = pressed,
            KeyCode::KeyQ if !ctrl || !pressed => m.down = pressed,
            KeyCode::KeyE => m.up = pressed,
            _ if !pressed || repeat && !matches!(code, KeyCode::Equal | KeyCode::Minus) => {}
            KeyCode::KeyR => {
                self.model.camera.reset();
                self.camera_moved();
            }
            KeyCode::KeyH if !self.model.view.has_light_radius() => self.flash(
                "H: no light here has a radius to change (the scene is lit by its environment \
                 or emissive surfaces)",
            ),
            KeyCode::KeyH => {
                self.model.view.toggle_hard_shadows();
                self.lights_changed();
            }
            KeyCode::KeyC => {
                let c = &mut self.model.camera;
                c.collision = !c.collision;
                let what = if c.collision {
                    "collision on: moves stop at walls"
                } else {
                    "collision off: moves pass through walls"
                };
                self.flash(what);
            }
            KeyCode::KeyV => {
                let name = super::gui::next_view_name(&self.gui.views);
                self.save_view(&name);
            }
            KeyCode::KeyO => {
                let next = match self.model.camera.mode {
                    Mode::Fly => Mode::Orbit,
                    Mode::Orbit => Mode::Fly,
                };
                self.model.camera.set_mode(next);
            }
            KeyCode::Equal | KeyCode::NumpadAdd => self.model.camera.scale_speed(1.0),
            KeyCode::Minus | KeyCode::NumpadSubtract => self.model.camera.scale_speed(-1.0),
            KeyCode::KeyQ if ctrl => self.quit = true,
            KeyCode::Tab => self.overlay = !self.overlay,
            KeyCode::F1 => self.gui.help = !self.gui.help,
            KeyCode::Space => self.model.timeline.toggle(),
            KeyCode::KeyN => {
                self.model.view.denoise = !self.model.view.denoise;
                self.frame_loop.invalidate(Changes {
                    settings: true,
                    ..Changes::default()
                });
            }
            KeyCode::KeyM => self.next_heat_map(),
            KeyCode::F12 => self.screenshot(),
            _ => {}
        }
    }

    /// M: image, samples per pixel, error, image. The maps need adaptive sampling: with it off,
    /// M turns it on at the overlay's default threshold (the image restarts) and says so.
    fn next_heat_map(&mut self) {
        let v = &mut self.model.view;
        v.heat_map = v.heat_map.next();
        let turned_on = v.heat_map != HeatMap::Off && v.noise_threshold.is_none();
        if turned_on {
            v.noise_threshold = Some(super::gui::DEFAULT_NOISE_THRESHOLD);
            self.frame_loop.invalidate(Changes {
                settings: true,
                ..Changes::default()
            });
        }
        let v = &self.model.view;
        let text = match (v.heat_map, turned_on) {
            (HeatMap::Off, _) => "the image".to_string(),
            (map, true) => format!(
                "{}: adaptive sampling on (noise threshold {})",
                map.name(),
                v.noise_threshold.unwrap_or_default()
            ),
            (map, false) => map.name().to_string(),
        };
        self.flash(&text);
    }

    /// Shows `text` in the middle of the image for a moment.
    pub(super) fn flash(&mut self, text: &str) {
        self.gui.flash = Some((text.to_string(), Instant::now()));
    }

    /// Saves the camera as `name` in the views file beside the scene and lists it.
    pub(super) fn save_view(&mut self, name: &str) {
        let Some(path) = self.scene_path.clone() else {
            self.flash("views are saved beside a scene file: open one first");
            return;
        };
        match crate::scene::views::save_view(&path, name, &self.model.camera.camera) {
            Ok(file) => {
                println!("penumbra: saved view '{name}' in {}", file.display());
                self.flash(&format!("saved view '{name}'"));
                self.load_views();
            }
            Err(e) => self.gui.file_error = Some(format!("{e:#}")),
        }
    }

    /// Reads the scene's saved views for the overlay's list.
    pub(super) fn load_views(&mut self) {
        self.gui.views = match &self.scene_path {
            Some(p) => crate::scene::views::load_views(p).unwrap_or_else(|e| {
                log::warn!("{e:#}");
                Vec::new()
            }),
            None => Vec::new(),
        };
    }

    fn lights_changed(&mut self) {
        self.last_motion = Some(Instant::now());
        self.lights = self.model.view.lights();
        let at = self.change_time();
        self.frame_loop.invalidate_at(
            Changes {
                lights: true,
                ..Changes::default()
            },
            at,
        );
    }

    /// Picks the object under the cursor (host BVH ray cast).
    fn pick(&mut self) {
        let Some((x, y)) = self.input.cursor else {
            return;
        };
        let Some(host) = self.frame_loop.renderer.host_scene() else {
            return;
        };
        let area = self.image_area();
        let Some((u, v)) = area.image_position(x, y) else {
            return;
        };
        let hit = pick::pick(host, &self.model.camera.camera, area.aspect(), u, v);
        log::debug!("pick at ({x:.0}, {y:.0}): {hit:?}");
        match hit {
            Some(hit) => {
                self.model.selected = Some(hit.object);
                if self.model.camera.mode == Mode::Orbit {
                    // The object's centre keeps it in frame while orbiting.
                    let center = pick::object_center(&self.model.scene, hit.object);
                    self.model.camera.set_pivot(center.unwrap_or(hit.point));
                }
                // With a lens, a click also focuses on the clicked point.
                if self.model.view.aperture > 0.0 {
                    self.focus_at(hit.point);
                }
            }
            None => self.model.selected = None,
        }
    }

    /// Focuses the lens on `point`: the plane in focus goes through it.
    pub(super) fn focus_at(&mut self, point: DVec3) {
        let cam = &self.model.camera.camera;
        self.model.view.focus_distance = (point - cam.eye).dot(cam.forward) as f32;
        self.frame_loop.invalidate(Changes {
            settings: true,
            ..Changes::default()
        });
    }
}
