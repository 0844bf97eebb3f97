//! Every error variant of the core is reached through the API and through the CLI: typed
//! errors, non-zero exit codes, a message on stderr, never a panic.

use crate::common::cli::{assert_clean_failure, gvi};
use galerkin_vi::prelude::*;
use galerkin_vi_lab::scene::Scene;

fn kepler() -> Kepler {
    Kepler::new(1.0).unwrap()
}

#[test]
fn invalid_method_parameters() {
    assert!(matches!(
        GalerkinIntegrator::spectral(1, 1.0),
        Err(GviError::InvalidBasisSize { n: 1, .. })
    ));
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            GalerkinIntegrator::spectral(8, h),
            Err(GviError::InvalidStepSize { .. })
        ));
    }
    let gvi = GalerkinIntegrator::spectral(8, 0.1).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let e = gvi.integrate(&kepler(), 0.0, &q0, &p0, 0).unwrap_err();
    assert!(matches!(
        e.error,
        GviError::InvalidStepCount { steps: 0, .. }
    ));
    assert!(e.partial.is_none());
}

#[test]
fn quadrature_too_weak_for_the_basis() {
    // φ_a'φ_b' has degree 2n − 4: Gauss–Legendre needs n − 1 points. With n − 2 the stage
    // matrix is singular; the typed error says so instead of returning garbage.
    for n in [4, 8, 16] {
        let basis = ChebyshevLagrange::new(n).unwrap();
        let weak = GaussLegendre::new(n - 2).unwrap();
        match GalerkinIntegrator::new(basis.clone(), weak, 1.0) {
            Err(GviError::QuadratureTooWeak {
                n: got, required, ..
            }) => {
                assert_eq!(got, n);
                assert_eq!(required, 2 * n - 4);
            }
            other => panic!("n = {n}: expected QuadratureTooWeak, got {other:?}"),
        }
        // The minimum that keeps it invertible is accepted.
        assert!(GalerkinIntegrator::new(basis, GaussLegendre::new(n - 1).unwrap(), 1.0).is_ok());
    }
}

#[test]
fn mismatched_dimensions_and_non_finite_states() {
    let gvi = GalerkinIntegrator::spectral(8, 0.1).unwrap();
    let e = gvi
        .integrate(&kepler(), 0.0, &[0.4], &[0.0, 2.0], 5)
        .unwrap_err();
    assert!(matches!(
        e.error,
        GviError::DimensionMismatch {
            expected: 2,
            got: 1,
            ..
        }
    ));
    let e = gvi
        .integrate(&kepler(), 0.0, &[0.4, 0.0], &[0.0, 2.0, 1.0], 5)
        .unwrap_err();
    assert!(matches!(
        e.error,
        GviError::DimensionMismatch {
            expected: 2,
            got: 3,
            ..
        }
    ));
    let e = gvi
        .integrate(&kepler(), 0.0, &[f64::NAN, 0.0], &[0.0, 2.0], 5)
        .unwrap_err();
    assert!(matches!(e.error, GviError::NonFinite { .. }));
    let e = gvi
        .integrate(&kepler(), 0.0, &[0.4, 0.0], &[f64::INFINITY, 2.0], 5)
        .unwrap_err();
    assert!(matches!(e.error, GviError::NonFinite { .. }));
    let e = gvi
        .integrate(&kepler(), f64::NAN, &[0.4, 0.0], &[0.0, 2.0], 5)
        .unwrap_err();
    assert!(matches!(e.error, GviError::NonFinite { .. }));
    assert!(matches!(
        Kepler::new(-1.0),
        Err(GviError::InvalidParameter { .. })
    ));
}

