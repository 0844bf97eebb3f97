//! Geometric properties of the Galerkin integrator: exact step Jacobian, symplecticity,
//! discrete Noether theorem, long-run energy behaviour, curve-rate convergence of the
//! invariants, and RK4 / Störmer–Verlet as negative / positive controls.
//!
//! Measured numbers quoted in comments were obtained in the test profile (opt-level 3).

use galerkin_vi::baselines::{
    GalerkinMethod, OneStepMethod, Rk4, StormerVerlet, integrate_one_step,
};
use galerkin_vi::geometry::{
    MomentumMap, Rotation, Translation, check_report, energy_along_curves, energy_at_step_ends,
    linear_trend, momentum_along_curves, momentum_at_step_ends, relative_symplecticity_defect,
    symplecticity_defect,
};
use galerkin_vi::prelude::*;
use nalgebra::DMatrix;
use proptest::prelude::*;

use crate::common::systems;
use systems::Coupled;

/// Charged particle in a uniform magnetic field B = 1 with an anisotropic potential
/// (non-separable: L_qv ≠ 0), written directly as a `Lagrangian`.
struct Magnetic;
impl Lagrangian for Magnetic {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        (v[0] * v[0] + v[1] * v[1]) * 0.5 + (q[0] * v[1] - q[1] * v[0]) * 0.5
            - (q[0] * q[0] + q[1] * q[1] * 2.0) * 0.5
            - (q[0] * q[0] + q[1] * q[1]).powi(2) * 0.05
    }
}

/// Two gravitating bodies in the plane in absolute coordinates (D = 4): translation and
/// rotation invariant.
struct TwoBody {
    m1: f64,
    m2: f64,
}
impl Mechanical for TwoBody {
    fn degrees_of_freedom(&self) -> usize {
        4
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![
            self.m1, self.m1, self.m2, self.m2,
        ]))
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let dx = q[0] - q[2];
        let dy = q[1] - q[3];
        -(dx * dx + dy * dy).sqrt().recip() * (self.m1 * self.m2)
    }
}

fn max_abs(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// Central finite difference of one step (fresh workspace per evaluation).
fn fd_step_jacobian<F>(step: F, q: &[f64], p: &[f64], eps: f64) -> DMatrix<f64>
where
    F: Fn(&[f64], &[f64]) -> (Vec<f64>, Vec<f64>),
{
    let d = q.len();
    let mut j = DMatrix::zeros(2 * d, 2 * d);
    for c in 0..2 * d {
        let mut x_plus: Vec<f64> = q.iter().chain(p).copied().collect();
        let mut x_minus = x_plus.clone();
        x_plus[c] += eps;
        x_minus[c] -= eps;
        let (qp, pp) = step(&x_plus[..d], &x_plus[d..]);
        let (qm, pm) = step(&x_minus[..d], &x_minus[d..]);
        for r in 0..d {
            j[(r, c)] = (qp[r] - qm[r]) / (2.0 * eps);
            j[(d + r, c)] = (pp[r] - pm[r]) / (2.0 * eps);
        }
    }
    j
}

fn galerkin_step<L: Lagrangian>(
    gvi: &GalerkinIntegrator<impl Basis, impl Quadrature>,
    lag: &L,
    q: &[f64],
    p: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let t = gvi.integrate(lag, 0.0, q, p, 1).unwrap();
    (t.q[1].clone(), t.p[1].clone())
}

const EPS: f64 = f64::EPSILON;

/// Every (basis, quadrature) pairing that can be built at this n (weak rules are skipped:
/// they are rejected with a clear error, which another test covers).
fn all_integrators(n: usize, h: f64) -> Vec<GalerkinIntegrator<AnyBasis, QuadratureRule>> {
    let mut out = Vec::new();
    for b in BasisKind::ALL {
        for q in QuadratureKind::ALL {
            if let Ok(g) = GalerkinIntegrator::from_kinds(b, n, q, None, h) {
                out.push(g);
            }
        }
    }
    assert!(!out.is_empty());
    out
}

/// Max relative symplecticity defect over `steps` consecutive step Jacobians.
fn max_defect_along<L: Lagrangian>(
    gvi: &GalerkinIntegrator<AnyBasis, QuadratureRule>,
    lag: &L,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
) -> f64 {
    let mut ws = gvi.workspace(lag).unwrap();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let mut worst = 0.0f64;
    for k in 0..steps {
        let sj = gvi.step_jacobian_in(lag, &mut ws, &q, &p, k).unwrap();
        worst = worst.max(relative_symplecticity_defect(&sj.matrix));
        q = sj.q_next;
        p = sj.p_next;
    }
    worst
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 24,
        failure_persistence: None,
        .. ProptestConfig::default()
    })]

    /// Bound Kepler orbits away from collision: start at distance r on the x-axis with a
    /// tangential speed f·√(μ/r), f ∈ [0.85, 1.1], so the periapsis is ≥ 0.45.
    #[test]
    fn kepler_steps_are_symplectic(
        n in 3usize..=20, h in 0.05f64..0.3, r in 0.8f64..1.2, f in 0.85f64..1.1,
    ) {
        let kepler = Kepler::new(1.0).unwrap();
        let (q0, p0) = ([r, 0.0], [0.0, f / r.sqrt()]);
        for gvi in all_integrators(n, h) {
            let d = max_defect_along(&gvi, &kepler, &q0, &p0, 3);
            prop_assert!(d <= 1e-10, "n = {n}, h = {h}: relative defect {d:e}");
        }
    }

    #[test]
    fn pendulum_steps_are_symplectic(
        n in 3usize..=20, h in 0.05f64..0.5, th in -2.0f64..2.0, w in -1.0f64..1.0,
    ) {
        let pend = Pendulum::unit();
        for gvi in all_integrators(n, h) {
            let d = max_defect_along(&gvi, &pend, &[th], &[w], 3);
            prop_assert!(d <= 1e-10, "n = {n}, h = {h}: relative defect {d:e}");
        }
    }

    #[test]
    fn coupled_anharmonic_steps_are_symplectic(
        n in 3usize..=20, h in 0.05f64..0.4,
        q in proptest::array::uniform2(-0.8f64..0.8), p in proptest::array::uniform2(-0.8f64..0.8),
    ) {
        for gvi in all_integrators(n, h) {
            let d = max_defect_along(&gvi, &Coupled, &q, &p, 3);
            prop_assert!(d <= 1e-10, "n = {n}, h = {h}: relative defect {d:e}");
        }
    }
}

