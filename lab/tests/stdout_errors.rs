//! Nothing lost, round 2 (issue 32, class 3 of the issue: panics and aborts). Every write to
//! stdout returns a typed error: a full device is a clear error with exit status 1, a reader
//! that has gone (a closed pipe) stops the tool quietly with status 141 (as SIGPIPE would),
//! and nothing panics. Scene values get the range checks their flags get, and the message
//! names the scene key, not the flag.

use crate::common::robust;
use robust::*;
use std::process::{Command, Output, Stdio};

/// `gvi ARGS` with stdout on /dev/full (every write fails with ENOSPC).
fn gvi_full(args: &[&str]) -> Output {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full opens");
    Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args(args)
        .stdout(Stdio::from(full))
        .output()
        .expect("the gvi binary runs")
}

fn no_panic(o: &Output) {
    let err = stderr(o);
    assert!(
        !err.contains("panicked") && o.status.code() != Some(101),
        "panic: {err}"
    );
}

/// Commands that print to stdout, each cheap.
fn printing_commands(dir: &std::path::Path) -> Vec<Vec<String>> {
    let out = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let cmds: Vec<Vec<&str>> = vec![
        vec!["check", "kepler", "--steps", "5"],
        vec!["scenes"],
        vec![
            "tolerance-study",
            "harmonic",
            "--steps",
            "4",
            "--tols",
            "1e-3",
            "--ladder",
            "4,6",
            "--controls",
            "embedded",
        ],
        vec!["run", "harmonic", "--steps", "3"],
        vec!["run", "harmonic", "--steps", "3", "--format", "json"],
    ];
    let mut cmds: Vec<Vec<String>> = cmds
        .into_iter()
        .map(|c| c.into_iter().map(String::from).collect())
        .collect();
    cmds.push(
        [
            "nbody-report",
            "two-body",
            "--steps",
            "3",
            "--no-cross-check",
            "--out",
            &out("nb"),
        ]
        .map(String::from)
        .to_vec(),
    );
    cmds
}

#[test]
fn a_full_stdout_is_a_clear_error_not_a_panic() {
    let dir = scratch("devfull");
    for cmd in printing_commands(&dir) {
        let args: Vec<&str> = cmd.iter().map(String::as_str).collect();
        // Negative control: the command works with a usable stdout.
        let ok = gvi(&args);
        assert!(ok.status.success(), "{args:?}: {}", stderr(&ok));
        assert!(!ok.stdout.is_empty(), "{args:?} prints to stdout");
        let o = gvi_full(&args);
        no_panic(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("No space left on device"),
            "{args:?}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn a_closed_pipe_stops_the_tool_quietly() {
    // A streamed run far longer than a pipe's buffer, whose reader goes after one line.
    let mut child = Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args(["run", "harmonic", "--h", "0.1", "--steps", "10000000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = child.stdout.take().unwrap();
    let mut first = [0u8; 64];
    std::io::Read::read_exact(&mut out, &mut first).unwrap();
    assert!(first.starts_with(b"step,t,"));
    drop(out);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(141), "{}", stderr(&o));
    assert!(stderr(&o).is_empty(), "quiet: {}", stderr(&o));
    // A report printed at the end, after the reader has gone.
    let mut child = Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args(["check", "kepler", "--steps", "200"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(141), "{}", stderr(&o));
    assert!(stderr(&o).is_empty(), "quiet: {}", stderr(&o));
}

/// `gvi run` without --output: to a terminal, the summary and a hint, not hundreds of rows
/// (stdout made a terminal by `script`, util-linux; skipped where it is missing); to a pipe,
/// the CSV as before (the negative control).
#[test]
fn run_prints_a_summary_not_the_table_to_a_terminal() {
    let gvi = env!("CARGO_BIN_EXE_gvi");
    let tty = Command::new("script")
        .args([
            "-qec",
            &format!("'{gvi}' run kepler --steps 50"),
            "/dev/null",
        ])
        .stdin(Stdio::null())
        .output();
    match tty {
        Ok(o) => {
            assert!(o.status.success(), "gvi under `script`: {}", stdout(&o));
            // `script` merges the child's stdout and stderr into its own stdout.
            let text = stdout(&o);
            assert!(text.contains("max position error"), "summary: {text}");
            assert!(
                text.contains("table not printed: stdout is a terminal"),
                "{text}"
            );
            assert!(!text.contains("step,t,"), "no CSV to a terminal: {text}");
            assert!(text.lines().count() < 12, "a short summary: {text}");
        }
        Err(e) => eprintln!("skipped: no `script` (util-linux) to give gvi a terminal: {e}"),
    }
    let piped = robust::gvi(&["run", "kepler", "--steps", "50"]);
    assert!(piped.status.success(), "{}", stderr(&piped));
    assert!(stdout(&piped).starts_with("step,t,"), "CSV to a pipe");
    assert_eq!(stdout(&piped).lines().count(), 52, "header and 51 rows");
    assert!(!stderr(&piped).contains("table not printed"));
}

const FIGURE_EIGHT: &str = include_str!("../../scenes/figure-eight.toml");

#[test]
fn scene_modes_get_the_range_check_of_the_flag_and_name_the_key() {
    let dir = scratch("scene-modes");
    for (value, shown) in [("1000000", "got 1000000"), ("0", "got 0")] {
        let path = dir.join(format!("m{value}.toml"));
        let text = FIGURE_EIGHT.replace("modes = 60", &format!("modes = {value}"));
        assert_ne!(text, FIGURE_EIGHT, "the scene has `modes = 60`");
        std::fs::write(&path, text).unwrap();
        let o = gvi(&["periodic", s(&path)]);
        no_panic(&o);
        fails_with(&o, "[periodic] modes");
        fails_with(&o, shown);
        assert!(!stderr(&o).contains("--modes"), "{}", stderr(&o));
    }
    // The flag's message names the flag (negative control of the key's name).
    let o = gvi(&["periodic", "figure-eight", "--modes", "1000000"]);
    fails_with(&o, "--modes");
    // steps = 0 per period was silently one step per period.
    let path = dir.join("steps0.toml");
    let text = FIGURE_EIGHT.replace("steps = 64", "steps = 0");
    assert_ne!(text, FIGURE_EIGHT);
    std::fs::write(&path, text).unwrap();
    let o = gvi(&["periodic", s(&path)]);
    fails_with(&o, "[periodic] steps");
}
