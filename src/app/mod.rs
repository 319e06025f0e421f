//! The interactive viewer: a winit window showing the progressive render through `pixels`, with
//! an egui overlay, fly/orbit camera controls, picking, light and object editing, and
//! screenshots. See `docs/viewer.md` for the frame loop.

mod budget;
mod camera;
mod display;
mod exposure;
mod frame_loop;
mod framework;
mod gui;
mod heat;
mod input;
mod layout;
mod light_editor;
mod loading;
mod pick;
mod screenshot;
mod state;
mod stats;
mod timeline;

use crate::cl::DeviceChoice;
use crate::render::background::Background;
use crate::render::exposure::ExposureMode;
use crate::render::tonemap::ToneMapper;
use crate::render::{RenderSettings, Renderer};
use crate::scene::{Camera, EnvMap, Light, Scene, Shadows};
use anyhow::{Context, Result, anyhow, bail};
use camera::CameraController;
use display::{DisplayKey, FilmKey};
use frame_loop::{Changes, FrameLoop, World};
use framework::Framework;
use gui::{Gui, Info, Model};
use input::Input;
use loading::Loader;
use pixels::{Pixels, PixelsBuilder, ScalingMode, SurfaceTexture};
use state::ViewState;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// The window size when `--width`/`--height` are not given.
pub const DEFAULT_SIZE: (u32, u32) = (960, 600);
/// How long after the last camera change the view still counts as moving.
const MOVING_FOR: Duration = Duration::from_millis(250);
/// Display frame interval while something happens, and while only waiting for the device.
const ACTIVE_INTERVAL: Duration = Duration::from_millis(16);
const IDLE_INTERVAL: Duration = Duration::from_millis(33);
/// How often a batch past its expected end is polled.
const POLL_INTERVAL: Duration = Duration::from_millis(2);

/// The controls, for the overlay and the docs.
pub const CONTROLS: &[(&str, &str)] = &[
    ("W A S D", "move forward, left, back, right"),
    ("Q / E", "move down / up"),
    ("Shift", "move 4× faster"),
    ("right drag", "look around (fly) / orbit the pivot (orbit)"),
    ("middle drag, Shift + right drag", "pan"),
    ("wheel", "fly speed (fly) / zoom to the pivot (orbit)"),
    ("+ / −", "fly speed"),
    ("O", "switch fly / orbit mode"),
    (
        "left click",
        "pick an object (orbit: also the pivot; with a lens: focus)",
    ),
    ("R", "reset the view"),
    (
        "C",
        "collision on / off (on at the start inside interiors: moves stop at walls)",
    ),
    (
        "V",
        "save the view (beside the scene, for --view NAME; recall in Views)",
    ),
    ("H", "hard / soft shadows"),
    ("F12", "screenshot (PNG + EXR in screenshots/)"),
    ("Tab", "hide / show the overlay"),
    ("F1", "this list in a window"),
    ("N", "denoise the image on / off"),
    (
        "M",
        "heat maps: samples per pixel, error, image (turns adaptive sampling on)",
    ),
    ("Space", "play / pause the animation"),
    ("Ctrl + Q", "quit (like closing the window)"),
    ("drop a file", "open a .gltf / .glb scene"),
];

/// What the viewer opens with: the command line's choices, checked, with the scene loaded.
pub struct ViewerConfig {
    /// The scene file (`None`: the bundled Cornell box); shown in the overlay's path field.
    pub path: Option<PathBuf>,
    /// The scene.
    pub scene: Scene,
    /// Its lights with the radii `shadows` gives them.
    pub lights: Vec<Light>,
    /// The light radius and the hard-shadow switch.
    pub shadows: Shadows,
    /// The camera to start from.
    pub camera: Camera,
    /// Scene loading time in milliseconds.
    pub load_ms: f64,
    /// Render settings; width × height is the window's size.
    pub settings: RenderSettings,
    /// Stop accumulating at this many samples per pixel; `None` renders on and on.
    pub spp_target: Option<u32>,
    /// The OpenCL device.
    pub device: DeviceChoice,
    /// The kernels (`--kernel`).
    pub kernel: crate::render::KernelChoice,
    /// The acceleration structure (`--bvh`).
    pub bvh: crate::render::BvhChoice,
    /// The environment map, if one lights the scene.
    pub env_map: Option<EnvMap>,
    /// An environment (map or color) lights the scene: files opened later without lights get
    /// no default rig.
    pub env_lights: bool,
    /// How the exposure is chosen: metered on the film, or fixed (incident metering fixes it).
    pub exposure: ExposureMode,
    /// The tone curve (`--tonemap`).
    pub tone_mapper: ToneMapper,
    /// What escaped camera rays show (`--background`).
    pub background: Background,
    /// Focus the lens on what the image centre sees once the scene is on the device (a lens
    /// without a focus distance).
    pub autofocus: bool,
    /// Exit after this many frames (for tests).
    pub frames: Option<u64>,
    /// Save the final frame to this PNG path on exit (for tests), an EXR beside it.
    pub screenshot: Option<PathBuf>,
    /// Show the overlay at the start.
    pub overlay: bool,
    /// Append one JSON line per presented image here (`--stats-file`).
    pub stats_file: Option<PathBuf>,
    /// The first view is inside an interior: collision starts on.
    pub interior: bool,
}

