//! Tolerance-driven n: the modal indicator against the true one-step error, the achieved
//! accuracy and cost against fixed n, the geometric structure with varying n, and the
//! behaviour on unreachable tolerances.

use galerkin_vi::adaptive::{AdaptiveOptions, DEFAULT_LADDER, ErrorControl, integrate_adaptive};
use galerkin_vi::geometry::relative_symplecticity_defect;
use galerkin_vi::prelude::*;
use galerkin_vi::systems::ExactSolution;
use galerkin_vi_lab::error::LabError;

fn max_norm(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// One step from the exact state at each t0: (true one-step error, indicator).
fn one_step_errors<S: System>(
    sys: &S,
    exact: &ExactSolution,
    n: usize,
    h: f64,
    starts: &[f64],
) -> Vec<(f64, f64)> {
    let gvi = GalerkinIntegrator::spectral(n, h).unwrap();
    starts
        .iter()
        .map(|&t0| {
            let (q0, p0) = exact.state(t0);
            let tr = gvi.integrate(sys, t0, &q0, &p0, 1).unwrap();
            let err = max_norm(&tr.q[1], &exact.position(t0 + h));
            (err, gvi.modal_indicator(&tr.coefficients[0], q0.len()))
        })
        .collect()
}

#[test]
fn indicator_bounds_the_one_step_error() {
    // Stated factor: above the round-off floor the one-step error is at most 4× the
    // indicator (measured worst 3.5×, Kepler h = 2, n = 6); it is often far smaller, because
    // the one-step map is superconvergent while the indicator measures the curve.
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let kex = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    let ho = HarmonicOscillator::unit();
    let hex = ho.exact_solution(0.0, &[1.0], &[0.0]).unwrap().unwrap();
    let mut checked = 0;
    for n in (6..=24).step_by(2) {
        for (pairs, label) in [
            (
                one_step_errors(&kepler, &kex, n, 2.0, &[0.0, 1.0, 2.5, 3.1]),
                "kepler h=2",
            ),
            (
                one_step_errors(&kepler, &kex, n, 0.5, &[0.0, 1.0, 2.5]),
                "kepler h=0.5",
            ),
            (
                one_step_errors(&ho, &hex, n, 5.0, &[0.0, 1.0, 2.0]),
                "oscillator h=5",
            ),
        ] {
            for (err, ind) in pairs {
                if err > 1e-12 {
                    checked += 1;
                    assert!(
                        err <= 4.0 * ind,
                        "{label} n = {n}: error {err:e} > 4 × indicator {ind:e}"
                    );
                }
            }
        }
    }
    assert!(checked > 20, "too few points above round-off: {checked}");
    // The indicator falls with n as the error does (the negative control: a constant
    // indicator would fail the bound above for small n or this decay test).
    let a = one_step_errors(&kepler, &kex, 10, 2.0, &[0.0])[0].1;
    let b = one_step_errors(&kepler, &kex, 20, 2.0, &[0.0])[0].1;
    assert!(b < 1e-2 * a, "{a:e} -> {b:e}");
}

fn kepler_state(e: f64) -> ([f64; 2], [f64; 2]) {
    ([1.0 - e, 0.0], [0.0, ((1.0 + e) / (1.0 - e)).sqrt()])
}

#[test]
fn indicator_control_meets_tolerance_within_a_stated_factor_on_kepler_06() {
    // The indicator control (ErrorControl::Indicator, α calibrated on this orbit). Measured:
    // achieved / tol = 4.4, 3.8, 3.5 for tol = 1e-6, 1e-8, 1e-10; cost 0.96–0.98 of the
    // cheapest ladder n meeting the tolerance. Asserted: ≤ 10× and ≤ 1.1×.
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = kepler_state(0.6);
    let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    for tol in [1e-6, 1e-8, 1e-10] {
        let opts =
            AdaptiveOptions::new(tol, BasisKind::Legendre, QuadratureKind::GaussLegendre, 1.0)
                .with_control(ErrorControl::Indicator);
        let run = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, 100).unwrap();
        let err = (0..=100)
            .map(|k| {
                max_norm(
                    &run.trajectory.q[k],
                    &exact.position(run.trajectory.time(k)),
                )
            })
            .fold(0.0, f64::max);
        assert!(err <= 10.0 * tol, "tol {tol:e}: achieved {err:e}");
        assert!(run.warnings.is_empty(), "{:?}", run.warnings);
        let ns = &run.trajectory.step_n;
        assert!(
            ns.iter().min() < ns.iter().max(),
            "n should vary along the orbit: {ns:?}"
        );
        let mut cheapest = None;
        for &n in &DEFAULT_LADDER {
            let gvi = GalerkinIntegrator::from_kinds(
                BasisKind::Legendre,
                n,
                QuadratureKind::GaussLegendre,
                None,
                1.0,
            )
            .unwrap();
            if let Ok(t) = gvi.integrate(&kepler, 0.0, &q0, &p0, 100) {
                let e = (0..=100)
                    .map(|k| max_norm(&t.q[k], &exact.position(t.time(k))))
                    .fold(0.0, f64::max);
                if e <= tol {
                    cheapest = Some(t.gradient_evaluations());
                    break;
                }
            }
        }
        let fixed = cheapest.expect("some fixed n meets the tolerance");
        assert!(
            (run.gradient_evaluations as f64) <= 1.1 * fixed as f64,
            "tol {tol:e}: adaptive {} vs fixed {fixed}",
            run.gradient_evaluations
        );
    }
}

