//! The overlay (egui): a top bar with the screenshot button and the frame's figures, and a
//! controls window with render, camera, light, scene and statistics sections. It edits the
//! [`Model`] and reports what changed in [`Actions`]; the window loop applies them.

use super::camera::{CameraController, Mode};
use super::exposure::HeldExposure;
use super::frame_loop::{Changes, Film, Progress};
use super::heat::{self, HeatMap};
use super::state::ViewState;
use crate::render::SceneStats;
use crate::render::background::Background;
use crate::render::tonemap::ToneMapper;
use crate::scene::views::SavedView;
use crate::scene::{EnvPreset, LightPreset, Scene};
use egui::{Color32, RichText, Ui};
use glam::{DMat4, DQuat, DVec3, EulerRot};
use std::path::PathBuf;
use std::time::Instant;

/// What the overlay edits.
pub struct Model {
    /// The scene (objects are hidden, shown and moved here).
    pub scene: Scene,
    /// Each object's transform as loaded, for "reset transform".
    pub loaded_transforms: Vec<DMat4>,
    /// Render settings and lights.
    pub view: ViewState,
    /// The camera.
    pub camera: CameraController,
    /// The picked object.
    pub selected: Option<usize>,
    /// The animation timeline (idle for a scene without clips).
    pub timeline: super::timeline::Timeline,
}

impl Model {
    /// The model of a freshly loaded scene.
    pub fn new(scene: Scene, view: ViewState, camera: CameraController) -> Self {
        Self {
            loaded_transforms: scene.objects.iter().map(|o| o.world_from_object).collect(),
            timeline: super::timeline::Timeline::for_scene(&scene),
            scene,
            view,
            camera,
            selected: None,
        }
    }
}

/// Read-only figures the overlay shows.
pub struct Info<'a> {
    /// The OpenCL device.
    pub device: &'a str,
    /// Progress of the accumulation.
    pub progress: &'a Progress,
    /// The image on screen.
    pub film: &'a Film,
    /// The last BVH rebuild.
    pub scene_stats: Option<&'a SceneStats>,
    /// Scene file loading time.
    pub load_ms: f64,
    /// New images presented per second (not the panel's redraws).
    pub images_per_second: f64,
    /// Milliseconds from the last input to the first image after it.
    pub latency_ms: Option<f64>,
    /// The file being loaded in the background.
    pub loading: Option<&'a std::path::Path>,
    /// The last screenshot's PNG path.
    pub last_screenshot: Option<&'a std::path::Path>,
    /// A device failure; rendering has stopped.
    pub device_error: Option<&'a str>,
    /// How long the last denoising took, while the image is denoised.
    pub denoise_ms: Option<f64>,
}

/// What the user asked for this frame.
#[derive(Debug, Default)]
pub struct Actions {
    /// What to re-upload.
    pub changes: Changes,
    /// Save a screenshot.
    pub screenshot: bool,
    /// Open this file.
    pub open: Option<PathBuf>,
    /// Switch to this environment.
    pub environment: Option<EnvSource>,
    /// Hide the overlay.
    pub hide_overlay: bool,
    /// Save the current camera under this name in the scene's views file.
    pub save_view: Option<String>,
    /// Go to this saved view.
    pub recall_view: Option<crate::scene::Camera>,
}

/// A line in the middle of the window (e.g. while the kernels build).
pub fn notice(ctx: &egui::Context, text: &str, panel_width: f32) {
    egui::Area::new(egui::Id::new("notice"))
        .anchor(
            egui::Align2::CENTER_CENTER,
            egui::vec2(0.5 * panel_width, 0.0),
        )
        .interactable(false)
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                ui.label(RichText::new(text).size(18.0).color(Color32::WHITE));
            });
        });
}

/// An environment the overlay asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvSource {
    /// No environment map (the uniform sky, black by default).
    None,
    /// A bundled one.
    Preset(EnvPreset),
    /// An .hdr or .exr file.
    File(PathBuf),
}

/// The selected object's transform as the overlay edits it.
#[derive(Clone, Debug, PartialEq)]
struct TransformEdit {
    object: usize,
    translation: DVec3,
    /// XYZ Euler angles in degrees.
    rotation: DVec3,
    scale: DVec3,
}