/// The image's width over height in a window of `size` pixels, beside the overlay's panel
/// when `overlay` (at one pixel per point), for framing the first view.
pub fn image_aspect(size: (u32, u32), overlay: bool) -> f64 {
    let panel = if overlay {
        layout::panel_points(size.0 as f32) as u32
    } else {
        0
    };
    layout::ImageArea::new(size, panel).aspect() as f64
}

/// Checks what needs no scene before one is loaded: that there is a display to open a window
/// on, and that `screenshot` names a PNG in an existing folder.
pub fn preflight(screenshot: Option<&Path>) -> Result<()> {
    check_display()?;
    if let Some(p) = screenshot {
        check_screenshot_path(p)?;
    }
    Ok(())
}

/// Opens the viewer and runs it until the window closes (or `frames` are shown).
pub fn run(config: ViewerConfig) -> Result<()> {
    let size = (config.settings.width, config.settings.height);
    let event_loop = EventLoop::new().map_err(|e| {
        // winit's message starts with its source location; keep the reason only.
        let text = e.to_string();
        let reason = text.rsplit(": ").next().unwrap_or(&text).to_string();
        let display = std::env::var("WAYLAND_DISPLAY")
            .or_else(|_| std::env::var("DISPLAY"))
            .unwrap_or_default();
        anyhow!(
            "cannot open a window on display '{display}' ({reason}); use `penumbra render SCENE \
             -o OUT.png` to render without one"
        )
    })?;
    let stats = stats::ImageStats::new(config.stats_file.as_deref())?;
    let mut renderer = Renderer::new(&config.device)
        .context("cannot open the OpenCL device (see `penumbra devices`)")?;
    renderer.set_kernel(config.kernel)?;
    renderer.set_bvh_choice(config.bvh);
    // A large scene's first image comes from quick BLASes; the SAH ones follow.
    renderer.set_quick_first(Some(crate::render::instancing::QUICK_FIRST_TRIANGLES));
    let env_name = config.env_map.as_ref().map(|m| m.name.clone());
    if let Some(map) = config.env_map {
        renderer
            .set_environment(Some(map))
            .context("cannot upload the environment map")?;
    }
    let bounds = config.scene.bounds();
    let view = ViewState::new(
        config.settings,
        config.spp_target,
        config.shadows,
        config.exposure,
        &config.lights,
        bounds,
    );
    let mut view = view;
    view.background = config.background;
    view.tone_mapper = config.tone_mapper;
    // On by default where the network takes milliseconds (a GPU); a CPU takes seconds a frame.
    view.denoise = renderer.device.info.is_gpu;
    let mut camera = CameraController::new(config.camera, &bounds);
    camera.collision = config.interior;
    let path_text = config
        .path
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    let mut app = App {
        scene_path: config.path.clone(),
        seen_for: None,
        size,
        device: renderer.device.description(),
        frame_loop: FrameLoop::new(renderer),
        lights: view.lights(),
        model: Model::new(config.scene, view, camera),
        gui: Gui::new(path_text, env_name),
        load_ms: config.load_ms,
        frames_limit: config.frames,
        screenshot_on_exit: config.screenshot,
        gfx: None,
        input: Input::default(),
        overlay: config.overlay,
        last_motion: None,
        last_redraw: Instant::now(),
        wake: None,
        input_at: None,
        frames: 0,
        stats,
        pump_image: false,
        display: Vec::new(),
        denoised: None,
        denoise_ms: None,
        display_key: None,
        display_generation: 0,
        loader: None,
        device_error: None,
        fatal: None,
        last_screenshot: None,
        converged: false,
        quit: false,
        autofocus: config.autofocus,
        env_lights: config.env_lights,
        notice_frames: 0,
        deferred_env: None,
        frame_key: None,
        shown_spp: 0,
    };
    app.load_views();
    event_loop.run_app(&mut app)?;
    if let Some(e) = app.fatal.take() {
        return Err(e);
    }
    if let Some(path) = app.screenshot_on_exit.clone() {
        app.save_final(&path)?;
    }
    Ok(())
}

