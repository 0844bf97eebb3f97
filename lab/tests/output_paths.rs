//! Nothing lost, round 2 (issue 32, class 1): every output of every subcommand goes through
//! one check (`output::Plan`) that resolves paths (`..` through directories that do not exist
//! yet, symlinks, relative spellings) before comparing the outputs with each other and with
//! every input (the scene file, `--external` files), and that refuses file names too long for
//! the atomic writer's temporary name, all before any work. Each refusal has a negative
//! control: the same command with a harmless path succeeds, so the refusal is not vacuous.

use crate::common::robust;
use robust::*;
use std::path::Path;
use std::process::{Command, Output};

/// `gvi ARGS` run in `dir`, so that relative paths are relative to it.
fn gvi_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gvi"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the gvi binary runs")
}

fn ok(o: &Output) {
    assert!(o.status.success(), "expected success: {}", stderr(o));
}

const FIGURE_EIGHT: &str = include_str!("../../scenes/figure-eight.toml");

#[test]
fn dot_dot_through_a_missing_directory_cannot_reach_the_scene() {
    let dir = scratch("dotdot");
    std::fs::write(dir.join("scene.toml"), TWO_BODY).unwrap();
    let o = gvi_in(
        &dir,
        &[
            "run",
            "scene.toml",
            "--steps",
            "5",
            "--output",
            "nope/../scene.toml",
        ],
    );
    fails_with(&o, "scene file");
    assert_eq!(
        std::fs::read_to_string(dir.join("scene.toml")).unwrap(),
        TWO_BODY
    );
    assert!(!dir.join("nope").exists(), "nothing is created");
    // A `..` out of a deeper missing path.
    let o = gvi_in(
        &dir,
        &[
            "run",
            "scene.toml",
            "--steps",
            "5",
            "--output",
            "a/b/../../scene.toml",
        ],
    );
    fails_with(&o, "scene file");
    // --plot through `..`: a scene file named like a chart.
    std::fs::write(dir.join("scene.svg"), TWO_BODY).unwrap();
    let o = gvi_in(
        &dir,
        &[
            "run",
            "scene.svg",
            "--steps",
            "5",
            "--plot",
            "a/b/../../scene.svg",
        ],
    );
    fails_with(&o, "scene file");
    assert_eq!(
        std::fs::read_to_string(dir.join("scene.svg")).unwrap(),
        TWO_BODY
    );
    // Negative control: the same spelling naming another file is written.
    let o = gvi_in(
        &dir,
        &[
            "run",
            "scene.toml",
            "--steps",
            "5",
            "--output",
            "nope/../other.csv",
        ],
    );
    ok(&o);
    assert!(
        std::fs::read_to_string(dir.join("other.csv"))
            .unwrap()
            .starts_with("step,")
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("scene.toml")).unwrap(),
        TWO_BODY
    );
}

#[test]
fn dot_dot_after_a_symlink_follows_the_link() {
    let dir = scratch("symdotdot");
    std::fs::write(dir.join("scene.toml"), TWO_BODY).unwrap();
    std::fs::create_dir_all(dir.join("real/sub")).unwrap();
    std::os::unix::fs::symlink(dir.join("real/sub"), dir.join("link")).unwrap();
    std::fs::write(dir.join("real/scene.toml"), TWO_BODY).unwrap();
    // link/.. is real/ (the kernel follows the link first), so this is real/scene.toml.
    let o = gvi_in(
        &dir,
        &[
            "run",
            "real/scene.toml",
            "--steps",
            "3",
            "--output",
            "link/../scene.toml",
        ],
    );
    fails_with(&o, "scene file");
    // A symlink to the scene is the scene.
    std::os::unix::fs::symlink(dir.join("scene.toml"), dir.join("alias.csv")).unwrap();
    let o = gvi_in(
        &dir,
        &["run", "scene.toml", "--steps", "3", "--output", "alias.csv"],
    );
    fails_with(&o, "scene file");
    // Negative control: link/../scene.toml is not ./scene.toml.
    let o = gvi_in(
        &dir,
        &[
            "run",
            "scene.toml",
            "--steps",
            "3",
            "--output",
            "link/../scene.toml",
        ],
    );
    ok(&o);
    assert_eq!(
        std::fs::read_to_string(dir.join("scene.toml")).unwrap(),
        TWO_BODY
    );
}

