//! The enriched basis (polynomials plus sin/cos of a fast frequency ω) and the
//! Fermi–Pasta–Ulam problem: the geometric properties every Galerkin variational integrator
//! must keep, each with a negative control that lacks it; convergence in the polynomial
//! degree at a fixed large ωh beside a polynomial basis; the ωh → 0 limit; the adiabatic
//! invariant of FPU. Numbers quoted are measured with
//! `cargo test --test integration enriched:: -- --nocapture` and are what docs/guide/enriched-bases.md
//! reports.

use crate::enriched_checks;
use galerkin_vi::GalerkinIntegrator;
use galerkin_vi::baselines::{Rk4, integrate_one_step};
use galerkin_vi::basis::{Basis, Enriched, Legendre};
use galerkin_vi::quadrature::{GaussLegendre, Quadrature};
use galerkin_vi::refinement::{ErrorMeasure, Problem, RefineBy, fitted_rate, n_refinement};
use galerkin_vi::systems::{Fpu, Kepler, System};
use galerkin_vi::{GviError, Result};

/// The enriched integrator at its recommended Gauss rule (at least 2n points).
fn enriched(
    degree: usize,
    omega: f64,
    h: f64,
) -> Result<GalerkinIntegrator<Enriched, GaussLegendre>> {
    let basis = Enriched::new(degree, omega, h)?;
    let points = basis.gauss_points().max(2 * basis.len());
    GalerkinIntegrator::new(basis, GaussLegendre::new(points)?, h)
}

fn rk4_states(
    fpu: &Fpu,
    q: &[f64],
    p: &[f64],
    h: f64,
    steps: usize,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let mut rk4 = Rk4::new(fpu, h).unwrap();
    integrate_one_step(&mut rk4, q, p, steps).unwrap()
}

/// Symplecticity of the enriched map on FPU at ωh = 2 (h = 0.04, two radians of the fast
/// oscillation per step): the relative defect ‖JᵀΩJ − Ω‖/‖J‖² of the exact step Jacobian
/// stays at round-off along 20 steps, and the Jacobian agrees with central differences of the
/// map. Measured: defect 1.0e-18, Jacobian against differences 3.7e-12. Negative control:
/// RK4 at the same h, differenced the same way: 3.3e-4.
#[test]
fn enriched_map_is_symplectic_on_fpu() {
    let fpu = Fpu::hlw();
    let h = 0.04;
    let gvi = enriched(4, fpu.omega(), h).unwrap();
    let (q0, p0) = fpu.hlw_initial_state();
    let (worst, fd_error, rk4_defect) = enriched_checks::symplecticity(&gvi, &fpu, &q0, &p0, h);
    println!(
        "enriched symplecticity defect {worst:.1e} (20 steps); FD vs exact Jacobian {fd_error:.1e}; \
         RK4 {rk4_defect:.1e}"
    );
    assert!(worst < 1e-12, "enriched defect {worst:e}");
    assert!(fd_error < 1e-6, "FD mismatch {fd_error:e}");
    // Measured 3.3e-4: fourteen orders of magnitude above the enriched map's 1e-18.
    assert!(rk4_defect > 1e-5, "RK4 should fail: {rk4_defect:e}");
}

/// The discrete Noether theorem for the enriched basis: on Kepler (rotation-invariant), the
/// angular momentum x p_y − y p_x of the enriched map (p = 6, ω = 1, h = 0.5) is conserved to
/// round-off over 400 steps. Negative control: RK4 at the same h drifts.
#[test]
fn enriched_map_conserves_angular_momentum() {
    let gvi = enriched(6, 1.0, 0.5).unwrap();
    let (drift, rk4_drift) = enriched_checks::kepler_angular_momentum_drift(&gvi, 400);
    println!("angular momentum drift: enriched {drift:.1e}, RK4 {rk4_drift:.1e}");
    assert!(drift < 1e-13, "enriched drift {drift:e}");
    assert!(rk4_drift > 1e-6, "RK4 should drift: {rk4_drift:e}");
}

