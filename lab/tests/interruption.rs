//! Nothing lost, round 2 (issue 32, class 6, interruption): Ctrl-C on a streamed run keeps
//! what was computed (the stream is finalised: the rows so far are committed to the output,
//! and the message says where), and the temporary files of runs that were killed are cleaned
//! up the next time the same output is written.

use crate::common::robust;
use robust::*;
use std::process::{Command, Stdio};

#[test]
fn ctrl_c_on_a_streamed_run_commits_the_rows_so_far() {
    let dir = scratch("sigint");
    let out = dir.join("k.csv");
    std::fs::write(&out, "previous\n").unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_gvi"))
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
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until rows are being streamed (the temporary file grows), then Ctrl-C.
    let temp = dir.join(format!(".k.csv.gvi-tmp-{}", child.id()));
    for _ in 0..400 {
        if std::fs::metadata(&temp).is_ok_and(|m| m.len() > 100_000) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(25));
    }
    assert!(
        std::fs::metadata(&temp).is_ok_and(|m| m.len() > 0),
        "rows are streamed"
    );
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted (Ctrl-C)"), "{err}");
    assert!(
        err.contains(s(&out)),
        "the message says where the rows are: {err}"
    );
    // The rows computed are in the output, whole, and no temporary file is left.
    let text = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("step,t,"));
    assert!(lines.len() > 1000, "{} lines", lines.len());
    assert!(text.ends_with('\n'));
    let fields = lines[0].split(',').count();
    assert!(lines.iter().all(|l| l.split(',').count() == fields));
    let last_step: usize = lines[lines.len() - 1]
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(last_step, lines.len() - 2, "rows 0…k in order");
    assert!(!temp.exists());
}

#[test]
fn temporary_files_of_killed_runs_are_removed() {
    let dir = scratch("stale");
    // 4194305 is above the largest PID Linux hands out: no process has it.
    let stale = dir.join(".k.csv.gvi-tmp-4194305");
    let alive = dir.join(format!(".k.csv.gvi-tmp-{}", std::process::id()));
    let other = dir.join(".other.csv.gvi-tmp-4194305");
    for f in [&stale, &alive, &other] {
        std::fs::write(f, "partial").unwrap();
    }
    let o = gvi(&[
        "run",
        "kepler",
        "--steps",
        "3",
        "--output",
        s(&dir.join("k.csv")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !stale.exists(),
        "the killed run's temporary file is removed"
    );
    assert!(stderr(&o).contains("removed"), "{}", stderr(&o));
    // Negative controls: a live process's file and another destination's are kept.
    assert!(alive.exists() && other.exists());
}
