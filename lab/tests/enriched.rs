//! The enriched basis and the Fermi–Pasta–Ulam scene selected by name: the `fpu` and
//! `varying-frequency` scenes, `--basis enriched --omega`, and the typed errors of bad input
//! (docs/guide/enriched-bases.md).

use crate::common::cli::gvi;
use galerkin_vi::GviError;
use galerkin_vi::basis::BasisKind;
use galerkin_vi::solve::solve;
use galerkin_vi::systems::System;
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::scene::{BuiltSystem, Overrides, Scene};

/// The `fpu` scene builds the book's chain and initial value with the enriched basis at
/// ωh = 2; 500 steps (T = 20) keep the oscillatory energy I within the exact flow's own
/// O(1/ω) excursion (0.062 over T = 200, measured against DOP853) of I(0) = 1.
#[test]
fn fpu_scene_runs_with_the_enriched_basis() {
    let scene = Scene::load("fpu")
        .unwrap()
        .with_overrides(&Overrides {
            steps: Some(500),
            ..Overrides::default()
        })
        .build()
        .unwrap();
    assert_eq!(
        (scene.method.basis, scene.method.omega.clone(), scene.method.n),
        (BasisKind::Enriched, Some(vec![50.0]), 7)
    );
    let BuiltSystem::Euclidean(system) = &scene.system else {
        panic!("fpu is Euclidean");
    };
    assert_eq!(system.name(), "fpu");
    let solution = solve(system, &scene.initial, &scene.method).unwrap();
    let traj = solution.trajectory;
    let mut inv = vec![0.0; system.invariant_names().len()];
    let worst = traj.q.iter().zip(&traj.p).fold(0.0f64, |m, (q, p)| {
        system.invariants(q, p, &mut inv);
        m.max((inv[1] - 1.0).abs())
    });
    assert!(worst < 0.07, "I deviates by {worst}");
    // The enriched integrator took at least its own Gauss count.
    let gvi = scene.method.integrator().unwrap();
    assert!(gvi.rule().len() >= 14);
}

/// By name on any scene, with its typed errors: ω missing, ω bad, ω given to another basis,
/// too few functions, and a basis change that drops the scene's ω.
#[test]
fn enriched_by_name_and_its_errors() {
    let with = |name: &str, o: Overrides| -> Result<_, LabError> {
        let scene = Scene::load(name)?.with_overrides(&o).build()?;
        Ok(scene.method.integrator()?)
    };
    let enriched = |omega: Option<f64>, n: usize| Overrides {
        basis: Some(BasisKind::Enriched),
        omega: omega.map(|w| vec![w]),
        n: Some(n),
        ..Overrides::default()
    };
    let gvi = with("kepler", enriched(Some(1.0), 9)).unwrap();
    assert_eq!(gvi.basis().kind(), BasisKind::Enriched);
    let core = |r: Result<_, LabError>| match r {
        Err(LabError::Core(e)) => e,
        Err(e) => panic!("expected a core error, got {e}"),
        Ok(_) => panic!("expected an error"),
    };
    let e = core(with("kepler", enriched(None, 9)));
    assert!(
        matches!(&e, GviError::InvalidInput { name, .. } if name == "basis"),
        "{e}"
    );
    for bad in [0.0, -2.0, f64::NAN, f64::INFINITY] {
        let e = core(with("kepler", enriched(Some(bad), 9)));
        assert!(
            matches!(&e, GviError::InvalidParameter { name, .. } if name == "omega"),
            "{e}"
        );
    }
    let e = core(with("kepler", enriched(Some(1.0), 3)));
    assert!(matches!(e, GviError::InvalidBasisSize { .. }), "{e}");
    let e = core(with(
        "kepler",
        Overrides {
            omega: Some(vec![1.0]),
            ..Overrides::default()
        },
    ));
    assert!(
        matches!(&e, GviError::InvalidInput { name, .. } if name == "omega"),
        "{e}"
    );
    // `--basis chebyshev` on the enriched fpu scene drops its ω instead of failing.
    let gvi = with(
        "fpu",
        Overrides {
            basis: Some(BasisKind::Chebyshev),
            ..Overrides::default()
        },
    )
    .unwrap();
    assert_eq!(gvi.basis().kind(), BasisKind::Chebyshev);
}

/// The command line: `--basis enriched --omega` runs, and bad values are refused with the
/// parameter named (exit status 1, nothing on stdout).
#[test]
fn command_line_selects_the_enriched_basis() {
    let (code, out, err) = gvi(&["run", "fpu", "--steps", "50"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.lines()
            .next()
            .unwrap_or("")
            .contains("oscillatory_energy"),
        "{out}"
    );
    let (code, _, err) = gvi(&[
        "run", "kepler", "--basis", "enriched", "--omega", "1", "--n", "9", "--steps", "10",
    ]);
    assert_eq!(code, 0, "{err}");
    for (args, needle) in [
        (
            vec!["run", "kepler", "--basis", "enriched", "--n", "9"],
            "omega",
        ),
        (
            vec![
                "run", "kepler", "--basis", "enriched", "--omega", "-1", "--n", "9",
            ],
            "omega",
        ),
        (vec!["run", "kepler", "--omega", "2"], "omega"),
        (vec!["run", "fpu", "--quad-points", "8"], "Gauss"),
    ] {
        let (code, out, err) = gvi(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(out.is_empty() && err.contains(needle), "{args:?}: {err}");
    }
}
