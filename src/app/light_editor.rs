//! The light editor of the overlay: the hard-shadow switch, the light radius, presets, and the
//! position, direction, cone, color, intensity and radius of each light of the rig.

use super::state::{NewLight, RigLight, ViewState};
use crate::scene::{Camera, LightKind, LightPreset};
use egui::Ui;
use glam::DVec3;

/// The "Shadows & lights" section: hard shadows, the light radius, presets, and one editor per
/// light of the rig; returns whether the rendered lights changed.
pub fn lights_section(
    ui: &mut Ui,
    preset: &mut LightPreset,
    v: &mut ViewState,
    camera: &Camera,
) -> bool {
    let mut changed = false;
    egui::CollapsingHeader::new("Shadows & lights")
        .default_open(false)
        .show(ui, |ui| {
            if ui
                .checkbox(&mut v.shadows.hard, "hard shadows (H)")
                .changed()
            {
                changed = true;
            }
            let max = v.max_light_radius();
            if ui
                .add_enabled(
                    !v.shadows.hard,
                    egui::Slider::new(&mut v.shadows.light_radius, 0.0..=max)
                        .logarithmic(true)
                        .text("light radius"),
                )
                .changed()
            {
                changed = true;
            }
            // The presets as a list in place (a drop-down would cover the controls below).
            ui.horizontal_wrapped(|ui| {
                ui.label("preset");
                for p in LightPreset::ALL {
                    ui.selectable_value(preset, p, p.name());
                }
            });
            ui.horizontal(|ui| {
                if ui.button("replace the lights").clicked() {
                    v.apply_preset(*preset, true);
                    changed = true;
                }
                if ui.button("add").clicked() {
                    v.apply_preset(*preset, false);
                    changed = true;
                }
            });
            ui.horizontal_wrapped(|ui| {
                ui.label("add");
                for kind in NewLight::ALL {
                    if ui.button(kind.name()).clicked() {
                        v.add_light(kind, camera);
                        changed = true;
                    }
                }
            });
            let mut remove = None;
            let size = v.diagonal();
            for i in 0..v.rig.len() {
                let radius = v.effective_radius(&v.rig[i]);
                let hard = v.shadows.hard;
                let l = &mut v.rig[i];
                let id = ui.make_persistent_id(("light", i));
                egui::collapsing_header::CollapsingState::load_with_default_open(
                    ui.ctx(),
                    id,
                    false,
                )
                .show_header(ui, |ui| {
                    if ui.checkbox(&mut l.enabled, "").changed() {
                        changed = true;
                    }
                    ui.label(format!("{} ({})", l.light.name, kind_name(l.light.kind)));
                    if ui.small_button("✖").on_hover_text("remove").clicked() {
                        remove = Some(i);
                    }
                })
                .body(|ui| {
                    if light_editor(ui, l, radius, hard, size) {
                        changed = true;
                    }
                });
            }
            if let Some(i) = remove {
                v.rig.remove(i);
                changed = true;
            }
        });
    changed
}

fn kind_name(kind: LightKind) -> &'static str {
    match kind {
        LightKind::Point => "point",
        LightKind::Spot { .. } => "spot",
        LightKind::Directional => "directional",
    }
}

/// The editor of one light; returns whether it changed.
fn light_editor(ui: &mut Ui, l: &mut RigLight, radius: f32, hard: bool, size: f64) -> bool {
    let mut changed = false;
    let light = &mut l.light;
    if light.kind != LightKind::Directional {
        ui.horizontal_wrapped(|ui| {
            ui.label("position");
            for c in [
                &mut light.position.x,
                &mut light.position.y,
                &mut light.position.z,
            ] {
                changed |= ui
                    .add(egui::DragValue::new(c).speed(0.002 * size))
                    .changed();
            }
        });
    }
    if light.kind != LightKind::Point {
        // Direction as azimuth and elevation (the direction the light travels).
        let d = light.direction.normalize_or(DVec3::NEG_Y);
        let mut elevation = d.y.clamp(-1.0, 1.0).asin().to_degrees();
        let mut azimuth = d.x.atan2(d.z).to_degrees();
        ui.horizontal_wrapped(|ui| {
            ui.label("direction");
            let a = ui.add(
                egui::DragValue::new(&mut azimuth)
                    .speed(0.5)
                    .range(-180.0..=180.0)
                    .prefix("az ")
                    .suffix("°"),
            );
            let e = ui.add(
                egui::DragValue::new(&mut elevation)
                    .speed(0.5)
                    .range(-90.0..=90.0)
                    .prefix("el ")
                    .suffix("°"),
            );
            if a.changed() || e.changed() {
                let (az, el) = (azimuth.to_radians(), elevation.to_radians());
                light.direction = DVec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
                changed = true;
            }
        });
    }
    if let LightKind::Spot { inner, outer } = &mut light.kind {
        let mut deg = [inner.to_degrees(), outer.to_degrees()];
        ui.horizontal_wrapped(|ui| {
            ui.label("cone");
            let a = ui.add(
                egui::DragValue::new(&mut deg[0])
                    .range(0.0..=90.0)
                    .prefix("inner ")
                    .suffix("°"),
            );
            let b = ui.add(
                egui::DragValue::new(&mut deg[1])
                    .range(0.0..=90.0)
                    .prefix("outer ")
                    .suffix("°"),
            );
            if a.changed() || b.changed() {
                *outer = deg[1].to_radians().max(1e-3);
                *inner = deg[0].to_radians().min(*outer);
                changed = true;
            }
        });
    }
    ui.horizontal_wrapped(|ui| {
        ui.label("color");
        changed |= ui.color_edit_button_rgb(&mut light.color).changed();
        let speed = (light.intensity.abs() * 0.01).max(1e-3);
        changed |= ui
            .add(
                egui::DragValue::new(&mut light.intensity)
                    .speed(speed)
                    .range(0.0..=f32::MAX)
                    .prefix("intensity "),
            )
            .changed();
    });
    ui.horizontal_wrapped(|ui| {
        let unit = if light.kind == LightKind::Directional {
            " rad"
        } else {
            ""
        };
        let mut r = radius;
        let edited = ui
            .add_enabled(
                !hard,
                egui::DragValue::new(&mut r)
                    .speed(0.001 * size)
                    .range(0.0..=f32::MAX)
                    .prefix("radius ")
                    .suffix(unit),
            )
            .changed();
        if edited {
            light.light_radius = r;
            l.follows_light_radius = false;
            changed = true;
        }
        if !l.follows_light_radius && ui.small_button("follow light radius").clicked() {
            l.follows_light_radius = true;
            changed = true;
        }
    });
    changed
}