#[test]
fn n_rises_near_periapsis_on_kepler_09() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = kepler_state(0.9);
    let opts = AdaptiveOptions::new(
        1e-8,
        BasisKind::Legendre,
        QuadratureKind::GaussLegendre,
        0.25,
    );
    let run = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, 60).unwrap();
    let t = &run.trajectory;
    // Radius at the middle of each step, against that step's n.
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for k in 0..t.steps() {
        let q = t.position_at(t.time(k) + 0.5 * t.h).unwrap();
        let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
        if r < 0.4 {
            near.push(t.n_of_step(k))
        } else if r > 1.5 {
            far.push(t.n_of_step(k))
        }
    }
    let mean = |v: &[usize]| v.iter().sum::<usize>() as f64 / v.len().max(1) as f64;
    assert!(!near.is_empty() && !far.is_empty());
    assert!(mean(&near) > mean(&far) + 8.0, "near {near:?} far {far:?}");
}

#[test]
fn varying_n_keeps_symplecticity_and_momentum() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = kepler_state(0.6);
    let opts = AdaptiveOptions::new(
        1e-9,
        BasisKind::Chebyshev,
        QuadratureKind::GaussLegendre,
        1.0,
    );
    let run = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, 60).unwrap();
    let t = &run.trajectory;
    let l0 = q0[0] * p0[1] - q0[1] * p0[0];
    let mut worst_defect: f64 = 0.0;
    for k in 0..t.steps() {
        let gvi = GalerkinIntegrator::spectral(t.n_of_step(k), 1.0).unwrap();
        let j = gvi
            .step_jacobian_from_coefficients(&kepler, &t.coefficients[k])
            .unwrap();
        worst_defect = worst_defect.max(relative_symplecticity_defect(&j));
        let (q, p) = (&t.q[k + 1], &t.p[k + 1]);
        let l = q[0] * p[1] - q[1] * p[0];
        assert!(
            (l - l0).abs() < 1e-12,
            "step {k}: angular momentum drift {:e}",
            l - l0
        );
    }
    assert!(worst_defect < 1e-10, "{worst_defect:e}");
    let distinct: std::collections::BTreeSet<usize> = t.step_n.iter().copied().collect();
    assert!(distinct.len() >= 2, "n did not vary: {distinct:?}");
}

#[test]
fn unreachable_and_invalid_tolerances() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    // Below round-off: the first step climbs to the largest n and is kept as best effort;
    // its estimate (6.7e-13) is the round-off floor, and later steps use twice that as their
    // budget (measured n = 64, 48, 40) — with warnings, never a silent miss.
    let opts = AdaptiveOptions::new(
        1e-30,
        BasisKind::Chebyshev,
        QuadratureKind::GaussLegendre,
        2.0,
    );
    let run = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, 3).unwrap();
    assert_eq!(run.trajectory.step_n[0], 64);
    assert!(
        run.warnings[0].contains("round-off floor") && run.warnings.len() >= 3,
        "{:?}",
        run.warnings
    );
    let floor = run.estimates[0].expect("the first step is checked");
    assert!(floor < 1e-11, "floor {floor:e}");
    for e in run.estimates.iter().skip(1).flatten() {
        assert!(
            *e <= 2.0 * floor,
            "estimate {e:e} above twice the floor {floor:e}"
        );
    }
    for tol in [0.0, -1.0, f64::NAN] {
        let opts = AdaptiveOptions::new(
            tol,
            BasisKind::Chebyshev,
            QuadratureKind::GaussLegendre,
            2.0,
        );
        let e = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, 3).unwrap_err();
        assert!(matches!(e.error, GviError::InvalidInput { .. }));
    }
}

