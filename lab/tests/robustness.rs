//! Nothing lost, nothing silently wrong: every case of issue #22 through the `gvi` binary.
//! Outputs are atomic and checked before any work, non-finite results are typed failures
//! with the steps before them kept, suspicious runs warn (errors with `--strict`), studies
//! refuse invalid input, commands refuse flags they would ignore, and messages name the
//! field and the value.

use crate::common::robust;
use robust::*;
use std::path::{Path, PathBuf};

fn rows(text: &str) -> Vec<&str> {
    text.lines().skip(1).collect()
}

#[test]
fn a_blow_up_is_a_typed_failure_with_the_steps_before_it_written() {
    let dir = scratch("blowup");
    let out = dir.join("h.csv");
    let o = gvi(&[
        "run",
        "harmonic",
        "--h",
        "1000",
        "--n",
        "4",
        "--steps",
        "1000",
        "--output",
        s(&out),
    ]);
    fails_with(&o, "non-finite");
    let text = std::fs::read_to_string(&out).unwrap();
    let rows = rows(&text);
    assert!(rows.len() > 100 && rows.len() < 1001, "{} rows", rows.len());
    for r in &rows {
        assert!(
            !r.contains("inf") && !r.contains("NaN"),
            "non-finite row: {r}"
        );
    }
    // The failing step is the one after the last row written.
    let last: usize = rows
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        stderr(&o).contains(&format!("at step {}", last + 1)),
        "{}",
        stderr(&o)
    );
}

#[test]
fn non_finite_invariants_at_the_start_are_errors_not_zero_errors() {
    let o = gvi(&["run", "kepler", "--q0", "1e308,1e308", "--steps", "3"]);
    fails_with(&o, "non-finite");
    assert!(!stderr(&o).contains("error: 0.000e0"));
    let o = gvi(&[
        "run",
        "figure-eight",
        "--p0",
        "1e300,0,0,0,0,0",
        "--steps",
        "3",
    ]);
    fails_with(&o, "non-finite");
}

#[test]
fn wildly_wrong_runs_warn_and_fail_with_strict() {
    for args in [
        &[
            "run", "harmonic", "--h", "1000", "--n", "4", "--steps", "10",
        ][..],
        &["run", "kepler", "--h", "6", "--n", "8", "--steps", "20"],
        &["run", "kepler", "--h", "1e5", "--steps", "3"],
        &[
            "run",
            "figure-eight",
            "--h",
            "5",
            "--n",
            "8",
            "--steps",
            "20",
        ],
        &["run", "kepler", "--tol", "1e10", "--steps", "3"],
    ] {
        let o = gvi(args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains("warning: relative"), "{args:?}: {err}");
        let mut strict = args.to_vec();
        strict.push("--strict");
        fails_with(&gvi(&strict), "--strict");
    }
    // A good run has no warning and passes --strict (the negative control).
    let o = gvi(&["run", "kepler", "--steps", "20", "--strict"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

#[test]
fn huge_step_is_printed_in_scientific_notation() {
    let o = gvi(&["run", "kepler", "--h", "1e300", "--steps", "2"]);
    let err = stderr(&o);
    assert!(err.contains("h = 1e300"), "{err}");
    assert!(!err.contains("10000000000000000000000"), "{err}");
}

#[test]
fn nbody_runs_report_relative_energy_errors_and_the_closest_approach() {
    let o = gvi(&["run", "two-body", "--steps", "10"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("max energy error:") && err.contains("(relative"),
        "{err}"
    );
    assert!(
        err.contains("closest approach on the Galerkin curves: body 1 and body 2"),
        "{err}"
    );
}

fn write_scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn coincident_bodies_are_a_collision_error() {
    let dir = scratch("collide");
    let text = TWO_BODY.replace("q = [0.2, 0.0]", "q = [-0.2, 0.0]");
    let scene = write_scene(&dir, "c.toml", &text);
    let o = gvi(&["run", s(&scene), "--steps", "3"]);
    fails_with(&o, "collide");
    // A head-on approach the step cannot resolve is reported.
    let text = TWO_BODY
        .replace("v = [0.0, -1.0]", "v = [3.0, 0.0]")
        .replace("v = [0.0, 1.0]", "v = [-3.0, 0.0]");
    let scene = write_scene(&dir, "head-on.toml", &text);
    let o = gvi(&["run", s(&scene), "--steps", "40", "--h", "0.01", "--n", "8"]);
    let err = stderr(&o);
    assert!(
        err.contains("closest approach on the Galerkin curves: body 1 and body 2"),
        "{err}"
    );
    assert!(err.contains("close encounter not resolved"), "{err}");
    fails_with(
        &gvi(&[
            "run",
            s(&scene),
            "--steps",
            "40",
            "--h",
            "0.01",
            "--n",
            "8",
            "--strict",
        ]),
        "close encounter",
    );
}

#[test]
fn a_huge_t0_is_rejected() {
    let dir = scratch("t0");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/kepler.toml"
    ))
    .unwrap();
    let text = text.replace("t0 = 0.0", "t0 = 1.7e308");
    let scene = write_scene(&dir, "t0.toml", &text);
    let o = gvi(&["run", s(&scene), "--steps", "3"]);
    fails_with(&o, "invalid parameter t0 = 1.7e308");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/kepler.toml"
    ))
    .unwrap()
    .replace("t0 = 0.0", "t0 = nan");
    let scene = write_scene(&dir, "nan.toml", &text);
    fails_with(
        &gvi(&["run", s(&scene), "--steps", "3"]),
        "t0 in [initial]): NaN",
    );
}

