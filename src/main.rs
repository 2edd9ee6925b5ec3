//! The `leafmagic` binary: parses arguments and reports errors once.

mod cli;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    quiet_broken_pipe();
    let args = cli::Cli::parse();
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// `leafmagic ... | head` closes stdout early; `println!` then panics with
/// "failed printing to stdout: Broken pipe". That is the reader's choice,
/// not an error of ours: exit quietly (status 141, as a shell reports a
/// process ended by SIGPIPE) instead of printing a panic and a backtrace.
/// Files are written atomically elsewhere, so stopping here leaves nothing
/// half-written.
fn quiet_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.contains("failed printing to stdout") && message.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
    }));
}
