//! How penumbra speaks on stderr: `penumbra: error: …`, `penumbra: warning: …` and plain
//! `penumbra: …` progress lines. `log` records take the same form (env_logger with this
//! format): `RUST_LOG` still chooses what is shown, and its info and debug lines name their
//! module.

use log::Level;
use std::io::Write;

/// The filter without `RUST_LOG`: penumbra's warnings, and only the errors of the window and
/// GPU crates (their warnings are about the driver, not the user's input).
const DEFAULT_FILTER: &str = "warn,egui_wgpu=error,winit=error";

/// Sends `log` records to stderr as penumbra's message lines.
pub fn init_logging() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or(DEFAULT_FILTER))
        .format(|buf, record| {
            // Control characters escaped: a file's text cannot forge a second line.
            let text = record.args().to_string();
            let message = crate::message::one_line(&text);
            let line = log_line(record.level(), record.target(), &message);
            writeln!(buf, "{line}")
        })
        .init();
}

/// One record as a message line; another crate's warnings and errors name the crate's module.
fn log_line(level: Level, target: &str, message: &str) -> String {
    let ours = target == "penumbra" || target.starts_with("penumbra::");
    let source = if ours {
        String::new()
    } else {
        format!("{target}: ")
    };
    match level {
        Level::Error => format!("penumbra: error: {source}{message}"),
        Level::Warn => format!("penumbra: warning: {source}{message}"),
        _ => format!(
            "penumbra: {} {target}: {message}",
            level.as_str().to_ascii_lowercase()
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_records_read_like_penumbras_own_lines() {
        assert_eq!(
            log_line(
                Level::Warn,
                "penumbra::args",
                "a.glb: materials[0]: clamped"
            ),
            "penumbra: warning: a.glb: materials[0]: clamped"
        );
        assert_eq!(
            log_line(Level::Error, "penumbra", "boom"),
            "penumbra: error: boom"
        );
        assert_eq!(
            log_line(Level::Warn, "wgpu_hal::vulkan", "slow path"),
            "penumbra: warning: wgpu_hal::vulkan: slow path"
        );
        assert_eq!(
            log_line(Level::Debug, "penumbra::render", "built"),
            "penumbra: debug penumbra::render: built"
        );
    }
}
