//! Periodic Galerkin: choreographies and periodic orbits with the Fourier basis
//! (docs/guide/periodic-orbits.md).

use galerkin_vi::GviError;
use galerkin_vi::systems::{NBody, Pendulum};
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::periodic::{
    self, FourierCurve, Layout, PeriodCondition, PeriodicOptions, PeriodicRequest, Symmetry,
};
use galerkin_vi_lab::scene::Scene;

/// Simó's figure-eight data: the energy of his initial state (G = m = 1).
fn simo_energy() -> f64 {
    let x1: [f64; 2] = [0.97000436, -0.24308753];
    let v1 = [0.466203685, 0.43236573];
    let v3 = [-0.93240737, -0.86473146];
    let kinetic = (v1[0] * v1[0] + v1[1] * v1[1]) + 0.5 * (v3[0] * v3[0] + v3[1] * v3[1]);
    let r13 = x1[0].hypot(x1[1]);
    kinetic - (2.0 / r13 + 1.0 / (2.0 * r13))
}

fn figure_eight_solution() -> periodic::PeriodicSolution {
    let scene = Scene::load("figure-eight").unwrap();
    let scene = scene.build().unwrap();
    let spec = periodic::spec_of(&scene).unwrap();
    let (layout, symmetries, _) = periodic::problem_of(&scene, spec).unwrap();
    let guess = spec.guess_curve(layout, spec.modes).unwrap();
    let nb = NBody::new(vec![1.0; 3], 1.0, 2).unwrap();
    periodic::solve(
        &nb,
        guess,
        PeriodCondition::Energy(simo_energy()),
        &symmetries,
        &PeriodicOptions::default(),
    )
    .unwrap()
}

#[test]
fn figure_eight_is_found_from_a_crude_guess() {
    let sol = figure_eight_solution();
    // Measured: T = 6.325914011423, 3.1e-8 above Simó's 6.32591398 (his data carry 8 digits).
    assert!(
        (sol.curve.period - 6.32591398).abs() < 5e-8,
        "period {}",
        sol.curve.period
    );
    assert!(sol.residual <= 1e-10, "residual {:.3e}", sol.residual);
    // The energy is constant along the curve, not only on average (measured spread ~1e-13).
    assert!(
        sol.energy_spread < 1e-10,
        "spread {:.3e}",
        sol.energy_spread
    );
    assert!((sol.energy - simo_energy()).abs() < 1e-12);
    assert!(sol.iterations <= 10, "{} iterations", sol.iterations);

    // At Simó's period, fixed, the energy is Simó's to the precision of his data:
    // dE/E = −(2/3) dT/T for the homogeneous potential, i.e. about 4e-9 here.
    let nb = NBody::new(vec![1.0; 3], 1.0, 2).unwrap();
    let mut at_period = sol.curve.clone();
    at_period.period = 6.32591398;
    let fixed = periodic::solve(
        &nb,
        at_period,
        PeriodCondition::Fixed,
        &Symmetry::nbody(2),
        &PeriodicOptions::default(),
    )
    .unwrap();
    assert!(fixed.residual <= 1e-10);
    assert!(
        (fixed.energy - simo_energy()).abs() < 1e-8,
        "energy {} against Simó's {}",
        fixed.energy,
        simo_energy()
    );
    // The choreography passes through Simó's configuration: some time has one body at
    // the centre of mass (the origin), the others at ±(0.97000436, −0.24308753) up to rotation.
    let c = &sol.curve;
    let d_simo = 2.0 * 0.97000436f64.hypot(0.24308753);
    let mut best = f64::INFINITY;
    for i in 0..20_000 {
        let q = c.position(c.period * i as f64 / 20_000.0);
        let (r1, r2) = (q[0].hypot(q[1]), q[2].hypot(q[3]));
        if r1 < 2e-3 || r2 < 2e-3 {
            let d = if r1 < r2 {
                (q[2] - q[4]).hypot(q[3] - q[5])
            } else {
                (q[0] - q[4]).hypot(q[1] - q[5])
            };
            best = best.min((d - d_simo).abs());
        }
    }
    assert!(
        best < 1e-3,
        "distance at the Euler configuration differs by {best:.2e}"
    );
}

