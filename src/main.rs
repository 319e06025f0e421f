//! The `penumbra` command: parses the arguments and runs the library's command line.
#![deny(unsafe_code)]

use clap::Parser;
use penumbra::message::print;

fn main() {
    penumbra::cli::messages::init_logging();
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