/// The exact step Jacobian against central differences with ε = 1e-6. FD error: truncation
/// ε²|f‴|/6 ≈ 1e-12·O(10), round-off (step results carry ~1e-15 noise from the Newton
/// solve) / ε ≈ 1e-9. Tolerance 1e-6 · max(1, max|J|) leaves a wide margin above that.
#[test]
fn step_jacobian_matches_finite_differences() {
    let eps = 1e-6;
    let kepler = Kepler::new(1.0).unwrap();
    let gvi = GalerkinIntegrator::spectral(8, 0.5).unwrap();
    let check = |name: &str, exact: &DMatrix<f64>, fd: &DMatrix<f64>| {
        let err = max_abs(&(exact - fd));
        let scale = max_abs(exact).max(1.0);
        println!("{name}: max |J − J_fd| = {err:.3e} (max|J| = {scale:.3e})");
        assert!(err <= 1e-6 * scale, "{name}: {err:e}");
    };
    let (q, p) = ([0.4, 0.0], [0.0, 2.0]);
    let j = gvi.step_jacobian(&kepler, &q, &p).unwrap();
    let fd = fd_step_jacobian(|q, p| galerkin_step(&gvi, &kepler, q, p), &q, &p, eps);
    check("kepler periapsis", &j.matrix, &fd);
    let (qs, ps) = galerkin_step(&gvi, &kepler, &q, &p);
    assert_eq!((qs, ps), (j.q_next.clone(), j.p_next.clone()));

    let gvi = GalerkinIntegrator::spectral(7, 0.3).unwrap();
    let (q, p) = ([0.5, -0.3], [0.2, 0.6]);
    let j = gvi.step_jacobian(&Coupled, &q, &p).unwrap();
    let fd = fd_step_jacobian(|q, p| galerkin_step(&gvi, &Coupled, q, p), &q, &p, eps);
    check("coupled anharmonic", &j.matrix, &fd);

    let j = gvi.step_jacobian(&Magnetic, &q, &p).unwrap();
    let fd = fd_step_jacobian(|q, p| galerkin_step(&gvi, &Magnetic, q, p), &q, &p, eps);
    check("magnetic (non-separable)", &j.matrix, &fd);
}

/// The general (non-separable) path: a charged particle in a magnetic field.
#[test]
fn non_separable_lagrangian_is_symplectic() {
    let mut worst = 0.0f64;
    for (n, h) in [(4, 0.2), (9, 0.5), (16, 1.0)] {
        for gvi in all_integrators(n, h) {
            let d = max_defect_along(&gvi, &Magnetic, &[0.5, -0.3], &[0.2, 0.6], 20);
            worst = worst.max(d);
        }
    }
    println!("magnetic: max relative defect {worst:.3e}");
    assert!(worst <= 1e-10);
}