fn max_error_kepler(run_q: &Trajectory, exact: &galerkin_vi::systems::ExactSolution) -> f64 {
    (0..run_q.q.len())
        .map(|k| max_norm(&run_q.q[k], &exact.position(run_q.time(k))))
        .fold(0.0, f64::max)
}

/// The cheapest fixed n in `ns` (scanned upwards: the cost grows with n) whose max position
/// error over the run meets tol: its force evaluations.
fn cheapest_fixed_cost(
    kepler: &Kepler,
    exact: &ExactSolution,
    q0: &[f64],
    p0: &[f64],
    h: f64,
    tol: f64,
    ns: std::ops::RangeInclusive<usize>,
) -> usize {
    ns.into_iter()
        .find_map(|n| {
            let gvi = GalerkinIntegrator::from_kinds(
                BasisKind::Legendre,
                n,
                QuadratureKind::GaussLegendre,
                None,
                h,
            )
            .ok()?;
            let t = gvi.integrate(kepler, 0.0, q0, p0, 100).ok()?;
            (max_error_kepler(&t, exact) <= tol).then(|| t.gradient_evaluations())
        })
        .expect("some fixed n in the range meets tol")
}

#[test]
fn embedded_control_meets_tolerance_and_beats_fixed_n_on_kepler_09() {
    // The default control (ErrorControl::Embedded: warm-started pairs, unchecked steps, local
    // extrapolation), 100 steps, tol = 1e-6 and 1e-9 (`gvi tolerance-study`,
    // docs/guide/tolerance-driven-n.md).
    // Measured achieved / tol and cost (force evaluations, the RK4 predictor's included) /
    // cheapest fixed n meeting tol:
    // - e = 0.6, h = 0.25: 0.025, 0.0004; cost 0.77, 0.75 (cheaper);
    // - e = 0.6, h = 1 (≈ 6 steps per orbit: the needed n changes 4× from step to step, each
    //   step is a fresh search): 0.16, 0.02; cost 1.03, 0.99 (1.14, 1.13 before the run
    //   followed the swings of the need);
    // - e = 0.9, h = 0.25: 1.80, 0.02; cost 0.25, 0.27.
    // Asserted: ≤ 2.2× tol (the stated factor); cost ≤ 0.85 of the fixed n at e = 0.6,
    // h = 0.25, ≤ 0.32 at e = 0.9 and ≤ 1.1 at e = 0.6, h = 1 (a regression bound); some steps
    // unchecked.
    let kepler = Kepler::new(1.0).unwrap();
    for (e, h, max_ratio, fixed_from) in [
        (0.6, 0.25, 0.85, 4),
        (0.6, 1.0, 1.1, 10),
        (0.9, 0.25, 0.32, 30),
    ] {
        let (q0, p0) = kepler_state(e);
        let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
        for tol in [1e-6, 1e-9] {
            let opts =
                AdaptiveOptions::new(tol, BasisKind::Legendre, QuadratureKind::GaussLegendre, h);
            let run = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, 100).unwrap();
            assert_eq!(run.control, ErrorControl::Embedded);
            assert!(
                (30..100).contains(&run.checks),
                "e = {e}, tol {tol:e}: {} checks",
                run.checks
            );
            assert_eq!(
                run.estimates.iter().filter(|x| x.is_some()).count(),
                run.checks
            );
            let err = max_error_kepler(&run.trajectory, &exact);
            assert!(err <= 2.2 * tol, "e = {e}, tol {tol:e}: achieved {err:e}");
            // At e = 0.9, tol = 1e-9 the per-step budget 5e-12 is not reached at n = 64 on two
            // periapsis steps: warned (best effort), never silent.
            assert_eq!(
                run.warnings.is_empty(),
                e < 0.8 || tol > 1e-8,
                "{:?}",
                run.warnings
            );
            let fixed = cheapest_fixed_cost(&kepler, &exact, &q0, &p0, h, tol, fixed_from..=64);
            let ratio = run.gradient_evaluations as f64 / fixed as f64;
            assert!(
                ratio <= max_ratio,
                "e = {e}, tol {tol:e}: adaptive {} vs fixed {fixed} ({ratio:.3})",
                run.gradient_evaluations
            );
        }
    }
}

