//! The `penumbra` command: parses the arguments and runs the library's command line.
#![deny(unsafe_code)]

use clap::Parser;
use penumbra::message::print;

fn main() {
    penumbra::cli::messages::init_logging();
    quiet_on_closed_stdout();
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
        let usage = e.downcast_ref::<penumbra::cli::UsageError>().is_some();
        std::process::exit(if usage { 2 } else { 1 });
    }
}

/// A reader of the summary that goes away early (`penumbra bench … | head -1`, a pipeline
/// killed by a timeout) makes `println!` panic on the broken pipe. Ends the process as a Unix
/// tool killed by SIGPIPE ends, quietly with status 141, instead of a panic and a backtrace;
/// every other panic is reported as before.
fn quiet_on_closed_stdout() {
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let text = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if text.starts_with("failed printing to stdout") && text.contains("Broken pipe") {
            std::process::exit(141);
        }
        report(info);
    }));
}
