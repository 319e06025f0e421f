//! What the viewer's window shows: the film (or its denoised image, or a heat map) exposed and
//! tone-mapped into the display image, composed beside the overlay's panel and presented.

use super::{ACTIVE_INTERVAL, App, exposure, frame_loop, heat, layout, stats};
use crate::render::background::{Background, unpremultiply};
use crate::render::tonemap::{ToneMapper, to_rgba8};
use anyhow::{Result, anyhow};
use std::time::Instant;

/// Exposure, tone mapper, samples, size, background, heat map (with the error map's threshold,
/// as bits) and denoised of the displayed frame.
pub(super) type DisplayKey = (
    f32,
    ToneMapper,
    u32,
    usize,
    u64,
    Option<(heat::HeatMap, u32)>,
    bool,
);

/// What a denoised image belongs to: the film's view, width and height.
pub(super) type FilmKey = (u64, u32, u32);

impl App {
    /// Draws the frame and the overlay into the window.
    pub(super) fn present(&mut self) -> Result<()> {
        let Some(gfx) = self.gfx.as_mut() else {
            return Ok(());
        };
        let framework = &mut gfx.framework;
        gfx.pixels
            .render_with(|encoder, target, context| {
                context.scaling_renderer.render(encoder, target);
                framework.render(encoder, target, context);
                Ok(())
            })
            .map_err(|e| anyhow!("cannot draw the window: {e}"))
    }

    /// A new image is on screen: counts it, and measures the latency of the input it answers.
    pub(super) fn image_presented(&mut self) {
        let film = &mut self.frame_loop.film;
        let answers = film.answers.take();
        let line = stats::ImageLine {
            t: 0.0,
            spp: film.spp,
            width: film.width,
            height: film.height,
            divisor: film.divisor,
            bounces: film.bounces,
            exposure: self.model.view.exposure,
            latency_ms: None,
            heat_map: self
                .display_key
                .and_then(|k| k.5)
                .map(|(map, _)| map.name()),
            converged_share: self.frame_loop.progress.converged_share,
        };
        self.stats.image_shown(Instant::now(), answers, line);
    }

    /// Where the image goes in the window: right of the overlay's panel (all of it without).
    pub(super) fn image_area(&self) -> layout::ImageArea {
        let panel = match (&self.gfx, self.overlay) {
            (Some(gfx), true) => {
                let ppp = gfx.framework.pixels_per_point();
                (layout::panel_points(self.size.0 as f32 / ppp) * ppp).round() as u32
            }
            _ => 0,
        };
        layout::ImageArea::new(self.size, panel)
    }

    /// The denoised image of the film on screen, when it is shown.
    pub(super) fn shown_denoised(&self) -> Option<&Vec<[f32; 3]>> {
        let film = &self.frame_loop.film;
        let key = (film.view, film.width, film.height);
        self.denoised
            .as_ref()
            .filter(|(k, _)| self.model.view.denoise && *k == key)
            .map(|(_, pixels)| pixels)
    }

    /// Takes the new film's denoised image, which the frame loop made on the device when it
    /// was worth it; between those, the last denoised image of the view stays on screen. A
    /// denoiser that failed turns the toggle off and says why.
    pub(super) fn update_denoised(&mut self) {
        if let Some(e) = self.frame_loop.denoise_error.take() {
            self.gui.file_error = Some(format!("denoiser: {e}"));
            self.model.view.denoise = false;
        }
        if !self.model.view.denoise {
            self.denoised = None;
            self.denoise_ms = None;
            return;
        }
        let film = &mut self.frame_loop.film;
        let key = (film.view, film.width, film.height);
        if self.denoised.as_ref().is_some_and(|(k, _)| *k != key) {
            self.denoised = None;
        }
        if let Some((pixels, ms)) = film.denoised.take() {
            self.denoised = Some((key, pixels));
            self.denoise_ms = Some(ms);
        }
    }

