//! OpenCL on the host: device choice, the context and queue, program builds with scene-feature
//! defines and line-mapped errors, typed buffers, and the typed kernel wrappers (`kernels`), the
//! one place with `unsafe` code and positional kernel arguments.

mod device;
pub mod kernels;
mod program;
mod source;
pub mod types;

/// Serialises device opening and program builds within a process: PoCL (3.x, Debian 12) can
/// crash when two threads create contexts or compile at the same time, as test binaries do.
pub(crate) static CL_SETUP: std::sync::Mutex<()> = std::sync::Mutex::new(());

pub use device::{DeviceChoice, DeviceInfo, Gpu, list_devices};
pub use kernels::{Buffer, Program, Stage};
pub use program::{
    KernelFeatures, LANES_MIN_TRIANGLES, Lanes, SMALL_SCENE_MAX, build_program, build_test_program,
    lanes_load_rows, lanes_megakernel, lanes_shade, lanes_small,
};

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