/// Tangent map of the harmonic oscillator: the exact flow is a rotation of phase space; the
/// cumulative product matches it to the method's accuracy and the Lyapunov exponents vanish.
#[test]
fn tangent_map_and_lyapunov_of_harmonic_oscillator() {
    let ho = HarmonicOscillator::unit();
    let gvi = GalerkinIntegrator::spectral(10, 0.5).unwrap();
    let maps = gvi.tangent_map(&ho, &[1.0], &[0.0], 40).unwrap();
    assert_eq!(maps.len(), 40);
    let t = 20.0f64;
    let exact = DMatrix::from_row_slice(2, 2, &[t.cos(), t.sin(), -t.sin(), t.cos()]);
    let err = max_abs(&(&maps[39] - exact));
    assert!(err < 1e-8, "{err:e}");
    let defect = symplecticity_defect(&maps[39]);
    println!("HO: tangent map after 40 steps: error {err:.3e}, defect {defect:.3e}");
    assert!(defect < 1e-10, "{defect:e}"); // measured 2.9e-12 (≈ 7e-14 per step)
    let lyap = gvi.lyapunov_estimate(&ho, &[1.0], &[0.0], 200).unwrap();
    assert!(lyap.iter().all(|l| l.abs() < 1e-3), "{lyap:?}");
    assert!(gvi.tangent_map(&ho, &[1.0], &[0.0], 0).is_err());
    assert!(gvi.step_jacobian(&ho, &[f64::NAN], &[0.0]).is_err());
    assert!(gvi.step_jacobian(&ho, &[1.0, 2.0], &[0.0]).is_err());
}

/// Discrete Noether theorem for the rotation-invariant Kepler problem (n = 10, h = 0.5,
/// 10⁴ steps): max |J_k − J_0| ≤ C·ε·√steps·|J_0|. Measured C ≈ 330 (drift ≈ 5.8e-12; the
/// round-off walk has a small bias, slope ≈ 1e-15 per step); asserted C = 1000.
#[test]
fn kepler_angular_momentum_is_conserved() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::spectral(10, 0.5).unwrap();
    let steps = 10_000;
    let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, steps).unwrap();
    let rot = Rotation::planar(2, 1, 0, 1).unwrap();
    let j = momentum_at_step_ends(&rot, &traj);
    let j0 = j.values[0].abs();
    let drift = j.max_deviation();
    let c = drift / (EPS * (steps as f64).sqrt() * j0);
    println!("kepler: angular momentum drift {drift:.3e}, C = {c:.1}");
    assert!(c <= 1000.0, "C = {c}");
}

/// Linear and angular momentum of a translation- and rotation-invariant two-body problem in
/// absolute coordinates (D = 4) over 10⁴ steps, same bound as for Kepler.
#[test]
fn two_body_momenta_are_conserved() {
    let sys = TwoBody { m1: 1.0, m2: 0.5 };
    let m = sys.m1 + sys.m2;
    // Separation 1 along x, relative speed 0.9 × circular, plus a total momentum (0.1, 0.05).
    let v_rel = 0.9 * m.sqrt();
    let q0 = [sys.m2 / m, 0.0, -sys.m1 / m, 0.0];
    let pr = sys.m1 * sys.m2 / m * v_rel;
    let (px, py) = (0.1, 0.05);
    let p0 = [
        px * sys.m1 / m,
        pr + py * sys.m1 / m,
        px * sys.m2 / m,
        -pr + py * sys.m2 / m,
    ];
    let gvi = GalerkinIntegrator::spectral(10, 0.25).unwrap();
    let steps = 10_000;
    let traj = gvi.integrate(&sys, 0.0, &q0, &p0, steps).unwrap();
    let tx = Translation::axis(2, 2, 0).unwrap();
    let ty = Translation::axis(2, 2, 1).unwrap();
    let rot = Rotation::planar(2, 2, 0, 1).unwrap();
    assert!((tx.value(&q0, &p0) - px).abs() < 1e-15);
    let l0 = rot.value(&q0, &p0).abs();
    for (name, map, scale) in [
        ("P_x", &tx as &dyn MomentumMap, px),
        ("P_y", &ty, py),
        ("L", &rot, l0),
    ] {
        let s = momentum_at_step_ends(map, &traj);
        let c = s.max_deviation() / (EPS * (steps as f64).sqrt() * scale.max(1.0));
        println!(
            "two-body {name}: drift {:.3e}, C = {c:.1}",
            s.max_deviation()
        );
        assert!(c <= 1000.0, "{name}: C = {c}");
    }
}