    /// Tone-maps the film when the film, the exposure, the tone mapper or the background
    /// changed, and composes the window's frame (the image beside the panel) when that or the
    /// layout changed.
    pub(super) fn update_display(&mut self, new_image: bool, dt: f64) {
        self.update_denoised();
        let area = self.image_area();
        let Some(gfx) = self.gfx.as_mut() else {
            return;
        };
        let film = &self.frame_loop.film;
        if film.pixels.is_empty() {
            return;
        }
        let full_bounces = film.bounces == self.model.view.bounces;
        if let Some(auto) = self.model.view.auto_exposure.as_mut() {
            if new_image && full_bounces && auto.wants(film.view) {
                // The subject without the background (the straight color when it is cut out).
                let coverage = (!film.coverage.is_empty()).then_some(film.coverage.as_slice());
                let width = film.width as usize;
                let metering = match coverage.filter(|_| film.cutout) {
                    Some(c) => exposure::meter_film(
                        &unpremultiply(&film.pixels, c),
                        coverage,
                        width,
                        film.spp,
                    ),
                    None => exposure::meter_film(&film.pixels, coverage, width, film.spp),
                };
                auto.decide(film.view, metering.as_ref());
            }
            if let Some(stops) = auto.advance(dt) {
                self.model.view.exposure = stops;
            }
            if auto.settling() {
                self.wake = Some(Instant::now() + ACTIVE_INTERVAL);
            }
        }
        let v = &self.model.view;
        // A color background is painted into the display: its value is part of the key.
        let background = match v.background {
            Background::Env => 0,
            Background::Transparent => 1,
            Background::Color(c) => c.iter().fold(2u64, |h, x| h * 31 + x.to_bits() as u64),
        };
        // A heat map replaces the image once the film carries its data; the error map's scale
        // is the threshold.
        let heat = match (v.heat_map, v.noise_threshold) {
            (heat::HeatMap::Samples, Some(_)) if film.samples.len() == film.pixels.len() => {
                Some((heat::HeatMap::Samples, 0.0))
            }
            (heat::HeatMap::Error, Some(t)) if film.errors.len() == film.pixels.len() => {
                Some((heat::HeatMap::Error, t))
            }
            _ => None,
        };
        let denoised = self
            .denoised
            .as_ref()
            .filter(|(k, _)| v.denoise && *k == (film.view, film.width, film.height))
            .map(|(_, pixels)| pixels);
        let key = (
            v.exposure,
            v.tone_mapper,
            film.spp,
            film.pixels.len(),
            background,
            heat.map(|(h, t)| (h, t.to_bits())),
            denoised.is_some(),
        );
        if self.display_key != Some(key) || new_image {
            self.display_key = Some(key);
            self.display = match (heat, denoised) {
                (Some((heat::HeatMap::Error, threshold)), _) => {
                    heat::error_rgba(&film.errors, threshold)
                }
                (Some(_), _) => heat::samples_rgba(&film.samples),
                (None, Some(pixels)) => {
                    let shown = frame_loop::Film {
                        pixels: pixels.clone(),
                        ..film.clone()
                    };
                    display_rgba(&shown, v.exposure, v.tone_mapper, v.background)
                }
                (None, None) => display_rgba(film, v.exposure, v.tone_mapper, v.background),
            };
            self.display_generation += 1;
        }
        let frame_key = (self.display_generation, area, self.size);
        if self.frame_key == Some(frame_key) {
            return;
        }
        let texture = gfx.pixels.texture();
        if (texture.width(), texture.height()) != self.size
            && let Err(e) = gfx.pixels.resize_buffer(self.size.0, self.size.1)
        {
            log::warn!(
                "cannot resize the frame to {}×{}: {e}",
                self.size.0,
                self.size.1
            );
            return;
        }
        layout::compose(
            gfx.pixels.frame_mut(),
            self.size,
            area,
            &self.display,
            (film.width, film.height),
        );
        self.frame_key = Some(frame_key);
    }
}

/// The film as shown: exposed and tone-mapped RGBA8, with the background applied when it is
/// cut out (alpha for transparent, the color painted behind).
pub(super) fn display_rgba(
    film: &frame_loop::Film,
    exposure: f32,
    mapper: ToneMapper,
    background: Background,
) -> Vec<u8> {
    if !film.cutout {
        return to_rgba8(&film.pixels, exposure, mapper);
    }
    let mut rgba = to_rgba8(
        &unpremultiply(&film.pixels, &film.coverage),
        exposure,
        mapper,
    );
    crate::render::background::apply(&mut rgba, &film.coverage, background);
    rgba
}
