//! The glue between egui and the window: egui's context, its winit input state and its wgpu
//! renderer, drawing over the pixels frame inside `Pixels::render_with` (after the pixels crate's
//! `minimal-egui` example, adapted to egui 0.35).

use egui::{ClippedPrimitive, Context, TexturesDelta, ViewportId};
use egui_wgpu::{Renderer, RendererOptions, ScreenDescriptor};
use pixels::{PixelsContext, wgpu};
use std::time::Duration;
use winit::window::Window;

/// egui's state for one window.
pub struct Framework {
    ctx: Context,
    state: egui_winit::State,
    screen: ScreenDescriptor,
    renderer: Renderer,
    paint_jobs: Vec<ClippedPrimitive>,
    textures: TexturesDelta,
}

impl Framework {
    /// egui for `window`, drawing with the device and format of `pixels`.
    pub fn new(window: &Window, pixels: &pixels::Pixels) -> Self {
        let size = window.inner_size();
        let scale = window.scale_factor() as f32;
        let max_texture = pixels.device().limits().max_texture_dimension_2d as usize;
        let ctx = Context::default();
        let state = egui_winit::State::new(
            ctx.clone(),
            ViewportId::ROOT,
            window,
            Some(scale),
            None,
            Some(max_texture),
        );
        let renderer = Renderer::new(
            pixels.device(),
            pixels.render_texture_format(),
            RendererOptions::default(),
        );
        Self {
            ctx,
            state,
            screen: ScreenDescriptor {
                size_in_pixels: [size.width.max(1), size.height.max(1)],
                pixels_per_point: scale,
            },
            renderer,
            paint_jobs: Vec::new(),
            textures: TexturesDelta::default(),
        }
    }

    /// The egui context (to ask whether egui wants the pointer or the keyboard).
    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Passes a window event to egui; returns whether egui consumed it.
    pub fn handle_event(&mut self, window: &Window, event: &winit::event::WindowEvent) -> bool {
        self.state.on_window_event(window, event).consumed
    }

    /// Physical pixels per point.
    pub fn pixels_per_point(&self) -> f32 {
        self.screen.pixels_per_point
    }

    /// Follows a window resize.
    pub fn resize(&mut self, width: u32, height: u32) {
        if width > 0 && height > 0 {
            self.screen.size_in_pixels = [width, height];
        }
    }

    /// Follows a change of the window's scale factor.
    pub fn set_scale_factor(&mut self, scale: f64) {
        self.screen.pixels_per_point = scale as f32;
    }

    /// Runs the overlay's ui code and tessellates it; returns how soon egui wants to be
    /// redrawn (for animations and tooltips; `Duration::MAX` when it does not).
    pub fn prepare(&mut self, window: &Window, ui: impl FnMut(&mut egui::Ui)) -> Duration {
        let input = self.state.take_egui_input(window);
        let output = self.ctx.run_ui(input, ui);
        self.textures.append(output.textures_delta);
        self.state
            .handle_platform_output(window, output.platform_output);
        self.paint_jobs = self
            .ctx
            .tessellate(output.shapes, self.screen.pixels_per_point);
        output
            .viewport_output
            .get(&ViewportId::ROOT)
            .map_or(Duration::MAX, |v| v.repaint_delay)
    }

    /// Draws the prepared overlay over `target`.
    pub fn render(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        context: &PixelsContext,
    ) {
        for (id, delta) in &self.textures.set {
            self.renderer
                .update_texture(&context.device, &context.queue, *id, delta);
        }
        let commands = self.renderer.update_buffers(
            &context.device,
            &context.queue,
            encoder,
            &self.paint_jobs,
            &self.screen,
        );
        if !commands.is_empty() {
            context.queue.submit(commands);
        }
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: target,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.renderer
                .render(&mut pass, &self.paint_jobs, &self.screen);
        }
        for id in std::mem::take(&mut self.textures).free {
            self.renderer.free_texture(&id);
        }
    }
}
