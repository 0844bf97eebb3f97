//! Extending the framework from outside the crate, with the public API only: a basis
//! (Bernstein), a quadrature (Gauss–Radau), a stage solver (capped Newton) and a
//! non-separable Lagrangian (a charged particle in a non-uniform magnetic field), written in
//! `examples/extending/user.rs` (the example's own, included here), and every facility of the library used with them — step map, dense output,
//! tangent map and symplecticity, discrete action and Legendre transforms, refinement
//! studies, serialisation with `attach_basis`. Each claim has a negative control that must
//! fail it. Tolerances are measured (the numbers in the comments; `-- --nocapture` prints
//! them) and docs/guide/extending.md quotes them.
//!
//! Run: `cargo test --test integration extension:: -- --nocapture`.

use galerkin_vi::basis::{Basis, ChebyshevLagrange};
use galerkin_vi::geometry::{
    finite_difference_jacobian, relative_symplecticity_defect, symplecticity_defect,
};
use galerkin_vi::integrator::{
    DiscreteLagrangian, StageEquations, StageSolve, StageSolver, StepFailure,
};
use galerkin_vi::quadrature::{GaussLegendre, Quadrature};
use galerkin_vi::refinement::{
    ErrorMeasure, Problem, RefineBy, compare_bases, fitted_rate, h_refinement, n_refinement,
};
use galerkin_vi::systems::{Kepler, System};
use galerkin_vi::{GalerkinIntegrator, GviError, Lagrangian, NewtonOptions};

#[path = "../examples/extending/user.rs"]
mod user;
use user::*;

// ---------------------------------------------------------------------------------------
// Helpers.
// ---------------------------------------------------------------------------------------

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn exact_solver() -> NewtonOptions {
    NewtonOptions {
        solver: StageSolver::Exact,
        ..NewtonOptions::default()
    }
}

