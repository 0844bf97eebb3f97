//! The enriched basis and the Fermi–Pasta–Ulam scene selected by name: the `fpu` and
//! `varying-frequency` scenes, `--basis enriched --omega`, and the typed errors of bad input
//! (docs/guide/enriched-bases.md).

use crate::common::cli::gvi;
use crate::common::scenes::{built, euclidean, invariants_along};
use galerkin_vi::GviError;
use galerkin_vi::basis::{Basis, BasisKind};
use galerkin_vi::systems::System;
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::scene::{Overrides, Scene};

/// The `fpu` scene builds the book's chain and initial value with the enriched basis at
/// ωh = 2; 500 steps (T = 20) keep the oscillatory energy I within the exact flow's own
/// O(1/ω) excursion (0.062 over T = 200, measured against DOP853) of I(0) = 1.
#[test]
fn fpu_scene_runs_with_the_enriched_basis() {
    let scene = built("fpu", Some(500));
    assert_eq!(
        (
            scene.method.basis,
            scene.method.omega.clone(),
            scene.method.n
        ),
        (BasisKind::Enriched, Some(vec![50.0]), 7)
    );
    assert_eq!(euclidean(&scene).name(), "fpu");
    let worst = invariants_along(&scene)
        .iter()
        .fold(0.0f64, |m, inv| m.max((inv[1] - 1.0).abs()));
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

/// Several frequencies by name: the `fpu-two-frequency` scene (stiff springs of ω = 50 and
/// ω = 20, `omega = [50.0, 20.0]` in its method) builds the two-frequency basis and keeps the
/// energy to round-off; `--omega 50,20` selects it on the command line; a frequency list that
/// does not match the springs, and frequencies that cannot be told apart, are typed errors.
#[test]
fn several_frequencies_by_name_and_their_errors() {
    let scene = built("fpu-two-frequency", Some(48));
    assert_eq!(
        (scene.method.omega.clone(), scene.method.n),
        (Some(vec![50.0, 20.0]), 9)
    );
    let gvi_built = scene.method.integrator().unwrap();
    assert_eq!(gvi_built.basis().len(), 9);
    let inv = invariants_along(&scene);
    let (h0, i0) = (inv[0][0], inv[0][1]);
    assert_eq!(i0, 2.0);
    let worst = inv.iter().fold(0.0f64, |m, i| m.max((i[0] - h0).abs()));
    // A symplectic map at ωh = 5 and 2: the energy error stays at round-off level (measured
    // 3.6e-12 over the scene's 200 steps, `gvi run fpu-two-frequency`).
    assert!(worst < 1e-9, "energy error {worst}");

    let (code, out, err) = gvi(&["run", "fpu-two-frequency", "--steps", "10"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.lines().next().unwrap_or("").contains("I4"), "{out}");
    let (code, _, err) = gvi(&[
        "run", "fpu", "--omega", "50,20", "--n", "9", "--h", "0.1", "--steps", "10",
    ]);
    assert_eq!(code, 0, "{err}");
    for (args, needle) in [
        // Equal frequencies: refused, not merged.
        (
            vec!["run", "fpu", "--omega", "50,50", "--n", "9", "--h", "0.1"],
            "cannot be told apart",
        ),
        (
            vec!["run", "fpu", "--omega", "50,x", "--n", "9"],
            "not a number",
        ),
        // Two frequencies take 4 functions: n = 5 leaves no polynomial degree ≥ 1.
        (vec!["run", "fpu", "--omega", "50,20", "--n", "5"], "n ≥ 6"),
    ] {
        let (code, out, err) = gvi(&args);
        assert_ne!(code, 0, "{args:?}: {err}");
        assert!(out.is_empty() && err.contains(needle), "{args:?}: {err}");
    }

    // A frequency list that matches neither one frequency nor one per spring.
    let text = "name = \"bad\"\n[system]\ntype = \"fpu\"\nsprings = 3\nomega = [50.0, 20.0]\n\
                [initial]\nq = [1, 0, 0, 0.02, 0, 0]\np = [1, 0, 0, 1, 0, 0]\n\
                [method]\nn = 8\nh = 0.1\nsteps = 10\n";
    let e = Scene::from_toml_str("bad", text)
        .unwrap()
        .build()
        .unwrap_err();
    assert!(
        matches!(&e, LabError::Scene { reason, .. } if reason.contains("one per spring")),
        "{e}"
    );
    // Round trip: a single frequency is written back as a number, a list as a list.
    let fpu = Scene::load("fpu-two-frequency").unwrap();
    let again = Scene::from_toml_str("again", &toml::to_string(&fpu).unwrap()).unwrap();
    assert_eq!(again.method.omega, fpu.method.omega);
}

/// The `spring-pendulum` scene: the stiff spring pendulum with the enriched basis at its rest
/// frequency, ωh = 2. The energy stays at round-off level along the run, the spring's
/// oscillatory energy near its initial 1/2, and the reported fast frequency sweeps above 50.
#[test]
fn spring_pendulum_scene_runs_with_the_enriched_basis() {
    let scene = built("spring-pendulum", None);
    assert_eq!(euclidean(&scene).name(), "spring-pendulum");
    let along = invariants_along(&scene);
    let (h0, i0) = (along[0][0], along[0][1]);
    let (mut worst_h, mut worst_i, mut top) = (0.0f64, 0.0f64, 0.0f64);
    for inv in &along {
        worst_h = worst_h.max((inv[0] - h0).abs());
        worst_i = worst_i.max((inv[1] - i0).abs());
        top = top.max(inv[2]);
    }
    println!(
        "spring pendulum: |ΔH| {worst_h:.1e}, |ΔI| {worst_i:.1e}, I(0) {i0:.4}, max ω_fast {top:.3}"
    );
    assert!((i0 - 0.5).abs() < 0.01, "I(0) = {i0}");
    assert!(worst_h < 1e-8, "energy error {worst_h}");
    // Measured 0.042 over T = 20: the flow's own O(1/ω)-type wobble of I about its mean as the
    // swing modulates the fast frequency (the energy error is 5.7e-12).
    assert!(worst_i < 0.06, "oscillatory energy moved by {worst_i}");
    // Measured 50.035 (√(50² + 3φ̇²) with φ̇ ≤ 1.02 at the bottom).
    assert!(top > 50.0 && top < 50.1, "fast frequency {top}");
}
