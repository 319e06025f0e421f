//! Quick BLASes first: a two-level scene loaded with quick BLASes while its SAH BLASes build
//! on threads of their own, then loaded again with those, so that the image from then on is
//! the one a plain load gives.

use super::{Renderer, SceneStats, instancing};
use crate::cl::ClError;
use crate::scene::{Light, Scene};
use std::sync::Arc;
use std::time::Instant;

/// The BLASes of a background build, with their meshes in the plan's order, and its time (ms).
type BuiltBlases = (Vec<(Arc<crate::scene::Mesh>, crate::bvh::Blas)>, f64);

/// SAH BLASes building on threads of their own behind the quick ones on the device; dropping
/// it stops the build at the next mesh.
pub(super) struct SahBuild {
    /// The BLASes when done.
    done: std::sync::mpsc::Receiver<BuiltBlases>,
    /// Set to stop the build (a new scene was loaded).
    cancel: Arc<std::sync::atomic::AtomicBool>,
}

impl Drop for SahBuild {
    fn drop(&mut self) {
        self.cancel
            .store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

impl Renderer {
    /// `Some(n)`: a two-level scene of at least n distinct triangles is loaded with quick
    /// BLASes ([`crate::bvh::quick_blas`], several times faster to build) while its SAH BLASes
    /// build on threads behind them; [`Renderer::swap_in_sah`] then loads the scene again with
    /// those, so that the image from then on is the one a plain load gives. The viewer opens
    /// scenes so ([`instancing::QUICK_FIRST_TRIANGLES`]); `None` (the default, `render`):
    /// SAH BLASes at once.
    pub fn set_quick_first(&mut self, from: Option<usize>) {
        self.quick_first = from;
    }

    /// Whether SAH BLASes are building (or waiting to) behind the quick ones on the device.
    pub fn sah_pending(&self) -> bool {
        self.sah.is_some() || self.sah_waiting.is_some()
    }

    /// When the SAH BLASes behind the quick ones are done, loads `scene` (the one loaded, as it
    /// is now: moved or hidden objects stay so) with them in the current render space and
    /// resets the film; its figures, the wait for the BLASes (ms) in `bvh_build_ms`. `None`
    /// while they build or when none are. The first call after the quick scene's first
    /// samples starts their build.
    pub fn swap_in_sah(
        &mut self,
        scene: &Scene,
        lights: &[Light],
    ) -> Result<Option<SceneStats>, ClError> {
        // The SAH BLASes start once the quick scene has samples: on a CPU device their
        // threads would otherwise share the cores with the first image.
        if self.samples > 0
            && let Some(meshes) = self.sah_waiting.take()
        {
            self.sah = Self::sah_behind(meshes);
        }
        let Some(build) = &self.sah else {
            return Ok(None);
        };
        let (blases, build_ms) = match build.done.try_recv() {
            Ok(b) => b,
            Err(std::sync::mpsc::TryRecvError::Empty) => return Ok(None),
            // The thread died (it cannot, short of running out of memory): build them here.
            Err(std::sync::mpsc::TryRecvError::Disconnected) => (vec![], 0.0),
        };
        self.sah = None;
        let space = self.space();
        // The quick scene's host side goes first; its buffers take the new contents where the
        // sizes agree (triangles and shading data: the same, reordered).
        let old = self.scene.take().map(|(buffers, _)| buffers);
        let how = instancing::Blases::Built(blases);
        let mut stats = self.load_with(scene, lights, space, how, old)?;
        stats.bvh_build_ms += build_ms;
        Ok(Some(stats))
    }

    /// The meshes of `plan`'s BLASes (of `scene`), in order.
    pub(super) fn sah_meshes(
        scene: &Scene,
        plan: &instancing::Instancing,
    ) -> Vec<Arc<crate::scene::Mesh>> {
        plan.mesh_objects
            .iter()
            .map(|&o| scene.objects[o as usize].mesh.clone())
            .collect()
    }

    /// Starts building the SAH BLASes of `meshes` on a pool of threads of
    /// their own, so that the host work of frames (rayon's global pool) never queues behind
    /// them; `None` when no thread could be started (the quick trees then stay).
    fn sah_behind(meshes: Vec<Arc<crate::scene::Mesh>>) -> Option<SahBuild> {
        use rayon::prelude::*;
        use std::sync::atomic::Ordering;
        let pool = rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("sah-blas-{i}"))
            .build()
            .ok()?;
        let cancel = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stop = cancel.clone();
        let (tx, done) = std::sync::mpsc::channel();
        std::thread::Builder::new()
            .name("sah-blas".into())
            .spawn(move || {
                let _memory = crate::cl::kernels::OpeningMemory::begin();
                let t = Instant::now();
                let blases: Option<Vec<_>> = pool.install(|| {
                    meshes
                        .into_par_iter()
                        .map(|m| {
                            (!stop.load(Ordering::Relaxed)).then(|| {
                                let b = crate::bvh::Blas::of_shared_mesh(&m);
                                (m, b)
                            })
                        })
                        .collect()
                });
                if let Some(blases) = blases {
                    // Nobody waits when a new scene replaced this one.
                    let _ = tx.send((blases, t.elapsed().as_secs_f64() * 1e3));
                }
            })
            .ok()?;
        Some(SahBuild { done, cancel })
    }
}