/// Fails with a pointer to `penumbra render` when there is no display to open a window on.
fn check_display() -> Result<()> {
    if cfg!(all(unix, not(target_os = "macos"))) {
        let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
            bail!(
                "no display (neither DISPLAY nor WAYLAND_DISPLAY is set): the viewer needs a \
                 window; use `penumbra render SCENE -o OUT.png` to render without one"
            );
        }
    }
    Ok(())
}

/// `--screenshot` must name a PNG in an existing folder.
fn check_screenshot_path(p: &Path) -> Result<()> {
    let is_png = p
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        bail!("--screenshot {}: must end in .png", p.display());
    }
    if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        bail!("--screenshot {}: the folder does not exist", p.display());
    }
    Ok(())
}

/// The window and what draws into it.
struct Gfx {
    window: Arc<Window>,
    pixels: Pixels<'static>,
    framework: Framework,
}

struct App {
    /// The scene file (views are saved beside it); `None` for the bundled scene.
    scene_path: Option<PathBuf>,
    /// The camera (eye, forward) the fly speed was last sized for.
    seen_for: Option<(glam::DVec3, glam::DVec3)>,
    /// The window's inner size in physical pixels (the full film size).
    size: (u32, u32),
    device: String,
    frame_loop: FrameLoop,
    model: Model,
    gui: Gui,
    /// The lights as rendered, kept in step with the model.
    lights: Vec<Light>,
    load_ms: f64,
    frames_limit: Option<u64>,
    screenshot_on_exit: Option<PathBuf>,
    gfx: Option<Gfx>,
    input: Input,
    overlay: bool,
    last_motion: Option<Instant>,
    last_redraw: Instant,
    /// When egui asked to be redrawn.
    wake: Option<Instant>,
    /// When input arrived that is not drawn yet.
    input_at: Option<Instant>,
    frames: u64,
    /// Presented images and input latency.
    stats: stats::ImageStats,
    /// A new image arrived between redraws (a batch collected while waiting): show it.
    pump_image: bool,
    /// The film tone-mapped (RGBA8), as on screen.
    display: Vec<u8>,
    /// The latest denoised image and the view, width and height of the film it came from:
    /// shown until the frame loop denoises a newer one of the same view
    /// (`FrameLoop::denoise_film`).
    denoised: Option<(FilmKey, Vec<[f32; 3]>)>,
    /// How long the last denoising took.
    denoise_ms: Option<f64>,
    /// What `display` shows.
    display_key: Option<DisplayKey>,
    /// Counts the changes of `display`.
    display_generation: u64,
    /// The scene file being loaded in the background.
    loader: Option<Loader>,
    device_error: Option<String>,
    fatal: Option<anyhow::Error>,
    last_screenshot: Option<PathBuf>,
    /// Whether the last frame had reached the samples-per-pixel target.
    converged: bool,
    /// Ctrl+Q was pressed.
    quit: bool,
    /// Focus the lens on the image centre once the scene is on the device.
    autofocus: bool,
    /// `--env` lights the scene: files without lights get no default rig.
    env_lights: bool,
    /// Frames drawn saying "Compiling kernels…" before a (blocking) kernel build: egui lays a
    /// new area out unseen in its first frame, so the build waits until one was shown.
    notice_frames: u8,
    /// An environment the overlay asked for whose kernels build after the notice is shown.
    deferred_env: Option<gui::EnvSource>,
    /// The display generation, image area and window size the frame buffer was composed for.
    frame_key: Option<(u64, layout::ImageArea, (u32, u32))>,
    /// Samples per pixel of the last frame shown (0: none yet since the scene changed).
    shown_spp: u32,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        match self.open_window(event_loop) {
            Ok(gfx) => self.gfx = Some(gfx),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gfx) = self.gfx.as_mut() else {
            return;
        };
        let ctx = gfx.framework.context().clone();
        // Keys are the viewer's unless text is being typed; Tab then never reaches egui (where
        // it would move the keyboard focus instead of hiding the overlay).
        let typing = self.overlay && ctx.text_edit_focused();
        let overlay_key = matches!(
            &event,
            WindowEvent::KeyboardInput { event: k, .. }
                if matches!(k.physical_key, PhysicalKey::Code(KeyCode::Tab | KeyCode::F1))
        );
        let consumed = if overlay_key && !typing {
            false
        } else {
            gfx.framework.handle_event(&gfx.window, &event)
        };
        let egui_wants_pointer = self.overlay && ctx.egui_wants_pointer_input();
        // Any input may change what is shown: draw soon (about_to_wait keeps the frame rate).
        if !matches!(event, WindowEvent::RedrawRequested) {
            self.input_at = Some(self.last_redraw + ACTIVE_INTERVAL);
        }
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            // A minimized window is 0×0: keep the last size.
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                if let Err(e) = gfx.pixels.resize_surface(size.width, size.height) {
                    self.fail(event_loop, anyhow!("cannot resize the window surface: {e}"));
                    return;
                }
                gfx.framework.resize(size.width, size.height);
                self.size = (size.width, size.height);
                self.frame_loop.invalidate(Changes {
                    camera: true,
                    ..Changes::default()
                });
            }
            WindowEvent::ScaleFactorChanged { scale_factor, .. } => {
                gfx.framework.set_scale_factor(scale_factor);
            }
            WindowEvent::DroppedFile(path) => self.open(path),
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            other => self.input_event(other, typing, !egui_wants_pointer && !consumed),
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_none() {
            return;
        }
        let now = Instant::now();
        let active = self.input.motion.any()
            || self.input.look
            || self.input.pan
            || self.moving(now)
            || self.model.timeline.playing
            || self.loader.is_some();
        let interval = if active {
            ACTIVE_INTERVAL
        } else {
            IDLE_INTERVAL
        };
        let rendering = self.device_error.is_none()
            && !self.frame_loop.converged(self.model.view.spp_target)
            || self.frame_loop.busy();
        let mut next = (active || rendering || self.frames_limit.is_some())
            .then(|| self.last_redraw + interval);
        // A batch due to finish is polled at once and the next one started without waiting for
        // a display frame, so the device never idles between bands.
        let due = self.frame_loop.expected_done();
        // (Not when the step would build kernels: that waits for the notice in `redraw`.)
        if due.is_some_and(|t| t <= now) && !self.builds_next() && self.step_frame_loop(now) {
            self.pump_image = true;
            self.wake = Some(now);
        }
        let poll = self
            .frame_loop
            .expected_done()
            .map(|t| t.max(now + POLL_INTERVAL));
        for w in [self.wake, self.input_at, poll].into_iter().flatten() {
            next = Some(next.map_or(w, |n| n.min(w)));
        }
        let Some(gfx) = self.gfx.as_ref() else {
            return;
        };
        match next {
            Some(t) if t <= now => {
                gfx.window.request_redraw();
                event_loop.set_control_flow(ControlFlow::WaitUntil(now + interval));
            }
            Some(t) => event_loop.set_control_flow(ControlFlow::WaitUntil(t)),
            None => event_loop.set_control_flow(ControlFlow::Wait),
        }
    }
}

