//! The paper's objects as the library exposes them: the Galerkin curve of a step
//! ([`GalerkinCurveRef`]), the discrete action S_d and its gradient, and the discrete Legendre
//! transforms. Each check has a negative control that must fail it.

use galerkin_vi::basis::Basis;
use galerkin_vi::curve::{GalerkinCurve, GalerkinCurveRef};
use galerkin_vi::integrator::Workspace;
use galerkin_vi::prelude::*;

use crate::counting::allocations;

/// Charged particle in a magnetic field with a quartic potential: not separable (L_qv ≠ 0),
/// so the general gradient path is exercised.
struct Magnetic;
impl Lagrangian for Magnetic {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        (v[0] * v[0] + v[1] * v[1]) * 0.5 + (q[0] * v[1] - q[1] * v[0]) * 0.75
            - (q[0] * q[0] + q[1] * q[1]) * 0.5
            - (q[0] * q[0] + q[1] * q[1]) * (q[0] * q[0] + q[1] * q[1]) * 0.125
    }
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Three steps of `lag` from (q0, p0); the last step's curve (absolute coefficients) and its
/// start and end states.
fn solved_step<L: Lagrangian>(
    gvi: &GalerkinIntegrator,
    lag: &L,
    q0: &[f64],
    p0: &[f64],
) -> (Vec<f64>, [Vec<f64>; 4]) {
    let mut ws = gvi.workspace(lag).unwrap();
    let d = q0.len();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
    for _ in 0..2 {
        gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
    }
    gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
    (ws.curve().coefficients().to_vec(), [q, p, qn, pn])
}

/// Central differences of `action` in every coefficient, step `delta` (n×D).
fn central_differences(coeffs: &[f64], delta: f64, action: impl Fn(&[f64]) -> f64) -> Vec<f64> {
    let mut c = coeffs.to_vec();
    (0..coeffs.len())
        .map(|i| {
            c[i] = coeffs[i] + delta;
            let plus = action(&c);
            c[i] = coeffs[i] - delta;
            let minus = action(&c);
            c[i] = coeffs[i];
            (plus - minus) / (2.0 * delta)
        })
        .collect()
}

/// The discrete action written out independently of the library: h Σ_j b_j L(q(c_j), q̇(c_j))
/// with q = Σ Q_i φ_i and q̇ = Σ Q_i φ_i' / h (`velocity_scale` = 1), or with the velocity
/// mis-scaled (the negative control's perturbed formula).
fn action_by_hand<L: Lagrangian>(
    gvi: &GalerkinIntegrator,
    lag: &L,
    coeffs: &[f64],
    velocity_scale: f64,
) -> f64 {
    let (n, d, h) = (gvi.n(), lag.dim(), gvi.step_size());
    let rule = gvi.rule();
    let (mut phi, mut dphi) = (vec![0.0; n], vec![0.0; n]);
    let mut s = 0.0;
    for (&c, &b) in rule.nodes.iter().zip(&rule.weights) {
        gvi.basis().eval(c, &mut phi, &mut dphi);
        let (mut q, mut v) = (vec![0.0; d], vec![0.0; d]);
        for i in 0..n {
            for r in 0..d {
                q[r] += phi[i] * coeffs[i * d + r];
                v[r] += velocity_scale * dphi[i] * coeffs[i * d + r] / h;
            }
        }
        s += b * lag.value(&q, &v);
    }
    h * s
}

/// ∂S_d/∂Q by central differences of the library's `discrete_action` agrees with its analytic
/// gradient (the stage residual's ∂S/∂Q), at a solved step's curve — where it is (−p_k, 0, …,
/// 0, p_{k+1}) — and at a perturbed curve. Central differences with δ = 1e-5 err by
/// O(δ² S''') + O(ε S / δ) ≈ 1e-10 relative; measured max errors relative to max|∂S/∂Q| over
/// the solved and the perturbed curve: Kepler (n = 12, h = 1) 3.3e-11, magnetic (n = 10,
/// h = 0.5) 5.6e-12, so the bound is 1e-9. Negative control: the same differences of the
/// action with the velocity mis-scaled by 1 + 1e-3 (a perturbed formula) miss by about 1e-3
/// relative (measured 2.0e-3 and 1.8e-3; required > 1e-4).
#[test]
fn action_gradient_by_central_differences_matches_the_stage_residual() {
    let kepler = Kepler::new(1.0).unwrap();
    let (kq, kp) = Kepler::paper_initial_state();
    let kepler_case = check_gradient(
        &kepler,
        &GalerkinIntegrator::spectral(12, 1.0).unwrap(),
        &kq,
        &kp,
    );
    let magnetic_case = check_gradient(
        &Magnetic,
        &GalerkinIntegrator::spectral(10, 0.5).unwrap(),
        &[0.6, 0.1],
        &[0.2, 0.5],
    );
    for ((good, wrong), name) in [(kepler_case, "kepler"), (magnetic_case, "magnetic")] {
        eprintln!("{name}: central differences {good:.2e}, perturbed formula {wrong:.2e}");
        assert!(good < 1e-9, "{name}: {good:.3e}");
        assert!(wrong > 1e-4, "{name}: negative control {wrong:.3e}");
    }
}

