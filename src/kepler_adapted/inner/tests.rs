//! Tests of [`InnerKeplerGalerkin`]: the map of `with_kepler_bodies(1 … k)` in other
//! coordinates, freezing that changes the cost and not the map, symplecticity and angular
//! momentum with a non-symplectic tableau in the same coordinates as the negative control,
//! and typed errors.

use super::super::KeplerAdaptedGalerkin;
use super::super::jacobi::{dot, sub};
use super::super::tests::{angular_momentum, defect, j2000, run, strong_three_body};
use super::*;
use crate::baselines::{GaussCollocationBaseline, integrate_one_step};

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Radau IIA with 2 stages (order 3): collocation, neither symplectic nor conserving quadratic
/// invariants — the negative control in the same coordinates and iteration.
fn radau_iia(nb: &NBody, h: f64, kepler: usize) -> InnerKeplerGalerkin {
    let (c, b) = (vec![1.0 / 3.0, 1.0], vec![0.75, 0.25]);
    let a = vec![5.0 / 12.0, -1.0 / 12.0, 0.75, 0.25];
    InnerKeplerGalerkin::from_tableau(nb, c, b, a, h, kepler).unwrap()
}

#[test]
fn the_map_is_that_of_the_kepler_adapted_bodies_one_to_k() {
    // One step (s = 4, h = 0.5) from each of 8 states 5 time units apart on an orbit of the
    // strongly perturbed three-body system, by fresh integrators (no history): k = 1 against
    // `with_kepler_bodies(&[1])`, k = 2 against `new`. Measured: at most 8.9e-16 in the
    // positions (of size 1) and 1.3e-17 in the momenta (of size 1e-2): the two iterations'
    // round-off.
    let (nb, q, p) = strong_three_body();
    let mut orbit = GaussCollocationBaseline::new(&nb, 6, 0.05).unwrap();
    let (qs, ps) = integrate_one_step(&mut orbit, &q, &p, 800).unwrap();
    for (k, bodies) in [(1, vec![1]), (2, vec![1, 2])] {
        let (mut dq, mut dp) = (0.0f64, 0.0f64);
        for (q0, p0) in qs.iter().zip(&ps).step_by(100) {
            let mut fast = InnerKeplerGalerkin::new(&nb, 4, 0.5, k).unwrap();
            let mut reference =
                KeplerAdaptedGalerkin::with_kepler_bodies(&nb, 4, 0.5, &bodies).unwrap();
            let (qi, pi) = run(&mut fast, q0, p0, 1);
            let (qr, pr) = run(&mut reference, q0, p0, 1);
            dq = dq.max(max_diff(&qi, &qr));
            dp = dp.max(max_diff(&pi, &pr));
        }
        eprintln!("k = {k}: one step, positions {dq:e}, momenta {dp:e}");
        assert!(dq < 4e-15 && dp < 6e-17, "k = {k}: {dq:e} {dp:e}");
    }
}

#[test]
fn on_j2000_mercury_kepler_adapted_is_the_same_map_and_freezing_saves_force_evaluations() {
    // J2000, Mercury on its Kepler orbit, s = 8, h = 20 d, 100 steps (2 000 days). The scale
    // of round-off here: `with_kepler_bodies(&[1])` from a start one part in 5e15 away (one
    // coordinate of Mercury) ends 5.7e-13 AU away. Measured against that reference:
    // 7.4e-14 AU; against the same integrator without freezing 5.7e-13 AU, with 3.0 full
    // (+ 2.9 partial) against 4.9 full force evaluations per stage and step. (Unfrozen and
    // frozen differ by the round-off scale: freezing changes where the iterations stop, by
    // less than the tolerance.)
    let (nb, q, p) = j2000();
    let steps = 100;
    let mut reference = KeplerAdaptedGalerkin::with_kepler_bodies(&nb, 8, 20.0, &[1]).unwrap();
    let (qr, _) = run(&mut reference, &q, &p, steps);
    let mut nudged = q.clone();
    nudged[4] *= 1.0 + 2e-16;
    let mut reference = KeplerAdaptedGalerkin::with_kepler_bodies(&nb, 8, 20.0, &[1]).unwrap();
    let round_off = max_diff(&qr, &run(&mut reference, &nudged, &p, steps).0);
    let mut fast = InnerKeplerGalerkin::new(&nb, 8, 20.0, 1).unwrap();
    let (qf, _) = run(&mut fast, &q, &p, steps);
    let mut unfrozen = InnerKeplerGalerkin::new(&nb, 8, 20.0, 1).unwrap();
    unfrozen.freezing = false;
    let (qu, _) = run(&mut unfrozen, &q, &p, steps);
    let (against_reference, against_unfrozen) = (max_diff(&qf, &qr), max_diff(&qf, &qu));
    let per_step = |m: &InnerKeplerGalerkin| m.force_evaluations() as f64 / (8 * steps) as f64;
    let (full_frozen, full_unfrozen) = (per_step(&fast), per_step(&unfrozen));
    eprintln!(
        "J2000: round-off scale {round_off:.2e}; against with_kepler_bodies \
         {against_reference:.2e}, against unfrozen {against_unfrozen:.2e}; full evaluations \
         per step {full_frozen} (+{} partial) vs {full_unfrozen}",
        fast.partial_force_evaluations() as f64 / (8 * steps) as f64
    );
    assert!(round_off < 5e-12, "{round_off:e}");
    assert!(against_reference < 4.0 * round_off, "{against_reference:e}");
    assert!(against_unfrozen < 4.0 * round_off, "{against_unfrozen:e}");
    assert!(fast.partial_force_evaluations() > 0);
    assert!(
        full_frozen < 0.7 * full_unfrozen,
        "{full_frozen} {full_unfrozen}"
    );
}