impl TransformEdit {
    fn of(object: usize, m: &DMat4) -> Self {
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        let (x, y, z) = rotation.to_euler(EulerRot::XYZ);
        Self {
            object,
            translation,
            rotation: DVec3::new(x, y, z).map(f64::to_degrees),
            scale,
        }
    }

    fn matrix(&self) -> DMat4 {
        let r = self.rotation.map(f64::to_radians);
        DMat4::from_scale_rotation_translation(
            self.scale,
            DQuat::from_euler(EulerRot::XYZ, r.x, r.y, r.z),
            self.translation,
        )
    }
}

/// The overlay's own state (text being typed, the open editors).
pub struct Gui {
    /// The file path field.
    pub path_text: String,
    preset: LightPreset,
    edit: Option<TransformEdit>,
    /// The last error about a file (shown in red until the next file loads).
    pub file_error: Option<String>,
    /// The environment map path field.
    pub env_text: String,
    /// The last error about an environment map.
    pub env_error: Option<String>,
    /// The loaded environment map's name (`neutral`, `studio`, `outdoor` or the file's), if any; shows
    /// its controls.
    pub env_name: Option<String>,
    /// The help window (F1) is open.
    pub help: bool,
    /// The scene's saved views.
    pub views: Vec<SavedView>,
    /// The name field of "save view".
    view_name: String,
    /// A message shown for a moment in the middle of the image, and when it was set.
    pub flash: Option<(String, Instant)>,
}

impl Gui {
    /// The overlay with `path` in its file field and the environment map `env_name` on.
    pub fn new(path: String, env_name: Option<String>) -> Self {
        Self {
            path_text: path,
            preset: LightPreset::ThreePointStudio,
            edit: None,
            file_error: None,
            env_text: String::new(),
            env_error: None,
            env_name,
            help: false,
            views: Vec::new(),
            view_name: String::new(),
            flash: None,
        }
    }

    /// Draws the overlay, a side panel of fixed width ([`super::layout::panel_points`]) left of
    /// the image; returns what the user asked for.
    pub fn ui(&mut self, ui: &mut Ui, m: &mut Model, info: &Info) -> Actions {
        let mut actions = Actions::default();
        let width = super::layout::panel_points(ui.ctx().content_rect().width());
        egui::Panel::left("penumbra-panel")
            .resizable(false)
            .exact_size(width)
            .show(ui, |ui| {
                self.bar(ui, m, info, &mut actions);
                ui.separator();
                egui::ScrollArea::vertical()
                    .id_salt("panel")
                    .auto_shrink([false, false])
                    .show(ui, |ui| {
                        // Statistics first: visible without scrolling in a 600 px window.
                        stats_section(ui, m, info);
                        m.timeline.section(ui, &m.scene);
                        self.render_section(ui, m, info, &mut actions);
                        self.camera_section(ui, m, &mut actions);
                        self.lights_section(ui, m, &mut actions);
                        self.views_section(ui, &mut actions);
                        self.scene_section(ui, m, info, &mut actions);
                        controls_section(ui);
                    });
            });
        actions
    }

    fn bar(&mut self, ui: &mut Ui, m: &mut Model, info: &Info, actions: &mut Actions) {
        ui.horizontal_wrapped(|ui| {
            if ui.button("📷 Screenshot (F12)").clicked() {
                actions.screenshot = true;
            }
            if ui.button("Hide (Tab)").clicked() {
                actions.hide_overlay = true;
            }
            if ui.button("Keys (F1)").clicked() {
                self.help = !self.help;
            }
        });
        let target = m
            .view
            .spp_target
            .map_or_else(|| "∞".to_string(), |t| t.to_string());
        let converged = info
            .progress
            .converged_share
            .map_or_else(String::new, |c| format!(" · {:.0} % converged", c * 100.0));
        ui.label(format!(
            "{} / {target} spp{converged} · {:.2} MS/s",
            info.progress.spp,
            info.progress.samples_per_second * 1e-6,
        ));
        ui.label(live_figures(info))
            .on_hover_text("new images shown per second (not redraws of the panel); the time from the last input to the first image rendered after it");
        if let Some(e) = info.device_error {
            ui.label(RichText::new(format!("device error: {e}")).color(Color32::LIGHT_RED));
        }
    }

