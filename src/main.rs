//! The `leafmagic` binary: parses arguments and reports errors once.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    leafmagic::util::pipe::quiet_broken_pipe();
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