#[test]
fn converges_from_a_one_percent_perturbation_in_few_iterations() {
    let scene = Scene::load("figure-eight").unwrap();
    let scene = scene.build().unwrap();
    let spec = periodic::spec_of(&scene).unwrap();
    let (layout, symmetries, _) = periodic::problem_of(&scene, spec).unwrap();
    let nb = NBody::new(vec![1.0; 3], 1.0, 2).unwrap();
    let reference = figure_eight_solution();
    // Deterministic 1e-2 perturbations of every coefficient of the crude guess's modes
    // (k <= 3) and of the period guess, with several sign patterns; and of the solution's
    // low modes (k <= 5).
    let crude = spec.guess_curve(layout, spec.modes).unwrap();
    let nc = 2;
    let mut worst = 0;
    for (start, modes) in [(&crude, 3), (&crude, 3), (&crude, 3), (&reference.curve, 5)] {
        for pattern in 0..3 {
            let mut guess = start.clone();
            for (i, c) in guess.coefficients[..(2 * modes + 1) * nc]
                .iter_mut()
                .enumerate()
            {
                *c += 1e-2 * ((i * (pattern + 2)) as f64 * 1.7).sin().signum();
            }
            guess.period += 1e-2 * if pattern == 1 { -1.0 } else { 1.0 };
            let sol = periodic::solve(
                &nb,
                guess,
                PeriodCondition::Energy(simo_energy()),
                &symmetries,
                &PeriodicOptions::default(),
            )
            .unwrap();
            assert!((sol.curve.period - reference.curve.period).abs() < 1e-11);
            worst = worst.max(sol.iterations);
        }
    }
    eprintln!("worst Newton iterations from a 1e-2 perturbation: {worst}");
    assert!(worst <= 15, "{worst} iterations");
}

#[test]
fn figure_eight_is_linearly_stable_and_lagrange_123_is_not() {
    let scene = Scene::load("figure-eight").unwrap();
    let request = PeriodicRequest {
        periods: 0,
        ..Default::default()
    };
    let r = periodic::analyse_scene(&scene.build().unwrap(), &request).unwrap();
    assert_eq!(r.multipliers.len(), 12);
    // Measured max ||λ| − 1| = 1.1e-7 (the Jordan blocks at 1 split by √ε).
    let defect = r.max_modulus_defect.unwrap();
    assert!(
        defect < 1e-6,
        "multipliers off the unit circle by {defect:.2e}"
    );
    // 8 trivial multipliers: 2 each for the time shift, two translations and the rotation.
    assert_eq!(r.expected_trivial_multipliers, 8);
    assert_eq!(r.trivial_multipliers, 8, "{:?}", r.multipliers);
    // The other two pairs are genuinely complex (elliptic), not at 1.
    for z in &r.multipliers[8..] {
        assert!(z[1].abs() > 1e-2, "{z:?}");
    }
    // Negative control: Lagrange's triangle with masses 1, 2, 3 is unstable (Routh), and
    // the same test fails for it.
    let lagrange = Scene::load("lagrange-triangle").unwrap();
    let l = periodic::analyse_scene(&lagrange.build().unwrap(), &request).unwrap();
    assert!(l.max_modulus_defect.unwrap() > 10.0, "{:?}", l.multipliers);
}

#[test]
fn lagrange_triangle_is_equilateral_with_the_kepler_side() {
    let scene = Scene::load("lagrange-triangle").unwrap();
    let request = PeriodicRequest {
        periods: 0,
        floquet: false,
        ..Default::default()
    };
    let r = periodic::analyse_scene(&scene.build().unwrap(), &request).unwrap();
    assert!(r.residual <= 1e-10);
    // ω² = G Σm / a³ with T = 2π/√6 gives a = 1 for every side at every time.
    for q in &r.q {
        for (i, j) in [(0, 1), (1, 2), (0, 2)] {
            let side = (q[2 * i] - q[2 * j]).hypot(q[2 * i + 1] - q[2 * j + 1]);
            assert!((side - 1.0).abs() < 1e-9, "side {side}");
        }
    }
}

#[test]
fn pendulum_period_matches_the_elliptic_integral() {
    let scene = Scene::load("pendulum").unwrap();
    let request = PeriodicRequest {
        periods: 10,
        ..Default::default()
    };
    let r = periodic::analyse_scene(&scene.build().unwrap(), &request).unwrap();
    // T = 4 K(sin(θ₀/2)) for l = g = 1, K by the arithmetic–geometric mean.
    let (mut a, mut b) = (1.0f64, 1.25f64.cos());
    for _ in 0..12 {
        (a, b) = ((a + b) / 2.0, (a * b).sqrt());
    }
    let exact = 4.0 * std::f64::consts::PI / (2.0 * a);
    assert!((r.period - exact).abs() < 1e-10, "{} vs {exact}", r.period);
    assert!((r.q0[0].abs() - 2.5).abs() < 1e-10 || r.q.iter().any(|q| q[0] > 2.4999999));
    // The time-stepping run closes after 10 periods.
    assert!(r.closing.unwrap().position_distance < 1e-9);
}