#[test]
fn the_step_map_is_symplectic_and_radau_in_the_same_coordinates_is_not() {
    // Measured: Gauss 8.2e-10 (the finite differences' own error), Radau IIA 8.5e-5.
    let (nb, q, p) = strong_three_body();
    let gauss = defect(
        &mut InnerKeplerGalerkin::new(&nb, 3, 1.0, 1).unwrap(),
        &q,
        &p,
        1e-2,
        4,
    );
    let radau = defect(&mut radau_iia(&nb, 1.0, 1), &q, &p, 1e-2, 4);
    eprintln!("defects: Gauss {gauss:e}, Radau IIA {radau:e}");
    assert!(gauss < 1e-8, "Gauss defect {gauss:e}");
    assert!(radau > 1e-7, "negative control defect {radau:e}");
}

#[test]
fn angular_and_linear_momentum_are_conserved_and_radau_drifts() {
    // 400 steps. Measured: Gauss 2.2e-15, Radau IIA 6.7e-3 in the angular momentum.
    let (nb, q, p) = strong_three_body();
    let l0 = angular_momentum(&q, &p);
    let scale = dot(l0, l0).sqrt();
    let drift = |m: &mut InnerKeplerGalerkin| {
        let (q1, p1) = run(m, &q, &p, 400);
        let l1 = angular_momentum(&q1, &p1);
        let ptot: Vec<f64> = (0..3).map(|k| p1.iter().skip(k).step_by(3).sum()).collect();
        (dot(sub(l1, l0), sub(l1, l0)).sqrt() / scale, ptot)
    };
    let (gauss, ptot) = drift(&mut InnerKeplerGalerkin::new(&nb, 3, 0.5, 1).unwrap());
    let (radau, _) = drift(&mut radau_iia(&nb, 0.5, 1));
    eprintln!("L drift: Gauss {gauss:e}, Radau IIA {radau:e}; total momentum {ptot:?}");
    assert!(gauss < 1e-13, "Gauss angular momentum drift {gauss:e}");
    assert!(radau > 1e-9, "negative control drift {radau:e}");
    assert!(ptot.iter().all(|x| x.abs() < 1e-15), "{ptot:?}");
}

#[test]
fn bad_input_gets_typed_errors() {
    let (nb, q, p) = strong_three_body();
    let invalid = |r: Result<InnerKeplerGalerkin>| match r {
        Err(GviError::InvalidInput { .. } | GviError::InvalidStepSize { .. }) => {}
        other => panic!("expected a typed error, got {other:?}"),
    };
    invalid(InnerKeplerGalerkin::new(&nb, 4, 0.5, 0));
    invalid(InnerKeplerGalerkin::new(&nb, 4, 0.5, 3));
    invalid(InnerKeplerGalerkin::new(&nb, 0, 0.5, 1));
    invalid(InnerKeplerGalerkin::new(&nb, 17, 0.5, 1));
    invalid(InnerKeplerGalerkin::new(&nb, 4, 0.0, 1));
    invalid(InnerKeplerGalerkin::new(&nb, 4, f64::NAN, 1));
    let mut m = InnerKeplerGalerkin::new(&nb, 4, 0.5, 1).unwrap();
    let (mut q1, mut p1) = (vec![0.0; 9], vec![0.0; 9]);
    // Mismatched dimensions.
    assert!(m.step(0.0, &q[..6], &p, &mut q1, &mut p1).is_err());
    // A planet on the star: the Kepler drift fails, as a typed step failure.
    let mut bad = q.clone();
    bad[3..6].copy_from_slice(&q[0..3]);
    match m.step(0.0, &bad, &p, &mut q1, &mut p1) {
        Err(GviError::NewtonFailure { .. }) => {}
        other => panic!("expected a step failure, got {other:?}"),
    }
    // A non-finite state.
    let mut nan = p.clone();
    nan[4] = f64::NAN;
    assert!(m.step(0.0, &q, &nan, &mut q1, &mut p1).is_err());
}