/// (relative max error of the differences of the library's action, the same for the
/// perturbed formula), over a solved and a perturbed curve.
fn check_gradient<L: Lagrangian>(
    lag: &L,
    gvi: &GalerkinIntegrator,
    q0: &[f64],
    p0: &[f64],
) -> (f64, f64) {
    let (n, d, h) = (gvi.n(), lag.dim(), gvi.step_size());
    let (solved, [qk, pk, _, pk1]) = solved_step(gvi, lag, q0, p0);
    let mut perturbed = solved.clone();
    for (i, x) in perturbed.iter_mut().enumerate() {
        *x += 1e-3 * ((i as f64) * 0.7).sin();
    }
    let (mut good, mut wrong) = (0.0f64, 0.0f64);
    for coeffs in [&solved, &perturbed] {
        let curve = GalerkinCurveRef::new(coeffs, n, d, h, 0.0).unwrap();
        let grad = gvi.discrete_action_gradient(lag, curve).unwrap();
        let scale = max_abs(&grad);
        let action = |c: &[f64]| {
            let curve = GalerkinCurveRef::new(c, n, d, h, 0.0).unwrap();
            gvi.discrete_action(lag, curve).unwrap()
        };
        // The library's value is the formula written out by hand.
        let (lib, hand) = (action(coeffs), action_by_hand(gvi, lag, coeffs, 1.0));
        assert!(
            (lib - hand).abs() <= 1e-13 * lib.abs().max(1.0),
            "{lib} vs {hand}"
        );
        let fd = central_differences(coeffs, 1e-5, action);
        good = good.max(max_diff(&fd, &grad) / scale);
        let fd_wrong =
            central_differences(coeffs, 1e-5, |c| action_by_hand(gvi, lag, c, 1.0 + 1e-3));
        wrong = wrong.max(max_diff(&fd_wrong, &grad) / scale);
        if std::ptr::eq(coeffs, &solved) {
            // At the solution: interior rows vanish, the ends are the momenta.
            let interior = max_abs(&grad[d..(n - 1) * d]);
            assert!(
                interior <= 1e-12 * scale,
                "interior residual {interior:.3e}"
            );
            let p_first: Vec<f64> = grad[..d].iter().map(|x| -x).collect();
            assert!(max_diff(&p_first, &pk) <= 1e-12 * max_abs(&pk));
            assert!(max_diff(&grad[(n - 1) * d..], &pk1) <= 1e-12 * max_abs(&pk1));
            assert_eq!(&coeffs[..d], &qk[..]);
        }
    }
    (good, wrong)
}

/// The discrete Legendre transforms of a solved step's curve are the step's p_k and p_{k+1}
/// to round-off. The unit of round-off is ε (‖K‖∞/h · max|Q| + max|p|): the curve's absolute
/// coefficients are rounded to ε|Q| and the kinetic rows amplify that by ‖K‖∞/h (the step
/// solves in increments and does not). Measured max errors over 20 steps in that unit: Kepler
/// (n = 32, h = 2, periapsis included) 0.92 and 0.30, magnetic (n = 16, h = 0.5) 0.094 and
/// 0.14; the bound is 8. Negative control: one interior coefficient moved by 1e-8 (a curve that
/// no longer solves the stage equations) misses by more than the bound (measured ≥ 1e6 units).
#[test]
fn discrete_legendre_transforms_reproduce_the_steps_momenta() {
    let kepler = Kepler::new(1.0).unwrap();
    let (kq, kp) = Kepler::paper_initial_state();
    let (a, a_neg) = check_transforms(
        &kepler,
        &GalerkinIntegrator::spectral(32, 2.0).unwrap(),
        &kq,
        &kp,
        20,
    );
    let (b, b_neg) = check_transforms(
        &Magnetic,
        &GalerkinIntegrator::spectral(16, 0.5).unwrap(),
        &[0.6, 0.1],
        &[0.2, 0.5],
        20,
    );
    eprintln!("kepler {a:?} (control {a_neg:.2e}), magnetic {b:?} (control {b_neg:.2e})");
    for (x, neg) in [(a, a_neg), (b, b_neg)] {
        assert!(x.0 < 8.0 && x.1 < 8.0, "{x:?}");
        assert!(neg > 8.0, "negative control {neg:.3e}");
    }
}

