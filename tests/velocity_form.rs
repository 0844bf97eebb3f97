//! The velocity form of the stage equations (`StageSolver::Modal`, and `auto` where it
//! applies): built exactly when it is the nodal map — a polynomial basis and a rule that
//! integrates the kinetic term exactly — and then the same map, to the round-off of the
//! best-conditioned nodal solve, for every basis.

use galerkin_vi::integrator::{StageSolver, StepStats};
use galerkin_vi::prelude::*;

fn integrator(
    basis: BasisKind,
    n: usize,
    points: Option<usize>,
    h: f64,
    solver: StageSolver,
) -> GalerkinIntegrator<AnyBasis, QuadratureRule> {
    GalerkinIntegrator::from_kinds(basis, n, QuadratureKind::GaussLegendre, points, h)
        .unwrap()
        .with_options(NewtonOptions {
            solver,
            ..NewtonOptions::default()
        })
}

/// One Kepler step from the paper's initial state (periapsis) at n = 24, h = 1.
fn kepler_step(basis: BasisKind, solver: StageSolver) -> ([f64; 2], [f64; 2], StepStats) {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = integrator(basis, 24, None, 1.0, solver);
    let mut ws = gvi.workspace(&kepler).unwrap();
    let (mut q1, mut p1) = ([0.0; 2], [0.0; 2]);
    let stats = gvi
        .step(&kepler, &mut ws, &q0, &p0, &mut q1, &mut p1)
        .unwrap();
    (q1, p1, stats)
}

fn distance(a: &([f64; 2], [f64; 2], StepStats), b: &([f64; 2], [f64; 2], StepStats)) -> f64 {
    (0..2)
        .map(|r| (a.0[r] - b.0[r]).abs().max((a.1[r] - b.1[r]).abs()))
        .fold(0.0, f64::max)
}

/// Built for the polynomial bases with the paper's 2n points, the economical ⌈3n/2⌉ and the
/// least exact rule the integrator accepts (n − 1 points: degree 2n − 3 ≥ 2n − 4, the kinetic
/// integrand); not for the Fourier basis, whose space is another one, so that the check of
/// the basis's reproduction of the modes can fail. Rules too weak for the kinetic term are
/// refused by the integrator itself (`QuadratureTooWeak`).
#[test]
fn the_velocity_form_is_built_exactly_where_it_is_the_nodal_map() {
    for basis in [
        BasisKind::Chebyshev,
        BasisKind::Legendre,
        BasisKind::Hermite,
    ] {
        for points in [None, Some(18), Some(11)] {
            let gvi = integrator(basis, 12, points, 0.5, StageSolver::Auto);
            assert!(gvi.has_velocity_form(), "{basis} {points:?}");
        }
        let weak =
            GalerkinIntegrator::from_kinds(basis, 12, QuadratureKind::GaussLegendre, Some(10), 0.5);
        assert!(matches!(weak, Err(GviError::QuadratureTooWeak { .. })));
    }
    let fourier = integrator(BasisKind::Fourier, 12, None, 0.5, StageSolver::Auto);
    assert!(!fourier.has_velocity_form());
}

/// The same step as the nodal equations of the Legendre basis (condition number 2), to
/// 2.2e-16 measured; the nodal Chebyshev–Lagrange solve (condition ~n³) lies 5.1e-14 from
/// both, so the check resolves a solve at the nodal round-off. The velocity form does not
/// see the basis: Chebyshev and Legendre give the same step.
#[test]
fn one_step_is_the_nodal_map_to_round_off_for_every_basis() {
    let legendre_nodal = kepler_step(BasisKind::Legendre, StageSolver::Exact);
    let chebyshev_nodal = kepler_step(BasisKind::Chebyshev, StageSolver::Exact);
    for basis in [
        BasisKind::Chebyshev,
        BasisKind::Legendre,
        BasisKind::Hermite,
    ] {
        let modal = kepler_step(basis, StageSolver::Modal);
        // One escalation: at this periapsis step from the RK4 predictor the fixed-point
        // start contracts by less than 0.5 in its first iterations and hands over to the
        // frozen Hessian, which does not stall (it would continue densely: a second).
        assert_eq!(modal.2.fallbacks, 1, "{basis}: {:?}", modal.2);
        let d = distance(&modal, &legendre_nodal);
        println!("{basis}: velocity form − Legendre nodal = {d:.1e}");
        assert!(d <= 1e-15, "{basis}: {d:e}");
    }
    let d = distance(&chebyshev_nodal, &legendre_nodal);
    println!("Chebyshev nodal − Legendre nodal = {d:.1e}");
    assert!(d > 1e-14, "{d:e}");
}

/// At large steps the frozen Hessian stalls on some periapsis steps (Kepler, Legendre n = 16,
/// h = 2 and 3): those steps continue with the dense exact Newton matrix of the velocity form
/// (counted in `fallbacks`), and the trajectory is still the exact-Newton map (measured
/// 1.1e-11 and 1.3e-12 relative). Steps the velocity form cannot solve at all, and `auto`'s
/// hand-over to the nodal solvers, are checked on the paper's 10-body run in
/// `lab/tests/solvers.rs`.
#[test]
fn stalled_steps_continue_with_exact_newton_in_the_same_form() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    for h in [2.0, 3.0] {
        let run = |solver| {
            integrator(BasisKind::Legendre, 16, None, h, solver)
                .integrate(&kepler, 0.0, &q0, &p0, 100)
                .unwrap()
        };
        let (auto, exact) = (run(StageSolver::Auto), run(StageSolver::Exact));
        let fallbacks: usize = auto.stats.iter().map(|s| s.fallbacks).sum();
        let scale = exact.q[100].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let distance = (0..2)
            .map(|r| (auto.q[100][r] - exact.q[100][r]).abs())
            .fold(0.0, f64::max)
            / scale;
        println!("h = {h}: {fallbacks} escalations, distance {distance:.1e}");
        assert!(fallbacks >= 1);
        assert!(distance <= 1e-10, "{distance:e}");
    }
}

