//! Scene loading in the viewer: a file opened in the overlay or dropped on the window is loaded
//! on a background thread, prepared (lights, camera) and handed to the frame loop, which uploads
//! it; the environment map is loaded and uploaded here too.

use super::camera::CameraController;
use super::exposure::HeldExposure;
use super::frame_loop::Changes;
use super::gui::{EnvSource, Model};
use super::{App, pick};
use crate::scene::{Scene, SceneError};
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Instant;

/// A scene loaded in the background, with its loading time in milliseconds.
type Loaded = Result<(Scene, f64), SceneError>;

/// A scene file being loaded in the background.
pub(super) struct Loader {
    /// The file.
    pub path: PathBuf,
    rx: Receiver<Loaded>,
}

impl App {
    /// Switches the environment map (a bundled one, a file, or none); an error stays in the
    /// overlay and the current environment is kept.
    pub(super) fn set_environment(&mut self, source: EnvSource) {
        let map = match source {
            EnvSource::None => Ok(None),
            EnvSource::Preset(p) => Ok(Some(p.load())),
            EnvSource::File(path) => crate::scene::EnvMap::load(&path).map(Some),
        };
        let map = match map {
            Ok(map) => map,
            Err(e) => {
                self.gui.env_error = Some(e);
                return;
            }
        };
        let name = map.as_ref().map(|m| m.name.clone());
        match self.frame_loop.renderer.set_environment(map) {
            Ok(()) => {
                self.gui.env_error = None;
                self.gui.env_name = name;
                self.frame_loop.invalidate(Changes {
                    settings: true,
                    ..Changes::default()
                });
            }
            Err(e) => self.gui.env_error = Some(e.to_string()),
        }
    }

    /// Loads `path` on a background thread; the current scene stays until it succeeds.
    pub(super) fn open(&mut self, path: PathBuf) {
        self.gui.path_text = path.display().to_string();
        let (tx, rx) = std::sync::mpsc::channel();
        let p = path.clone();
        std::thread::spawn(move || {
            let t = Instant::now();
            let result = crate::scene::load(&p).map(|s| (s, t.elapsed().as_secs_f64() * 1e3));
            // The viewer may have closed meanwhile; nobody to tell then.
            let _ = tx.send(result);
        });
        self.loader = Some(Loader { path, rx });
    }

    /// Takes a finished background load.
    pub(super) fn poll_loader(&mut self) {
        let Some(Loader { path, rx }) = self.loader.as_ref() else {
            return;
        };
        let result = match rx.try_recv() {
            Ok(r) => r,
            Err(TryRecvError::Empty) => return,
            Err(TryRecvError::Disconnected) => Err(SceneError::Invalid {
                path: path.clone(),
                message: "the loader stopped unexpectedly".into(),
            }),
        };
        let opened = path.clone();
        self.loader = None;
        match result {
            Ok((mut scene, ms)) => {
                if self.env_lights {
                    scene.drop_default_rig();
                }
                self.autofocus = self.model.view.aperture > 0.0;
                let view = &mut self.model.view;
                if std::mem::take(&mut view.incident_exposure) {
                    view.auto_exposure = Some(HeldExposure::default());
                }
                if let Some(auto) = view.auto_exposure.as_mut() {
                    auto.reset();
                }
                for w in &scene.warnings {
                    log::warn!("{}: {w}", scene.source);
                }
                let bounds = scene.bounds();
                self.model.view.replace_scene_lights(&scene.lights, bounds);
                let mut camera = CameraController::new(scene.cameras[0].clone(), &bounds);
                camera.collision = self.model.camera.collision;
                let view = self.model.view.clone();
                if let Some(gfx) = &self.gfx {
                    gfx.window
                        .set_title(&format!("penumbra — {}", scene.source));
                }
                self.model = Model::new(scene, view, camera);
                self.load_ms = ms;
                self.lights = self.model.view.lights();
                self.gui.file_error = None;
                self.device_error = None;
                self.scene_path = Some(opened);
                self.load_views();
                self.frame_loop.invalidate(Changes::ALL);
            }
            Err(e) => self.gui.file_error = Some(e.to_string()),
        }
    }

    /// Once the scene is on the device and `autofocus` is set, focuses the lens on what the
    /// image centre sees.
    pub(super) fn autofocus_once(&mut self) {
        if !self.autofocus {
            return;
        }
        let Some(host) = self.frame_loop.renderer.host_scene() else {
            return;
        };
        self.autofocus = false;
        let aspect = self.image_area().aspect();
        if let Some(hit) = pick::pick(host, &self.model.camera.camera, aspect, 0.5, 0.5) {
            self.focus_at(hit.point);
        }
    }
}