/// ‖K‖∞, the largest row sum of |K_ab|.
fn kinetic_norm(gvi: &GalerkinIntegrator) -> f64 {
    gvi.kinetic_matrix()
        .chunks_exact(gvi.n())
        .map(|row| row.iter().map(|x| x.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

fn check_transforms<L: Lagrangian>(
    lag: &L,
    gvi: &GalerkinIntegrator,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
) -> ((f64, f64), f64) {
    let d = lag.dim();
    let mut ws = gvi.workspace(lag).unwrap();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
    let (mut e0, mut e1, mut neg) = (0.0f64, 0.0f64, f64::INFINITY);
    for _ in 0..steps {
        gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
        let (pk, pk1) = gvi.discrete_legendre_transforms(lag, ws.curve()).unwrap();
        // Round-off of the transforms as functions of the curve: the absolute coefficients
        // carry a rounding ε|Q| each, which the kinetic rows (1/h) Σ_b K_ab M Q_b amplify by
        // ‖K‖∞/h (unit mass here); the step itself solves in increments and does not see it.
        let scale = kinetic_norm(gvi) / gvi.step_size() * max_abs(ws.curve().coefficients());
        let eps = f64::EPSILON;
        e0 = e0.max(max_diff(&pk, &p) / (eps * (scale + max_abs(&p))));
        e1 = e1.max(max_diff(&pk1, &pn) / (eps * (scale + max_abs(&pn))));
        let mut moved = ws.curve().to_curve();
        moved.coefficients_mut()[d] += 1e-8;
        let (mk, mk1) = gvi
            .discrete_legendre_transforms(lag, moved.as_ref())
            .unwrap();
        neg = neg.min(
            (max_diff(&mk, &p) / (eps * (scale + max_abs(&p))))
                .max(max_diff(&mk1, &pn) / (eps * (scale + max_abs(&pn)))),
        );
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
    }
    ((e0, e1), neg)
}

/// At a solved step's curve the discrete action is the discrete Lagrangian L_d(q_k, q_{k+1})
/// of the two-point problem (the same extremal curve, paper eq. (1)): measured relative
/// difference 1.4e-16 (Kepler n = 16, h = 1); bound 1e-14. Negative control: the action of
/// the straight line between the same ends is not extremal and differs by more than 1e-3.
#[test]
fn the_action_at_a_solved_curve_is_the_discrete_lagrangian() {
    let kepler = Kepler::new(1.0).unwrap();
    let (kq, kp) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::spectral(16, 1.0).unwrap();
    let (curve, [qk, _, qk1, _]) = solved_step(&gvi, &kepler, &kq, &kp);
    let c = GalerkinCurveRef::new(&curve, 16, 2, 1.0, 0.0).unwrap();
    let s = gvi.discrete_action(&kepler, c).unwrap();
    let ld = gvi.discrete_lagrangian(&kepler, &qk, &qk1).unwrap();
    let rel = (s - ld.value).abs() / ld.value.abs();
    eprintln!("S_d(solved curve) − L_d: {rel:.2e}");
    assert!(rel < 1e-14, "{rel:.3e}");
    // The straight line from q_k to q_{k+1}: the Chebyshev–Lagrange nodes τ_i, Q_i = q_k +
    // τ_i (q_{k+1} − q_k).
    let nodes = ChebyshevLagrange::new(16).unwrap().nodes().to_vec();
    let line: Vec<f64> = nodes
        .iter()
        .flat_map(|&t| (0..2).map(move |r| (t, r)))
        .map(|(t, r)| qk[r] + t * (qk1[r] - qk[r]))
        .collect();
    let sl = gvi
        .discrete_action(
            &kepler,
            GalerkinCurveRef::new(&line, 16, 2, 1.0, 0.0).unwrap(),
        )
        .unwrap();
    assert!(
        (sl - ld.value).abs() / ld.value.abs() > 1e-3,
        "{sl} vs {}",
        ld.value
    );
}

/// A trajectory's step curves: their ends are the step states exactly, and their evaluation is
/// the trajectory's dense output bit for bit.
#[test]
fn trajectory_curves_are_the_dense_output() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::spectral(16, 2.0).unwrap();
    let traj = gvi.integrate(&kepler, 0.5, &q0, &p0, 6).unwrap();
    for k in 0..traj.steps() {
        let c = traj.curve(k).unwrap();
        assert_eq!(c.start(), &traj.q[k][..]);
        assert_eq!(c.end(), &traj.q[k + 1][..]);
        assert_eq!(
            (c.start_time(), c.end_time()),
            (traj.time(k), traj.time(k) + 2.0)
        );
        for s in [0.0, 0.3, 0.5, 0.9] {
            let t = c.start_time() + s * c.h();
            assert_eq!(
                c.state_at(gvi.basis(), t).unwrap(),
                traj.state_on_curve(t).unwrap()
            );
        }
    }
    // The workspace's curve is the last step's.
    let mut ws = gvi.workspace(&kepler).unwrap();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
    for _ in 0..6 {
        gvi.step(&kepler, &mut ws, &q, &p, &mut qn, &mut pn)
            .unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
    }
    assert_eq!(ws.curve().end(), &q[..]);
}

/// An owned curve refilled from curves of other sizes keeps its buffer (no allocation up to
/// its capacity), and bad input is a typed error.
#[test]
fn owned_curves_and_bad_input() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let mut keep = GalerkinCurve::with_capacity(16, 2, 2.0);
    let before = keep.coefficients().as_ptr();
    for n in [8, 16, 12] {
        let gvi = GalerkinIntegrator::spectral(n, 2.0).unwrap();
        let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 2).unwrap();
        keep.set(traj.curve(1).unwrap());
        assert_eq!((keep.n(), keep.start_time()), (n, 2.0));
        assert_eq!(keep.coefficients(), &traj.coefficients[1][..]);
    }
    assert_eq!(keep.coefficients().as_ptr(), before);

    let c = [0.0; 8];
    assert!(GalerkinCurveRef::new(&c, 4, 2, 1.0, 0.0).is_ok());
    assert!(GalerkinCurveRef::new(&c, 3, 2, 1.0, 0.0).is_err());
    assert!(GalerkinCurveRef::new(&c, 4, 2, 0.0, 0.0).is_err());
    assert!(GalerkinCurveRef::new(&c, 1, 8, 1.0, 0.0).is_err());
    assert!(GalerkinCurveRef::new(&[f64::NAN; 8], 4, 2, 1.0, 0.0).is_err());
    assert!(GalerkinCurve::new(vec![0.0; 8], 4, 2, 1.0, f64::INFINITY).is_err());
    let ok = GalerkinCurveRef::new(&c, 4, 2, 1.0, 0.0).unwrap();
    let basis4 = ChebyshevLagrange::new(4).unwrap();
    assert!(ok.state_at(&basis4, 1.5).is_err());
    assert!(
        ok.state_at(&ChebyshevLagrange::new(5).unwrap(), 0.5)
            .is_err()
    );
    // The integrator refuses curves of another n, h or dimension.
    let gvi = GalerkinIntegrator::spectral(4, 1.0).unwrap();
    assert!(gvi.discrete_action(&kepler, ok).is_ok());
    assert!(
        gvi.discrete_action(&kepler, GalerkinCurveRef::new(&c, 4, 2, 0.5, 0.0).unwrap())
            .is_err()
    );
    assert!(
        gvi.discrete_action(&kepler, GalerkinCurveRef::new(&c, 2, 4, 1.0, 0.0).unwrap())
            .is_err()
    );
    let gvi5 = GalerkinIntegrator::spectral(5, 1.0).unwrap();
    assert!(gvi5.discrete_legendre_transforms(&kepler, ok).is_err());
    let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 1).unwrap();
    assert!(traj.curve(1).is_err());
}

