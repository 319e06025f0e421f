//! The `penumbra` command: parses the arguments and runs the library's command line.
#![deny(unsafe_code)]

use clap::Parser;
use penumbra::message::{one_line, print};

fn main() {
    env_logger::Builder::from_env(
        env_logger::Env::default().default_filter_or("warn,egui_wgpu=error,winit=error"),
    )
    .format(|buf, record| {
        use std::io::Write;
        let kind = match record.level() {
            log::Level::Error => "error",
            log::Level::Warn => "warning",
            log::Level::Info => "info",
            log::Level::Debug => "debug",
            log::Level::Trace => "trace",
        };
        // Another crate's message says whose it is.
        let text = match record.target() {
            t if t.starts_with("penumbra") => record.args().to_string(),
            t => format!("{t}: {}", record.args()),
        };
        writeln!(buf, "penumbra: {kind}: {}", one_line(&text))
    })
    .init();
    let cli = match penumbra::cli::Cli::try_parse() {
        Ok(cli) => cli,
        // --help and --version print as clap makes them, with exit code 0.
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            print("error", &penumbra::cli::usage_error(&e));
            std::process::exit(2);
        }
    };
    if let Err(e) = penumbra::cli::run(cli) {
        // One line: the error and its causes, outermost first.
        let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
        print("error", &chain.join(": "));
        std::process::exit(1);
    }
}