#[test]
fn periodic_checks_every_output() {
    let dir = scratch("periodic-paths");
    std::fs::write(dir.join("f8.toml"), FIGURE_EIGHT).unwrap();
    let cases: [&[&str]; 4] = [
        &["--output", "f8.toml"],
        &["--output", "x/../f8.toml"],
        &["--output", "o.svg", "--plot", "o.svg"],
        &["--plot", "p.svg", "--refine-plot", "./p.svg"],
    ];
    for extra in cases {
        let mut args = vec!["periodic", "f8.toml"];
        args.extend_from_slice(extra);
        let o = gvi_in(&dir, &args);
        assert!(!o.status.success(), "{extra:?} must be refused");
        let err = stderr(&o);
        assert!(
            err.contains("scene file") || err.contains("name the same file"),
            "{extra:?}: {err}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("f8.toml")).unwrap(),
            FIGURE_EIGHT
        );
    }
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(left.len(), 1, "only the scene remains");
}

#[test]
fn work_precision_never_writes_over_its_inputs() {
    let dir = scratch("wp-paths");
    std::fs::write(dir.join("k.toml"), TWO_BODY).unwrap();
    let o = gvi_in(
        &dir,
        &["work-precision", "k.toml", "--write-reference", "k.toml"],
    );
    fails_with(&o, "scene file");
    assert_eq!(
        std::fs::read_to_string(dir.join("k.toml")).unwrap(),
        TWO_BODY
    );
    // An --external file inside --out with the name of a file the study writes.
    std::fs::create_dir_all(dir.join("out")).unwrap();
    std::fs::write(dir.join("out/work_precision.csv"), "precious\n").unwrap();
    let o = gvi_in(
        &dir,
        &[
            "work-precision",
            "kepler",
            "--quick",
            "--out",
            "out",
            "--external",
            "out/work_precision.csv",
        ],
    );
    fails_with(&o, "--external file");
    assert_eq!(
        std::fs::read_to_string(dir.join("out/work_precision.csv")).unwrap(),
        "precious\n"
    );
}

#[test]
fn study_directories_never_write_over_the_scene() {
    let dir = scratch("study-paths");
    // A scene file whose name is one the study writes into --out.
    std::fs::write(dir.join("refine.json"), TWO_BODY).unwrap();
    let o = gvi_in(
        &dir,
        &[
            "refine",
            "refine.json",
            "--vary",
            "n",
            "--range",
            "4:8:2",
            "--out",
            ".",
        ],
    );
    fails_with(&o, "scene file");
    assert_eq!(
        std::fs::read_to_string(dir.join("refine.json")).unwrap(),
        TWO_BODY
    );
    std::fs::write(dir.join("stability.csv"), TWO_BODY).unwrap();
    let o = gvi_in(&dir, &["stability", "stability.csv", "--out", "x/.."]);
    fails_with(&o, "scene file");
    assert_eq!(
        std::fs::read_to_string(dir.join("stability.csv")).unwrap(),
        TWO_BODY
    );
}

#[test]
fn ensemble_output_cannot_be_the_scene() {
    let dir = scratch("ens-paths");
    std::fs::write(dir.join("s.toml"), TWO_BODY).unwrap();
    let o = gvi_in(
        &dir,
        &[
            "ensemble",
            "s.toml",
            "--count",
            "2",
            "--perturb",
            "0",
            "--output",
            "no/../s.toml",
        ],
    );
    fails_with(&o, "scene file");
    assert_eq!(
        std::fs::read_to_string(dir.join("s.toml")).unwrap(),
        TWO_BODY
    );
}

#[test]
fn output_names_too_long_for_the_temporary_name_are_refused_before_the_work() {
    let dir = scratch("long-names");
    // 10^8 steps would take minutes: an immediate refusal shows the check comes first.
    for len in [239, 245, 255] {
        let name = format!("{}.csv", "x".repeat(len - 4));
        let o = gvi_in(
            &dir,
            &["run", "kepler", "--steps", "100000000", "--output", &name],
        );
        fails_with(&o, &format!("{len} bytes"));
        let chart = format!("{}.svg", "x".repeat(len - 4));
        let o = gvi_in(&dir, &["run", "kepler", "--steps", "3", "--plot", &chart]);
        fails_with(&o, &format!("{len} bytes"));
    }
    let long_dir = "d".repeat(256);
    let o = gvi_in(
        &dir,
        &[
            "refine", "kepler", "--vary", "n", "--range", "4:8:2", "--out", &long_dir,
        ],
    );
    fails_with(&o, "256 bytes");
    // Negative control: the longest allowed name is written.
    let name = format!("{}.csv", "x".repeat(238 - 4));
    let o = gvi_in(&dir, &["run", "kepler", "--steps", "3", "--output", &name]);
    ok(&o);
    assert!(dir.join(&name).is_file());
}