    fn render_section(&mut self, ui: &mut Ui, m: &mut Model, info: &Info, actions: &mut Actions) {
        egui::CollapsingHeader::new("Render")
            .default_open(true)
            .show(ui, |ui| {
                let v = &mut m.view;
                if ui
                    .add(egui::Slider::new(&mut v.bounces, 0..=32).text("bounces"))
                    .changed()
                {
                    actions.changes.settings = true;
                }
                ui.horizontal_wrapped(|ui| {
                    // Adaptive sampling: converged pixels stop (docs/adaptive-sampling.md).
                    let mut adaptive = v.noise_threshold.is_some();
                    if ui.checkbox(&mut adaptive, "adaptive").changed() {
                        v.noise_threshold = adaptive.then_some(DEFAULT_NOISE_THRESHOLD);
                        actions.changes.settings = true;
                    }
                    if let Some(t) = v.noise_threshold.as_mut()
                        && ui
                            .add(
                                egui::DragValue::new(t)
                                    .range(0.001..=1.0)
                                    .speed(0.001)
                                    .prefix("noise threshold "),
                            )
                            .changed()
                    {
                        actions.changes.settings = true;
                    }
                });
                if let Some(threshold) = v.noise_threshold {
                    heat_map_choice(ui, &mut v.heat_map);
                    heat_legend(ui, v.heat_map, threshold, info.film);
                }
                // The denoiser needs the guide buffers: turning it on or off builds the kernels.
                if ui
                    .checkbox(&mut v.denoise, "denoise (N)")
                    .on_hover_text("Open Image Denoise's network on the device (docs/denoiser.md)")
                    .changed()
                {
                    actions.changes.settings = true;
                }
                ui.horizontal_wrapped(|ui| {
                    let mut endless = v.spp_target.is_none();
                    if ui.checkbox(&mut endless, "endless").changed() {
                        v.spp_target = if endless { None } else { Some(256) };
                    }
                    if let Some(t) = v.spp_target.as_mut() {
                        ui.add(
                            egui::DragValue::new(t)
                                .range(1..=1_000_000)
                                .speed(1.0)
                                .suffix(" spp target"),
                        );
                    }
                });
                ui.horizontal_wrapped(|ui| {
                    ui.label("sky");
                    if ui.color_edit_button_rgb(&mut v.sky).changed() {
                        actions.changes.settings = true;
                    }
                    let mut level = v.sky.iter().copied().fold(0.0, f32::max);
                    if ui
                        .add(
                            egui::DragValue::new(&mut level)
                                .range(0.0..=100.0)
                                .speed(0.01)
                                .prefix("× "),
                        )
                        .changed()
                    {
                        let old = v.sky.iter().copied().fold(0.0, f32::max);
                        v.sky = if old > 0.0 {
                            v.sky.map(|c| c * level / old)
                        } else {
                            [level; 3]
                        };
                        actions.changes.settings = true;
                    }
                });
                ui.horizontal_wrapped(|ui| {
                    // Short labels keep each choice row on one line in the panel's width.
                    ui.label("env").on_hover_text("environment light");
                    for p in EnvPreset::ALL {
                        let on = self.env_name.as_deref() == Some(p.name());
                        if ui.selectable_label(on, p.name()).clicked() && !on {
                            actions.environment = Some(EnvSource::Preset(p));
                        }
                    }
                    let none = self.env_name.is_none();
                    if ui.selectable_label(none, "none").clicked() && !none {
                        actions.environment = Some(EnvSource::None);
                    }
                });
                ui.horizontal_wrapped(|ui| {
                    ui.label("file");
                    let field = ui.add(
                        egui::TextEdit::singleline(&mut self.env_text)
                            .hint_text("sky.hdr / .exr")
                            .desired_width(120.0),
                    );
                    let entered =
                        field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                    if ui.button("Load").clicked() || entered {
                        let path = self.env_text.trim();
                        if path.is_empty() {
                            self.env_error = Some("type a .hdr or .exr path first".into());
                        } else {
                            actions.environment = Some(EnvSource::File(PathBuf::from(path)));
                        }
                    }
                });
                if let Some(e) = &self.env_error {
                    ui.label(RichText::new(e).color(Color32::LIGHT_RED));
                }
                if self.env_name.is_some() {
                    let i = ui.add(
                        egui::DragValue::new(&mut v.env_intensity)
                            .range(0.0..=1.0e6)
                            .speed(0.01)
                            .prefix("environment intensity × "),
                    );
                    let r = ui.add(
                        egui::Slider::new(&mut v.env_rotation, -180.0..=180.0).text("rotation °"),
                    );
                    if i.changed() || r.changed() {
                        actions.changes.settings = true;
                    }
                }
                ui.horizontal(|ui| {
                    let mut auto = v.auto_exposure.is_some();
                    if ui.checkbox(&mut auto, "auto").changed() {
                        v.auto_exposure = auto.then(HeldExposure::default);
                        v.incident_exposure = false;
                    }
                    let s = ui.add(egui::Slider::new(&mut v.exposure, -24.0..=24.0).text("stops"));
                    if s.changed() {
                        v.auto_exposure = None;
                        v.incident_exposure = false;
                    }
                })
                .response
                .on_hover_text(
                    "exposure: automatic (metered on the image) or in stops (set at first from \
                     the light at the subject)",
                );
                exposure_lock(ui, v);
                ui.horizontal_wrapped(|ui| {
                    ui.label("tone").on_hover_text("tone mapper");
                    for t in ToneMapper::ALL {
                        let short = t.name().trim_start_matches("Khronos ");
                        ui.selectable_value(&mut v.tone_mapper, t, short)
                            .on_hover_text(t.name());
                    }
                });
                ui.horizontal_wrapped(|ui| {
                    ui.label("background");
                    let b = &mut v.background;
                    let before = *b;
                    if ui.selectable_label(*b == Background::Env, "env").clicked() {
                        *b = Background::Env;
                    }
                    if ui
                        .selectable_label(*b == Background::Transparent, "transparent")
                        .clicked()
                    {
                        *b = Background::Transparent;
                    }
                    let mut color = match *b {
                        Background::Color(c) => c,
                        _ => [1.0; 3],
                    };
                    let is_color = matches!(*b, Background::Color(_));
                    if ui.selectable_label(is_color, "color").clicked() {
                        *b = Background::Color(color);
                    }
                    if is_color && ui.color_edit_button_rgb(&mut color).changed() {
                        *b = Background::Color(color);
                    }
                    if b.cutout() != before.cutout() {
                        actions.changes.settings = true;
                    }
                });
            });
    }

