//! `gvi`: the command-line front end of galerkin-vi.

use clap::Parser;
use galerkin_vi_lab::cli;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::main_with(args) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of stdout has gone (`gvi scenes | head -1`): stop quietly, with the
        // status of a tool killed by SIGPIPE (128 + 13).
        Err(e) if e.is_broken_pipe() => ExitCode::from(141),
        // Ctrl-C on a streamed run: the rows computed are kept; the status of SIGINT.
        Err(e @ galerkin_vi_lab::error::LabError::Interrupted { .. }) => {
            eprintln!("error: {e}");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