/// The same pendulum written as an expression Lagrangian: the same period, and its own
/// coordinate names in the CSV header and the phase-portrait axes; the built-in keeps q0, p0.
#[test]
fn an_expression_pendulum_reports_its_own_names() {
    let text = "[system]\ntype = \"lagrangian\"\ncoordinates = [\"theta\"]\n\
                lagrangian = \"theta_dot^2/2 + cos(theta)\"\n\
                [initial]\nq = [2.5]\np = [0.0]\n[method]\nn = 16\nh = 0.5\nsteps = 40\n\
                [periodic]\nkind = \"orbit\"\nmodes = 48\ncondition = \"energy\"\n\
                period = 9.0\nsteps = 64\n[[periodic.guess]]\nk = 1\na = [2.0]\nb = [0.0]\n";
    let request = PeriodicRequest {
        periods: 0,
        floquet: false,
        ..Default::default()
    };
    let scene = Scene::from_toml_str("theta.toml", text).unwrap();
    let r = periodic::analyse_scene(&scene.build().unwrap(), &request).unwrap();
    let builtin = Scene::load("pendulum").unwrap();
    let b = periodic::analyse_scene(&builtin.build().unwrap(), &request).unwrap();
    assert!(
        (r.period - b.period).abs() < 1e-10,
        "{} vs {}",
        r.period,
        b.period
    );
    let header = |csv: &str| {
        csv.lines()
            .find(|l| !l.starts_with('#'))
            .unwrap()
            .to_string()
    };
    assert_eq!(header(&r.to_csv().unwrap()), "t,theta,p_theta");
    assert_eq!(header(&b.to_csv().unwrap()), "t,q0,p0");
    let chart = r.orbit_chart();
    assert_eq!(
        (chart.x_label.as_str(), chart.y_label.as_str()),
        ("theta", "p_theta")
    );
    let chart = b.orbit_chart();
    assert_eq!((chart.x_label.as_str(), chart.y_label.as_str()), ("q", "p"));
}

#[test]
fn refinement_in_k_converges_exponentially() {
    let scene = Scene::load("figure-eight").unwrap();
    let request = PeriodicRequest {
        modes: vec![12, 18, 24, 30, 36, 42],
        periods: 0,
        floquet: false,
        ..Default::default()
    };
    let r = periodic::analyse_scene(&scene.build().unwrap(), &request).unwrap();
    let fit = r.refinement_fit.clone().unwrap();
    // Measured rate per mode ≈ 0.6 (see the guide); exponential means a rate well below 1.
    assert!(fit.rate < 0.8, "rate {}", fit.rate);
    assert!(r.refinement[0].equation_residual > 1e3 * r.refinement[5].equation_residual);
}

