//! penumbra: an interactive path tracer for glTF scenes with OpenCL kernels.
#![warn(missing_docs)]
// All `unsafe` lives in `cl::kernels` (buffer transfers and kernel arguments).
#![deny(unsafe_code)]

pub mod app;
pub mod args;
pub mod bench;
pub mod bvh;
pub mod cl;
pub mod cli;
pub mod cpu_time;
pub mod date;
pub mod denoise;
pub mod image_io;
pub mod message;
pub mod render;
pub mod scene;
pub mod shard;
