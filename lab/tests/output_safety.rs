//! Nothing lost: outputs are checked before any work and written atomically (a killed run
//! leaves the old file intact), refused when they would clobber an input or each other, and
//! whole-trajectory runs that would need absurd memory are refused with the estimate. The rest
//! of the robustness cases (typed failures, warnings, messages) are in `robustness.rs`.

use crate::common::robust;
use robust::*;
use std::process::Command;

// ---- data lost or clobbered ----

#[test]
fn same_path_for_output_and_plot_is_refused() {
    let dir = scratch("same");
    let out = dir.join("out.csv");
    let o = gvi(&[
        "run",
        "kepler",
        "--steps",
        "5",
        "--output",
        s(&out),
        "--plot",
        s(&out),
    ]);
    fails_with(&o, "name the same file");
    assert!(!out.exists(), "nothing may be written");
}

#[test]
fn output_equal_to_the_scene_file_is_refused() {
    let dir = scratch("scene-out");
    let scene = dir.join("my.toml");
    std::fs::write(&scene, TWO_BODY).unwrap();
    let o = gvi(&["run", s(&scene), "--steps", "2", "--output", s(&scene)]);
    fails_with(&o, "scene file");
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), TWO_BODY);
    // The same file reached through another spelling of its path.
    let other = dir
        .join("../")
        .join(dir.file_name().unwrap())
        .join("my.toml");
    let o = gvi(&["run", s(&scene), "--steps", "2", "--plot", s(&other)]);
    fails_with(&o, "scene file");
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), TWO_BODY);
}

#[test]
fn unusable_output_paths_fail_before_computing() {
    let dir = scratch("paths");
    // 10^8 steps would take minutes: an immediate refusal shows the check comes first.
    let o = gvi(&[
        "run",
        "kepler",
        "--steps",
        "100000000",
        "--output",
        "/proc/version",
    ]);
    fails_with(&o, "pseudo-filesystem");
    let o = gvi(&["run", "kepler", "--steps", "100000000", "--output", s(&dir)]);
    fails_with(&o, "is a directory");
    let o = gvi(&["run", "kepler", "--steps", "100000000", "--plot", s(&dir)]);
    fails_with(&o, "is a directory");
    let file = dir.join("file");
    std::fs::write(&file, "x").unwrap();
    let o = gvi(&["reproduce", "--quick", "--out", s(&file)]);
    fails_with(&o, s(&file));
    fails_with(&o, "not a directory");
    let o = gvi(&[
        "run",
        "kepler",
        "--steps",
        "3",
        "--output",
        s(&file.join("x.csv")),
    ]);
    assert!(!o.status.success());
}

#[test]
fn a_missing_parent_directory_is_created_and_reported() {
    let dir = scratch("parent");
    let out = dir.join("new/sub/k.csv");
    let o = gvi(&["run", "kepler", "--steps", "3", "--output", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("created directory"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&out).unwrap().lines().count(), 5);
}

#[test]
fn writes_are_atomic_and_leave_no_temporary_files() {
    let dir = scratch("atomic");
    let out = dir.join("k.csv");
    std::fs::write(&out, "previous\n").unwrap();
    // A run refused after the checks (invalid n) leaves the old file intact.
    let o = gvi(&["run", "kepler", "--n", "1", "--output", s(&out)]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous\n");
    let o = gvi(&["run", "kepler", "--steps", "4", "--output", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["k.csv".to_string()], "stray files: {names:?}");
    assert!(
        std::fs::read_to_string(&out)
            .unwrap()
            .starts_with("step,t,")
    );
}

#[test]
fn dev_null_is_a_valid_output() {
    let o = gvi(&["run", "kepler", "--steps", "3", "--output", "/dev/null"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn whole_trajectory_runs_with_absurd_memory_are_refused_with_the_estimate() {
    let o = gvi(&["run", "kepler", "--steps", "100000000", "--format", "json"]);
    fails_with(&o, "refusing the run");
    fails_with(&o, "bytes");
    let dir = scratch("wp");
    let o = gvi(&[
        "work-precision",
        "kepler",
        "--quick",
        "--horizon",
        "1e300",
        "--out",
        s(&dir),
    ]);
    fails_with(&o, "5.000e299");
}

// ---- non-finite or meaningless results ----

/// Data lines of a CSV table.
#[test]
fn a_run_killed_while_writing_leaves_the_old_file_intact() {
    let dir = scratch("kill");
    let out = dir.join("k.csv");
    std::fs::write(&out, "previous\n").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args([
            "run",
            "harmonic",
            "--n",
            "4",
            "--h",
            "0.1",
            "--steps",
            "100000000",
        ])
        .args(["--output", s(&out)])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Wait until the streamed rows are being written (the temporary file grows), then kill.
    let temp = dir.join(format!(".k.csv.gvi-tmp-{}", child.id()));
    for _ in 0..200 {
        if std::fs::metadata(&temp).is_ok_and(|m| m.len() > 100_000) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
    }
    assert!(
        std::fs::metadata(&temp).is_ok_and(|m| m.len() > 0),
        "rows are streamed"
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous\n");
}
