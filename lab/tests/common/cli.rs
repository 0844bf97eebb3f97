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

/// Run `gvi ARGS` and require a clean refusal: a non-zero exit, `needle` in stderr, and no
/// panic (a panic would also exit non-zero, so the status alone does not tell them apart).
pub fn assert_clean_failure(args: &[&str], needle: &str) {
    let (code, _, err) = gvi(args);
    assert_ne!(code, 0, "{args:?} should fail");
    assert!(
        err.contains(needle),
        "{args:?}: stderr lacks {needle:?}:\n{err}"
    );
    assert!(!err.contains("panicked"), "{args:?} panicked:\n{err}");
}