// ---- studies ----

#[test]
fn studies_reject_invalid_input() {
    let dir = scratch("studies");
    let out = s(&dir);
    let o = gvi(&[
        "stability",
        "kepler",
        "--q0",
        "nan,nan",
        "--quick",
        "--out",
        out,
    ]);
    fails_with(&o, "--q0");
    let o = gvi(&[
        "stability",
        "kepler",
        "--h",
        "nan",
        "--n",
        "0",
        "--steps",
        "0",
        "--out",
        out,
    ]);
    fails_with(&o, "--h");
    let o = gvi(&[
        "refine",
        "kepler",
        "--vary",
        "h",
        "--range",
        "1e-300:1e-299:x1.1",
        "--out",
        out,
    ]);
    fails_with(&o, "--range");
    let o = gvi(&[
        "refine",
        "kepler",
        "--vary",
        "h",
        "--range",
        "1:1e300:x10",
        "--out",
        out,
    ]);
    fails_with(&o, "longer than the horizon");
    let o = gvi(&[
        "refine",
        "kepler",
        "--vary",
        "n",
        "--range",
        "4:6:1",
        "--quad-points",
        "2",
        "--out",
        out,
    ]);
    fails_with(&o, "all 3 runs of the study failed");
}

#[test]
fn failed_study_rows_carry_no_error_figures() {
    let dir = scratch("rows");
    // Four Gauss points (degree 7) integrate the kinetic terms up to n = 4: n = 6, 8 fail.
    let o = gvi(&[
        "refine",
        "kepler",
        "--vary",
        "n",
        "--range",
        "2:8:2",
        "--quad-points",
        "4",
        "--out",
        s(&dir),
    ]);
    let csv = std::fs::read_to_string(dir.join("refine.csv")).unwrap_or_default();
    assert!(o.status.success() || !csv.is_empty(), "{}", stderr(&o));
    let failed_rows = csv.lines().filter(|l| l.ends_with('"')).count();
    assert_eq!(failed_rows, 2, "{csv}");
    for line in csv.lines().skip(1) {
        let failed = line.ends_with('"');
        let cells: Vec<&str> = line.split(',').collect();
        if failed {
            // map_error, curve_error, energy_error
            for c in &cells[5..8] {
                assert_eq!(*c, "NaN", "failed row with an error figure: {line}");
            }
        }
    }
}

// ---- flags and messages ----

#[test]
fn commands_refuse_flags_they_would_ignore() {
    for args in [
        &["check", "kepler", "--output", "x.csv"][..],
        &["check", "kepler", "--plot", "x.svg"],
        &["check", "kepler", "--tol", "1e-6"],
        &["check", "kepler", "--auto-h"],
        &[
            "refine", "kepler", "--vary", "n", "--range", "4:8:2", "--output", "x",
        ],
        &[
            "refine", "kepler", "--vary", "n", "--range", "4:8:2", "--format", "json",
        ],
        &["run", "kepler", "--ladder", "4,6"],
        &["run", "kepler", "--control", "indicator"],
        &["run", "kepler", "--auto-h"],
    ] {
        let o = gvi(args);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{args:?} accepted: {}",
            stderr(&o)
        );
    }
}

#[test]
fn messages_name_the_field_and_the_value() {
    let dir = scratch("messages");
    fails_with(&gvi(&["run", "kepler", "--q0", "inf,0"]), "q0");
    let kepler = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/kepler.toml"
    ))
    .unwrap();
    let mu = kepler.replace("mu = 1.0", "mu = 1e308");
    let scene = write_scene(&dir, "mu.toml", &mu);
    fails_with(&gvi(&["run", s(&scene), "--steps", "2"]), "mu = 1e308");
    fails_with(&gvi(&["run", s(&dir)]), "a directory");
    fails_with(&gvi(&["run", "/dev/null"]), "not a regular file");
    fails_with(
        &gvi(&[
            "nbody-report",
            "two-body",
            "--substeps",
            "0",
            "--out",
            s(&dir),
        ]),
        "--substeps",
    );
    let gm = TWO_BODY
        .replace("mass = 0.5", "gm = -1")
        .replace("g = 1.0\n", "");
    let scene = write_scene(&dir, "gm.toml", &gm);
    fails_with(
        &gvi(&["run", s(&scene)]),
        "gm must be finite and positive, got -1",
    );
    let typo = TWO_BODY.replacen("mass = 0.5", "mass = 0.5\nmas = 1", 1);
    let line = typo.lines().position(|l| l == "mas = 1").unwrap() + 1;
    let scene = write_scene(&dir, "typo.toml", &typo);
    fails_with(
        &gvi(&["run", s(&scene)]),
        &format!("line {line}: unknown field `mas`"),
    );
    let help = stdout(&gvi(&["run", "--help"]));
    assert!(
        help.contains("legendre") && help.contains("gauss-lobatto"),
        "{help}"
    );
    assert!(!help.contains("as they are available"), "{help}");
}