/// As ωh → 0 the enriched space tends to the polynomials of degree p + 2, and the stable
/// representation reaches that limit by continuity: at ωh = 1e-8 the enriched map (p = 4)
/// equals the Legendre map with n = 7 under the same rule to round-off. Negative control: the
/// textbook functions sin(θτ) − τ sin θ, cos(θτ) − (1 − τ) − τ cos θ span the same space but
/// are numerically dependent on the polynomials there: the integrator refuses them (or, if it
/// accepted them, their map would be far from the limit).
#[test]
fn small_omega_h_reaches_the_polynomial_limit() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let h = 0.25;
    let rule = || GaussLegendre::new(14).unwrap();
    let poly = GalerkinIntegrator::new(Legendre::new(7).unwrap(), rule(), h).unwrap();
    let want = poly.integrate(&kepler, 0.0, &q0, &p0, 80).unwrap();
    for theta in [1e-8, 1e-5] {
        let e =
            GalerkinIntegrator::new(Enriched::new(4, theta / h, h).unwrap(), rule(), h).unwrap();
        let got = e.integrate(&kepler, 0.0, &q0, &p0, 80).unwrap();
        let diff = got
            .q
            .iter()
            .zip(&want.q)
            .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0f64, f64::max);
        println!(
            "ωh = {theta:e}: enriched vs Legendre(7) {diff:.1e}; kinetic condition {:.1e}",
            e.kinetic_condition_number()
        );
        assert!(diff < 1e-11, "ωh = {theta}: {diff:e}");
    }
    let naive = GalerkinIntegrator::new(NaiveEnriched::new(4, 1e-5), rule(), h);
    match naive {
        Err(e) => {
            println!("naive enrichment at ωh = 1e-5 refused: {e}");
            assert!(matches!(
                e,
                GviError::QuadratureTooWeak { .. } | GviError::InvalidBasisSize { .. }
            ));
        }
        Ok(gvi) => {
            let cond = gvi.kinetic_condition_number();
            let got = gvi.integrate(&kepler, 0.0, &q0, &p0, 80);
            let diff = match got {
                Ok(t) => {
                    t.q.iter()
                        .zip(&want.q)
                        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
                        .fold(0.0f64, f64::max)
                }
                Err(_) => f64::INFINITY,
            };
            println!(
                "naive enrichment at ωh = 1e-5: condition {cond:.1e}, off the limit by {diff:.1e}"
            );
            assert!(
                cond > 1e12 && diff > 1e-9,
                "the naive basis should be ill-conditioned"
            );
        }
    }
}

/// Convergence in the polynomial degree at a fixed large ωh = 10 (h = 0.2 on FPU with
/// ω = 50: 1.6 fast periods per step), T = 4: geometric, fitted. The polynomial Legendre
/// basis with the same n and h needs many more functions before it resolves the fast
/// oscillation (its error at n = 9 is still O(1e-2)...).
#[test]
fn convergence_is_geometric_in_the_degree_at_large_omega_h() {
    let fpu = Fpu::hlw();
    let (q0, p0) = fpu.hlw_initial_state();
    let horizon = 4.0;
    let problem = Problem::new(&fpu, 0.0, &q0, &p0, horizon).unwrap();
    // Reference: Chebyshev–Lagrange n = 16 at h = 0.01 (ωh = 0.5).
    let reference_gvi = GalerkinIntegrator::spectral(16, 0.01).unwrap();
    let reference = reference_gvi.integrate(&fpu, 0.0, &q0, &p0, 400).unwrap();
    let at = |t: f64| reference.position_at(t).unwrap();
    let h = 0.2;
    let ns: Vec<usize> = (5..=15).step_by(2).collect();
    let rich = n_refinement(|n| enriched(n - 3, fpu.omega(), h), &ns, &problem, at, 4).unwrap();
    let poly = n_refinement(
        |n| GalerkinIntegrator::new(Legendre::new(n)?, GaussLegendre::new(2 * n)?, h),
        &ns,
        &problem,
        at,
        4,
    );
    let fit = fitted_rate(&rich, RefineBy::N, ErrorMeasure::Map).unwrap();
    for (i, r) in rich.iter().enumerate() {
        let pe = poly.as_ref().map(|p| p[i].map_error).unwrap_or(f64::NAN);
        println!(
            "n = {:2}: enriched map error {:.2e} (curve {:.2e}), Legendre {pe:.2e}",
            r.n, r.map_error, r.error
        );
    }
    println!(
        "enriched: error ≈ C·{:.3}ⁿ (max log-residual {:.2}, {} points)",
        fit.rate, fit.max_residual, fit.used
    );
    assert!(fit.rate < 0.5 && fit.used >= 4, "rate {}", fit.rate);
    if let Ok(poly) = poly {
        for (r, p) in rich.iter().zip(&poly).skip(1) {
            assert!(
                r.map_error < 0.1 * p.map_error,
                "n = {}: {} vs {}",
                r.n,
                r.map_error,
                p.map_error
            );
        }
    }
}