/// Energy of Kepler (e = 0.6) over 10⁵ steps with n = 8, h = 0.5 (T = 5·10⁴, ~8000
/// periods): bounded, with no drift — the least-squares slope over the run, |slope|·T, is
/// small against the RMS spread of the error about the fitted line. RK4 at a comparable
/// cost (≈ 200 force evaluations per unit time each) drifts clearly.
#[test]
fn kepler_energy_long_run_has_no_drift_and_rk4_does() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::spectral(8, 0.5).unwrap();
    let steps = 100_000;
    let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, steps).unwrap();
    let e = energy_at_step_ends(&kepler, &traj).unwrap();
    let err: Vec<f64> = e.values.iter().map(|v| v - e.values[0]).collect();
    let trend = linear_trend(&e.t, &err);
    let max_err = e.max_deviation();
    let evals_per_time = traj.gradient_evaluations() as f64 / traj.end_time();
    println!(
        "galerkin n=8 h=0.5: max |ΔE| = {max_err:.3e}, slope·T = {:.3e}, spread = {:.3e}, \
         force evaluations per unit time = {evals_per_time:.0}",
        trend.drift(),
        trend.spread
    );
    assert!(max_err < 1e-6, "{max_err:e}");
    assert!(trend.drift() < 0.05 * trend.spread, "{trend:?}");

    // Negative control: RK4 with h = 0.02 (4 force evaluations per step, 200 per unit time),
    // energy sampled at the same times t = 0.5 k.
    let mut rk4 = Rk4::new(&kepler, 0.02).unwrap();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
    let mut inv = [0.0; 2];
    kepler.invariants(&q, &p, &mut inv);
    let e0 = inv[0];
    let (mut ts, mut es) = (vec![0.0], vec![0.0]);
    for k in 0..2_500_000usize {
        rk4.step(k as f64 * 0.02, &q, &p, &mut qn, &mut pn).unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
        if (k + 1) % 25 == 0 {
            kepler.invariants(&q, &p, &mut inv);
            ts.push((k + 1) as f64 * 0.02);
            es.push(inv[0] - e0);
        }
    }
    let rk = linear_trend(&ts, &es);
    println!(
        "rk4 h=0.02: final ΔE = {:.3e}, slope·T = {:.3e}, spread = {:.3e}",
        es[es.len() - 1],
        rk.drift(),
        rk.spread
    );
    assert!(rk.drift() > 10.0 * rk.spread, "{rk:?}");
}

/// Step Jacobians of the baselines on the harmonic oscillator (a linear map, so central
/// differences with ε = 1e-3 are exact up to round-off ~1e-13): Störmer–Verlet is
/// symplectic (defect ≤ 1e-10), RK4 is not (defect = √2·|det − 1| = √2·(h⁶/72 − h⁸/576)
/// ≈ 3.1e-4 at h = 0.5).
#[test]
fn baseline_symplecticity_controls() {
    let ho = HarmonicOscillator::unit();
    let h = 0.5;
    let one = |m: &mut dyn OneStepMethod, q: &[f64], p: &[f64]| {
        let (mut qn, mut pn) = (vec![0.0; 1], vec![0.0; 1]);
        m.step(0.0, q, p, &mut qn, &mut pn).unwrap();
        (qn, pn)
    };
    let mut sv = StormerVerlet::new(&ho, h).unwrap();
    let mut rk = Rk4::new(&ho, h).unwrap();
    let jv = fd_step_jacobian(|q, p| one(&mut sv.clone(), q, p), &[0.7], &[0.2], 1e-3);
    let jr = fd_step_jacobian(|q, p| one(&mut rk.clone(), q, p), &[0.7], &[0.2], 1e-3);
    let (dv, dr) = (symplecticity_defect(&jv), symplecticity_defect(&jr));
    println!("HO h=0.5: verlet defect {dv:.3e}, rk4 defect {dr:.3e}");
    assert!(dv <= 1e-10);
    assert!(dr >= 1e-4);
    let exact = 2f64.sqrt() * (h.powi(6) / 72.0 - h.powi(8) / 576.0);
    assert!((dr - exact).abs() < 1e-9, "{dr} vs {exact}");
    // The Galerkin step Jacobian is exactly symplectic at the same h.
    let gvi = GalerkinIntegrator::spectral(6, h).unwrap();
    let jg = gvi.step_jacobian(&ho, &[0.7], &[0.2]).unwrap().matrix;
    assert!(symplecticity_defect(&jg) <= 1e-13);
    // Verlet on the non-linear Kepler problem via FD (ε = 1e-5: truncation ε²·|f‴| and
    // round-off ε_mach/ε both ≲ 1e-10).
    let kepler = Kepler::new(1.0).unwrap();
    let mut svk = StormerVerlet::new(&kepler, 0.05).unwrap();
    let two = |m: &mut StormerVerlet<'_, Kepler>, q: &[f64], p: &[f64]| {
        let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
        m.step(0.0, q, p, &mut qn, &mut pn).unwrap();
        (qn, pn)
    };
    let jk = fd_step_jacobian(
        |q, p| two(&mut svk.clone(), q, p),
        &[0.4, 0.0],
        &[0.0, 2.0],
        1e-5,
    );
    let dk = symplecticity_defect(&jk);
    println!("kepler h=0.05: verlet defect (FD) {dk:.3e}");
    assert!(dk <= 1e-8);
    // Galerkin and baselines agree through the common interface and `integrate_one_step`.
    let mut g = GalerkinMethod::new(&gvi, &ho).unwrap();
    let (qs, ps) = integrate_one_step(&mut g, &[0.7], &[0.2], 10).unwrap();
    let (qr, _) = integrate_one_step(&mut rk, &[0.7], &[0.2], 10).unwrap();
    let (qv, _) = integrate_one_step(&mut svk, &[0.4, 0.0], &[0.0, 2.0], 3).unwrap();
    assert_eq!((qs.len(), ps.len(), qv.len()), (11, 11, 4));
    let exact = 0.7 * 5f64.cos() + 0.2 * 5f64.sin();
    assert!((qs[10][0] - exact).abs() < 1e-6 && (qr[10][0] - exact).abs() < 1e-2);
    assert!(g.name().starts_with("galerkin") && rk.name().starts_with("rk4"));
    assert!(Rk4::new(&Magnetic, 0.1).is_err());
    assert!(integrate_one_step(&mut sv, &[0.7], &[0.2], 0).is_err());
}

