//! `penumbra bench`: ray throughput of the traversal kernels (`trace`), where a frame's time
//! goes (`frame`), error against run time (`converge`), and a generator of large test scenes
//! (`generate`), the host BVH build and update (`bvh`), and how faithfully the first image shows
//! base colours (`albedo`), and the per-frame update of an animated scene (`animation`). What
//! each measures, and the figures,
//! are in `docs/benchmarks.md`.

mod albedo;
mod animation;
mod bvh;
mod converge;
mod curve;
mod denoise;
mod frame;
pub mod generate;
mod plot;
mod rays;
mod stats;
pub mod stress;
mod trace;

pub use albedo::AlbedoArgs;
pub use animation::AnimationBenchArgs;
pub use bvh::BvhArgs;
pub use converge::ConvergeArgs;
pub use denoise::DenoiseArgs;
pub use frame::FrameArgs;
pub use generate::GenerateArgs;
pub use stress::StressArgs;
pub use trace::TraceArgs;

use crate::cl::Device;
use anyhow::Result;
use clap::Subcommand;

/// Benchmarks.
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Rays per second of the traversal kernels alone (primary, diffuse-bounce and shadow
    /// rays), validated against the host traversal.
    #[command(
        mut_arg("width", |a| a.help("Width of the primary ray grid [default: 1280]")),
        mut_arg("height", |a| a.help("Height of the primary ray grid [default: 720]"))
    )]
    Trace(Box<TraceArgs>),
    /// Samples per second of the whole path tracer and the kernel time of each stage.
    Frame(Box<FrameArgs>),
    /// Error (RMSE, relMSE) against run time for several sampling settings, against a
    /// reference image; table, CSV/JSON and a log-log plot.
    Converge(Box<ConvergeArgs>),
    /// Host time to build the scene's BVH and to update it when one instance moves.
    Bvh(Box<BvhArgs>),
    /// Writes a large test scene (instanced spheres or copies of a mesh in a closed, lit room).
    Generate(Box<GenerateArgs>),
    /// The same image at any position and scale: moved and scaled copies of the Cornell box
    /// against the original, leaks from closed meshes, spawned-ray reintersection, grazing
    /// shadow rays and acne; a Markdown table.
    Stress(Box<StressArgs>),
    /// The mean displayed colour of materials of known base colour under a white environment
    /// against that base colour, per tone curve and exposure rule; a Markdown table.
    Albedo(Box<AlbedoArgs>),
    /// The denoiser's network time on the device, beside Intel's Open Image Denoise on the
    /// same input where pyoidn is installed.
    Denoise(Box<DenoiseArgs>),
    /// Host time of an animated scene's per-frame update: evaluating the clip, deforming
    /// skinned and morphed meshes, refitting their BVHs and rebuilding the top level.
    Animation(Box<AnimationBenchArgs>),
}

/// Runs a benchmark.
pub fn run(cmd: BenchCommand) -> Result<()> {
    match cmd {
        BenchCommand::Trace(a) => trace::run(&a),
        BenchCommand::Frame(a) => frame::run(&a),
        BenchCommand::Converge(a) => converge::run(&a),
        BenchCommand::Generate(a) => generate::run(&a),
        BenchCommand::Bvh(a) => bvh::run(&a),
        BenchCommand::Stress(a) => stress::run(&a),
        BenchCommand::Albedo(a) => albedo::run(&a),
        BenchCommand::Denoise(a) => denoise::run(&a),
        BenchCommand::Animation(a) => animation::run(&a),
    }
}

/// The device as benchmark outputs describe it.
fn device_json(device: &Device) -> serde_json::Value {
    let i = &device.info;
    serde_json::json!({
        "name": i.name,
        "platform": i.platform,
        "driver": i.driver,
        "version": i.version,
        "is_gpu": i.is_gpu,
        "compute_units": i.compute_units,
    })
}

/// One line naming the device, its platform and driver.
fn device_line(device: &Device) -> String {
    let i = &device.info;
    format!(
        "{} ({}), driver {}, {}, {} compute units",
        i.name, i.platform, i.driver, i.version, i.compute_units
    )
}

/// `1234567` as `1,234,567`.
pub(crate) fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thousands_are_grouped() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(1_234_567), "1,234,567");
    }
}