#[test]
fn shipped_scenes_pass_strict_without_warnings() {
    // The negative control of the sanity warnings: accurate runs raise none (the solar system
    // with h = 100 d steps over Mercury's 88-day orbit is not a "close encounter").
    for args in [
        &["run", "harmonic", "--strict"][..],
        &["run", "kepler", "--strict"],
        &["run", "pendulum", "--strict"],
        &["run", "two-body", "--strict"],
        &["run", "figure-eight", "--strict"],
        &["run", "solar-system", "--steps", "20", "--strict"],
    ] {
        let o = gvi(args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("warning"), "{args:?}: {}", stderr(&o));
    }
    // Mercury ejected by n = 6 is flagged. At n < 10 the stage equations at h = 100 d have
    // several nearby solutions (a degree-5 curve over more than one Mercury orbit), and which
    // one a solver finds depends on its path: exact Newton is the reference, and `auto` hands
    // a step its structured solvers fail on to exact Newton from the same guess, so it finds
    // the same one.
    for solver in ["exact", "auto"] {
        let o = gvi(&[
            "run",
            "solar-system",
            "--n",
            "6",
            "--steps",
            "100",
            "--solver",
            solver,
        ]);
        assert!(
            stderr(&o).contains("warning: relative energy error"),
            "{solver}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn absurd_study_sizes_are_refused_with_the_estimate() {
    let dir = scratch("sizes");
    let o = gvi(&[
        "stability",
        "kepler",
        "--cell-steps",
        "100000000",
        "--out",
        s(&dir),
    ]);
    fails_with(&o, "refusing the sweep");
    let o = gvi(&[
        "compare-bases",
        "kepler",
        "--steps",
        "100000000",
        "--out",
        s(&dir),
    ]);
    fails_with(&o, "refusing the sweep");
    let o = gvi(&[
        "refine",
        "kepler",
        "--vary",
        "n",
        "--range",
        "4:8:2",
        "--steps",
        "100000000",
        "--out",
        s(&dir),
    ]);
    fails_with(&o, "refusing the sweep");
}

#[test]
fn check_reports_an_overflowing_run_as_a_failure() {
    fails_with(
        &gvi(&[
            "check", "harmonic", "--h", "1000", "--n", "4", "--steps", "300",
        ]),
        "non-finite energy",
    );
    fails_with(
        &gvi(&["check", "kepler", "--q0", "1e308,1e308", "--steps", "3"]),
        "non-finite",
    );
    let o = gvi(&["check", "kepler", "--steps", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A Hermite basis so large that its kinetic matrix is numerically singular (the issue's
/// `--n 1024`; n = 256 shows the same in a fraction of the time) blames the basis size, not
/// the quadrature, which is exact for it.
#[test]
fn an_ill_conditioned_basis_is_blamed_not_the_quadrature() {
    let o = gvi(&[
        "run", "harmonic", "--basis", "hermite", "--n", "256", "--steps", "2",
    ]);
    fails_with(&o, "kinetic matrix is numerically singular");
    let err = stderr(&o);
    assert!(
        err.contains("is exact for it") && err.contains("smaller n"),
        "{err}"
    );
}

/// Studies refuse the scene flags they sweep themselves instead of ignoring them.
#[test]
fn studies_refuse_the_flags_they_sweep() {
    let dir = scratch("swept");
    let out = dir.join("study");
    let o = gvi(&["compare-bases", "kepler", "--n", "8", "--out", s(&out)]);
    fails_with(&o, "does not use --n");
    let o = gvi(&[
        "compare-bases",
        "kepler",
        "--basis",
        "legendre",
        "--out",
        s(&out),
    ]);
    fails_with(&o, "does not use --basis");
    let o = gvi(&[
        "refine",
        "kepler",
        "--vary",
        "n",
        "--range",
        "4:8:2",
        "--n",
        "6",
        "--out",
        s(&out),
    ]);
    fails_with(&o, "does not use --n");
    let o = gvi(&[
        "refine",
        "kepler",
        "--vary",
        "h",
        "--range",
        "0.5:1:x2",
        "--h",
        "1",
        "--out",
        s(&out),
    ]);
    fails_with(&o, "does not use --h");
    let o = gvi(&[
        "work-precision",
        "kepler",
        "--quick",
        "--solver",
        "exact",
        "--out",
        s(&out),
    ]);
    fails_with(&o, "does not use --solver");
    let o = gvi(&[
        "compare-refinement",
        "kepler",
        "--quick",
        "--n",
        "8",
        "--out",
        s(&out),
    ]);
    fails_with(&o, "does not use --n");
    assert!(!out.exists(), "nothing is written for a refused command");
}
