//! The library stays a library: none of the application's dependencies (command line, charts,
//! progress bars, scene files, tables, JSON, the DOP853 peer, benches, property tests) may reach
//! the normal dependency tree of `galerkin-vi`. They belong to the lab (`galerkin-vi-lab`),
//! whose tree is the negative control: the same query must find clap and plotters there, so
//! the test can fail.

use std::collections::BTreeSet;
use std::process::Command;

/// Crates the library must not depend on (normal edges, any feature).
const APPLICATION_ONLY: [&str; 9] = [
    "clap",
    "plotters",
    "indicatif",
    "toml",
    "csv",
    "serde_json",
    "differential-equations",
    "criterion",
    "proptest",
];

/// Package names in the normal dependency tree of `package`, with every feature enabled;
/// `None` (and a message) if cargo cannot be run.
fn normal_dependencies(package: &str) -> Option<BTreeSet<String>> {
    // Under `cargo test` the variable names the cargo that builds us; env!() is the fallback.
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| env!("CARGO").to_string());
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml");
    let output = match Command::new(&cargo)
        .args(["tree", "--offline", "--all-features", "-e", "normal"])
        .args([
            "--prefix",
            "none",
            "--manifest-path",
            manifest,
            "-p",
            package,
        ])
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            eprintln!("skipped: cannot run `{cargo} tree` ({e})");
            return None;
        }
    };
    assert!(
        output.status.success(),
        "`cargo tree -p {package}` failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = String::from_utf8(output.stdout).expect("cargo tree prints UTF-8");
    Some(
        text.lines()
            .filter_map(|l| l.split_whitespace().next())
            .map(str::to_string)
            .collect(),
    )
}

#[test]
fn library_has_no_application_dependencies() {
    let Some(lib) = normal_dependencies("galerkin-vi") else {
        return;
    };
    assert!(
        lib.contains("nalgebra"),
        "the query lists dependencies: {lib:?}"
    );
    let leaked: Vec<&str> = APPLICATION_ONLY
        .into_iter()
        .filter(|d| lib.contains(*d))
        .collect();
    assert!(
        leaked.is_empty(),
        "application dependencies in the library's tree: {leaked:?}"
    );
}

#[test]
fn negative_control_the_lab_has_them() {
    let Some(lab) = normal_dependencies("galerkin-vi-lab") else {
        return;
    };
    for d in ["clap", "plotters", "csv", "serde_json"] {
        assert!(lab.contains(d), "{d} missing from the lab's tree: {lab:?}");
    }
}