/// The adiabatic invariant of FPU: the total oscillatory energy I = I₁ + I₂ + I₃ of the
/// enriched map at ωh = 2 (p = 4, h = 0.04) stays within O(1/ω) of I(0) = 1 up to T = 200,
/// as the exact flow's does (GNI §XIII.2), while the stiff springs exchange energy.
/// Negative control: RK4 at the same h damps the fast oscillation (|R(2i)| = 0.745 per step)
/// and loses I.
#[test]
fn fpu_oscillatory_energy_is_near_constant() {
    let fpu = Fpu::hlw();
    let (q0, p0) = fpu.hlw_initial_state();
    let h = 0.04;
    let steps = 5000;
    let gvi = enriched(4, fpu.omega(), h).unwrap();
    let traj = gvi.integrate(&fpu, 0.0, &q0, &p0, steps).unwrap();
    let mut inv = vec![0.0; fpu.invariant_names().len()];
    let (mut worst_i, mut worst_h) = (0.0f64, 0.0f64);
    let mut max_i3 = 0.0f64;
    fpu.invariants(&q0, &p0, &mut inv);
    let (h0, i0) = (inv[0], inv[1]);
    for (q, p) in traj.q.iter().zip(&traj.p) {
        fpu.invariants(q, p, &mut inv);
        worst_h = worst_h.max((inv[0] - h0).abs());
        worst_i = worst_i.max((inv[1] - i0).abs());
        max_i3 = max_i3.max(inv[4]);
    }
    let (qs, ps) = rk4_states(&fpu, &q0, &p0, h, steps);
    fpu.invariants(&qs[steps], &ps[steps], &mut inv);
    let rk4_i = inv[1];
    println!(
        "enriched ωh = 2, T = 200: max |I − I(0)| {worst_i:.2e}, max |H − H(0)| {worst_h:.2e}, max I₃ {max_i3:.3}; RK4 I(T) = {rk4_i:.2e}"
    );
    // The exact flow's I itself deviates from I(0) by up to 0.0624 over T = 200 (DOP853 at
    // 1e-13, lab/examples/enriched_fpu.rs); measured here 0.0649.
    assert!(worst_i < 0.07, "I deviates by {worst_i}");
    assert!(
        max_i3 > 0.1,
        "the third stiff spring never took energy: {max_i3}"
    );
    assert!((rk4_i - i0).abs() > 0.5, "RK4 should lose I: {rk4_i}");
}

/// The textbook enrichment (the negative control of the conditioning tests), one copy shared
/// with the library's unit tests (src/basis/enriched/tests.rs).
mod naive {
    use galerkin_vi::basis::{Basis, Legendre};
    include!("common/naive_enriched.rs");
}
use naive::NaiveEnriched;

/// Typed errors through the integrator: a step size other than the basis's, and a rule too
/// weak for its products at large ωh.
#[test]
fn integrator_refuses_a_mismatched_h_and_a_weak_rule() {
    let b = Enriched::new(4, 50.0, 0.2).unwrap();
    let e = GalerkinIntegrator::new(b.clone(), GaussLegendre::new(60).unwrap(), 0.1).unwrap_err();
    assert!(matches!(e, GviError::Mismatch { .. }), "{e}");
    let e = GalerkinIntegrator::new(b.clone(), GaussLegendre::new(14).unwrap(), 0.2).unwrap_err();
    assert!(matches!(e, GviError::InvalidQuadrature { .. }), "{e}");
    println!("{e}");
    let m = b.gauss_points();
    let rule = GaussLegendre::new(m).unwrap();
    assert_eq!(rule.points(), m);
    assert!(GalerkinIntegrator::new(b, rule, 0.2).is_ok());
}