#[test]
fn warm_starts_and_unchecked_steps_each_cut_the_cost() {
    // Kepler e = 0.6, h = 0.25, tol = 1e-8, 100 steps (the need varies smoothly along the
    // orbit, so unchecked steps are possible; at h = 1 most steps are a fresh search and
    // checking every step costs only 1.07× the defaults). Measured force evaluations: 8 248
    // with the defaults, 15 344 without warm starts (every solve from the integrator's guess
    // competition), 10 896 checking every step (check_every = 1); achieved / tol 0.047, 0.029
    // and 0.001. Asserted: the defaults cost ≤ 0.8 and ≤ 0.9 of those, all within 2.2× tol.
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = kepler_state(0.6);
    let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    let tol = 1e-8;
    let base = AdaptiveOptions::new(
        tol,
        BasisKind::Legendre,
        QuadratureKind::GaussLegendre,
        0.25,
    );
    let run = |opts: &AdaptiveOptions| {
        let r = integrate_adaptive(&kepler, opts, 0.0, &q0, &p0, 100).unwrap();
        let err = max_error_kepler(&r.trajectory, &exact);
        assert!(err <= 2.2 * tol, "{opts:?}: achieved {err:e}");
        r
    };
    let default = run(&base);
    let cold = run(&AdaptiveOptions {
        warm_start: false,
        ..base.clone()
    });
    let every = run(&AdaptiveOptions {
        check_every: 1,
        ..base.clone()
    });
    assert_eq!(every.checks, 100);
    let c = |r: &galerkin_vi::adaptive::AdaptiveRun| r.gradient_evaluations as f64;
    assert!(
        c(&default) <= 0.8 * c(&cold),
        "{} vs {} without warm starts",
        c(&default),
        c(&cold)
    );
    assert!(
        c(&default) <= 0.9 * c(&every),
        "{} vs {} checking every step",
        c(&default),
        c(&every)
    );
    // Warm starts are used, and only the first steps' or rejected warm starts run the
    // integrator's own guesses.
    let warm = default
        .trajectory
        .stats
        .iter()
        .filter(|s| s.guess == InitialGuess::Warm)
        .count();
    assert!(warm >= 80, "{warm} warm-started kept steps");
    assert!(
        cold.trajectory
            .stats
            .iter()
            .all(|s| s.guess != InitialGuess::Warm)
    );
}

#[test]
fn kept_steps_are_solved_to_round_off() {
    // The lower member of an embedded pair is solved with a Newton tolerance loosened to the
    // error budget and never kept: every kept step's stage residual is at round-off
    // (measured worst 1.6e-15 on Kepler e = 0.9 at tol = 1e-6; keeping the loosely solved
    // lower member instead was measured at 8.6e-9). Asserted: ≤ 1e-13.
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = kepler_state(0.9);
    let opts = AdaptiveOptions::new(
        1e-6,
        BasisKind::Legendre,
        QuadratureKind::GaussLegendre,
        0.25,
    );
    let run = integrate_adaptive(&kepler, &opts, 0.0, &q0, &p0, 100).unwrap();
    let worst = run
        .trajectory
        .stats
        .iter()
        .map(|s| s.residual)
        .fold(0.0f64, f64::max);
    eprintln!("worst kept residual {worst:e}");
    assert!(worst <= 1e-13, "worst kept residual {worst:e}");
}

