//! Running the `gvi` binary from a test: exit code, stdout and stderr. Include with
//! `#[path = "common/cli.rs"] mod cli;`.

use std::process::Command;

/// Run `gvi ARGS`: (exit code, or −1 if killed by a signal; stdout; stderr).
pub fn gvi(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args(args)
        .output()
        .expect("gvi runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