/// Final states' largest relative difference in q and p.
fn final_distance(a: &Trajectory, b: &Trajectory) -> f64 {
    let (qa, qb) = (a.q.last().unwrap(), b.q.last().unwrap());
    let (pa, pb) = (a.p.last().unwrap(), b.p.last().unwrap());
    let rel = |x: &[f64], y: &[f64]| {
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        x.iter()
            .zip(y)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max)
            / scale
    };
    rel(qa, qb).max(rel(pa, pb))
}

fn with_handover(
    gvi: GalerkinIntegrator<AnyBasis, QuadratureRule>,
    handover: f64,
) -> GalerkinIntegrator<AnyBasis, QuadratureRule> {
    let mut options = *gvi.options();
    options.structured.velocity_fixed_point_handover = handover;
    gvi.with_options(options)
}

fn total(t: &Trajectory, f: fn(&StepStats) -> usize) -> usize {
    t.stats.iter().map(f).sum()
}

/// The fixed-point start of the velocity form (`StructuredOptions::
/// velocity_fixed_point_handover`, docs/solvers.md). Its iteration matrix is I ⊗ M, so it
/// contracts at about h² ρ(C) max|M⁻¹H| and needs no force Jacobian.
///
/// - Kepler e = 0.6, T = 200 at issue 35's configuration (Legendre n = 12, 12 points,
///   h = 1/3): h² ρ(C) · 2/r_p³ = 0.11 · 4.1e-3 · 31 = 0.014 at periapsis, so no step hands
///   over and none evaluates a force Jacobian: 43 428 force evaluations and no Hessian
///   against 38 676 and 7 200 with the start off (the negative control: every step freezes
///   H̄ and factors the Kronecker matrix). Both are the exact-Newton map to round-off.
/// - The harmonic oscillator at hω = 20, n = 8: (hω)² ρ(C) = 400 · 9.3e-3 = 3.7, the
///   fixed-point iteration diverges. The first two steps hand over (from the guess), which
///   starts the frozen Hessian for the next 32 steps without trying the fixed point; the map
///   is that of the start off to round-off.
#[test]
fn the_fixed_point_start_needs_no_force_jacobian_and_hands_over_where_it_diverges() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = |solver| integrator(BasisKind::Legendre, 12, Some(12), 1.0 / 3.0, solver);
    let steps = 600;
    let run = |g: GalerkinIntegrator<AnyBasis, QuadratureRule>| {
        g.integrate(&kepler, 0.0, &q0, &p0, steps).unwrap()
    };
    let start = run(gvi(StageSolver::Auto));
    let frozen = run(with_handover(gvi(StageSolver::Auto), 0.0));
    let exact = run(gvi(StageSolver::Exact));
    let hessians = |t: &Trajectory| total(t, |s| s.hessian_evaluations);
    let forces = |t: &Trajectory| total(t, |s| s.gradient_evaluations);
    let (ds, df) = (
        final_distance(&start, &exact),
        final_distance(&frozen, &exact),
    );
    println!(
        "Kepler n = 12, h = 1/3, T = 200: fixed-point start {} force and {} Hessian \
         evaluations, {} hand-overs, {ds:.1e} from exact Newton; frozen Hessian {} and {}, \
         {df:.1e}",
        forces(&start),
        hessians(&start),
        total(&start, |s| s.fallbacks),
        forces(&frozen),
        hessians(&frozen),
    );
    assert_eq!(hessians(&start), 0);
    assert_eq!(total(&start, |s| s.factorizations), 0);
    assert!(hessians(&frozen) >= 12 * steps);
    // Measured 9.7e-14 and 8.1e-15 (600 steps; per step both within an ulp or two).
    assert!(ds <= 1e-12 && df <= 1e-12, "{ds:e} {df:e}");

    let ho = HarmonicOscillator::unit();
    let gvi = |handover| {
        with_handover(
            integrator(BasisKind::Legendre, 8, None, 20.0, StageSolver::Auto),
            handover,
        )
    };
    let steps = 40;
    let start = gvi(NewtonOptions::default()
        .structured
        .velocity_fixed_point_handover)
    .integrate(&ho, 0.0, &[1.0], &[0.0], steps)
    .unwrap();
    let frozen = gvi(0.0).integrate(&ho, 0.0, &[1.0], &[0.0], steps).unwrap();
    let handed: Vec<usize> = start.stats.iter().map(|s| s.fallbacks).collect();
    let d = final_distance(&start, &frozen);
    println!("harmonic, hω = 20: hand-overs per step {handed:?}, {d:.1e} from the start off");
    assert!(handed[..2].iter().all(|&f| f == 1), "{handed:?}");
    assert!(handed[2..34].iter().all(|&f| f == 0), "{handed:?}");
    assert!(handed[34..].contains(&1), "{handed:?}");
    assert!(d <= 1e-12, "{d:e}");
}
