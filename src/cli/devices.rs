//! `penumbra devices`.

use crate::cl::{DeviceChoice, list_devices};
use anyhow::Result;

/// Prints every OpenCL device with the index `--device` takes, marking the default.
pub fn run() -> Result<()> {
    let devices = list_devices()?;
    let default = devices
        .iter()
        .find(|d| d.is_gpu)
        .or(devices.first())
        .map(|d| d.index);
    let chosen = DeviceChoice::from_arg_or_env(None).ok();
    for d in &devices {
        let mark = if Some(d.index) == default { "*" } else { " " };
        println!(
            "{mark} {}: {} [{}] — {}, {} compute units, {} MiB, {}, driver {}",
            d.index,
            d.name,
            if d.is_gpu { "GPU" } else { "CPU" },
            d.platform,
            d.compute_units,
            d.memory >> 20,
            d.version.trim(),
            d.driver.trim()
        );
    }
    println!(
        "* = default (first GPU, else first CPU); choose with --device gpu|cpu|INDEX, or for \
         render all|INDEX,INDEX… (several at once)"
    );
    if let Some(c) = chosen.filter(|c| *c != DeviceChoice::Auto) {
        println!("PENUMBRA_DEVICE selects {c:?}");
    }
    Ok(())
}