    fn camera_section(&mut self, ui: &mut Ui, m: &mut Model, actions: &mut Actions) {
        egui::CollapsingHeader::new("Camera")
            .default_open(false)
            .show(ui, |ui| {
                let c: &mut CameraController = &mut m.camera;
                ui.horizontal_wrapped(|ui| {
                    ui.label("mode (O)");
                    for mode in [Mode::Fly, Mode::Orbit] {
                        if ui.radio(c.mode == mode, mode.name()).clicked() {
                            c.set_mode(mode);
                        }
                    }
                });
                if m.scene.cameras.len() > 1 || m.scene.cameras[0].name != "auto" {
                    egui::ComboBox::from_label("file camera")
                        .selected_text(c.camera.name.clone())
                        .show_ui(ui, |ui| {
                            for cam in &m.scene.cameras {
                                if ui.selectable_label(false, &cam.name).clicked() {
                                    c.set_initial(cam.clone());
                                    actions.changes.camera = true;
                                }
                            }
                        });
                }
                let mut fov = c.camera.yfov.to_degrees();
                if ui
                    .add(egui::Slider::new(&mut fov, 5.0..=150.0).text("fov °"))
                    .changed()
                {
                    c.camera.yfov = fov.to_radians();
                    actions.changes.camera = true;
                }
                let v = &mut m.view;
                ui.horizontal_wrapped(|ui| {
                    ui.label("lens");
                    let size = v.diagonal() as f32;
                    let a = ui
                        .add(
                            egui::DragValue::new(&mut v.aperture)
                                .speed(0.0005 * size)
                                .range(0.0..=size)
                                .prefix("aperture "),
                        )
                        .on_hover_text("thin-lens radius; 0 keeps everything sharp");
                    let f = ui
                        .add_enabled(
                            v.aperture > 0.0,
                            egui::DragValue::new(&mut v.focus_distance)
                                .speed(0.002 * size)
                                .range(1e-4..=1e6)
                                .prefix("focus "),
                        )
                        .on_hover_text("distance in focus; a click on the image focuses there");
                    if a.changed() || f.changed() {
                        actions.changes.settings = true;
                    }
                });
                let c: &mut CameraController = &mut m.camera;
                ui.horizontal_wrapped(|ui| {
                    ui.label("fly speed");
                    let speed = c.speed;
                    ui.add(
                        egui::DragValue::new(&mut c.speed)
                            .speed(speed * 0.01)
                            .range(1e-6..=1e9)
                            .suffix(" /s"),
                    );
                });
                if c.mode == Mode::Orbit {
                    let p = c.pivot;
                    ui.label(format!("pivot {:.3} {:.3} {:.3}", p.x, p.y, p.z));
                }
                if ui.button("Reset view (R)").clicked() {
                    c.reset();
                    actions.changes.camera = true;
                }
            });
    }

