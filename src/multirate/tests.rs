//! Tests of the multirate Galerkin step: the single-rate map for one micro step, the fitted
//! order, symplecticity and momentum conservation with a negative control (the coupling
//! weighted differently in the slow bodies' equations), and typed errors.

use super::*;
use crate::baselines::{GalerkinMethod, GaussCollocationBaseline, integrate_one_step};
use crate::basis::BasisKind;
use crate::geometry::{finite_difference_jacobian, relative_symplecticity_defect};
use crate::integrator::GalerkinIntegrator;
use crate::quadrature::QuadratureKind;

/// A unit star, an inner planet of 1e-3 at radius 0.35 (period 1.3: the fast body) and an
/// outer one of 5e-3 at radius 1.6 (period 12.7), slightly inclined and eccentric (G = 1),
/// barycentric.
fn star_and_two_planets() -> (NBody, Vec<f64>, Vec<f64>) {
    let nb = NBody::new(vec![1.0, 1e-3, 5e-3], 1.0, 3).unwrap();
    let mut q = vec![0.0, 0.0, 0.0, 0.35, 0.0, 0.01, -0.9, 1.32, -0.04];
    let (w1, w2) = (1.0 / 0.35f64.sqrt(), 1.0 / 1.6f64.sqrt());
    let mut v = vec![
        0.0,
        0.0,
        0.0,
        0.02,
        1.08 * w1,
        0.03,
        -w2 * 0.82,
        -w2 * 0.56,
        0.01,
    ];
    nb.to_barycentric(&mut q, &mut v).unwrap();
    let p = nb.momenta(&v);
    (nb, q, p)
}