/// The paper's claim: energy and angular momentum errors along the Galerkin curves converge
/// at the curve rate (≈ 0.74ⁿ for Kepler e = 0.6, h = 2, 100 steps).
#[test]
fn invariants_along_curves_converge_at_the_curve_rate() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let rot = Rotation::planar(2, 1, 0, 1).unwrap();
    let (mut ns, mut e_err, mut j_err) = (vec![], vec![], vec![]);
    for n in (24..=44).step_by(4) {
        let gvi = GalerkinIntegrator::spectral(n, 2.0).unwrap();
        let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 100).unwrap();
        let e = energy_along_curves(&kepler, &traj, 16).unwrap();
        let j = momentum_along_curves(&kepler, &rot, &traj, 16).unwrap();
        let ee = e.values.iter().map(|v| (v + 0.5).abs()).fold(0.0, f64::max);
        let je = j.values.iter().map(|v| (v - 0.8).abs()).fold(0.0, f64::max);
        println!("n = {n}: energy error {ee:.3e}, angular momentum error {je:.3e}");
        ns.push(n as f64);
        e_err.push(ee);
        j_err.push(je);
    }
    let fe = galerkin_vi_lab::fit::fit_geometric(&ns, &e_err).unwrap();
    let fj = galerkin_vi_lab::fit::fit_geometric(&ns, &j_err).unwrap();
    println!(
        "rates: energy {:.4}, angular momentum {:.4}",
        fe.rate, fj.rate
    );
    // Measured: energy 0.7426, angular momentum 0.7469 (n = 24 … 44 step 4).
    assert!((fe.rate - 0.74).abs() < 0.04, "{fe:?}");
    assert!((fj.rate - 0.74).abs() < 0.04, "{fj:?}");
}

/// The `gvi check` report on Kepler.
#[test]
fn check_report_on_kepler() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::spectral(12, 0.5).unwrap();
    let report = check_report(&gvi, &kepler, &q0, &p0, 200).unwrap();
    println!("{report}");
    assert!(report.max_relative_symplecticity_defect <= 1e-10);
    assert_eq!(report.momenta.len(), 1);
    assert!(report.momenta[0].max_drift_ends < 1e-12);
    assert!(report.energy_max_error_ends.unwrap() < 1e-7);
    assert!(report.energy_max_error_curves.unwrap() >= report.energy_max_error_ends.unwrap());
    let text = report.to_string();
    assert!(text.contains("angular_momentum") && text.contains("symplecticity"));
    let pend = Pendulum::unit();
    let r = check_report(&gvi, &pend, &[1.0], &[0.0], 20).unwrap();
    assert!(r.momenta.is_empty() && r.energy_max_error_ends.is_some());
}
