//! Issue 32 class 7 through the CLI: the run summary's relative energy error has a scale that
//! does not vanish (a parabolic orbit passes `--strict`), the summary gives the whole
//! command's wall time beside the integration's, the closest approach of two bodies is found
//! on the Galerkin curves (not only at step ends), and over-long output names are refused
//! before the work by every command that writes a file.

use crate::common::robust;

use robust::{TWO_BODY, fails_with, gvi, s, scratch, stderr, stdout};
use std::path::Path;
use std::process::Output;

fn gvi_in(dir: &Path, args: &[&str]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_gvi"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the gvi binary runs")
}

/// The number after `label` in `text` (up to the next space, comma, `;` or `)`).
fn number_after(text: &str, label: &str) -> f64 {
    let at = text
        .find(label)
        .unwrap_or_else(|| panic!("no {label:?} in {text}"));
    let rest = &text[at + label.len()..];
    let end = rest.find([' ', ',', ';', ')']).unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|e| panic!("{label:?} {:?}: {e}", &rest[..end]))
}

#[test]
fn a_parabolic_orbit_passes_strict_its_relative_energy_error_over_t0_plus_v0() {
    // E₀ = |p|²/2 − 1/|q| = 1 − 1 = 0 (to round-off): over |E₀| the relative error was
    // round-off over round-off (1.5 measured) and --strict failed a good run.
    let o = gvi(&[
        "run",
        "kepler",
        "--q0",
        "1,0",
        "--p0",
        "0,1.4142135623730951",
        "--n",
        "16",
        "--h",
        "0.5",
        "--steps",
        "40",
        "--strict",
        "--output",
        "/dev/null",
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("to T₀ + |V₀| = 2.000e0"), "{err}");
    assert!(number_after(&err, "(relative ") < 1e-12, "{err}");
    // Negative control: a run whose energy really drifts still fails --strict, the message
    // naming the scale.
    let o = gvi(&[
        "run",
        "kepler",
        "--n",
        "4",
        "--h",
        "2",
        "--steps",
        "30",
        "--strict",
        "--output",
        "/dev/null",
    ]);
    fails_with(&o, "not trustworthy");
    fails_with(&o, "over T₀ + |V₀| = 4.500e0");
}

/// The parabolic Kepler start of `a_parabolic_orbit_passes_strict…`: E₀ = |p|²/2 − 1/|q| = 0
/// to round-off, T₀ + |V₀| = 2.
const PARABOLIC: [&str; 4] = ["--q0", "1,0", "--p0", "0,1.4142135623730951"];

/// |E₀| of that start, the old scale (2.2e-16).
fn parabolic_e0() -> f64 {
    (0.5 * std::f64::consts::SQRT_2.powi(2) - 1.0).abs()
}

/// `gvi ensemble`, `gvi stability` and `gvi nbody-report` measure the relative energy error
/// over `gvi run`'s T₀ + |V₀| and say so: on a parabolic orbit a good run is small, where the
/// same absolute error over |E₀| (the negative control, the old scale) would be large.
#[test]
fn ensemble_stability_and_nbody_report_use_the_runs_energy_scale() {
    let dir = scratch("energy-scale");
    // Ensemble: one unperturbed member.
    let csv = dir.join("e.csv");
    let mut args = vec!["ensemble", "kepler"];
    args.extend(PARABOLIC);
    args.extend([
        "--n",
        "16",
        "--h",
        "0.5",
        "--steps",
        "40",
        "--count",
        "1",
        "--perturb",
        "0",
        "--output",
        s(&csv),
    ]);
    let o = gvi(&args);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("/ (T₀ + |V₀| at each member's start)"),
        "{err}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let column = header
        .iter()
        .position(|c| *c == "max_rel_energy_error")
        .unwrap();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    let relative: f64 = row[column].parse().unwrap();
    assert!(relative < 1e-12, "{text}");
    let absolute = relative * 2.0;
    assert!(
        absolute / parabolic_e0() > 1e-2,
        "control: over |E₀| the same run reads {:e}",
        absolute / parabolic_e0()
    );

    // Stability: the accurate cells of the quick grid.
    let out = dir.join("stability");
    let mut args = vec!["stability", "kepler"];
    args.extend(PARABOLIC);
    args.extend(["--quick", "--cell-steps", "20", "--out", s(&out)]);
    let o = gvi(&args);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("classified by the max energy error relative to T₀ + |V₀| = 2.000e0"),
        "{err}"
    );
    let text = std::fs::read_to_string(out.join("stability.csv")).unwrap();
    let best = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .find(|c| c[0].parse::<f64>() == Ok(1.0) && c[1] == "40")
        .unwrap_or_else(|| panic!("no cell h = 1, n = 40 in {text}"));
    let relative: f64 = best[3].parse().unwrap();
    assert!(relative < 1e-12 && best[2] == "accurate", "{text}");
    assert!(relative * 2.0 / parabolic_e0() > 1e-2, "control: {text}");

    // N-body report: a parabolic two-body encounter (masses 1/2, G = 1, separation 1,
    // relative speed √2: T₀ = 1/4, V₀ = −1/4).
    let scene = dir.join("parabolic.toml");
    let toml = TWO_BODY
        .replace("name = \"two-body\"", "name = \"parabolic\"")
        .replace("q = [-0.2, 0.0]", "q = [-0.5, 0.0]")
        .replace("q = [0.2, 0.0]", "q = [0.5, 0.0]")
        .replace("v = [0.0, -1.0]", "v = [0.0, -0.7071067811865476]")
        .replace("v = [0.0, 1.0]", "v = [0.0, 0.7071067811865476]");
    assert!(toml.contains("0.7071067811865476") && toml.contains("-0.5"));
    std::fs::write(&scene, toml).unwrap();
    let o = gvi(&[
        "nbody-report",
        s(&scene),
        "--n",
        "16",
        "--h",
        "0.5",
        "--steps",
        "20",
        "--no-cross-check",
        "--out",
        s(&dir),
    ]);
    let (out, err) = (stdout(&o), stderr(&o));
    assert!(o.status.success(), "{err}");
    assert!(out.contains("energy relative to T₀ + |V₀|"), "{out}");
    let line = out
        .lines()
        .find(|l| l.trim_start().starts_with("energy "))
        .unwrap_or_else(|| panic!("no energy line in {out}"));
    assert!(line.contains("(T₀ + |V₀| = 5.000e-1)"), "{line}");
    let relative: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(relative < 1e-12, "{out}");
    // Two bodies × ½ m v², minus G m₁ m₂ / r.
    let e0 = (2.0 * 0.5 * 0.5 * std::f64::consts::FRAC_1_SQRT_2.powi(2) - 0.25).abs();
    // |E₀| is round-off (or exactly 0, where the old ratio was ∞ or NaN).
    assert!(
        e0 < 1e-15 && (relative * 0.5 / e0 > 1e-2 || relative == 0.0),
        "{e0:e}"
    );
}

