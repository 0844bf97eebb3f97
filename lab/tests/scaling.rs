//! The solver-scaling study and the planetesimal-ring generator.

use galerkin_vi::GviError;
use galerkin_vi::systems::System;
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::ring::{RingConfig, planetesimal_ring};
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::scaling::{SOLVERS, ScalingConfig, solver_scaling};

#[test]
fn quick_study_runs_every_solver_and_agrees_with_exact() {
    let study = solver_scaling(&ScalingConfig::quick(), false).unwrap();
    for family in ["kepler", "outer-solar-system", "ring"] {
        for solver in SOLVERS {
            let rows: Vec<_> = study
                .points
                .iter()
                .filter(|p| p.family == family && p.solver == solver.as_str())
                .collect();
            assert_eq!(rows.len(), 3, "{family} {solver}");
            for p in rows {
                assert!(p.failure.is_none() && p.skipped.is_none(), "{p:?}");
                assert!(p.seconds_per_step > 0.0 && p.iterations >= 1.0, "{p:?}");
                // Every solver converges the same stage equations to the Newton tolerance:
                // measured ≤ 1.2e-13 relative over these runs (outer solar system, n = 32,
                // 2 steps of 5 years); 1e-11 leaves room for other machines' rounding.
                let d = p.map_difference.unwrap();
                assert!(d <= 1e-11, "{family} {solver} n = {}: {d:e}", p.n);
            }
        }
    }
    assert_eq!(study.fits.len(), 15); // five solvers, three families
    for f in &study.fits {
        let p = f.exponent.unwrap();
        assert!(p.is_finite() && f.points == 3, "{f:?}");
    }
    // auto runs at every point, so there is a ratio at each.
    assert_eq!(study.ratios.len(), 9);
    assert!(
        study
            .ratios
            .iter()
            .all(|r| r.ratio.is_finite() && r.ratio > 0.0)
    );
    let dir = std::env::temp_dir().join(format!("gvi-scaling-{}", std::process::id()));
    let files = study.write(&dir).unwrap();
    assert_eq!(files.len(), 5);
    let csv = std::fs::read_to_string(&files[0]).unwrap();
    assert_eq!(csv.lines().count(), 1 + 45); // nine points, five solvers
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn skipped_points_are_recorded_with_a_reason() {
    let config = ScalingConfig {
        ns: vec![8],
        bodies: vec![64],
        budget_seconds: 1e-3,
        ..ScalingConfig::quick()
    };
    let study = solver_scaling(&config, false).unwrap();
    let exact = study
        .points
        .iter()
        .find(|p| p.family == "ring" && p.solver == "exact")
        .unwrap();
    // (n − 1)·D = 15·192 = 2880: a ~16 Gflop factorisation.
    assert!(
        exact.skipped.as_deref().unwrap().contains("2880"),
        "{exact:?}"
    );
    assert!(exact.seconds_per_step.is_nan() && exact.map_difference.is_none());
}

#[test]
fn ring_is_barycentric_and_deterministic() {
    let config = RingConfig::with_bodies(32);
    let (system, init) = planetesimal_ring(&config).unwrap();
    assert_eq!(system.bodies(), 32);
    assert_eq!(init.q.len(), 96);
    let (again_system, again) = planetesimal_ring(&config).unwrap();
    assert_eq!((again.q, again.p), (init.q.clone(), init.p.clone()));
    assert_eq!(again_system.masses(), system.masses());
    let other = planetesimal_ring(&RingConfig {
        seed: 7,
        ..config.clone()
    })
    .unwrap()
    .1;
    assert_ne!(other.q, init.q);
    // Total momentum and mass-weighted position vanish to round-off.
    for k in 0..3 {
        let p: f64 = (0..32).map(|b| init.p[3 * b + k]).sum();
        let c: f64 = (0..32)
            .map(|b| system.masses()[b] * init.q[3 * b + k])
            .sum();
        assert!(p.abs() < 1e-16 && c.abs() < 1e-16, "{k}: {p:e} {c:e}");
    }
    // Near-Keplerian: every planetesimal within [inner(1 − e), outer(1 + e)] of the star,
    // and the energy is that of the orbits (−Σ m/(2a) within the planetesimals' coupling).
    for b in 1..32 {
        let r: f64 = (0..3)
            .map(|k| (init.q[3 * b + k] - init.q[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((0.95..=2.1).contains(&r), "body {b}: r = {r}");
    }
    let mut inv = vec![0.0; system.invariant_names().len()];
    system.invariants(&init.q, &init.p, &mut inv);
    assert!(inv[0] < 0.0 && inv[0] > -31.0 * 1e-7, "energy {}", inv[0]);
}

#[test]
fn ring_scene_file_matches_the_generator() {
    let text = RingConfig::default().scene_toml().unwrap();
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/planetesimal-ring.toml"
    );
    if std::env::var_os("GVI_WRITE_RING_SCENE").is_some() {
        std::fs::write(path, &text).unwrap();
    }
    assert_eq!(std::fs::read_to_string(path).unwrap(), text);
    let scene = Scene::load("planetesimal-ring").unwrap().build().unwrap();
    let (_, init) = planetesimal_ring(&RingConfig::default()).unwrap();
    assert_eq!((scene.initial.q, scene.initial.p), (init.q, init.p));
    assert!((scene.method.h - std::f64::consts::TAU / 8.0).abs() < 1e-15);
}

#[test]
fn bad_input_is_a_typed_error() {
    for bodies in [0, 1] {
        assert!(matches!(
            planetesimal_ring(&RingConfig::with_bodies(bodies)),
            Err(LabError::InvalidArgument { .. })
        ));
    }
    for bad in [
        RingConfig {
            planetesimal_mass: f64::NAN,
            ..RingConfig::default()
        },
        RingConfig {
            inner: 2.0,
            outer: 1.0,
            ..RingConfig::default()
        },
        RingConfig {
            max_eccentricity: f64::INFINITY,
            ..RingConfig::default()
        },
    ] {
        assert!(matches!(
            planetesimal_ring(&bad),
            Err(LabError::InvalidArgument { .. })
        ));
    }
    let quick = ScalingConfig::quick;
    let cases = [
        ScalingConfig {
            ns: vec![1],
            ..quick()
        },
        ScalingConfig {
            ns: vec![],
            ..quick()
        },
        ScalingConfig {
            bodies: vec![1],
            ..quick()
        },
        ScalingConfig {
            ring_n: 0,
            ..quick()
        },
        ScalingConfig {
            repeats: 0,
            ..quick()
        },
        ScalingConfig {
            budget_seconds: f64::NAN,
            ..quick()
        },
    ];
    for c in cases {
        assert!(matches!(
            solver_scaling(&c, false),
            Err(LabError::InvalidArgument { .. })
        ));
    }
    assert!(matches!(
        solver_scaling(
            &ScalingConfig {
                kepler_h: f64::NAN,
                ..quick()
            },
            false
        ),
        Err(LabError::Core(GviError::InvalidStepSize { .. }))
    ));
}