#[test]
fn newton_failure_names_the_step_and_keeps_the_trajectory() {
    // A large-amplitude pendulum with a step of 1.6 small-oscillation periods and only n = 4:
    // the first step converges, the second has no root near any guess of exact Newton on the
    // nodal equations (it diverges). The default's velocity form, with other guesses and a
    // different route to the round-off, follows another branch of roots there; every
    // solver's failure reporting is checked in `solvers.rs`.
    let exact = NewtonOptions {
        solver: galerkin_vi::integrator::StageSolver::Exact,
        ..NewtonOptions::default()
    };
    let gvi = GalerkinIntegrator::spectral(4, 10.0)
        .unwrap()
        .with_options(exact);
    let failure = gvi
        .integrate(&Pendulum::unit(), 0.0, &[2.5], &[0.0], 40)
        .unwrap_err();
    match &failure.error {
        GviError::NewtonFailure {
            step,
            t,
            residual,
            iterations,
            ..
        } => {
            assert!(*step >= 1, "the first steps succeed");
            assert!((*t - 10.0 * *step as f64).abs() < 1e-12);
            assert!(*residual > 1e-6 && *iterations > 0);
            let partial = failure.partial.as_ref().expect("partial trajectory kept");
            assert_eq!(partial.steps(), *step);
            assert_eq!(partial.q.len(), step + 1);
        }
        other => panic!("expected a Newton failure, got {other:?}"),
    }
    let msg = failure.to_string();
    assert!(msg.contains("step") && msg.contains("residual"), "{msg}");
}

#[test]
fn dense_output_outside_the_time_span_is_an_error() {
    let gvi = GalerkinIntegrator::spectral(8, 0.5).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let traj = gvi.integrate(&kepler(), 0.0, &q0, &p0, 4).unwrap();
    assert!(traj.position_at(1.3).is_ok());
    assert!(matches!(
        traj.position_at(2.5),
        Err(GviError::InvalidInput { .. })
    ));
    assert!(matches!(
        traj.position_at(f64::NAN),
        Err(GviError::InvalidInput { .. })
    ));
}