#[test]
fn the_summary_gives_the_whole_commands_wall_time_beside_the_integrations() {
    let dir = scratch("wall-time");
    let chart = dir.join("k.svg");
    let o = gvi(&[
        "run",
        "kepler",
        "--n",
        "8",
        "--h",
        "0.5",
        "--steps",
        "400",
        "--plot",
        s(&chart),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let integration = number_after(&err, "integration time: ");
    let whole = number_after(&err, "whole command: ");
    assert!(err.contains("s (wall clock)"), "{err}");
    // The command includes the integration, the errors along the curves and the chart.
    assert!(whole >= integration, "{err}");
}

/// Two bodies of mass 1/2 on the e = 0.6 orbit of `two-body`, started at apocentre
/// (separation 1.6): pericentre (separation 0.4) is at t = π, inside the second step of h = 2.
const APOCENTRE: [&str; 8] = [
    "--q0",
    "-0.8,0,0.8,0",
    "--p0",
    "0,-0.125,0,0.125",
    "--steps",
    "3",
    "--h",
    "2",
];

#[test]
fn the_closest_approach_is_found_on_the_galerkin_curves_between_step_ends() {
    let dir = scratch("closest");
    let csv = dir.join("t.csv");
    let json = dir.join("t.json");
    for (extra, path) in [(&[][..], &csv), (&["--format", "json"][..], &json)] {
        let mut args = vec!["run", "two-body"];
        args.extend(APOCENTRE);
        args.extend(extra);
        args.extend(["--output", s(path)]);
        let o = gvi(&args);
        let err = stderr(&o);
        assert!(o.status.success(), "{err}");
        let label = "closest approach on the Galerkin curves: body 1 and body 2 at ";
        let separation = number_after(&err, label);
        let t = number_after(&err, "(t = ");
        assert!((separation - 0.4).abs() < 1e-6, "{err}");
        assert!((t - std::f64::consts::PI).abs() < 1e-3, "{err}");
    }
    // Negative control: at the step ends the bodies are never closer than 0.9 apart, so a
    // monitor of step ends alone would report 0.93 or more.
    let table = std::fs::read_to_string(&csv).unwrap();
    let nearest_end = table
        .lines()
        .skip(1)
        .map(|line| {
            let x: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
            ((x[2] - x[4]).powi(2) + (x[3] - x[5]).powi(2)).sqrt()
        })
        .fold(f64::INFINITY, f64::min);
    assert!(nearest_end > 0.9, "{nearest_end}");
}

#[test]
fn over_long_output_names_are_refused_before_the_work_by_every_file_writer() {
    let dir = scratch("long-names-all");
    std::fs::write(dir.join("s.toml"), robust::TWO_BODY).unwrap();
    for len in [241, 248, 255] {
        let csv = format!("{}.csv", "x".repeat(len - 4));
        let svg = format!("{}.svg", "x".repeat(len - 4));
        let json = format!("{}.json", "x".repeat(len - 5));
        let cases: [&[&str]; 7] = [
            &[
                "run", "kepler", "--steps", "3", "--format", "json", "--output", &json,
            ],
            &[
                "run", "kepler", "--steps", "3", "--tol", "1e-6", "--output", &csv,
            ],
            &["periodic", "figure-eight", "--output", &json],
            &["periodic", "figure-eight", "--plot", &svg],
            &[
                "ensemble",
                "s.toml",
                "--count",
                "2",
                "--perturb",
                "0",
                "--steps",
                "3",
                "--output",
                &csv,
            ],
            &[
                "work-precision",
                "kepler",
                "--quick",
                "--write-reference",
                &csv,
            ],
            // The chart's sibling for the inner bodies is 6 bytes longer than --plot.
            &["run", "s.toml", "--steps", "3", "--plot", &svg[6..]],
        ];
        for args in cases {
            let o = gvi_in(&dir, args);
            let err = stderr(&o);
            assert!(!o.status.success(), "{args:?}: {err}");
            assert!(err.contains(" bytes; at most 238"), "{args:?}: {err}");
            // Before the work: no run summary, no orbit found.
            assert!(!err.contains("Newton iterations"), "{args:?}: {err}");
            assert!(!err.contains("period"), "{args:?}: {err}");
        }
    }
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["s.toml"]);
}