#[test]
fn embedded_estimate_tracks_the_one_step_error_across_n() {
    // From exact states, one step at n and at n + 2: the estimate |q_n − q_{n+2}| against the
    // true one-step error of q_n. Stated factor: within [1/2, 2] wherever the true error is
    // above 1e-12 (the next rung's own error is far smaller, so the estimate is close to
    // the true error). Measured: 0.958…1.000 over 20 steps.
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let kex = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    let ho = HarmonicOscillator::unit();
    let hex = ho.exact_solution(0.0, &[1.0], &[0.0]).unwrap().unwrap();
    let (mut lo, mut hi, mut checked) = (f64::INFINITY, 0.0f64, 0);
    for n in (6..=24).step_by(2) {
        for (a, b, label) in [
            (
                one_step_errors_q(&kepler, &kex, n, 1.0, &[0.0, 1.0, 2.5, 3.1]),
                one_step_errors_q(&kepler, &kex, n + 2, 1.0, &[0.0, 1.0, 2.5, 3.1]),
                "kepler h=1",
            ),
            (
                one_step_errors_q(&ho, &hex, n, 5.0, &[0.0, 1.0, 2.0]),
                one_step_errors_q(&ho, &hex, n + 2, 5.0, &[0.0, 1.0, 2.0]),
                "oscillator h=5",
            ),
        ] {
            for ((err, q), (_, q2)) in a.iter().zip(&b) {
                if *err > 1e-12 {
                    checked += 1;
                    let ratio = max_norm(q, q2) / err;
                    lo = lo.min(ratio);
                    hi = hi.max(ratio);
                    assert!(
                        (0.5..=2.0).contains(&ratio),
                        "{label} n = {n}: estimate / error = {ratio}"
                    );
                }
            }
        }
    }
    eprintln!("estimate / true error in [{lo:.3}, {hi:.3}] over {checked} steps");
    assert!(checked >= 15, "too few points above round-off: {checked}");
}

/// One step from the exact state at each t0: (true one-step error, q_1).
fn one_step_errors_q<S: System>(
    sys: &S,
    exact: &ExactSolution,
    n: usize,
    h: f64,
    starts: &[f64],
) -> Vec<(f64, Vec<f64>)> {
    let gvi = GalerkinIntegrator::spectral(n, h).unwrap();
    starts
        .iter()
        .map(|&t0| {
            let (q0, p0) = exact.state(t0);
            let tr = gvi.integrate(sys, t0, &q0, &p0, 1).unwrap();
            (max_norm(&tr.q[1], &exact.position(t0 + h)), tr.q[1].clone())
        })
        .collect()
}

#[test]
fn oracle_allocation_finds_savings_only_where_the_need_varies() {
    // The oracle bound of `gvi tolerance-study` (studies::allocation): the cheapest per-step
    // choice of n with every one-step error known exactly, within the summed one-step error
    // of the cheapest fixed n. Measured (tol = 1e-6, 100 steps): Kepler e = 0.9, h = 0.25,
    // 5.5× cheaper than the fixed n = 38 (the need peaks at periapsis); the oscillator at
    // h = 20, whose every step is the same rotation, 1.01× (negative control: the bound
    // must not invent savings); the outer solar system 1.01–1.02×
    // (docs/guide/tolerance-driven-n.md).
    use galerkin_vi_lab::scene::Scene;
    use galerkin_vi_lab::studies::tolerance::{ToleranceConfig, tolerance_study};
    let config = ToleranceConfig {
        tols: vec![1e-6],
        controls: vec![ErrorControl::Embedded],
        ladder: DEFAULT_LADDER.to_vec(),
    };
    let saving = |scene: &Scene| {
        let study = tolerance_study(&scene.build().unwrap(), &config).unwrap();
        let row = &study.rows[0];
        let fixed = row.fixed.expect("a fixed n meets tol");
        let oracle = row.oracle.expect("oracle bound");
        assert!(oracle.error_sum <= row.oracle_budget.unwrap() * (1.0 + 1e-12));
        fixed.2 as f64 / oracle.cost
    };
    let mut kepler = Scene::load("kepler").unwrap();
    let e = 0.9;
    kepler.initial.q = vec![1.0 - e, 0.0];
    kepler.initial.p = vec![0.0, ((1.0 + e) / (1.0 - e)).sqrt()];
    kepler.method.basis = BasisKind::Legendre;
    kepler.method.h = 0.25;
    kepler.method.steps = 100;
    let s = saving(&kepler);
    assert!(s >= 4.0, "Kepler e = 0.9: oracle saving {s:.2}");
    let s = saving(&Scene::load("harmonic").unwrap());
    assert!(
        (1.0..=1.05).contains(&s),
        "oscillator: oracle saving {s:.2}"
    );
}