    fn lights_section(&mut self, ui: &mut Ui, m: &mut Model, actions: &mut Actions) {
        if super::light_editor::lights_section(ui, &mut self.preset, &mut m.view, &m.camera.camera)
        {
            actions.changes.lights = true;
        }
    }

    fn scene_section(&mut self, ui: &mut Ui, m: &mut Model, info: &Info, actions: &mut Actions) {
        egui::CollapsingHeader::new("Scene")
            .default_open(false)
            .show(ui, |ui| {
                ui.add(egui::Label::new(m.scene.source.as_str()).truncate());
                ui.horizontal(|ui| {
                    let field = ui.add(
                        egui::TextEdit::singleline(&mut self.path_text)
                            .hint_text("path/to/scene.glb")
                            .desired_width(180.0),
                    );
                    let entered =
                        field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
                    if ui.button("Open").clicked() || entered {
                        let path = self.path_text.trim();
                        if path.is_empty() {
                            self.file_error = Some("type a .gltf or .glb path first".into());
                        } else {
                            actions.open = Some(PathBuf::from(path));
                        }
                    }
                });
                ui.label(RichText::new("or drop a .gltf / .glb file on the window").weak());
                if let Some(p) = info.loading {
                    ui.horizontal(|ui| {
                        ui.spinner();
                        ui.label(format!("loading {}", p.display()));
                    });
                }
                if let Some(e) = &self.file_error {
                    ui.label(RichText::new(e).color(Color32::LIGHT_RED));
                }
                if let Some(s) = info.scene_stats {
                    ui.label(format!(
                        "{} triangles · load {:.1} ms · BVH rebuild {:.2} ms · kernels {:.0} ms",
                        s.triangles, info.load_ms, s.bvh_build_ms, s.kernel_build_ms
                    ));
                }
                variant_picker(ui, m, actions);
                ui.label("objects (click one in the image to pick it):");
                egui::ScrollArea::vertical()
                    .id_salt("objects")
                    .max_height(140.0)
                    .min_scrolled_height(140.0)
                    .show(ui, |ui| {
                        for (i, o) in m.scene.objects.iter_mut().enumerate() {
                            ui.horizontal(|ui| {
                                if ui.checkbox(&mut o.visible, "").changed() {
                                    actions.changes.scene = true;
                                }
                                let name = if o.name.is_empty() {
                                    format!("object {i}")
                                } else {
                                    o.name.clone()
                                };
                                if ui.selectable_label(m.selected == Some(i), name).clicked() {
                                    m.selected = if m.selected == Some(i) { None } else { Some(i) };
                                }
                            });
                        }
                    });
                self.transform_editor(ui, m, actions);
            });
    }

