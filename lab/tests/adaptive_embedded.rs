//! Tolerance-driven n with the embedded error control: tolerance met at fewer force
//! evaluations than fixed n, warm starts, kept steps solved to round-off, the estimate against
//! the one-step error, the oracle allocation bound, h chosen from the tolerance, and following
//! the swings of the need. The indicator control and the geometric structure are in
//! `adaptive.rs`.

use galerkin_vi::adaptive::{AdaptiveOptions, DEFAULT_LADDER, ErrorControl, integrate_adaptive};
use galerkin_vi::prelude::*;
use galerkin_vi::systems::ExactSolution;
use galerkin_vi_lab::error::LabError;

use crate::common::adaptive as adaptive_common;
use adaptive_common::*;

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
            .ok()?
            // The adaptive runs solve with exact Newton (tolerance-driven runs keep it), so
            // the fixed-n runs they are compared with do too: the same solver, the same
            // evaluations per solve.
            .with_options(NewtonOptions {
                solver: galerkin_vi::integrator::StageSolver::Exact,
                ..NewtonOptions::default()
            });
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
    // Refused by the library's `solve` (`MethodSpec::validate`), before any step.
    let scene = Scene::from_toml_str("inline", &text("auto_h = true")).unwrap();
    assert!(matches!(
        run_scene(&scene.build().unwrap(), RunOptions::default()),
        Err(LabError::Core(GviError::InvalidInput { name, .. })) if name == "auto_h"
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