#[test]
fn uniform_need_stays_near_the_fixed_n_cost() {
    // The oscillator at h = 20 (3.2 periods per step, every step the same rotation): the
    // need does not vary, so the adaptive run can at best match the cheapest fixed n. Before
    // the step-down memory and the amortised step-down the run settled on n = 40 with checks
    // at 48 (1.5–1.6× the fixed cost). Measured (Chebyshev, 100 steps, q0 = 1): tol = 1e-6
    // and 1e-9 cost 1.18 and 0.97 of the cheapest fixed n, achieved 2.2e-11 and 2.4e-11.
    // Asserted: cost ≤ 1.3 and ≤ 1.1, achieved ≤ tol.
    let sys = HarmonicOscillator::new(1.0, 1.0).unwrap();
    let (q0, p0) = ([1.0], [0.0]);
    let exact = sys.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    let h = 20.0;
    for (tol, max_ratio) in [(1e-6, 1.3), (1e-9, 1.1)] {
        let opts =
            AdaptiveOptions::new(tol, BasisKind::Chebyshev, QuadratureKind::GaussLegendre, h);
        let run = integrate_adaptive(&sys, &opts, 0.0, &q0, &p0, 100).unwrap();
        let err = max_error_kepler(&run.trajectory, &exact);
        assert!(err <= tol, "tol {tol:e}: achieved {err:e}");
        let fixed = (8..=40)
            .find_map(|n| {
                let gvi = GalerkinIntegrator::from_kinds(
                    BasisKind::Chebyshev,
                    n,
                    QuadratureKind::GaussLegendre,
                    None,
                    h,
                )
                .ok()?;
                let t = gvi.integrate(&sys, 0.0, &q0, &p0, 100).ok()?;
                (max_error_kepler(&t, &exact) <= tol).then(|| t.gradient_evaluations())
            })
            .expect("a fixed n meets tol");
        let ratio = run.gradient_evaluations as f64 / fixed as f64;
        assert!(ratio <= max_ratio, "tol {tol:e}: cost ratio {ratio:.3}");
    }
}

#[test]
fn step_size_is_chosen_from_the_tolerance_and_time_scale() {
    // Kepler (period 2π), tol = 1e-8, horizon 100, pilots at h = 2π/2^j over one period.
    // Measured: chosen h = 0.787 (e = 0.6) and 0.196 (e = 0.9). Full runs at every pilot's
    // h: e = 0.6 costs 25 784 force evaluations at the chosen h against 28 576–38 200 at the
    // others; e = 0.9 costs 58 040 (0.69 tol) against 111 984 at h = 0.049, the only other
    // meeting 2.2 tol (larger steps miss it by 25× up to 8e7×; h = 0.098, 1 019 steps, reaches
    // 3.2 tol: over thousands of steps the phase error grows faster than the sum of the
    // per-step budgets). The pilots cost 11 272 and 33 144 evaluations (0.44 and 0.57 of the
    // run). Asserted: the chosen h's full run meets 2.2 tol and costs at most 1.1× the
    // cheapest full run at a pilot's h that meets 2.2 tol.
    use galerkin_vi::adaptive::choose_step;
    let kepler = Kepler::new(1.0).unwrap();
    let horizon = 100.0;
    let tol = 1e-8;
    for e in [0.6, 0.9] {
        let (q0, p0) = kepler_state(e);
        let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
        let opts =
            AdaptiveOptions::new(tol, BasisKind::Legendre, QuadratureKind::GaussLegendre, 1.0);
        let choice = choose_step(&kepler, &opts, 0.0, &q0, &p0, horizon).unwrap();
        assert!((choice.time_scale - std::f64::consts::TAU).abs() < 1e-12);
        assert!((choice.h * choice.steps as f64 - horizon).abs() < 1e-9);
        let full = |h: f64| {
            let steps = (horizon / h).round() as usize;
            let o = AdaptiveOptions {
                h: horizon / steps as f64,
                ..opts.clone()
            };
            let run = integrate_adaptive(&kepler, &o, 0.0, &q0, &p0, steps).ok()?;
            let err = max_error_kepler(&run.trajectory, &exact);
            (err <= 2.2 * tol).then_some(run.gradient_evaluations)
        };
        let chosen = full(choice.h).expect("the chosen h meets tol");
        let cheapest = choice
            .pilots
            .iter()
            .filter_map(|p| full(p.h))
            .min()
            .unwrap();
        assert!(
            chosen as f64 <= 1.1 * cheapest as f64,
            "e = {e}: chosen h = {} costs {chosen}, cheapest candidate {cheapest}",
            choice.h
        );
    }
    // Bad input: a non-positive horizon.
    let (q0, p0) = kepler_state(0.6);
    let opts = AdaptiveOptions::new(tol, BasisKind::Legendre, QuadratureKind::GaussLegendre, 1.0);
    let err = choose_step(&kepler, &opts, 0.0, &q0, &p0, 0.0).unwrap_err();
    assert!(matches!(err, GviError::InvalidInput { .. }));
}