/// Reading a step's curve inside a step loop allocates nothing: the workspace's view, its
/// evaluation into caller buffers, and an owned curve refilled within its capacity (counted by
/// the test's allocator; negative control: the allocating convenience `state_at` is counted).
#[test]
fn curve_views_allocate_nothing_in_a_step_loop() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::spectral(16, 2.0).unwrap();
    let mut ws = gvi.workspace(&kepler).unwrap();
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
    let (mut phi, mut dphi) = (vec![0.0; 16], vec![0.0; 16]);
    let (mut x, mut v) = (vec![0.0; 2], vec![0.0; 2]);
    let mut keep = GalerkinCurve::with_capacity(16, 2, 2.0);
    let mut sum = 0.0;
    let mut step = |k: usize, ws: &mut Workspace, sum: &mut f64| {
        gvi.step(&kepler, ws, &q, &p, &mut qn, &mut pn).unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
        let curve = ws.curve().starting_at(2.0 * k as f64);
        curve.state_into(gvi.basis(), 0.5, &mut phi, &mut dphi, &mut x, &mut v);
        keep.set(curve);
        *sum += x[0] + v[1] + keep.coefficients()[3];
    };
    for k in 0..3 {
        step(k, &mut ws, &mut sum);
    }
    let before = allocations();
    for k in 3..10 {
        step(k, &mut ws, &mut sum);
    }
    assert_eq!(allocations() - before, 0);
    assert!(sum.is_finite());
    let before = allocations();
    let _ = ws.curve().state_at(gvi.basis(), 1.0).unwrap();
    assert!(allocations() > before, "the negative control must allocate");
}