#[test]
fn negative_controls_and_bad_input_are_typed_errors() {
    let nb = NBody::new(vec![1.0; 3], 1.0, 2).unwrap();
    let layout = Layout::Choreography {
        bodies: 3,
        body_dim: 2,
    };
    // A guess far from any orbit: the bodies pass through each other on a line. Newton
    // reaches a stationary point of the discrete action through the collisions, whose energy
    // is far from constant: not an orbit.
    let mut far = FourierCurve::zeros(16, layout.clone(), 6.0).unwrap();
    far.set_mode(1, &[0.0, 0.0], &[1.0, 0.0]).unwrap();
    match periodic::solve(
        &nb,
        far.clone(),
        PeriodCondition::Energy(simo_energy()),
        &Symmetry::nbody(2),
        &PeriodicOptions::default(),
    ) {
        Err(e @ GviError::PeriodicNotConverged { .. }) => {
            assert!(e.to_string().contains("residual"), "{e}");
            assert!(e.to_string().contains("not an orbit"), "{e}");
        }
        other => panic!("expected PeriodicNotConverged, got {other:?}"),
    }
    // No periodic orbit exists at positive energy (virial theorem: E = <V>/2 < 0, exactly
    // for the discrete action too): Newton must fail and say at which residual.
    match periodic::solve(
        &nb,
        far,
        PeriodCondition::Energy(0.5),
        &Symmetry::nbody(2),
        &PeriodicOptions::default(),
    ) {
        Err(e @ GviError::PeriodicNotConverged { residual, .. }) => {
            assert!(residual > 1e-11 || residual.is_nan(), "{residual}");
            assert!(e.to_string().contains("residual"), "{e}");
        }
        other => panic!("expected PeriodicNotConverged, got {other:?}"),
    }
    // Too few modes: the figure-eight with K = 6 is not resolved.
    let scene = Scene::load("figure-eight").unwrap();
    let few = PeriodicRequest {
        modes: vec![6],
        periods: 0,
        floquet: false,
        ..Default::default()
    };
    match periodic::analyse_scene(&scene.build().unwrap(), &few) {
        Err(e @ LabError::Core(GviError::PeriodicUnderResolved { modes: 6, .. })) => {
            assert!(e.to_string().contains("too few modes"), "{e}");
        }
        other => panic!("expected PeriodicUnderResolved, got {other:?}"),
    }
    // Fewer modes than the guess uses (the library's curve refuses it).
    let two = PeriodicRequest {
        modes: vec![2],
        ..few.clone()
    };
    // The library's guess refuses it (GviError::InvalidInput since the error split).
    let r = periodic::analyse_scene(&scene.build().unwrap(), &two);
    assert!(
        matches!(r, Err(LabError::Core(GviError::InvalidInput { .. }))),
        "{r:?}"
    );
    // K < 1.
    let zero = PeriodicRequest {
        modes: vec![0],
        ..few.clone()
    };
    assert!(matches!(
        periodic::analyse_scene(&scene.build().unwrap(), &zero),
        Err(LabError::InvalidArgument { .. })
    ));
    assert!(FourierCurve::zeros(0, layout.clone(), 1.0).is_err());
    // A scene without periodic data.
    assert!(matches!(
        periodic::analyse_scene(&Scene::load("kepler").unwrap().build().unwrap(), &few),
        Err(LabError::Scene { .. })
    ));
    // No convergence within the iteration limit.
    let scene = scene.build().unwrap();
    let spec = periodic::spec_of(&scene).unwrap();
    let guess = spec.guess_curve(layout.clone(), 40).unwrap();
    let one = PeriodicOptions {
        max_iterations: 1,
        ..Default::default()
    };
    assert!(matches!(
        periodic::solve(
            &nb,
            guess,
            PeriodCondition::Energy(simo_energy()),
            &Symmetry::nbody(2),
            &one
        ),
        Err(GviError::PeriodicNotConverged { iterations: 1, .. })
    ));
    // Non-finite guess, period and energy.
    let mut bad = FourierCurve::zeros(4, layout.clone(), 6.0).unwrap();
    assert!(bad.set_mode(1, &[f64::NAN, 0.0], &[1.0, 0.0]).is_err());
    bad.coefficients[3] = f64::INFINITY;
    assert!(matches!(
        periodic::solve(&nb, bad, PeriodCondition::Fixed, &Symmetry::nbody(2), &one),
        Err(GviError::NonFinite { .. })
    ));
    let ok = FourierCurve::zeros(4, layout.clone(), 6.0).unwrap();
    assert!(matches!(
        periodic::solve(
            &nb,
            ok,
            PeriodCondition::Energy(f64::NAN),
            &Symmetry::nbody(2),
            &one
        ),
        Err(GviError::NonFinite { .. })
    ));
    assert!(FourierCurve::zeros(4, layout, f64::INFINITY).is_err());
    // Dimension mismatch between the Lagrangian and the layout.
    let pendulum = Pendulum::new(1.0, 1.0, 1.0).unwrap();
    let wrong = FourierCurve::zeros(4, Layout::Orbit { dim: 2 }, 6.0).unwrap();
    assert!(matches!(
        periodic::solve(
            &pendulum,
            wrong,
            PeriodCondition::Fixed,
            &[Symmetry::TimeShift],
            &one
        ),
        Err(GviError::DimensionMismatch { .. })
    ));
}

#[test]
fn command_writes_json_csv_and_svg() {
    let dir = std::env::temp_dir().join(format!("gvi-periodic-{}", std::process::id()));
    let json = dir.join("eight.json");
    let svg = dir.join("eight.svg");
    let refine = dir.join("refine.svg");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args([
            "periodic",
            "figure-eight",
            "--modes",
            "20,30,40,50,60",
            "--periods",
            "2",
        ])
        .arg("--output")
        .arg(&json)
        .arg("--plot")
        .arg(&svg)
        .arg("--refine-plot")
        .arg(&refine)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for key in [
        "period",
        "energy",
        "action",
        "residual",
        "modes",
        "multipliers",
        "q0",
        "p0",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["multipliers"].as_array().unwrap().len(), 12);
    assert_eq!(v["modes"].as_u64(), Some(60));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    assert!(std::fs::read_to_string(&refine).unwrap().contains("<svg"));
    let csv = std::process::Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args(["periodic", "pendulum", "--format", "csv", "--periods", "1"])
        .output()
        .unwrap();
    assert!(csv.status.success());
    let text = String::from_utf8_lossy(&csv.stdout);
    assert!(text.contains("# period = ") && text.contains("t,q0,p0"));
    // Bad input: no [periodic] table, K = 0.
    for args in [
        vec!["periodic", "kepler"],
        vec!["periodic", "figure-eight", "--modes", "0"],
    ] {
        let bad = std::process::Command::new(env!("CARGO_BIN_EXE_gvi"))
            .args(&args)
            .output()
            .unwrap();
        assert!(!bad.status.success());
        let err = String::from_utf8_lossy(&bad.stderr);
        assert!(
            err.starts_with("error:") && !err.contains("panicked"),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
