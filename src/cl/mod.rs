//! OpenCL on the host: device choice, the context and queue (`device`), program builds with
//! scene-feature defines and line-mapped errors (`program`), the structs shared with the kernels
//! (`types`), typed buffers (`buffer`) and the scene's (`scene_buffers`), the host memory policy
//! (`host_memory`), the path tracer's stages (`stage`), and the typed kernel wrappers
//! (`kernels`), the one place with positional kernel arguments. `buffer`, `host_memory` and
//! `kernels` are the only modules with `unsafe` code.

mod buffer;
mod device;
mod host_memory;
pub mod kernels;
mod program;
mod scene_buffers;
mod source;
mod stage;
pub mod types;

/// Serialises device opening and program builds within a process: PoCL (3.x, Debian 12) can
/// crash when two threads create contexts or compile at the same time, as test binaries do.
pub(crate) static CL_SETUP: std::sync::Mutex<()> = std::sync::Mutex::new(());

pub use buffer::Buffer;
pub use device::{Device, DeviceChoice, DeviceInfo, DeviceSet, list_devices};
pub use host_memory::{OpeningMemory, map_file};
pub use kernels::{
    ColorSource, ConvArgs, DenoiseKernels, FilmCount, GuideSums, Launch, PlaneCurve, Program,
    TileWindow,
};
pub use program::{KernelFeatures, build_denoise_program, build_program, build_test_program};
pub use scene_buffers::{EnvBuffers, NodeForms, SceneBuffers};
pub use stage::Stage;

/// Errors from OpenCL: no usable device, a failed build, a failed launch.
#[derive(Debug, thiserror::Error)]
pub enum ClError {
    /// No platform or device matched.
    #[error("{0}")]
    Device(String),
    /// A kernel failed to build; the message names the `.cl` file and line.
    #[error("kernel build failed: {0}")]
    Build(String),
    /// An OpenCL call failed during `stage`.
    #[error("OpenCL error in {stage}: {message}")]
    Call {
        /// The stage or operation.
        stage: String,
        /// The OpenCL error.
        message: String,
    },
}

/// Wraps an OpenCL error with the stage it happened in.
pub(crate) fn call_err(stage: &str) -> impl Fn(opencl3::error_codes::ClError) -> ClError + '_ {
    move |e| ClError::Call {
        stage: stage.to_string(),
        message: e.to_string(),
    }
}