#[test]
fn scene_files_choose_h_from_tol() {
    // `[method] tol = …, auto_h = true` in a scene file: h chosen for the horizon h·steps and
    // reported in the run summary; auto_h without tol is an error.
    use galerkin_vi_lab::run::{RunOptions, run_scene};
    use galerkin_vi_lab::scene::Scene;
    let text = |extra: &str| {
        format!(
            "[system]\ntype = \"harmonic\"\n[initial]\nq = [1.0]\np = [0.0]\n[method]\n\
             n = 12\nh = 1.0\nsteps = 40\n{extra}\n"
        )
    };
    let scene = Scene::from_toml_str("inline", &text("tol = 1e-8\nauto_h = true")).unwrap();
    let result = run_scene(&scene.build().unwrap(), RunOptions::default()).unwrap();
    let choice = result.summary.step_choice.expect("h was chosen");
    let traj = result.trajectory.expect("trajectory");
    assert_eq!(traj.h, choice.h);
    assert_eq!(traj.steps(), choice.steps);
    assert!((choice.h * choice.steps as f64 - 40.0).abs() < 1e-9);
    assert!(result.summary.max_position_error.unwrap() <= 2.2e-8);
    let scene = Scene::from_toml_str("inline", &text("auto_h = true")).unwrap();
    assert!(matches!(
        run_scene(&scene.build().unwrap(), RunOptions::default()),
        Err(LabError::InvalidArgument { .. })
    ));
}

/// 100-step tolerance-driven runs (Chebyshev) with and without following the swings of the
/// need.
fn with_and_without_swings<L: Lagrangian>(
    lag: &L,
    tol: f64,
    h: f64,
    q0: &[f64],
    p0: &[f64],
) -> (
    galerkin_vi::adaptive::AdaptiveRun,
    galerkin_vi::adaptive::AdaptiveRun,
) {
    let on = AdaptiveOptions::new(tol, BasisKind::Chebyshev, QuadratureKind::GaussLegendre, h);
    let off = AdaptiveOptions {
        follow_swings: false,
        ..on.clone()
    };
    let run = |o: &AdaptiveOptions| integrate_adaptive(lag, o, 0.0, q0, p0, 100).unwrap();
    (run(&on), run(&off))
}

#[test]
fn following_swings_cuts_the_cost_only_where_the_need_swings() {
    // Kepler e = 0.6 at the scene's h = 2 (Chebyshev, three steps per orbit): the steps need
    // n ≈ 45, 10 and 13 in turn (tol = 1e-8), and without following the swings the step after
    // the hardest one started at its rung. Measured force evaluations (100 steps) with and
    // without: 58 252 and 70 388 at tol = 1e-6 (achieved 0.48 and 0.085 tol), 61 728 and
    // 82 412 at 1e-8 (0.14 and 0.045 tol). Asserted: ≤ 0.85 of the cost, within 2.2× tol.
    // The oscillator at h = 20 (the need never varies), the negative control: the swing
    // condition never fires and the runs are identical (25 936 and 23 428 at 1e-6 and 1e-9).
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = kepler_state(0.6);
    let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    for tol in [1e-6, 1e-8] {
        let (a, b) = with_and_without_swings(&kepler, tol, 2.0, &q0, &p0);
        let (ea, eb) = (
            max_error_kepler(&a.trajectory, &exact),
            max_error_kepler(&b.trajectory, &exact),
        );
        assert!(
            ea <= 2.2 * tol && eb <= 2.2 * tol,
            "tol {tol:e}: {ea:e}, {eb:e}"
        );
        let ratio = a.gradient_evaluations as f64 / b.gradient_evaluations as f64;
        assert!(ratio <= 0.85, "tol {tol:e}: {ratio:.3} of the cost without");
    }
    let sys = HarmonicOscillator::new(1.0, 1.0).unwrap();
    for tol in [1e-6, 1e-9] {
        let (a, b) = with_and_without_swings(&sys, tol, 20.0, &[1.0], &[0.0]);
        assert_eq!(a.trajectory.step_n, b.trajectory.step_n);
        assert_eq!(a.gradient_evaluations, b.gradient_evaluations);
    }
}