    fn transform_editor(&mut self, ui: &mut Ui, m: &mut Model, actions: &mut Actions) {
        let Some(i) = m.selected.filter(|&i| i < m.scene.objects.len()) else {
            self.edit = None;
            return;
        };
        if self.edit.as_ref().is_none_or(|e| e.object != i) {
            self.edit = Some(TransformEdit::of(i, &m.scene.objects[i].world_from_object));
        }
        let Some(edit) = self.edit.as_mut() else {
            return;
        };
        let size = m.view.diagonal();
        ui.separator();
        ui.label(RichText::new(format!("selected: {}", m.scene.objects[i].name)).strong());
        let mut changed = false;
        egui::Grid::new("transform").num_columns(4).show(ui, |ui| {
            let mut row = |ui: &mut Ui, label: &str, v: &mut DVec3, speed: f64| {
                ui.label(label);
                for c in [&mut v.x, &mut v.y, &mut v.z] {
                    changed |= ui.add(egui::DragValue::new(c).speed(speed)).changed();
                }
                ui.end_row();
            };
            row(ui, "move", &mut edit.translation, 0.002 * size);
            row(ui, "rotate °", &mut edit.rotation, 0.5);
            row(ui, "scale", &mut edit.scale, 0.005);
        });
        ui.horizontal(|ui| {
            let mut uniform = (edit.scale.x + edit.scale.y + edit.scale.z) / 3.0;
            ui.label("uniform scale");
            if ui
                .add(egui::DragValue::new(&mut uniform).speed(0.005))
                .changed()
                && uniform.abs() > 1e-9
            {
                let mean = (edit.scale.x + edit.scale.y + edit.scale.z) / 3.0;
                edit.scale *= if mean.abs() > 1e-12 {
                    uniform / mean
                } else {
                    1.0
                };
                changed = true;
            }
        });
        // A zero scale would flatten the object into nothing; keep it pickable.
        edit.scale = edit.scale.map(|s| if s.abs() < 1e-6 { 1e-6 } else { s });
        if changed {
            m.scene.objects[i].world_from_object = edit.matrix();
            actions.changes.scene = true;
        }
        if ui.button("reset transform").clicked()
            && let Some(t) = m.loaded_transforms.get(i)
        {
            m.scene.objects[i].world_from_object = *t;
            self.edit = Some(TransformEdit::of(i, t));
            actions.changes.scene = true;
        }
    }
}

/// The `KHR_materials_variants` picker (only for scenes with variants): choosing one gives the
/// triangles its materials and re-uploads the scene.
fn variant_picker(ui: &mut Ui, m: &mut Model, actions: &mut Actions) {
    if m.scene.variants.is_empty() {
        return;
    }
    let name = |v: Option<usize>| v.map_or("default".to_string(), |v| m.scene.variants[v].clone());
    let mut chosen = m.scene.variant;
    egui::ComboBox::from_label("material variant")
        .selected_text(name(chosen))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut chosen, None, "default");
            for (i, v) in m.scene.variants.iter().enumerate() {
                ui.selectable_value(&mut chosen, Some(i), v);
            }
        });
    if chosen != m.scene.variant {
        m.scene.select_variant(chosen);
        actions.changes.scene = true;
    }
}

/// A byte count for the overlay: MB, or kB below a tenth of a MB (a small scene's buffers
/// would read "0.0 MB").
fn memory_size(bytes: usize) -> String {
    if bytes < 100_000 {
        format!("{:.1} kB", bytes as f64 / 1e3)
    } else {
        format!("{:.1} MB", bytes as f64 / 1e6)
    }
}

