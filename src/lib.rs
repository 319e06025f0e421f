//! penumbra: an interactive path tracer for glTF scenes with OpenCL kernels.
#![warn(missing_docs)]

pub mod app;
pub mod bvh;
pub mod cl;
pub mod cli;
pub mod date;
pub mod image_io;
pub mod render;
pub mod scene;