/// One classical RK4 step of Hamilton's equations of `Magnetic`: q̇ = v, ṗ = L_q(q, v)
/// with v = p − A(q) (L_vv = I). Not symplectic: the negative control.
fn rk4_magnetic(lag: &Magnetic, q: &[f64], p: &[f64], h: f64) -> (Vec<f64>, Vec<f64>) {
    let f = |y: &[f64; 4]| -> [f64; 4] {
        let a = lag.vector_potential(&y[..2]);
        let v = [y[2] - a[0], y[3] - a[1]];
        let (mut lq, mut lv) = ([0.0; 2], [0.0; 2]);
        lag.gradient(&y[..2], &v, &mut lq, &mut lv);
        [v[0], v[1], lq[0], lq[1]]
    };
    let y0 = [q[0], q[1], p[0], p[1]];
    let add =
        |y: &[f64; 4], k: &[f64; 4], c: f64| std::array::from_fn::<f64, 4, _>(|i| y[i] + c * k[i]);
    let k1 = f(&y0);
    let k2 = f(&add(&y0, &k1, 0.5 * h));
    let k3 = f(&add(&y0, &k2, 0.5 * h));
    let k4 = f(&add(&y0, &k3, h));
    let y: [f64; 4] =
        std::array::from_fn(|i| y0[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
    (y[..2].to_vec(), y[2..].to_vec())
}

fn kepler_problem() -> (
    Kepler,
    [f64; 2],
    [f64; 2],
    galerkin_vi::systems::ExactSolution,
) {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
    (kepler, q0, p0, exact)
}

const MAG_Q0: [f64; 2] = [0.8, 0.1];
const MAG_P0: [f64; 2] = [0.2, 0.9];

// ---------------------------------------------------------------------------------------
// The pieces on their own.
// ---------------------------------------------------------------------------------------

/// The Bernstein basis obeys the contract and its derivatives are right, on τ ∈ [−0.1, 1.1]:
/// values against the closed form C(p, i) τⁱ (1 − τ)^{p−i} (measured ≤ 5.3e-15 at n = 20,
/// bound 1e-13), derivatives against central differences with δ = 1e-6 (truncation
/// δ²|φ‴|/6 plus round-off ε/δ; measured ≤ 4.1e-8 at n = 20, bound 1e-6). Partition of
/// unity Σφ = 1, Σφ' = 0. Negative control: a derivative off by 1e-3 fails the difference
/// check.
#[test]
fn bernstein_obeys_the_contract() {
    for n in [2, 3, 5, 12, 20] {
        let b = Bernstein::new(n).unwrap();
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        b.eval(0.0, &mut v, &mut d);
        assert_eq!(v[0], 1.0);
        assert!(v[1..].iter().all(|x| *x == 0.0));
        b.eval(1.0, &mut v, &mut d);
        assert_eq!(v[n - 1], 1.0);
        assert!(v[..n - 1].iter().all(|x| *x == 0.0));
        let p = n - 1;
        let binom = |k: usize| (0..k).fold(1.0, |c, j| c * (p - j) as f64 / (j + 1) as f64);
        let mut worst_value = 0.0f64;
        let mut worst_slope = 0.0f64;
        for s in 0..=40 {
            let tau = -0.1 + 1.2 * s as f64 / 40.0;
            b.eval(tau, &mut v, &mut d);
            for (i, vi) in v.iter().enumerate() {
                let exact = binom(i) * tau.powi(i as i32) * (1.0 - tau).powi((p - i) as i32);
                worst_value = worst_value.max((vi - exact).abs());
            }
            assert!((v.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!(d.iter().sum::<f64>().abs() < 1e-11);
            let delta = 1e-6;
            let (mut vp, mut vm, mut scratch) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            b.eval(tau + delta, &mut vp, &mut scratch);
            b.eval(tau - delta, &mut vm, &mut scratch);
            for ((di, a), b) in d.iter().zip(&vp).zip(&vm) {
                worst_slope = worst_slope.max((di - (a - b) / (2.0 * delta)).abs());
            }
            // Negative control: a wrong derivative is seen.
            let wrong = d[0] + 1e-3;
            assert!((wrong - (vp[0] - vm[0]) / (2.0 * delta)).abs() > 1e-4);
        }
        println!(
            "Bernstein n = {n}: value error {worst_value:.1e}, derivative error {worst_slope:.1e}"
        );
        assert!(worst_value < 1e-13 && worst_slope < 1e-6, "n = {n}");
    }
    assert!(matches!(
        Bernstein::new(1),
        Err(GviError::InvalidBasisSize { .. })
    ));
}

/// Gauss–Radau with m points integrates the shifted Legendre polynomials P_k(2τ − 1) exactly
/// (∫ = δ_k0) for k ≤ 2m − 2 — measured error ≤ 8.2e-15 up to m = 40 (bound 1e-14) — and
/// not for k = 2m − 1 (negative control: missed by ≥ 0.10 for every m ≤ 40). It includes
/// τ = 0, has positive increasing nodes and positive weights, and matches the closed forms
/// for m = 2 (nodes 0, 2/3; weights 1/4, 3/4) and m = 3.
#[test]
fn gauss_radau_is_exact_to_degree_2m_minus_2() {
    let mut worst = 0.0f64;
    let mut weakest_miss = f64::INFINITY;
    for m in 1..=40 {
        let q = GaussRadau::new(m).unwrap();
        let rule = q.rule().unwrap();
        assert_eq!(
            (rule.len(), rule.degree, q.degree_of_exactness()),
            (m, 2 * m - 2, 2 * m - 2)
        );
        assert_eq!(rule.nodes[0], 0.0);
        assert!(rule.weights.iter().all(|w| *w > 0.0));
        assert!(rule.nodes.windows(2).all(|w| w[0] < w[1]) && rule.nodes[m - 1] < 1.0);
        for k in 0..=2 * m - 1 {
            let integral = rule.integrate(|t| legendre_pair(k, 2.0 * t - 1.0).1);
            let exact = if k == 0 { 1.0 } else { 0.0 };
            if k <= 2 * m - 2 {
                worst = worst.max((integral - exact).abs());
            } else {
                weakest_miss = weakest_miss.min((integral - exact).abs());
            }
        }
    }
    println!(
        "Gauss–Radau: exactness error {worst:.1e}; degree 2m − 1 missed by ≥ {weakest_miss:.2e}"
    );
    assert!(worst < 1e-14 && weakest_miss > 1e-3);
    let r2 = GaussRadau::new(2).unwrap().rule().unwrap();
    assert!(max_diff(&r2.nodes, &[0.0, 2.0 / 3.0]) < 1e-15);
    assert!(max_diff(&r2.weights, &[0.25, 0.75]) < 1e-15);
    let (s6, r3) = (6f64.sqrt(), GaussRadau::new(3).unwrap().rule().unwrap());
    assert!(max_diff(&r3.nodes, &[0.0, (6.0 - s6) / 10.0, (6.0 + s6) / 10.0]) < 1e-15);
    assert!(
        max_diff(
            &r3.weights,
            &[1.0 / 9.0, (16.0 + s6) / 36.0, (16.0 - s6) / 36.0]
        ) < 1e-15
    );
    assert!(matches!(
        GaussRadau::new(0),
        Err(GviError::InvalidQuadrature { .. })
    ));
}

// ---------------------------------------------------------------------------------------
// The step map.
// ---------------------------------------------------------------------------------------

/// Bernstein and Chebyshev–Lagrange with n = 12 span the same polynomials; under the same
/// quadrature they define the same discrete Lagrangian, hence the same map to round-off —
/// with the user's Gauss–Radau (m = 12, degree 22 ≥ 2(n − 2) = 20, accepted) as with
/// Gauss–Legendre. Measured over 40 steps of Kepler (h = 0.5, T = 20): max |Δq|, |Δp| at the
/// step ends 7.6e-14 (Radau) and 2.5e-14 (Legendre) — one-step differences of an ulp,
/// amplified by the periapsis passages (see `custom_solver_gives_the_exact_solvers_map`);
/// bound 1e-12. The same under the user's Lagrangian (magnetic, 40 steps of h = 0.25):
/// 1.7e-15. The integrator refuses Radau m = 10 (degree 18 < 20) with `QuadratureTooWeak`.
/// Negative control: Bernstein under Radau vs Bernstein under Legendre, two different
/// discrete Lagrangians, are 9.5e-8 apart (bound: > 1e-9).
#[test]
fn bernstein_and_chebyshev_give_the_same_map_under_one_quadrature() {
    let (kepler, q0, p0, _) = kepler_problem();
    let steps = 40;
    let bern = |quad| GalerkinIntegrator::new(Bernstein::new(12).unwrap(), quad, 0.5).unwrap();
    let run = |t: &galerkin_vi::Trajectory, u: &galerkin_vi::Trajectory| {
        (0..=steps)
            .map(|k| max_diff(&t.q[k], &u.q[k]).max(max_diff(&t.p[k], &u.p[k])))
            .fold(0.0, f64::max)
    };
    let radau = GaussRadau::new(12).unwrap();
    let br = bern(radau)
        .integrate(&kepler, 0.0, &q0, &p0, steps)
        .unwrap();
    let cr = GalerkinIntegrator::new(ChebyshevLagrange::new(12).unwrap(), radau, 0.5)
        .unwrap()
        .integrate(&kepler, 0.0, &q0, &p0, steps)
        .unwrap();
    let gl = GaussLegendre::new(24).unwrap();
    let bl = GalerkinIntegrator::new(Bernstein::new(12).unwrap(), gl, 0.5)
        .unwrap()
        .integrate(&kepler, 0.0, &q0, &p0, steps)
        .unwrap();
    let cl = GalerkinIntegrator::spectral(12, 0.5)
        .unwrap()
        .integrate(&kepler, 0.0, &q0, &p0, steps)
        .unwrap();
    let (same_radau, same_legendre, across) = (run(&br, &cr), run(&bl, &cl), run(&br, &bl));
    // The user's Lagrangian, both bases under Radau.
    let bm = GalerkinIntegrator::new(Bernstein::new(12).unwrap(), radau, 0.25)
        .unwrap()
        .integrate(&MAGNETIC, 0.0, &MAG_Q0, &MAG_P0, steps)
        .unwrap();
    let cm = GalerkinIntegrator::new(ChebyshevLagrange::new(12).unwrap(), radau, 0.25)
        .unwrap()
        .integrate(&MAGNETIC, 0.0, &MAG_Q0, &MAG_P0, steps)
        .unwrap();
    let same_magnetic = run(&bm, &cm);
    println!(
        "same map: Radau {same_radau:.1e}, Legendre {same_legendre:.1e}, magnetic {same_magnetic:.1e}; \
         Radau vs Legendre {across:.1e}"
    );
    assert!(same_radau < 1e-12 && same_legendre < 1e-12 && same_magnetic < 1e-12);
    assert!(
        across > 1e-9,
        "different quadratures should differ: {across:e}"
    );
    assert_eq!(br.basis, "bernstein");
    assert!(br.user_basis && !cr.user_basis);
    assert_eq!(br.quadrature, "gauss-radau");
    let weak = GalerkinIntegrator::new(
        Bernstein::new(12).unwrap(),
        GaussRadau::new(10).unwrap(),
        0.5,
    );
    assert!(
        matches!(
            weak,
            Err(GviError::QuadratureTooWeak {
                required: 20,
                degree: 18,
                ..
            })
        ),
        "{weak:?}"
    );
}

/// Gauss–Radau with m points has order of accuracy 2m − 1 (exact to degree 2m − 2), so with
/// n = 4 (degree s = 3, whose exact-quadrature order is 2s = 6) the map's order is
/// min(2s, 2m − 1): 5 with m = 3 (the fewest points the integrator accepts: degree 4 =
/// 2(n − 2)) and 6 with m = 4. Measured on Kepler over one period, h = 2π/128 … 2π/512,
/// with the Bernstein basis: order 4.93 (m = 3, errors 3.0e-7 … 3.2e-10, max log-residual
/// 0.006) and 6.00 (m = 4, residual 2e-4). At h = 2π/64 … 2π/256 the m = 3 fit was 5.32
/// with residual 0.17: an h⁶ term still visible, so the range starts at 2π/128. Tolerance
/// 0.15, well inside the gap of 1 between the two orders (each is the other's negative
/// control).
#[test]
fn gauss_radau_converges_at_the_order_of_its_degree() {
    let (kepler, q0, p0, exact) = kepler_problem();
    let period = std::f64::consts::TAU;
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, period).unwrap();
    let hs: Vec<f64> = [128.0, 192.0, 256.0, 384.0, 512.0]
        .iter()
        .map(|s| period / s)
        .collect();
    let mut orders = Vec::new();
    for m in [3, 4] {
        let points = h_refinement(
            |h| GalerkinIntegrator::new(Bernstein::new(4)?, GaussRadau::new(m)?, h),
            &hs,
            &problem,
            |t| exact.position(t),
            4,
        )
        .unwrap();
        let fit = fitted_rate(&points, RefineBy::H, ErrorMeasure::Map).unwrap();
        let errors: Vec<String> = points
            .iter()
            .map(|p| format!("{:.2e}", p.map_error))
            .collect();
        println!(
            "Radau m = {m}: map errors {errors:?}, order {:.3}, residual {:.1e}",
            fit.rate, fit.max_residual
        );
        assert_eq!(fit.used, hs.len());
        assert!(fit.max_residual < 0.1);
        orders.push(fit.rate);
    }
    assert!((orders[0] - 5.0).abs() < 0.15, "{orders:?}");
    assert!((orders[1] - 6.0).abs() < 0.15, "{orders:?}");
}

// ---------------------------------------------------------------------------------------
// Dense output.
// ---------------------------------------------------------------------------------------

/// The trajectory keeps the integrator's basis, so q(t), q̇(t), p(t) of a Bernstein run are
/// its own curves: within 1e-12 of Chebyshev's (same quadrature, Kepler h = 0.5, T = 20) at
/// 0.25, 3.3, 10.1 and at 8 samples per step. Measured: 1.3e-14 (q), 1.2e-13 (q̇ and p).
/// Negative control (the old bug): Bernstein's coefficients read with the Chebyshev basis,
/// through `curve(k).state_at`, are wrong by 2.3e-2 in q (bound: > 1e-2).
#[test]
fn dense_output_uses_the_users_basis() {
    let (kepler, q0, p0, _) = kepler_problem();
    let quad = GaussLegendre::new(24).unwrap();
    let bern = GalerkinIntegrator::new(Bernstein::new(12).unwrap(), quad, 0.5).unwrap();
    let cheb = GalerkinIntegrator::new(ChebyshevLagrange::new(12).unwrap(), quad, 0.5).unwrap();
    let tb = bern.integrate(&kepler, 0.0, &q0, &p0, 40).unwrap();
    let tc = cheb.integrate(&kepler, 0.0, &q0, &p0, 40).unwrap();
    let mut times = vec![0.25, 3.3, 10.1];
    times.extend(tb.sample_times(8));
    let (mut dq, mut dv, mut dp) = (0.0f64, 0.0f64, 0.0f64);
    for &t in &times {
        dq = dq.max(max_diff(
            &tb.position_at(t).unwrap(),
            &tc.position_at(t).unwrap(),
        ));
        dv = dv.max(max_diff(
            &tb.velocity_at(t).unwrap(),
            &tc.velocity_at(t).unwrap(),
        ));
        dp = dp.max(max_diff(
            &tb.momentum_at(&kepler, t).unwrap(),
            &tc.momentum_at(&kepler, t).unwrap(),
        ));
    }
    // Negative control: the coefficients of a Bernstein curve are control points, not the
    // values at the Chebyshev nodes.
    let wrong_basis = ChebyshevLagrange::new(12).unwrap();
    let mut misread = 0.0f64;
    for &t in &[0.25, 3.3, 10.1] {
        let k = (t / 0.5) as usize;
        let (q_wrong, _) = tb.curve(k).unwrap().state_at(&wrong_basis, t).unwrap();
        let (q_right, _) = tb.curve(k).unwrap().state_at(bern.basis(), t).unwrap();
        assert_eq!(q_right, tb.position_at(t).unwrap());
        misread = misread.max(max_diff(&q_wrong, &tc.position_at(t).unwrap()));
    }
    println!(
        "dense output Bernstein vs Chebyshev: q {dq:.1e}, v {dv:.1e}, p {dp:.1e}; misread {misread:.2e}"
    );
    assert!(dq < 1e-12 && dv < 1e-12 && dp < 1e-12);
    assert!(
        misread > 1e-2,
        "the negative control should fail: {misread:e}"
    );
}

// ---------------------------------------------------------------------------------------
// Tangent map and symplecticity with everything the user's.
// ---------------------------------------------------------------------------------------

/// User basis, quadrature, stage solver and non-separable Lagrangian together (Bernstein
/// n = 10, Radau m = 10, capped Newton, magnetic, h = 0.5): the exact step Jacobian
/// (implicit function theorem) is symplectic to round-off — measured relative defect
/// ≤ 8.9e-16 over 20 steps, 1.3e-15 for the 20-step tangent map (bound 1e-12) — and agrees
/// with central differences of the map (δ = 1e-5) to 3.5e-11, the positive control of the
/// difference check (bound 1e-7). Negative control: RK4 on the same Hamiltonian at the same
/// h, differenced the same way, has relative defect 2.3e-2 (bound: > 1e-6).
#[test]
fn tangent_map_is_symplectic_with_everything_user_defined() {
    let h = 0.5;
    let gvi = GalerkinIntegrator::new(Bernstein::new(10).unwrap(), GaussRadau::new(10).unwrap(), h)
        .unwrap()
        .with_stage_solver(CappedNewton { cap: 10.0 });
    let (mut q, mut p) = (MAG_Q0.to_vec(), MAG_P0.to_vec());
    let mut worst = 0.0f64;
    for _ in 0..20 {
        let jac = gvi.step_jacobian(&MAGNETIC, &q, &p).unwrap();
        worst = worst.max(relative_symplecticity_defect(&jac.matrix));
        q = jac.q_next;
        p = jac.p_next;
    }
    let maps = gvi.tangent_map(&MAGNETIC, &MAG_Q0, &MAG_P0, 20).unwrap();
    let cumulative = relative_symplecticity_defect(&maps[19]);
    let step = |q: &[f64], p: &[f64]| {
        let t = gvi.integrate(&MAGNETIC, 0.0, q, p, 1).unwrap();
        (t.q[1].clone(), t.p[1].clone())
    };
    let fd = finite_difference_jacobian(step, &MAG_Q0, &MAG_P0, 1e-5);
    let jac0 = gvi
        .step_jacobian(&MAGNETIC, &MAG_Q0, &MAG_P0)
        .unwrap()
        .matrix;
    let fd_error = (&fd - &jac0).amax();
    let rk4 = finite_difference_jacobian(
        |q, p| rk4_magnetic(&MAGNETIC, q, p, h),
        &MAG_Q0,
        &MAG_P0,
        1e-5,
    );
    let rk4_defect = relative_symplecticity_defect(&rk4);
    println!(
        "symplecticity: step {worst:.1e}, 20-step tangent map {cumulative:.1e}; FD vs exact {fd_error:.1e}; \
         RK4 {rk4_defect:.1e} (absolute {:.1e})",
        symplecticity_defect(&rk4)
    );
    assert!(worst < 1e-12 && cumulative < 1e-12);
    assert!(fd_error < 1e-7);
    assert!(relative_symplecticity_defect(&fd) < 1e-7);
    assert!(rk4_defect > 1e-6, "RK4 should fail: {rk4_defect:e}");
}

/// The discrete Noether theorem with the user's pieces (Bernstein n = 5, Radau m = 5, capped
/// Newton, h = 1): the canonical angular momentum x p_y − y p_x of the rotation-invariant
/// magnetic Lagrangian is conserved to round-off over 400 steps (measured drift 1.6e-15;
/// bound 1e-12), and the energy ½|v|² + V has a bounded error (measured 1.9e-5 in each half
/// of the run: no growth). Negative control: RK4 at the same h drifts in angular momentum by
/// 5.3e-2 (bound: > 1e-9).
#[test]
fn noether_momentum_is_conserved_with_the_users_pieces() {
    let h = 1.0;
    let steps = 400;
    let gvi = GalerkinIntegrator::new(Bernstein::new(5).unwrap(), GaussRadau::new(5).unwrap(), h)
        .unwrap()
        .with_stage_solver(CappedNewton { cap: 10.0 });
    let traj = gvi
        .integrate(&MAGNETIC, 0.0, &MAG_Q0, &MAG_P0, steps)
        .unwrap();
    let ang = |q: &[f64], p: &[f64]| q[0] * p[1] - q[1] * p[0];
    let j0 = ang(&MAG_Q0, &MAG_P0);
    let e0 = MAGNETIC.energy(&MAG_Q0, &MAG_P0);
    let drift = (0..=steps)
        .map(|k| (ang(&traj.q[k], &traj.p[k]) - j0).abs())
        .fold(0.0, f64::max);
    let energy = |range: std::ops::Range<usize>| {
        range
            .map(|k| (MAGNETIC.energy(&traj.q[k], &traj.p[k]) - e0).abs())
            .fold(0.0, f64::max)
    };
    let (first, second) = (energy(0..steps / 2), energy(steps / 2..steps + 1));
    let (mut q, mut p) = (MAG_Q0.to_vec(), MAG_P0.to_vec());
    let mut rk4_drift = 0.0f64;
    for _ in 0..steps {
        (q, p) = rk4_magnetic(&MAGNETIC, &q, &p, h);
        rk4_drift = rk4_drift.max((ang(&q, &p) - j0).abs());
    }
    println!(
        "angular momentum drift {drift:.1e} (RK4 {rk4_drift:.1e}); energy error {first:.1e} then {second:.1e}"
    );
    assert!(drift < 1e-12);
    assert!(rk4_drift > 1e-9);
    assert!(second < 3.0 * first.max(1e-12) && second < 1e-4);
}

// ---------------------------------------------------------------------------------------
// The custom stage solver.
// ---------------------------------------------------------------------------------------

/// The capped Newton solver, built from `solve_exact` and `apply_correction`, computes the
/// built-in exact solver's map to round-off (Bernstein + Radau, n = 12). From each of 40
/// states of a Kepler run (h = 0.5) and of a magnetic run (h = 0.25), one step of each
/// solver: measured max |Δq|, |Δp| 4.4e-16 and 1.1e-16 (bound 2e-15, a few ulps of |p| ≈ 2).
/// Over the 40-step runs the differences grow with the flow (Kepler's periapsis passages
/// amplify any ulp): custom vs exact 2.4e-13, the same size as two built-in solvers (auto
/// vs exact, 2.8e-13) — the bound is 3× the latter. Negative control: a solver that stops
/// after one Newton iteration is wrong by 7.2e-8 (bound: > 1e-10).
#[test]
fn custom_solver_gives_the_exact_solvers_map() {
    let (kepler, q0, p0, _) = kepler_problem();
    let make = |h| {
        GalerkinIntegrator::new(Bernstein::new(12).unwrap(), GaussRadau::new(12).unwrap(), h)
            .unwrap()
    };
    let diff = |a: &galerkin_vi::Trajectory, b: &galerkin_vi::Trajectory| {
        (0..=a.steps().min(b.steps()))
            .map(|k| max_diff(&a.q[k], &b.q[k]).max(max_diff(&a.p[k], &b.p[k])))
            .fold(0.0, f64::max)
    };
    let custom = make(0.5).with_stage_solver(CappedNewton { cap: 10.0 });
    assert_eq!(
        custom.stage_solver().map(|s| s.name()),
        Some("capped-newton")
    );
    let builtin = make(0.5).with_options(exact_solver());
    let auto = make(0.5);
    let (a, b, u) = (
        custom.integrate(&kepler, 0.0, &q0, &p0, 40).unwrap(),
        builtin.integrate(&kepler, 0.0, &q0, &p0, 40).unwrap(),
        auto.integrate(&kepler, 0.0, &q0, &p0, 40).unwrap(),
    );
    assert!(a.newton_iterations() > 0);
    let (run_diff, builtin_spread) = (diff(&a, &b), diff(&u, &b));
    type Gvi = GalerkinIntegrator<Bernstein, GaussRadau>;
    type OneStep<'a> = &'a dyn Fn(&Gvi, &[f64], &[f64]) -> galerkin_vi::Trajectory;
    let one_step =
        |gvi_a: &Gvi, gvi_b: &Gvi, lag: OneStep<'_>, states: &galerkin_vi::Trajectory| {
            (0..states.steps())
                .map(|k| {
                    let (x, y) = (
                        lag(gvi_a, &states.q[k], &states.p[k]),
                        lag(gvi_b, &states.q[k], &states.p[k]),
                    );
                    diff(&x, &y)
                })
                .fold(0.0, f64::max)
        };
    let kepler_step = |g: &Gvi, q: &[f64], p: &[f64]| g.integrate(&kepler, 0.0, q, p, 1).unwrap();
    let magnetic_step =
        |g: &Gvi, q: &[f64], p: &[f64]| g.integrate(&MAGNETIC, 0.0, q, p, 1).unwrap();
    let kepler_one = one_step(&custom, &builtin, &kepler_step, &b);
    let custom_m = make(0.25).with_stage_solver(CappedNewton { cap: 10.0 });
    let builtin_m = make(0.25).with_options(exact_solver());
    let bm = builtin_m
        .integrate(&MAGNETIC, 0.0, &MAG_Q0, &MAG_P0, 40)
        .unwrap();
    let magnetic_one = one_step(&custom_m, &builtin_m, &magnetic_step, &bm);
    /// One Newton iteration and stop: not converged.
    #[derive(Debug)]
    struct OneIteration;
    impl StageSolve for OneIteration {
        fn name(&self) -> &str {
            "one-iteration"
        }
        fn solve(&self, eq: &mut dyn StageEquations) -> std::result::Result<(), StepFailure> {
            eq.residual();
            eq.solve_exact()?;
            eq.apply_correction();
            Ok(())
        }
    }
    let sloppy = make(0.5).with_stage_solver(OneIteration);
    let sloppy_diff = match sloppy.integrate(&kepler, 0.0, &q0, &p0, 40) {
        Ok(t) => diff(&t, &b),
        Err(_) => f64::INFINITY,
    };
    println!(
        "custom vs exact solver: one step {kepler_one:.1e} (Kepler), {magnetic_one:.1e} \
         (magnetic); 40 steps {run_diff:.1e} vs auto–exact {builtin_spread:.1e}; one \
         iteration {sloppy_diff:.1e}"
    );
    assert!(kepler_one < 2e-15 && magnetic_one < 2e-15);
    assert!(run_diff <= 3.0 * builtin_spread.max(1e-15) && run_diff < 1e-12);
    assert!(sloppy_diff > 1e-10);
}

// ---------------------------------------------------------------------------------------
// Studies over the user's basis family.
// ---------------------------------------------------------------------------------------

/// n-refinement with `galerkin_vi::refinement` over the user's family n ↦ Bernstein(n) +
/// Gauss–Radau(n + 1) at h = 1 on Kepler (T = 20, n = 6 … 20): map errors 2.9e-1 … 3.3e-8,
/// decreasing at every n; fitted factor per basis function r = 0.317 (ρ = 3.16, max
/// log-residual 1.0), curves 0.371 — the same r as Chebyshev–Lagrange under the same rules,
/// since it is the same method (measured |Δr| 2.3e-8, bound 1e-6). `compare_bases` on the
/// user basis vs Chebyshev, same rule: 1.4e-14 apart in position (bound 1e-12). Negative
/// control: the weakest accepted rule, Radau(n − 1), is another method: r = 0.334,
/// |Δr| = 1.7e-2 (bound: > 1e-4).
#[test]
fn refinement_study_over_the_users_family() {
    let (kepler, q0, p0, exact) = kepler_problem();
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, 20.0).unwrap();
    let ns: Vec<usize> = (6..=20).step_by(2).collect();
    let reference = |t: f64| exact.position(t);
    let bern = n_refinement(
        |n| GalerkinIntegrator::new(Bernstein::new(n)?, GaussRadau::new(n + 1)?, 1.0),
        &ns,
        &problem,
        reference,
        8,
    )
    .unwrap();
    let cheb = n_refinement(
        |n| GalerkinIntegrator::new(ChebyshevLagrange::new(n)?, GaussRadau::new(n + 1)?, 1.0),
        &ns,
        &problem,
        reference,
        8,
    )
    .unwrap();
    for p in &bern {
        println!(
            "Bernstein + Radau(n + 1), n = {:2}: map {:.3e}, curve {:.3e}, {} gradient evaluations",
            p.n, p.map_error, p.error, p.gradient_evaluations
        );
    }
    // Negative control: the weakest rule the integrator accepts, Radau(n − 1) (degree
    // 2n − 4 = 2(n − 2)), is another discrete Lagrangian.
    let weak = n_refinement(
        |n| GalerkinIntegrator::new(Bernstein::new(n)?, GaussRadau::new(n - 1)?, 1.0),
        &ns,
        &problem,
        reference,
        8,
    )
    .unwrap();
    let fb = fitted_rate(&bern, RefineBy::N, ErrorMeasure::Map).unwrap();
    let fc = fitted_rate(&cheb, RefineBy::N, ErrorMeasure::Map).unwrap();
    let fw = fitted_rate(&weak, RefineBy::N, ErrorMeasure::Map).unwrap();
    let curve = fitted_rate(&bern, RefineBy::N, ErrorMeasure::Curve).unwrap();
    let (same, other) = ((fb.rate - fc.rate).abs(), (fw.rate - fc.rate).abs());
    println!(
        "fitted factor per n: Bernstein {:.4} (rho {:.3}, residual {:.2}), Chebyshev {:.4} \
         (|Δ| {same:.1e}), curves {:.4}; Radau(n − 1) {:.4} (|Δ| {other:.1e})",
        fb.rate,
        fb.rho().unwrap(),
        fb.max_residual,
        fc.rate,
        curve.rate,
        fw.rate
    );
    assert!(fb.rate < 0.6 && curve.rate < 0.7);
    assert!(same < 1e-6 && other > 1e-4);
    for w in bern.windows(2) {
        assert!(w[1].map_error < w[0].map_error);
    }
    // compare_bases over different types.
    let b12 = GalerkinIntegrator::new(
        Bernstein::new(12).unwrap(),
        GaussRadau::new(13).unwrap(),
        1.0,
    )
    .unwrap();
    let c12 = GalerkinIntegrator::new(
        ChebyshevLagrange::new(12).unwrap(),
        GaussRadau::new(13).unwrap(),
        1.0,
    )
    .unwrap();
    let cmp = compare_bases(&[&b12, &c12], &problem, 8).unwrap();
    println!(
        "compare_bases: {:?} position {:.1e} velocity {:.1e}",
        cmp.labels, cmp.max_position, cmp.max_velocity
    );
    assert_eq!(cmp.labels[0], "bernstein n=12 gauss-radau(13) h=1");
    assert!(cmp.max_position < 1e-12);
}

// ---------------------------------------------------------------------------------------
// Serialisation.
// ---------------------------------------------------------------------------------------

/// A trajectory of a built-in basis round-trips through JSON with working dense output. One
/// of the user's basis records its name and `user_basis: true`; after deserialising,
/// `position_at`, `velocity_at` and `momentum_at` are `BasisNotAttached` (never a curve in a
/// wrong basis); after `attach_basis(Bernstein::new)` the dense output is the Bernstein
/// curve of the stored coefficients and the original's, bit for bit; attaching a basis with
/// another name, or the right name with another n, is `Mismatch`.
///
/// Bit for bit needs serde_json's `float_roundtrip` feature (a dev-dependency feature here):
/// without it serde_json parses some 17-digit numbers one ulp off (measured: 2 of the 22
/// position coordinates of this run, e.g. −1.5190563216724209 read back as
/// −1.5190563216724207), which moved the dense output by 2.2e-16 in q and 7.1e-15 in q̇.
#[test]
fn serialisation_needs_the_users_basis_attached() {
    let (kepler, q0, p0, _) = kepler_problem();
    let ulps = |a: &[Vec<f64>], b: &[Vec<f64>]| {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .map(|(x, y)| (x.to_bits() as i64 - y.to_bits() as i64).unsigned_abs())
            .max()
            .unwrap_or(0)
    };
    let builtin = GalerkinIntegrator::spectral(12, 0.5)
        .unwrap()
        .integrate(&kepler, 0.0, &q0, &p0, 10)
        .unwrap();
    let json = serde_json::to_string(&builtin).unwrap();
    let back: galerkin_vi::Trajectory = serde_json::from_str(&json).unwrap();
    assert!(!back.user_basis);
    let d = max_diff(
        &back.position_at(3.3).unwrap(),
        &builtin.position_at(3.3).unwrap(),
    );
    assert!(d < 1e-15, "{d:e}");

    let bernstein = Bernstein::new(12).unwrap();
    let gvi =
        GalerkinIntegrator::new(bernstein.clone(), GaussRadau::new(12).unwrap(), 0.5).unwrap();
    let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 10).unwrap();
    let json = serde_json::to_string(&traj).unwrap();
    assert!(json.contains("\"basis\":\"bernstein\"") && json.contains("\"user_basis\":true"));
    let mut back: galerkin_vi::Trajectory = serde_json::from_str(&json).unwrap();
    assert!(
        matches!(back.position_at(3.3), Err(GviError::BasisNotAttached { ref basis }) if basis == "bernstein")
    );
    assert!(matches!(
        back.velocity_at(1.0),
        Err(GviError::BasisNotAttached { .. })
    ));
    assert!(matches!(
        back.momentum_at(&kepler, 1.0),
        Err(GviError::BasisNotAttached { .. })
    ));
    // The step-end states need no basis; the round trip is exact.
    let state_ulps = ulps(&back.q, &traj.q).max(ulps(&back.p, &traj.p));
    let coefficient_ulps = ulps(&back.coefficients, &traj.coefficients);
    assert_eq!((state_ulps, coefficient_ulps), (0, 0));
    // Wrong name, wrong n, or the family's own error: refused, and still not attached.
    assert!(matches!(
        back.attach_basis(ChebyshevLagrange::new),
        Err(GviError::Mismatch { .. })
    ));
    assert!(matches!(
        back.attach_basis(|_| Bernstein::new(5)),
        Err(GviError::Mismatch { .. })
    ));
    assert!(matches!(
        back.attach_basis(|_| Bernstein::new(1)),
        Err(GviError::InvalidBasisSize { .. })
    ));
    assert!(back.position_at(3.3).is_err());
    back.attach_basis(Bernstein::new).unwrap();
    let (mut worst_q, mut worst_v) = (0.0f64, 0.0f64);
    for t in traj.sample_times(8) {
        let (q, v) = back.state_on_curve(t).unwrap();
        let k = ((t / 0.5) as usize).min(9);
        // Exactly the user's basis applied to the stored coefficients …
        assert_eq!(
            (q.clone(), v.clone()),
            back.curve(k).unwrap().state_at(&bernstein, t).unwrap()
        );
        assert_eq!(q, back.position_at(t).unwrap());
        // … and the original's dense output, bit for bit.
        worst_q = worst_q.max(max_diff(&q, &traj.position_at(t).unwrap()));
        worst_v = worst_v
            .max(max_diff(&v, &traj.velocity_at(t).unwrap()))
            .max(max_diff(
                &back.momentum_at(&kepler, t).unwrap(),
                &traj.momentum_at(&kepler, t).unwrap(),
            ));
    }
    println!(
        "JSON round trip: states within {state_ulps} ulp, coefficients within \
         {coefficient_ulps} ulp; dense output after attach_basis within {worst_q:.1e} (q), \
         {worst_v:.1e} (q̇, p)"
    );
    assert!(worst_q == 0.0 && worst_v == 0.0, "{worst_q:e} {worst_v:e}");
}

