//! `penumbra bench`: ray throughput and error against time.

use anyhow::Result;
use clap::Subcommand;

/// Benchmarks.
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Rays per second of the traversal kernels.
    Trace,
}

/// Runs a benchmark.
pub fn run(_cmd: BenchCommand) -> Result<()> {
    anyhow::bail!("bench is not built yet")
}
