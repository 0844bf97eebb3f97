//! Nothing lost, round 2 (issue 32, memory): every command that keeps whole runs in memory
//! estimates the bytes before its work and refuses above the one limit (4 GB) with the estimate
//! in the message; charts of long runs are thinned to what a chart can show. The refusals are
//! immediate (the sizes refused would take minutes to compute), and each has a negative
//! control: the same command at a small size is not refused.

use crate::common::robust;
use robust::*;
use std::time::{Duration, Instant};

/// The command is refused by the memory estimate, at once.
fn refused_for_memory(args: &[&str]) {
    let start = Instant::now();
    let o = gvi(args);
    fails_with(&o, "refusing");
    fails_with(&o, "bytes of memory, above the limit 4e9");
    assert!(
        start.elapsed() < Duration::from_secs(20),
        "{args:?} took {:?}: the refusal must come before the work",
        start.elapsed()
    );
}

#[test]
fn every_in_memory_command_refuses_absurd_sizes_with_the_estimate() {
    let dir = scratch("memory");
    let out = |name: &str| dir.join(name).to_string_lossy().into_owned();
    refused_for_memory(&["check", "kepler", "--steps", "100000000"]);
    refused_for_memory(&[
        "compare-refinement",
        "kepler",
        "--quick",
        "--steps",
        "10000000",
        "--out",
        &out("cr"),
    ]);
    refused_for_memory(&["tolerance-study", "kepler", "--steps", "10000000"]);
    refused_for_memory(&[
        "nbody-report",
        "two-body",
        "--steps",
        "100000000",
        "--out",
        &out("nb"),
    ]);
    refused_for_memory(&["periodic", "figure-eight", "--modes", "4096"]);
    refused_for_memory(&["periodic", "figure-eight", "--periods", "100000000"]);
    refused_for_memory(&[
        "ensemble",
        "solar-system",
        "--count",
        "10000000",
        "--perturb",
        "0",
    ]);
    // Nothing was written by a refused command.
    assert!(!dir.join("cr").exists() && !dir.join("nb").exists());
}

#[test]
fn the_same_commands_at_small_sizes_are_not_refused() {
    let dir = scratch("memory-ok");
    let out = |name: &str| dir.join(name).to_string_lossy().into_owned();
    for args in [
        vec!["check", "kepler", "--steps", "5"],
        vec![
            "nbody-report",
            "two-body",
            "--steps",
            "3",
            "--no-cross-check",
            "--out",
            &out("nb"),
        ],
        vec![
            "ensemble",
            "kepler",
            "--count",
            "3",
            "--perturb",
            "1e-6",
            "--steps",
            "3",
        ],
        vec![
            "tolerance-study",
            "harmonic",
            "--steps",
            "4",
            "--tols",
            "1e-3",
            "--ladder",
            "4,6",
        ],
    ] {
        let o = gvi(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    }
}

/// Points of every `<polyline points="…">` and the number of circles of an SVG.
fn svg_counts(svg: &str) -> (Vec<usize>, usize) {
    let lines = svg
        .split("<polyline")
        .skip(1)
        .map(|p| {
            let pts = p.split("points=\"").nth(1).unwrap_or("");
            let pts = pts.split('"').next().unwrap_or("");
            pts.split_whitespace().count()
        })
        .collect();
    (lines, svg.matches("<circle").count())
}

#[test]
fn charts_of_long_runs_are_thinned_to_what_a_chart_can_show() {
    let dir = scratch("thin");
    // 6000 steps: 6001 step ends and 192 000 curve samples without thinning.
    let svg = dir.join("long.svg");
    let o = gvi(&[
        "run",
        "harmonic",
        "--n",
        "4",
        "--h",
        "0.5",
        "--steps",
        "6000",
        "--plot",
        s(&svg),
        "--output",
        "/dev/null",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&svg).unwrap();
    let (lines, circles) = svg_counts(&text);
    assert!(lines.iter().all(|&n| n <= 4000), "{lines:?}");
    assert!(circles <= 4001, "{circles} markers");
    assert!(text.len() < 3_000_000, "SVG of {} bytes", text.len());
    // Negative control: a short run keeps every step end (one more circle: the legend's).
    let svg = dir.join("short.svg");
    let o = gvi(&[
        "run",
        "harmonic",
        "--n",
        "4",
        "--h",
        "0.5",
        "--steps",
        "50",
        "--plot",
        s(&svg),
        "--output",
        "/dev/null",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, circles) = svg_counts(&std::fs::read_to_string(&svg).unwrap());
    assert_eq!(circles, 52);
}

#[test]
fn a_charted_run_is_refused_with_an_estimate_that_includes_no_unbounded_chart() {
    // The estimate of a charted run is per step (trajectory, table, text): a chart adds a
    // bounded amount, so 10^8 steps are refused and the message gives the estimate.
    let dir = scratch("plot-memory");
    let o = gvi(&[
        "run",
        "kepler",
        "--steps",
        "100000000",
        "--plot",
        s(&dir.join("m.svg")),
    ]);
    fails_with(&o, "refusing the run");
    fails_with(&o, "bytes");
}