// ---------------------------------------------------------------------------------------
// The paper's objects.
// ---------------------------------------------------------------------------------------

/// The discrete Lagrangian L_d(q0, q1) and its Legendre transforms (p0, p1) computed with
/// the user's basis equal Chebyshev's under the same quadrature (Radau m = 12, n = 12; on
/// Kepler and on the magnetic Lagrangian): measured max relative |ΔL_d|, |Δp| 8.2e-15
/// (bound 1e-12). For a solved Bernstein step the discrete action is L_d(q_k, q_{k+1}), its
/// discrete Legendre transforms are (p_k, p_{k+1}) and the interior gradient vanishes
/// (measured ≤ 2.8e-16, bound 1e-12). Negative control: Bernstein with n = 6 — another
/// polynomial space — under the same rule differs from Chebyshev n = 12 by 6.4e-9 (bound:
/// > 1e-10, a hundred times the agreement bound).
#[test]
fn discrete_action_and_legendre_transforms_agree_with_chebyshev() {
    let radau = GaussRadau::new(12).unwrap();
    let bern = GalerkinIntegrator::new(Bernstein::new(12).unwrap(), radau, 0.5).unwrap();
    let cheb = GalerkinIntegrator::new(ChebyshevLagrange::new(12).unwrap(), radau, 0.5).unwrap();
    let coarse = GalerkinIntegrator::new(Bernstein::new(6).unwrap(), radau, 0.5).unwrap();
    let (kepler, q0, _, _) = kepler_problem();
    let (q1k, q1m) = ([0.3, 0.6], [0.7, 0.6]);
    let differ = |a: &DiscreteLagrangian, b: &DiscreteLagrangian| {
        let dv = (a.value - b.value).abs() / b.value.abs().max(1.0);
        dv.max(max_diff(&a.p0, &b.p0)).max(max_diff(&a.p1, &b.p1))
    };
    let ld = |g: &GalerkinIntegrator<Bernstein, GaussRadau>| {
        (
            g.discrete_lagrangian(&kepler, &q0, &q1k).unwrap(),
            g.discrete_lagrangian(&MAGNETIC, &MAG_Q0, &q1m).unwrap(),
        )
    };
    let (bk, bm) = ld(&bern);
    let (ck, cm) = (
        cheb.discrete_lagrangian(&kepler, &q0, &q1k).unwrap(),
        cheb.discrete_lagrangian(&MAGNETIC, &MAG_Q0, &q1m).unwrap(),
    );
    let (gk, gm) = ld(&coarse);
    let same = differ(&bk, &ck).max(differ(&bm, &cm));
    let other = differ(&gk, &ck).min(differ(&gm, &cm));
    // A solved Bernstein step: S_d(curve) = L_d(q_k, q_{k+1}), its Legendre transforms are
    // (p_k, p_{k+1}), and the interior gradient vanishes.
    let mut stepper = bern.stepper(&MAGNETIC, 0.0, &MAG_Q0, &MAG_P0).unwrap();
    stepper.step().unwrap();
    let (q1, p1) = (stepper.position().to_vec(), stepper.momentum().to_vec());
    let curve = stepper.curve();
    let s = bern.discrete_action(&MAGNETIC, curve).unwrap();
    let l = bern.discrete_lagrangian(&MAGNETIC, &MAG_Q0, &q1).unwrap();
    let (pk, pk1) = bern.discrete_legendre_transforms(&MAGNETIC, curve).unwrap();
    let grad = bern.discrete_action_gradient(&MAGNETIC, curve).unwrap();
    let interior = grad[2..grad.len() - 2]
        .iter()
        .fold(0.0f64, |m, g| m.max(g.abs()));
    let step_check = (s - l.value)
        .abs()
        .max(max_diff(&pk, &MAG_P0))
        .max(max_diff(&pk1, &p1))
        .max(interior);
    println!(
        "L_d Bernstein vs Chebyshev {same:.1e} (Kepler {:.6}, magnetic {:.6}); n = 6 vs 12 \
         {other:.1e}; solved step |S_d − L_d|, |p − F±L_d|, interior gradient ≤ {step_check:.1e}",
        bk.value, bm.value
    );
    assert!(same < 1e-12, "{same:e}");
    assert!(step_check < 1e-12, "{step_check:e}");
    assert!(other > 1e-10, "another space should differ: {other:e}");
}