#[test]
fn cli_reports_every_error_without_panicking() {
    assert_clean_failure(
        &["run", "kepler", "--n", "1"],
        "invalid number of basis functions",
    );
    assert_clean_failure(&["run", "kepler", "--h", "0"], "invalid step size");
    assert_clean_failure(&["run", "kepler", "--h", "-2"], "invalid step size");
    assert_clean_failure(&["run", "kepler", "--h", "NaN"], "invalid step size");
    assert_clean_failure(
        &["run", "kepler", "--steps", "0"],
        "invalid number of steps",
    );
    assert_clean_failure(
        &["run", "kepler", "--n", "8", "--quad-points", "6"],
        "quadrature too weak",
    );
    assert_clean_failure(
        &["run", "kepler", "--quad-points", "0"],
        "invalid quadrature",
    );
    assert_clean_failure(&["run", "kepler", "--q0", "0.4"], "dimension mismatch");
    assert_clean_failure(&["run", "kepler", "--q0", "nan,0"], "non-finite");
    assert_clean_failure(&["run", "kepler", "--q0", "abc,0"], "not a number");
    assert_clean_failure(&["run", "kepler", "--basis", "spline"], "unknown basis");
    assert_clean_failure(
        &["run", "kepler", "--quadrature", "simpson"],
        "unknown quadrature",
    );
    assert_clean_failure(&["run", "no-such-scene"], "not a built-in scene");
    let dir = std::env::temp_dir().join(format!("gvi-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[system]\ntype = \"kepler\"\nmu = -1\n[initial]\nq = [1, 0]\np = [0, 1]\n[method]\nn = 8\nh = 0.1\nsteps = 3\n").unwrap();
    assert_clean_failure(&["run", bad.to_str().unwrap()], "invalid parameter mu");
    std::fs::write(&bad, "[system]\ntype = \"kepler\"\n[initial]\nq = [1, 0]\n").unwrap();
    assert_clean_failure(&["run", bad.to_str().unwrap()], "scene error");
    // Newton failure: the completed steps are still written, then a non-zero exit.
    let (code, out, err) = gvi(&[
        "run", "pendulum", "--n", "4", "--h", "10", "--steps", "40", "--solver", "exact",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("Newton solve failed at step"), "{err}");
    assert!(!err.contains("panicked"));
    let rows = out.lines().count();
    assert!(rows >= 3, "header plus the completed steps: {out}");
}

#[test]
fn cli_run_writes_the_documented_columns() {
    let (code, out, err) = gvi(&["run", "kepler", "--n", "12", "--steps", "5"]);
    assert_eq!(code, 0, "{err}");
    let header = out.lines().next().unwrap();
    assert_eq!(
        header,
        "step,t,q0,q1,p0,p1,energy,angular_momentum,position_error"
    );
    assert_eq!(out.lines().count(), 7);
    assert!(err.contains("max position error"), "{err}");
    let (code, out, _) = gvi(&[
        "run", "harmonic", "--n", "20", "--steps", "3", "--format", "json",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["trajectory"]["coefficients"].as_array().unwrap().len(), 3);
    let s = Scene::load("pendulum").unwrap();
    assert_eq!(s.initial.q.len(), 1);
}

#[test]
fn cli_check_prints_the_geometric_diagnostics() {
    let (code, out, err) = gvi(&[
        "check", "kepler", "--n", "12", "--h", "0.5", "--steps", "20",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("symplecticity defect"), "{out}");
    assert!(out.contains("angular_momentum"), "{out}");
    assert_clean_failure(
        &["check", "kepler", "--n", "0"],
        "invalid number of basis functions",
    );
}

#[test]
fn cli_tol_adds_the_n_column_and_rejects_bad_tolerances() {
    let (code, out, err) = gvi(&[
        "run", "kepler", "--tol", "1e-8", "--h", "1", "--steps", "10",
    ]);
    assert_eq!(code, 0, "{err}");
    let header = out.lines().next().unwrap();
    assert!(
        header.ends_with(",position_error,n,indicator,estimate"),
        "{header}"
    );
    let row: Vec<&str> = out.lines().nth(1 + 5).unwrap().split(',').collect();
    let n: usize = row[row.len() - 3].parse().unwrap();
    // The default (embedded) control checks every step: the estimate is a number.
    let estimate: f64 = row[row.len() - 1].parse().unwrap();
    assert!(estimate.is_finite() && estimate >= 0.0, "{estimate}");
    assert!((4..=64).contains(&n));
    assert_clean_failure(&["run", "kepler", "--tol", "-1"], "tol");
    assert_clean_failure(
        &["run", "kepler", "--tol", "1e-8", "--ladder", "8,4"],
        "ladder",
    );
    let (code, _, err) = gvi(&["run", "kepler", "--tol", "1e-30", "--steps", "2"]);
    assert_eq!(code, 0);
    assert!(err.contains("warning"), "{err}");
    assert_clean_failure(
        &["run", "kepler", "--tol", "1e-8", "--control", "magic"],
        "control",
    );
    // --auto-h: h chosen from the tolerance and the orbital period, reported; it needs --tol.
    let (code, out, err) = gvi(&[
        "run", "kepler", "--tol", "1e-8", "--h", "1", "--steps", "20", "--auto-h",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("h chosen from tol"), "{err}");
    let last: f64 = out
        .lines()
        .last()
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (last - 20.0).abs() < 1e-9,
        "the horizon h·steps is kept: t_end = {last}"
    );
    assert_clean_failure(&["run", "kepler", "--auto-h"], "--tol"); // clap: --auto-h requires --tol
}

#[test]
fn cli_tolerance_study_writes_table_csv_and_charts() {
    let dir = std::env::temp_dir().join(format!("gvi-tolstudy-{}", std::process::id()));
    let (code, out, err) = gvi(&[
        "tolerance-study",
        "harmonic",
        "--tols",
        "1e-6:1e-7",
        "--h",
        "1",
        "--steps",
        "10",
        "--ladder",
        "4,6,8,10,12",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("| 1e-6 | embedded |"), "{out}");
    for f in ["csv", "md"] {
        assert!(dir.join(format!("harmonic-tolerance.{f}")).exists());
    }
    assert!(dir.join("harmonic-tolerance-error.svg").exists());
    assert!(dir.join("harmonic-tolerance-cost.svg").exists());
    std::fs::remove_dir_all(&dir).ok();
    assert_clean_failure(&["tolerance-study", "harmonic", "--tols", "0:1e-6"], "tols");
}

#[test]
fn cli_economical_quadrature_uses_three_halves_n_points() {
    let (code, _, err) = gvi(&["run", "kepler", "--n", "32", "--steps", "3", "--economical"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("gauss-legendre with 48 points"), "{err}");
    assert_eq!(
        galerkin_vi::quadrature::QuadratureKind::GaussLegendre.economical_points(7),
        11
    );
}
