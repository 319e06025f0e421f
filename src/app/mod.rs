//! The interactive viewer.

use crate::cli::ViewArgs;
use anyhow::Result;

/// Opens the viewer.
pub fn run(_args: ViewArgs) -> Result<()> {
    anyhow::bail!("the viewer is not built yet")
}