impl App {
    fn open_window(&mut self, event_loop: &ActiveEventLoop) -> Result<Gfx> {
        let title = format!("penumbra — {}", self.model.scene.source);
        let attributes = Window::default_attributes()
            .with_title(title)
            .with_inner_size(PhysicalSize::new(self.size.0, self.size.1))
            .with_min_inner_size(PhysicalSize::new(16, 16));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .context("cannot create the window")?,
        );
        let size = window.inner_size();
        self.size = (size.width.max(1), size.height.max(1));
        let surface = SurfaceTexture::new(self.size.0, self.size.1, window.clone());
        let mut pixels = PixelsBuilder::new(self.size.0, self.size.1, surface)
            .build()
            .context("cannot draw into the window (no usable Vulkan, Metal or DX12 adapter)")?;
        // Fill the window whatever the film's size (it is smaller while moving); the scaling
        // matrix is only recomputed on a resize.
        pixels.set_scaling_mode(ScalingMode::Fill);
        pixels
            .resize_surface(self.size.0, self.size.1)
            .context("cannot size the window surface")?;
        let framework = Framework::new(&window, &pixels);
        window.request_redraw();
        Ok(Gfx {
            window,
            pixels,
            framework,
        })
    }

    /// Stops the viewer with an error that `run` returns.
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if self.fatal.is_none() {
            self.fatal = Some(e);
        }
        event_loop.exit();
    }

    fn moving(&self, now: Instant) -> bool {
        self.input.look
            || self.input.pan
            || self.input.motion.any()
            || self.last_motion.is_some_and(|t| now - t < MOVING_FOR)
    }

    /// One display frame: input, overlay, a step of the frame loop, tone mapping, present.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let now = Instant::now();
        let dt = (now - self.last_redraw).as_secs_f64().min(0.1);
        self.last_redraw = now;
        self.input_at = None;
        self.poll_loader();
        self.size_fly_speed();
        let host = self.frame_loop.renderer.host_scene();
        let obstacle = |o, d| host.and_then(|h| pick::distance_along(h, o, d));
        if self.model.camera.fly(&self.input.motion, dt, &obstacle) {
            self.camera_moved();
        }
        let Some(actions) = self.overlay_pass(now) else {
            return;
        };
        let screenshot = actions.screenshot;
        self.apply(actions, now);
        // A playing clip (or a scrubbed time) poses the scene: the image restarts at each new
        // time and accumulates while it stands.
        if self.model.timeline.update(&mut self.model.scene, now) {
            self.frame_loop.invalidate(Changes {
                scene: true,
                ..Changes::default()
            });
        }

        // Collect a finished batch and start the next one before showing this image. A step (or
        // an environment change) that builds kernels blocks for seconds with a cold cache: show
        // two frames that say so first.
        let v = &self.model.view;
        self.frame_loop.heat_map = match v.noise_threshold {
            Some(_) => v.heat_map,
            None => heat::HeatMap::Off,
        };
        self.frame_loop.denoise = v.denoise;
        let new_image = if self.builds_next() && self.notice_frames <= 2 {
            self.wake = Some(now);
            false
        } else {
            if let Some(env) = self.deferred_env.take() {
                self.set_environment(env);
            }
            let new = self.step_frame_loop(now);
            if !self.builds_next() {
                self.notice_frames = 0;
            }
            new || std::mem::take(&mut self.pump_image)
        };
        self.autofocus_once();
        self.update_display(new_image, dt);
        if new_image {
            // The overlay above was drawn with the previous figures: draw once more.
            self.wake = Some(now);
        }
        if screenshot {
            self.screenshot();
        }
        if let Err(e) = self.present() {
            self.fail(event_loop, e);
            return;
        }
        // An input not answered by a change this frame is forgotten.
        self.input.event_at = None;
        if new_image {
            self.image_presented();
        }
        self.frame_shown(event_loop);
    }

    /// Runs the overlay (it edits the model) and a mouse press held back for it; `None` without
    /// a window.
    fn overlay_pass(&mut self, now: Instant) -> Option<gui::Actions> {
        let compiling = self.device_error.is_none() && self.builds_next();
        let gfx = self.gfx.as_mut()?;
        let info = Info {
            device: &self.device,
            progress: &self.frame_loop.progress,
            film: &self.frame_loop.film,
            scene_stats: self.frame_loop.scene_stats.as_ref(),
            load_ms: self.load_ms,
            images_per_second: self.stats.images_per_second(now),
            latency_ms: self.stats.last_latency_ms,
            denoise_ms: self.denoise_ms,
            loading: self.loader.as_ref().map(|l| l.path.as_path()),
            last_screenshot: self.last_screenshot.as_deref(),
            device_error: self.device_error.as_deref(),
        };
        let mut actions = gui::Actions::default();
        let (overlay, gui, model) = (self.overlay, &mut self.gui, &mut self.model);
        let panel = if overlay {
            layout::panel_points(self.size.0 as f32 / gfx.framework.pixels_per_point())
        } else {
            0.0
        };
        let repaint = gfx.framework.prepare(&gfx.window, |ui| {
            if overlay {
                actions = gui.ui(ui, model, &info);
            }
            gui::help_window(ui.ctx(), &mut gui.help);
            gui::flash(ui.ctx(), &gui.flash, panel);
            if compiling {
                gui::notice(ui.ctx(), "Compiling kernels…", panel);
            }
        });
        if compiling {
            self.notice_frames = self.notice_frames.saturating_add(1);
        }
        self.wake = now.checked_add(repaint);
        if let Some(button) = self.input.press.take()
            && !(overlay && gfx.framework.context().is_pointer_over_egui())
        {
            self.press(button);
        }
        Some(actions)
    }

    /// Passes what the overlay changed to the frame loop and carries out its requests.
    fn apply(&mut self, actions: gui::Actions, now: Instant) {
        // Any edit counts as motion: dragging a slider or an object renders at a reduced
        // resolution like moving the camera does, and returns to full resolution after it.
        if actions.changes.any() {
            self.last_motion = Some(now);
        }
        if actions.changes.lights || actions.changes.scene {
            self.lights = self.model.view.lights();
        }
        let at = self.change_time();
        self.frame_loop.invalidate_at(actions.changes, at);
        if actions.hide_overlay {
            self.overlay = false;
        }
        if let Some(path) = actions.open {
            self.open(path);
        }
        if let Some(name) = actions.save_view {
            self.save_view(&name);
        }
        if let Some(camera) = actions.recall_view {
            self.model.camera.camera = camera;
            self.camera_moved();
        }
        if let Some(env) = actions.environment {
            // Applied in `redraw` once the "Compiling kernels…" notice is on screen if the
            // change builds kernels, else at once.
            let on = env != gui::EnvSource::None;
            if self.frame_loop.renderer.would_build_for_env(on) {
                self.deferred_env = Some(env);
            } else {
                self.set_environment(env);
            }
        }
    }

    /// One step of the frame loop; returns whether a new image arrived. A device error stops
    /// rendering and stays in the overlay.
    fn step_frame_loop(&mut self, now: Instant) -> bool {
        if self.device_error.is_some() {
            return false;
        }
        let world = World {
            scene: &self.model.scene,
            lights: &self.lights,
            camera: &self.model.camera.camera,
            settings: self.model.view.render_settings(self.image_area().size()),
            spp_target: self.model.view.spp_target,
            moving: self.moving(now),
        };
        // A heat map turned on while no batch runs reads its data from the film at once.
        let step = self.frame_loop.step(&world);
        match step.and_then(|new| Ok(self.frame_loop.read_heat_map()? || new)) {
            Ok(new) => new,
            Err(e) => {
                let message = e.to_string();
                log::error!("the device failed: {message}");
                self.device_error = Some(message);
                false
            }
        }
    }

    /// After a frame is shown: reports convergence, and exits on Ctrl+Q or after `--frames`.
    fn frame_shown(&mut self, event_loop: &ActiveEventLoop) {
        self.frames += 1;
        let spp = self.frame_loop.progress.spp;
        if self.shown_spp == 0 {
            // When the first image of a scene reaches the screen (opening times in the debug
            // log): the frames up to the first with samples.
            log::debug!("frame {} shown ({spp} spp)", self.frames);
        }
        self.shown_spp = spp;
        let converged = self.frame_loop.converged(self.model.view.spp_target);
        if converged && !self.converged {
            // One line per convergence, for scripts (and tests) that wait for a clean frame.
            println!(
                "penumbra: reached {} spp in {:.2} s",
                self.frame_loop.progress.spp, self.frame_loop.progress.seconds
            );
        }
        self.converged = converged;
        if self.quit {
            event_loop.exit();
        }
        if let Some(limit) = self.frames_limit {
            // The "Compiling kernels…" frame before the first load renders nothing.
            let target_reached = self.device_error.is_some()
                || self.model.view.spp_target.is_none() && !self.frame_loop.first_load()
                || self.frame_loop.converged(self.model.view.spp_target);
            if self.frames >= limit && target_reached {
                event_loop.exit();
            }
        }
    }

    /// Sizes the fly speed by the distance to what the camera sees, when the camera changed.
    fn size_fly_speed(&mut self) {
        let cam = &self.model.camera.camera;
        let key = (cam.eye, cam.forward);
        if self.seen_for == Some(key) {
            return;
        }
        let Some(host) = self.frame_loop.renderer.host_scene() else {
            return;
        };
        let aspect = self.image_area().aspect();
        if let Some(d) = pick::seen_distance(host, cam, aspect) {
            self.model.camera.set_seen_distance(d);
        }
        self.seen_for = Some(key);
    }

    /// The input event behind the change being recorded, if one is waiting for its image.
    pub(super) fn change_time(&mut self) -> Option<Instant> {
        self.input.event_at.take()
    }

    /// Whether the next frame-loop step (or a deferred environment) builds kernels.
    fn builds_next(&self) -> bool {
        self.frame_loop.builds_next(&self.model.scene)
            || self.deferred_env.as_ref().is_some_and(|e| {
                self.frame_loop
                    .renderer
                    .would_build_for_env(*e != gui::EnvSource::None)
            })
    }
}
