//! `gvi run` with a Poincaré time transformation: the built-in scenes `kepler-e099` and
//! `pythagorean`, the `--time-transform` flag and its options, rows in physical time, the
//! step-size chart, and typed errors for bad input.

use crate::common::cli::{assert_clean_failure, gvi};

/// The CSV's header and rows.
fn table(csv: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = csv.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

fn column(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// The e = 0.99 scene over 10 orbits: rows in physical time with the exact solution's error,
/// the run ending exactly at t_end, physical steps spanning orders of magnitude.
#[test]
fn kepler_e099_scene_runs_in_physical_time() {
    let t_end = 20.0 * std::f64::consts::PI;
    let (code, out, err) = gvi(&["run", "kepler-e099", "--t-end", &t_end.to_string()]);
    assert_eq!(code, 0, "{err}");
    let (header, rows) = table(&out);
    assert_eq!(&header[..4], ["step", "s", "t", "dt"]);
    let (t, dt, pos) = (
        column(&header, "t"),
        column(&header, "dt"),
        column(&header, "position_error"),
    );
    let last = rows.last().unwrap();
    assert_eq!(last[t], t_end);
    // 60 fictitious steps per orbit.
    assert!(
        (rows.len() as f64 - 601.0).abs() <= 2.0,
        "{} rows",
        rows.len()
    );
    let worst = rows.iter().map(|r| r[pos]).fold(0.0, f64::max);
    assert!(worst < 1e-7, "max position error {worst:e}");
    let steps: Vec<f64> = rows[1..].iter().map(|r| r[dt]).collect();
    let (lo, hi) = steps
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(hi / lo > 1e3, "physical steps from {lo:e} to {hi:e}");
    assert!(err.contains("fictitious steps to t ="), "{err}");
}

/// `--time-transform` on a scene without one, with output at t₀ + k·every located on t(s).
#[test]
fn time_transform_flag_with_output_every() {
    let (code, out, err) = gvi(&[
        "run",
        "kepler",
        "--time-transform",
        "radius",
        "--alpha",
        "1",
        "--h",
        "0.05",
        "--n",
        "10",
        "--steps",
        "5000",
        "--t-end",
        "20",
        "--every",
        "0.5",
    ]);
    assert_eq!(code, 0, "{err}");
    let (header, rows) = table(&out);
    let (t, pos) = (column(&header, "t"), column(&header, "position_error"));
    assert_eq!(rows.len(), 41);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r[t], 0.5 * k as f64);
        assert!(r[pos] < 1e-8, "t = {}: {}", r[t], r[pos]);
    }
    assert!(err.contains("r^1"), "{err}");
}

/// The Pythagorean problem to t = 70: through the encounters to the escape of the lightest
/// body, with the energy kept, and the chart of the physical step.
#[test]
fn pythagorean_scene_reaches_the_escape() {
    let dir = std::env::temp_dir().join(format!("gvi-tt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("steps.svg");
    let csv = dir.join("run.csv");
    let (code, _, err) = gvi(&[
        "run",
        "pythagorean",
        "--output",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let (header, rows) = table(&text);
    let (t, energy) = (column(&header, "t"), column(&header, "energy"));
    let last = rows.last().unwrap();
    assert_eq!(last[t], 70.0);
    let e0 = rows[0][energy];
    let worst = rows
        .iter()
        .map(|r| (r[energy] - e0).abs() / e0.abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-8, "relative energy error {worst:e}");
    // The lightest body (m3, first) escapes: far from the other two and moving away.
    let x = |r: &[f64], b: usize| (r[4 + 2 * b], r[5 + 2 * b]);
    let (a, b, c) = (x(last, 0), x(last, 1), x(last, 2));
    let binary = ((4.0 * b.0 + 5.0 * c.0) / 9.0, (4.0 * b.1 + 5.0 * c.1) / 9.0);
    let escape = (a.0 - binary.0).hypot(a.1 - binary.1);
    let pair = (b.0 - c.0).hypot(b.1 - c.1);
    assert!(escape > 5.0 && pair < 1.0, "escape {escape}, binary {pair}");
    let chart = std::fs::read_to_string(&svg).unwrap();
    assert!(chart.contains("<svg") && chart.contains("physical step"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad input is a typed error with a message, never a panic or a silent default.
#[test]
fn bad_time_transform_input_is_refused() {
    assert_clean_failure(
        &["run", "kepler", "--time-transform", "warp"],
        "unknown 'warp'",
    );
    assert_clean_failure(
        &["run", "kepler-e099", "--energy-level", "nan"],
        "energy E0",
    );
    assert_clean_failure(&["run", "kepler-e099", "--alpha", "inf"], "alpha");
    assert_clean_failure(&["run", "kepler-e099", "--every", "0"], "every");
    assert_clean_failure(&["run", "kepler-e099", "--t-end", "-1"], "t_end");
    assert_clean_failure(&["run", "kepler", "--alpha", "1"], "--alpha");
    assert_clean_failure(&["run", "kepler", "--t-end", "10"], "--t-end");
    assert_clean_failure(
        &["run", "pythagorean", "--time-transform", "radius"],
        "Kepler",
    );
    assert_clean_failure(
        &["run", "rigid-body", "--time-transform", "sundman"],
        "rigid body",
    );
    assert_clean_failure(
        &["run", "henon-heiles", "--time-transform", "sundman"],
        "N-body",
    );
    assert_clean_failure(&["run", "kepler-e099", "--tol", "1e-8"], "--tol");
    // The commands that step in physical time refuse a time-transformed scene.
    assert_clean_failure(&["check", "kepler-e099"], "only `gvi run`");
    assert_clean_failure(
        &["section", "pythagorean", "--every", "1"],
        "only `gvi run`",
    );
    // Two bodies at one point: refused as a collision before the monitor (zero there) is
    // evaluated; the monitor's own error is src/time_transform/tests.rs's.
    assert_clean_failure(&["run", "pythagorean", "--q0", "1,3,1,3,1,-1"], "collide");
    // Not enough fictitious steps for t_end: an error, with the rows kept.
    let (code, out, err) = gvi(&["run", "kepler-e099", "--steps", "30"]);
    assert_ne!(code, 0);
    assert!(err.contains("max_steps"), "{err}");
    assert_eq!(out.lines().count(), 32, "{out}");
}