fn stats_section(ui: &mut Ui, m: &Model, info: &Info) {
    egui::CollapsingHeader::new("Statistics")
        .default_open(true)
        .show(ui, |ui| {
            let p = info.progress;
            ui.label(format!("device: {}", info.device));
            if let Some(s) = info.scene_stats {
                ui.label(format!(
                    "device memory {} · {} BVH",
                    memory_size(s.device_bytes),
                    s.bvh
                ));
            }
            let moving = if info.film.full_quality {
                String::new()
            } else {
                format!(
                    " (preview: 1/{}, {} bounces)",
                    info.film.divisor, info.film.bounces
                )
            };
            ui.label(format!(
                "film {}×{}{moving}",
                info.film.width, info.film.height
            ));
            let target = m
                .view
                .spp_target
                .map_or_else(|| "endless".to_string(), |t| format!("target {t}"));
            ui.label(format!("{} spp ({target}) in {:.2} s", p.spp, p.seconds));
            if let Some(t) = m.view.noise_threshold {
                ui.label(adaptive_line(t, p.converged_share, info.film));
            }
            ui.label(format!(
                "{:.3} M samples/s · {:.3} M rays/s",
                p.samples_per_second * 1e-6,
                p.rays_per_second * 1e-6
            ));
            if let Some(plan) = p.plan {
                let band = if plan.bands > 1 {
                    format!(", band {}/{}", p.band + 1, plan.bands)
                } else {
                    String::new()
                };
                ui.label(format!(
                    "last batch: {} spp{band} in {:.1} ms (budget {:.0} ms)",
                    plan.spp,
                    p.batch_ms,
                    super::frame_loop::FRAME_BUDGET_MS
                ));
            }
            if !m.scene.animation.clips.is_empty()
                && let Some(s) = info.scene_stats
            {
                // A pose's host time, then the device update it caused (the last BVH build or
                // instance update, and the upload with the bytes it wrote).
                ui.label(format!(
                    "scene update: pose {:.2} ms · BVH {:.1} ms · upload {:.1} ms ({})",
                    m.timeline.pose_ms,
                    s.bvh_build_ms,
                    s.upload_ms,
                    memory_size(s.written_bytes)
                ));
            }
            if p.stats.nonfinite_samples > 0 {
                ui.label(format!(
                    "{} non-finite samples dropped",
                    p.stats.nonfinite_samples
                ));
            }
            if !p.stats.stage_ms.is_empty() {
                egui::Grid::new("stages").striped(true).show(ui, |ui| {
                    ui.label("stage");
                    ui.label("kernel ms");
                    ui.label("ms / spp");
                    ui.end_row();
                    let spp = p.spp.max(1) as f64;
                    // Stages that did not run (the other kernel shape's) are left out.
                    for (stage, ms) in p.stats.stage_ms.iter().filter(|(_, ms)| *ms > 0.0) {
                        ui.label(*stage);
                        ui.label(format!("{ms:.1}"));
                        ui.label(format!("{:.2}", ms / spp));
                        ui.end_row();
                    }
                });
            }
            if let Some(path) = info.last_screenshot {
                ui.label(format!("saved {}", path.display()));
            }
        });
}

/// Image updates per second and the last input's latency, for the top of the panel.
fn live_figures(info: &Info) -> String {
    let latency = info
        .latency_ms
        .map_or_else(|| "–".to_string(), |ms| format!("{ms:.0} ms"));
    let denoise = info
        .denoise_ms
        .map_or_else(String::new, |ms| format!(" · denoised in {ms:.0} ms"));
    format!(
        "{:.1} images/s · input answered in {latency}{denoise}",
        info.images_per_second
    )
}

fn controls_section(ui: &mut Ui) {
    egui::CollapsingHeader::new("Keys and mouse (F1)")
        .default_open(false)
        .show(ui, key_list);
}

/// The keys and what they do, each row wrapping within the width it is given.
fn key_list(ui: &mut Ui) {
    for (key, what) in super::CONTROLS {
        ui.horizontal_wrapped(|ui| {
            ui.label(RichText::new(*key).strong());
            ui.label(*what);
        });
    }
}

/// The help window (F1): every key, readable in full, over the image.
pub fn help_window(ctx: &egui::Context, open: &mut bool) {
    egui::Window::new("Keys and mouse")
        .open(open)
        .collapsible(false)
        .resizable(false)
        .default_width(420.0)
        .anchor(egui::Align2::RIGHT_TOP, egui::vec2(-10.0, 10.0))
        .show(ctx, key_list);
}

/// A message in the middle of the image for [`FLASH_SECONDS`] (e.g. why a key did nothing).
pub fn flash(ctx: &egui::Context, flash: &Option<(String, Instant)>, panel_width: f32) {
    if let Some((text, at)) = flash
        && at.elapsed().as_secs_f64() < FLASH_SECONDS
    {
        notice(ctx, text, panel_width);
    }
}

/// How long a flashed message stays.
pub const FLASH_SECONDS: f64 = 3.0;

/// Adaptive sampling's figures: the converged share at the last check, and what the heat map
/// read (the mean samples per pixel, or the mean error).
fn adaptive_line(threshold: f32, converged: Option<f64>, film: &Film) -> String {
    let mut line = match converged {
        Some(c) => format!("adaptive {threshold}: {:.0} % converged", c * 100.0),
        None => format!("adaptive {threshold}: no check yet"),
    };
    if !film.samples.is_empty() {
        let mean =
            film.samples.iter().map(|&s| f64::from(s)).sum::<f64>() / film.samples.len() as f64;
        line += &format!(" · mean {mean:.1} spp");
    }
    if !film.errors.is_empty() {
        line += &format!(" · mean error {:.4}", heat::mean_error(&film.errors));
    }
    line
}

