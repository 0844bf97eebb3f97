//! Issue 32 class 7 through the CLI: the run summary's relative energy error has a scale that
//! does not vanish (a parabolic orbit passes `--strict`), the summary gives the whole
//! command's wall time beside the integration's, the closest approach of two bodies is found
//! on the Galerkin curves (not only at step ends), and over-long output names are refused
//! before the work by every command that writes a file.

use crate::common::robust;

use robust::{fails_with, gvi, s, scratch, stderr};
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