fn run<M: OneStepMethod>(m: &mut M, q: &[f64], p: &[f64], steps: usize) -> (Vec<f64>, Vec<f64>) {
    let (qs, ps) = integrate_one_step(m, q, p, steps).unwrap();
    (qs[steps].clone(), ps[steps].clone())
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn one_micro_step_is_the_single_rate_velocity_form() {
    // R = 1 with the same rule for every body: the discrete action is the single-rate one,
    // so the map is the polynomial Galerkin step's (Legendre basis, Gauss points), to the
    // solves' tolerance and round-off. Measured after 40 steps: |Δq| 2.2e-14 and 1.0e-14,
    // |Δp| 6.7e-17 and 3.5e-17 (momenta ~1e-3).
    let (nb, q, p) = star_and_two_planets();
    for (n, points) in [(6usize, 5usize), (8, 8)] {
        let h = 0.2;
        let shape = MultirateShape {
            n,
            points,
            micro_steps: 1,
            fast_n: n,
            fast_points: points,
        };
        let mut multirate = MultirateGalerkin::new(&nb, &[1], shape, h).unwrap();
        let gvi = GalerkinIntegrator::from_kinds(
            BasisKind::Legendre,
            n,
            QuadratureKind::GaussLegendre,
            Some(points),
            h,
        )
        .unwrap();
        let mut single = GalerkinMethod::new(&gvi, &nb).unwrap();
        let (q1, p1) = run(&mut multirate, &q, &p, 40);
        let (q2, p2) = run(&mut single, &q, &p, 40);
        let (dq, dp) = (max_diff(&q1, &q2), max_diff(&p1, &p2));
        eprintln!("n = {n}, m = {points}: |Δq| {dq:e}, |Δp| {dp:e}");
        assert!(
            dq < 1e-13 && dp < 1e-15,
            "n = {n}: |Δq| {dq:e}, |Δp| {dp:e}"
        );
    }
}

#[test]
fn order_is_the_polynomial_steps_with_micro_steps() {
    // n = 3 (k = 2 modes, Gauss collocation with 2 points): order 4 in H at fixed R = 3, for
    // slow and fast bodies alike. Reference: 8-stage Gauss collocation, h = 0.005. Measured:
    // 8.6e-3, 5.5e-4, 3.5e-5 (rates 3.97, 3.99).
    let (nb, q, p) = star_and_two_planets();
    let t = 6.0;
    let mut reference = GaussCollocationBaseline::new(&nb, 8, 0.005).unwrap();
    let (qr, _) = run(&mut reference, &q, &p, 1200);
    let hs = [0.3, 0.15, 0.075];
    let errors: Vec<f64> = hs
        .iter()
        .map(|&h| {
            let shape = MultirateShape::collocation(3, 3);
            let mut m = MultirateGalerkin::new(&nb, &[1], shape, h).unwrap();
            let (q1, _) = run(&mut m, &q, &p, (t / h).round() as usize);
            max_diff(&q1, &qr)
        })
        .collect();
    eprintln!("errors {errors:?}");
    for w in errors.windows(2) {
        let rate = (w[0] / w[1]).log2();
        assert!((rate - 4.0).abs() < 0.4, "errors {errors:?}, rate {rate}");
    }
}

/// The relative symplecticity defect of `steps` steps at (q, p), in variables (q, p/c) (one
/// scale for every momentum, a conformal change that keeps symplectic maps symplectic).
fn defect(m: &mut MultirateGalerkin, q: &[f64], p: &[f64], c: f64, steps: usize) -> f64 {
    let cell = std::cell::RefCell::new(m);
    let map = |q0: &[f64], ps: &[f64]| {
        let p0: Vec<f64> = ps.iter().map(|x| x * c).collect();
        let mut m = cell.borrow_mut();
        m.state.has_prev = false;
        let (q1, p1) = run(&mut **m, q0, &p0, steps);
        (q1, p1.iter().map(|x| x / c).collect())
    };
    let scaled: Vec<f64> = p.iter().map(|x| x / c).collect();
    relative_symplecticity_defect(&finite_difference_jacobian(map, q, &scaled, 1e-5))
}

fn negative_control(nb: &NBody, shape: MultirateShape, h: f64) -> MultirateGalerkin {
    let mut m = MultirateGalerkin::new(nb, &[1], shape, h).unwrap();
    m.consistent = false;
    m
}

#[test]
fn step_map_is_symplectic_and_an_inconsistent_coupling_is_not() {
    let (nb, q, p) = star_and_two_planets();
    let shape = MultirateShape::collocation(5, 3);
    let h = 0.4;
    let method = defect(
        &mut MultirateGalerkin::new(&nb, &[1], shape, h).unwrap(),
        &q,
        &p,
        1e-3,
        3,
    );
    let control = defect(&mut negative_control(&nb, shape, h), &q, &p, 1e-3, 3);
    // Measured: 3.8e-9 (the finite differences' own error) against 2.3e-5.
    eprintln!("defects: method {method:e}, control {control:e}");
    assert!(method < 1e-8, "multirate defect {method:e}");
    assert!(
        control > 30.0 * method.max(1e-9),
        "control defect {control:e}"
    );
}

/// Total angular momentum Σ qᵢ × pᵢ and linear momentum Σ pᵢ.
fn momenta(q: &[f64], p: &[f64]) -> ([f64; 3], [f64; 3]) {
    let (mut l, mut total) = ([0.0; 3], [0.0; 3]);
    for (a, b) in q.chunks(3).zip(p.chunks(3)) {
        l[0] += a[1] * b[2] - a[2] * b[1];
        l[1] += a[2] * b[0] - a[0] * b[2];
        l[2] += a[0] * b[1] - a[1] * b[0];
        (0..3).for_each(|c| total[c] += b[c]);
    }
    (l, total)
}

#[test]
fn linear_and_angular_momentum_are_conserved_and_the_control_drifts() {
    let (nb, q, p) = star_and_two_planets();
    let (l0, p0) = momenta(&q, &p);
    let norm = |x: [f64; 3]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
    let drift = |m: &mut MultirateGalerkin| {
        let (q1, p1) = run(m, &q, &p, 300);
        let (l1, p1t) = momenta(&q1, &p1);
        let dl = norm(std::array::from_fn(|c| l1[c] - l0[c])) / norm(l0);
        let dp = norm(std::array::from_fn(|c| p1t[c] - p0[c])) / max_abs(&p);
        (dl, dp)
    };
    let shape = MultirateShape::collocation(6, 4);
    let (dl, dp) = drift(&mut MultirateGalerkin::new(&nb, &[1], shape, 0.3).unwrap());
    let (cl, cp) = drift(&mut negative_control(&nb, shape, 0.3));
    eprintln!("momentum drifts: method {dl:e} {dp:e}, control {cl:e} {cp:e}");
    // Round-off: a few ulp per step over 300 steps. Measured: 6e-16 and 7e-16, against
    // 2.7e-6 and 1.4e-3 for the control.
    assert!(dl < 1e-13 && dp < 1e-13, "multirate: L {dl:e}, P {dp:e}");
    assert!(cl > 1e-9 && cp > 1e-9, "control: L {cl:e}, P {cp:e}");
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

#[test]
fn the_fast_body_is_the_shortest_orbit() {
    let (nb, q, p) = star_and_two_planets();
    assert_eq!(
        MultirateGalerkin::shortest_period_body(&nb, &q, &p),
        Some(1)
    );
    assert_eq!(
        MultirateGalerkin::shortest_period_body(&nb, &q[..6], &p),
        None
    );
    // Unbound: no fast body.
    let fast: Vec<f64> = p.iter().map(|x| 100.0 * x).collect();
    assert_eq!(
        MultirateGalerkin::shortest_period_body(&nb, &q, &fast),
        None
    );
}

#[test]
fn bad_input_gets_typed_errors() {
    let (nb, q, p) = star_and_two_planets();
    let good = MultirateShape::collocation(6, 3);
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            MultirateGalerkin::new(&nb, &[1], good, h),
            Err(GviError::InvalidStepSize { .. })
        ));
    }
    for fast in [&[][..], &[0, 1, 2][..], &[3][..], &[1, 1][..]] {
        assert!(
            matches!(
                MultirateGalerkin::new(&nb, fast, good, 0.1),
                Err(GviError::InvalidInput { .. })
            ),
            "fast bodies {fast:?}"
        );
    }
    let shapes = [
        MultirateShape { n: 1, ..good },
        MultirateShape { fast_n: 0, ..good },
        MultirateShape { points: 3, ..good },
        MultirateShape {
            fast_points: 2,
            ..good
        },
        MultirateShape {
            micro_steps: 0,
            ..good
        },
        MultirateShape {
            micro_steps: MAX_MICRO_STEPS + 1,
            ..good
        },
        MultirateShape {
            n: MAX_MULTIRATE_N + 1,
            ..good
        },
    ];
    for shape in shapes {
        assert!(
            matches!(
                MultirateGalerkin::new(&nb, &[1], shape, 0.1),
                Err(GviError::InvalidInput { .. })
            ),
            "{shape:?}"
        );
    }
    let mut m = MultirateGalerkin::new(&nb, &[1], good, 0.1).unwrap();
    let (mut q1, mut p1) = (vec![0.0; 9], vec![0.0; 9]);
    assert!(matches!(
        m.step(0.0, &q[..6], &p, &mut q1, &mut p1),
        Err(GviError::DimensionMismatch { .. })
    ));
    let mut bad = q.clone();
    bad[4] = f64::NAN;
    assert!(m.step(0.0, &bad, &p, &mut q1, &mut p1).is_err());
    // A collision: the solve fails with a typed error naming the step, not a panic.
    let mut crash = q.clone();
    crash[3..6].copy_from_slice(&q[..3]);
    assert!(matches!(
        m.step(0.0, &crash, &p, &mut q1, &mut p1),
        Err(GviError::NewtonFailure { .. })
    ));
}