/// The noise threshold the adaptive box (and M, turning adaptive sampling on) starts with.
pub const DEFAULT_NOISE_THRESHOLD: f32 = 0.01;

/// What the display shows with adaptive sampling: the image or one of its heat maps (M).
fn heat_map_choice(ui: &mut Ui, map: &mut HeatMap) {
    ui.horizontal_wrapped(|ui| {
        ui.label("show (M):");
        for choice in [HeatMap::Off, HeatMap::Samples, HeatMap::Error] {
            ui.radio_value(map, choice, choice.name());
        }
    });
}

/// The heat map's key: the palette as a bar with what its ends and middle mean.
fn heat_legend(ui: &mut Ui, map: HeatMap, threshold: f32, film: &Film) {
    let (lo, mid, hi) = match map {
        HeatMap::Off => return,
        HeatMap::Samples if film.samples.is_empty() => return,
        HeatMap::Error if film.errors.is_empty() => return,
        HeatMap::Samples => {
            let (lo, hi) = heat::samples_range(&film.samples);
            (
                format!("{lo} spp"),
                format!("{} spp", (lo + hi) / 2),
                format!("{hi} spp"),
            )
        }
        HeatMap::Error => (
            format!("≤ {}", threshold / heat::ERROR_SPAN),
            format!("{threshold} (threshold)"),
            format!("≥ {} or none yet", threshold * heat::ERROR_SPAN),
        ),
    };
    let width = ui.available_width().min(260.0);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(width, 12.0), egui::Sense::hover());
    let steps = 32;
    for i in 0..steps {
        let [r, g, b] = heat::palette((i as f32 + 0.5) / steps as f32);
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        ui.painter().rect_filled(
            egui::Rect::from_x_y_ranges(x0..=x1, rect.y_range()),
            0.0,
            Color32::from_rgb(r, g, b),
        );
    }
    ui.label(format!("blue {lo} · green {mid} · red {hi}"));
    if map == HeatMap::Error {
        ui.label(
            "the relative error adaptive sampling judges pixels by: a pixel stops when it and \
             its 8 neighbours are under the threshold",
        );
    }
}

/// The exposure lock: automatic exposure keeps its value across views.
fn exposure_lock(ui: &mut Ui, v: &mut super::state::ViewState) {
    if let Some(auto) = v.auto_exposure.as_mut() {
        ui.checkbox(&mut auto.locked, "lock exposure")
            .on_hover_text("keep the automatic exposure when the view changes");
    }
}

impl Gui {
    /// Saved views (V saves one): recall by a click, save under a name.
    fn views_section(&mut self, ui: &mut Ui, actions: &mut Actions) {
        egui::CollapsingHeader::new("Views")
            .default_open(false)
            .show(ui, |ui| {
                if self.views.is_empty() {
                    ui.label(RichText::new("no saved views (V saves the camera)").weak());
                }
                ui.horizontal_wrapped(|ui| {
                    for v in &self.views {
                        if ui.button(&v.name).clicked() {
                            actions.recall_view = Some(v.camera());
                        }
                    }
                });
                ui.horizontal(|ui| {
                    ui.add(
                        egui::TextEdit::singleline(&mut self.view_name)
                            .hint_text("name")
                            .desired_width(120.0),
                    );
                    if ui.button("Save view (V)").clicked() {
                        let name = self.view_name.trim();
                        actions.save_view = Some(if name.is_empty() {
                            next_view_name(&self.views)
                        } else {
                            name.to_string()
                        });
                    }
                });
            });
    }
}

/// "view N" for the first N not taken.
pub fn next_view_name(views: &[SavedView]) -> String {
    (1..)
        .map(|n| format!("view {n}"))
        .find(|name| views.iter().all(|v| &v.name != name))
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::memory_size;

    #[test]
    fn memory_sizes_read_in_kilobytes_below_a_tenth_of_a_megabyte() {
        assert_eq!(memory_size(12_345), "12.3 kB");
        assert_eq!(memory_size(99_999), "100.0 kB");
        assert_eq!(memory_size(100_000), "0.1 MB");
        assert_eq!(memory_size(218_000_000), "218.0 MB");
    }
}
