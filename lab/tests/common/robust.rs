//! Helpers of the robustness tests (`robustness.rs`, `output_safety.rs`): run the `gvi`
//! binary, read its output, make scratch directories, expect failures. Include with
//! `#[path = "common/robust.rs"] mod robust;`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn gvi(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args(args)
        .output()
        .expect("the gvi binary runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A fresh scratch directory per test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gvi-robust-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

pub fn fails_with(o: &Output, needle: &str) {
    let err = stderr(o);
    assert!(
        !o.status.success(),
        "expected a failure, got rc 0; stderr: {err}"
    );
    assert!(err.contains(needle), "stderr lacks {needle:?}: {err}");
}

pub const TWO_BODY: &str = include_str!("../../../scenes/two-body.toml");
