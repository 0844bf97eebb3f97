//! The Poincaré time transformation (`galerkin_vi::time_transform`): Kepler at e = 0.9 and
//! e = 0.99 against the exact solution, energy without drift, symplecticity of the s-flow and
//! the N-body momentum maps — each geometric check with a negative control that lacks the
//! property and fails it. Measured numbers are in docs/guide/time-transformations.md.

use crate::kepler_periapsis::{fictitious_period, kepler_at_periapsis};
use galerkin_vi::GviError;
use galerkin_vi::events::{Event, EventOptions};
use galerkin_vi::geometry::{finite_difference_jacobian, relative_symplecticity_defect};
use galerkin_vi::prelude::*;
use galerkin_vi::systems::kepler_orbit::KeplerOrbit;
use galerkin_vi::time_transform::{
    CentralDistance, Combine, Monitor, PairDistances, TimeTransformOptions, TimeTransformed,
    integrate_time_transformed,
};
use std::f64::consts::{PI, TAU};

/// Max position error of the outputs of a time-transformed Kepler run at t = k·2π/16 over
/// `orbits` orbits, n basis functions, `per_orbit` fictitious steps per orbit.
fn kepler_error(e: f64, n: usize, per_orbit: usize, orbits: usize) -> (f64, usize) {
    let (q0, p0) = kepler_at_periapsis(e);
    let kepler = Kepler::new(1.0).unwrap();
    let tt =
        TimeTransformed::new(kepler, CentralDistance::new(1.5).unwrap(), &q0, &p0, None).unwrap();
    let ds = fictitious_period(e, 1.5) / per_orbit as f64;
    let gvi = GalerkinIntegrator::spectral(n, ds).unwrap();
    let options = TimeTransformOptions {
        t_end: Some(TAU * orbits as f64),
        max_steps: 2 * per_orbit * orbits,
        every: Some(TAU / 16.0),
        keep_steps: false,
        ..TimeTransformOptions::default()
    };
    let run = integrate_time_transformed(&gvi, &tt, 0.0, &q0, &p0, &mut [], &options).unwrap();
    let exact = KeplerOrbit::from_state(1.0, q0, p0, 0.0).unwrap();
    assert_eq!(run.outputs.len(), 16 * orbits + 1);
    let mut err: f64 = 0.0;
    for (k, o) in run.outputs.iter().enumerate() {
        // Output at exactly the requested physical time.
        assert_eq!(o.t, k as f64 * TAU / 16.0);
        let (qe, _) = exact.state_at(o.t);
        err = err.max((o.q[0] - qe[0]).abs().max((o.q[1] - qe[1]).abs()));
    }
    (err, run.steps())
}

/// Max position error at step ends of a fixed-step Galerkin run (physical time) with the same
/// n and the same number of steps; a solver failure counts as an infinite error.
fn fixed_step_error(e: f64, n: usize, steps: usize, orbits: usize) -> f64 {
    let (q0, p0) = kepler_at_periapsis(e);
    let kepler = Kepler::new(1.0).unwrap();
    let h = TAU * orbits as f64 / steps as f64;
    let gvi = GalerkinIntegrator::spectral(n, h).unwrap();
    let Ok(traj) = gvi.integrate(&kepler, 0.0, &q0, &p0, steps) else {
        return f64::INFINITY;
    };
    let exact = KeplerOrbit::from_state(1.0, q0, p0, 0.0).unwrap();
    (0..=steps)
        .map(|k| {
            let (qe, _) = exact.state_at(traj.time(k));
            let q = &traj.q[k];
            (q[0] - qe[0]).abs().max((q[1] - qe[1]).abs())
        })
        .fold(0.0, galerkin_vi::reduce::nan_max)
}

/// Kepler e = 0.9 and e = 0.99 over 100 orbits against the exact solution, at 16 physical
/// output times per orbit located on t(s). Negative control: the fixed-step Galerkin method
/// with the same n and the same number of steps misses by orders of magnitude more (or its
/// solver fails at periapsis).
#[test]
fn kepler_high_eccentricity_over_100_orbits_matches_the_exact_solution() {
    // Measured 1.1e-12 and 1.7e-12 (docs/guide/time-transformations.md).
    for (e, per_orbit, bound) in [(0.9, 40, 1e-11), (0.99, 60, 1e-11)] {
        let (err, steps) = kepler_error(e, 12, per_orbit, 100);
        eprintln!("e = {e}: time-transformed n = 12, {steps} steps: max error {err:.3e}");
        assert!(err < bound, "e = {e}: {err:e}");
        let fixed = fixed_step_error(e, 12, steps, 100);
        eprintln!("e = {e}: fixed step, same n and steps: max error {fixed:.3e}");
        assert!(
            fixed > 1e3 * err,
            "e = {e}: fixed-step {fixed:e} vs {err:e}"
        );
    }
}

/// The energy error of the s-flow stays bounded with no drift over 10⁴ orbits of e = 0.9;
/// negative control: RK4 on the same s-flow with the same Δs drifts.
#[test]
fn energy_error_is_bounded_without_drift() {
    let e = 0.9;
    let (q0, p0) = kepler_at_periapsis(e);
    let kepler = Kepler::new(1.0).unwrap();
    let tt =
        TimeTransformed::new(kepler, CentralDistance::new(1.5).unwrap(), &q0, &p0, None).unwrap();
    // Few steps at a low n, so that the energy error is truncation (1e-5), not round-off; a
    // step count per orbit that is not a whole number, so that the step ends visit every
    // phase of the orbit within a few orbits (with a whole number they creep along the orbit
    // with its small period error, and the sampled maximum follows them).
    let per_orbit = 16.37;
    let orbits = 10_000;
    let ds = fictitious_period(e, 1.5) / per_orbit;
    let gvi = GalerkinIntegrator::spectral(4, ds).unwrap();
    let mut stepper = tt.stepper(&gvi, 0.0, &q0, &p0).unwrap();
    let e0 = tt.hamiltonian(&q0, &p0);
    let steps = (per_orbit * orbits as f64) as usize;
    let mut errors = Vec::with_capacity(steps);
    for _ in 0..steps {
        stepper.step().unwrap();
        errors.push(tt.hamiltonian(stepper.position(), stepper.momentum()) - e0);
    }
    // The fictitious steps cover the orbits in physical time (to the period error).
    eprintln!("physical time: {} orbits", stepper.time() / TAU);
    assert!(
        (stepper.time() / TAU - orbits as f64).abs() < 0.5,
        "{}",
        stepper.time() / TAU
    );
    let (max, growth) = drift(&errors);
    let tenths: Vec<String> = errors
        .chunks(steps / 10)
        .map(|c| format!("{:.2e}", c.iter().fold(0.0f64, |m, x| m.max(x.abs()))))
        .collect();
    eprintln!("max |ΔH| per tenth of the run: {}", tenths.join(" "));
    eprintln!("Galerkin n = 4, {per_orbit} steps/orbit: max |ΔH| {max:.3e}, growth {growth:.2}");
    assert!(max < 2e-6, "{max:e}"); // measured 8.70e-7
    assert!(growth < 1.2, "growth {growth}"); // measured 1.00

    // RK4 on dq/ds = g M⁻¹p, dp/ds = −∇g (H − E₀) − g ∇V over the same span, at Δs/8 (at Δs
    // itself its energy error is O(1) within the run).
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let mut rk_errors = Vec::with_capacity(steps);
    for _ in 0..steps {
        for _ in 0..8 {
            rk4_step(&tt, ds / 8.0, &mut q, &mut p);
        }
        rk_errors.push(tt.hamiltonian(&q, &p) - e0);
    }
    let (rk_max, rk_growth) = drift(&rk_errors);
    eprintln!("RK4 on the s-flow: max |ΔH| {rk_max:.3e}, growth {rk_growth:.2}");
    assert!(rk_growth > 5.0, "RK4 growth {rk_growth}");
}

/// The largest |error| over the run, and the growth: the largest |error| over the last tenth
/// of the run over that over the first tenth (about 1 for a bounded error, about 10 or more
/// for one that grows linearly).
fn drift(errors: &[f64]) -> (f64, f64) {
    let tenth = errors.len() / 10;
    let max = |s: &[f64]| s.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    (
        max(errors),
        max(&errors[errors.len() - tenth..]) / max(&errors[..tenth]),
    )
}

fn rk4_step<S: Lagrangian, M: Monitor>(
    tt: &TimeTransformed<S, M>,
    h: f64,
    q: &mut [f64],
    p: &mut [f64],
) {
    let d = q.len();
    let mut kq = vec![vec![0.0; d]; 4];
    let mut kp = vec![vec![0.0; d]; 4];
    let c = [0.0, 0.5, 0.5, 1.0];
    for s in 0..4 {
        let qs: Vec<f64> = (0..d)
            .map(|r| q[r] + if s > 0 { c[s] * h * kq[s - 1][r] } else { 0.0 })
            .collect();
        let ps: Vec<f64> = (0..d)
            .map(|r| p[r] + if s > 0 { c[s] * h * kp[s - 1][r] } else { 0.0 })
            .collect();
        let (a, b) = (&mut kq[s], &mut kp[s]);
        tt.vector_field(&qs, &ps, a, b);
    }
    for r in 0..d {
        q[r] += h / 6.0 * (kq[0][r] + 2.0 * kq[1][r] + 2.0 * kq[2][r] + kq[3][r]);
        p[r] += h / 6.0 * (kp[0][r] + 2.0 * kp[1][r] + 2.0 * kp[2][r] + kp[3][r]);
    }
}

/// The s-flow's one-step map is symplectic (exact tangent map, and the finite-difference one
/// to its own accuracy). Negative controls: RK4 on the same s-flow, and a "naive" variable
/// step — the physical-time Galerkin step with h = Δs·g(q_k) chosen from the state — are not.
#[test]
fn the_s_flow_is_symplectic_and_naive_variable_steps_are_not() {
    let e = 0.99;
    let (q0, p0) = kepler_at_periapsis(e);
    let kepler = Kepler::new(1.0).unwrap();
    let tt =
        TimeTransformed::new(kepler, CentralDistance::new(1.5).unwrap(), &q0, &p0, None).unwrap();
    let ds = fictitious_period(e, 1.5) / 40.0;
    let gvi = GalerkinIntegrator::spectral(10, ds).unwrap();
    // At periapsis and a quarter of the fictitious period later.
    let mut stepper = tt.stepper(&gvi, 0.0, &q0, &p0).unwrap();
    for _ in 0..10 {
        stepper.step().unwrap();
    }
    let states = [
        (q0.to_vec(), p0.to_vec()),
        (stepper.position().to_vec(), stepper.momentum().to_vec()),
    ];
    for (q, p) in &states {
        let exact = gvi.step_jacobian(&tt, q, p).unwrap();
        let defect = relative_symplecticity_defect(&exact.matrix);
        eprintln!(
            "time-transformed step at r = {:.3}: exact tangent defect {defect:.2e}",
            q[0].hypot(q[1])
        );
        assert!(defect < 1e-12, "{defect:e}");
        let map = |q: &[f64], p: &[f64]| {
            let j = gvi.step_jacobian(&tt, q, p).unwrap();
            (j.q_next, j.p_next)
        };
        let fd = relative_symplecticity_defect(&finite_difference_jacobian(map, q, p, 1e-6));
        assert!(fd < 1e-7, "finite-difference defect {fd:e}");
        // RK4 on the s-flow.
        let rk = |q: &[f64], p: &[f64]| {
            let (mut q, mut p) = (q.to_vec(), p.to_vec());
            rk4_step(&tt, ds, &mut q, &mut p);
            (q, p)
        };
        let rk_defect = relative_symplecticity_defect(&finite_difference_jacobian(rk, q, p, 1e-6));
        eprintln!("  RK4 on the s-flow: {rk_defect:.2e}");
        assert!(rk_defect > 1e3 * fd.max(1e-10), "{rk_defect:e}");
        // The naive variable step in physical time.
        let naive = |q: &[f64], p: &[f64]| {
            let h = ds * tt.rate(q);
            let g = GalerkinIntegrator::spectral(10, h).unwrap();
            let j = g.step_jacobian(&kepler, q, p).unwrap();
            (j.q_next, j.p_next)
        };
        let naive_defect =
            relative_symplecticity_defect(&finite_difference_jacobian(naive, q, p, 1e-6));
        eprintln!("  naive variable physical step: {naive_defect:.2e}");
        assert!(naive_defect > 1e3 * fd.max(1e-10), "{naive_defect:e}");
    }
}

/// The Pythagorean three-body problem (Burrau): masses 3, 4, 5 at rest, G = 1.
fn pythagorean() -> (NBody, Vec<f64>, Vec<f64>) {
    let nb = NBody::new(vec![3.0, 4.0, 5.0], 1.0, 2).unwrap();
    (nb, vec![1.0, 3.0, -2.0, -1.0, 1.0, -1.0], vec![0.0; 6])
}

/// Total linear momentum (x, y) and angular momentum of a planar N-body state.
fn momenta(q: &[f64], p: &[f64]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for b in 0..q.len() / 2 {
        m[0] += p[2 * b];
        m[1] += p[2 * b + 1];
        m[2] += q[2 * b] * p[2 * b + 1] - q[2 * b + 1] * p[2 * b];
    }
    m
}

/// The largest change of the linear and the angular momentum over `steps` fictitious steps
/// (or up to a solver failure: the controls' monitors change the motion), and the physical
/// time reached.
fn momentum_changes<M: Monitor>(monitor: M, steps: usize) -> (f64, f64, f64) {
    let (nb, q0, p0) = pythagorean();
    let tt = TimeTransformed::new(nb, monitor, &q0, &p0, None).unwrap();
    let gvi = GalerkinIntegrator::spectral(8, 0.01).unwrap();
    let mut stepper = tt.stepper(&gvi, 0.0, &q0, &p0).unwrap();
    let start = momenta(&q0, &p0);
    let (mut linear, mut angular): (f64, f64) = (0.0, 0.0);
    for _ in 0..steps {
        if stepper.step().is_err() {
            break;
        }
        let m = momenta(stepper.position(), stepper.momentum());
        linear = linear
            .max((m[0] - start[0]).abs())
            .max((m[1] - start[1]).abs());
        angular = angular.max((m[2] - start[2]).abs());
    }
    (linear, angular, stepper.time())
}

/// A translation-invariant monitor that is not rotation-invariant: the smallest pair
/// separation along x only (smoothly, as a sum of x-separations squared).
struct AlongX;
impl Monitor for AlongX {
    fn name(&self) -> String {
        "x-separations".into()
    }
    fn value<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let (a, b, c) = (q[0] - q[2], q[2] - q[4], q[4] - q[0]);
        (a * a + b * b + c * c).sqrt()
    }
}

/// Linear and angular momentum are conserved to round-off by the time-transformed N-body
/// steps (the pair monitors are invariant under translations and rotations), through the
/// first close encounters of the Pythagorean problem. Negative controls: a monitor that is
/// not translation-invariant (|q| of the whole configuration) changes the linear momentum,
/// one that is not rotation-invariant (separations along x) the angular momentum.
#[test]
fn nbody_momentum_maps_are_conserved_in_s() {
    let steps = 400;
    for combine in [Combine::Min, Combine::Softmin] {
        let monitor = PairDistances::new(3, 2, 1.0, combine).unwrap();
        let (linear, angular, t) = momentum_changes(monitor, steps);
        eprintln!("{combine:?}: to t = {t:.3}: |ΔP| {linear:.2e}, |ΔL| {angular:.2e}");
        // Past the first close encounter (bodies 2 and 3 near t = 1.88).
        assert!(t > 1.8, "{t}");
        assert!(linear < 1e-12 && angular < 1e-12, "{linear:e} {angular:e}");
    }
    // On H = E₀ the s-flow of any monitor conserves the physical momenta (it is the physical
    // motion); what breaks them for an asymmetric monitor is the discrete energy error, so
    // the controls' changes are small, but far above round-off.
    let (linear, _, t) = momentum_changes(CentralDistance::new(1.0).unwrap(), steps);
    eprintln!("|q| monitor: to t = {t:.3}: |ΔP| {linear:.2e}");
    assert!(linear > 1e-10, "{linear:e}");
    let (linear, angular, t) = momentum_changes(AlongX, steps);
    eprintln!("x-separation monitor: to t = {t:.3}: |ΔP| {linear:.2e}, |ΔL| {angular:.2e}");
    assert!(linear < 1e-12, "{linear:e}");
    assert!(angular > 1e-10, "{angular:e}");
}

/// Events in physical time: apoapsis passages (y falls through 0) at t = π + 2πk, located on
/// t(s); a stopping event ends the run on the curve; dense output at any physical time.
#[test]
fn events_and_dense_output_in_physical_time() {
    let e = 0.9;
    let (q0, p0) = kepler_at_periapsis(e);
    let kepler = Kepler::new(1.0).unwrap();
    let tt =
        TimeTransformed::new(kepler, CentralDistance::new(1.5).unwrap(), &q0, &p0, None).unwrap();
    let ds = fictitious_period(e, 1.5) / 40.0;
    let gvi = GalerkinIntegrator::spectral(12, ds).unwrap();
    let mut events = [
        Event::new("apoapsis", |_t: f64, q: &[f64], _p: &[f64]| q[1]).falling(),
        Event::new("late", |t: f64, _q: &[f64], _p: &[f64]| t - 10.25 * TAU).stop(),
    ];
    let options = TimeTransformOptions {
        t_end: Some(20.0 * TAU),
        max_steps: 10_000,
        keep_curves: true,
        events: EventOptions::default(),
        ..TimeTransformOptions::default()
    };
    let run = integrate_time_transformed(&gvi, &tt, 0.0, &q0, &p0, &mut events, &options).unwrap();
    assert!(run.stopped);
    assert!((run.end.t - 10.25 * TAU).abs() < 1e-12, "{}", run.end.t);
    let apo: Vec<f64> = run
        .crossings
        .iter()
        .filter(|c| c.event == 0)
        .map(|c| c.t)
        .collect();
    assert_eq!(apo.len(), 10);
    let worst = apo
        .iter()
        .enumerate()
        .map(|(k, t)| (t - (PI + TAU * k as f64)).abs())
        .fold(0.0, f64::max);
    eprintln!("apoapsis times: max error {worst:.2e}");
    assert!(worst < 1e-8, "{worst:e}");
    // Dense output against the exact solution between step ends.
    let exact = KeplerOrbit::from_state(1.0, q0, p0, 0.0).unwrap();
    let mut dense: f64 = 0.0;
    for i in 0..200 {
        let t = 10.0 * TAU * i as f64 / 199.0;
        let (q, p) = run.state_at(&gvi, &tt, t).unwrap();
        let (qe, ve) = exact.state_at(t);
        dense = dense.max((q[0] - qe[0]).abs().max((q[1] - qe[1]).abs()));
        dense = dense.max((p[0] - ve[0]).abs().max((p[1] - ve[1]).abs()) * (1.0 - e));
    }
    eprintln!("dense output: max error {dense:.2e}");
    assert!(dense < 1e-7, "{dense:e}");
    assert!(run.state_at(&gvi, &tt, 11.0 * TAU).is_err());
    assert!(matches!(
        run.state_at(&gvi, &tt, f64::NAN),
        Err(GviError::InvalidInput { .. })
    ));
}

/// A time-transformed step allocates nothing once the workspace is warm (Kepler and the
/// Pythagorean problem through its first encounter, with the built-in monitors); the
/// negative control, a step of a monitor written with a `Vec` inside its value, does.
#[test]
fn a_time_transformed_step_allocates_nothing() {
    use crate::counting::allocations;
    let count = |steps: &mut dyn FnMut()| {
        let before = allocations();
        steps();
        allocations() - before
    };
    let (q0, p0) = kepler_at_periapsis(0.99);
    let tt = TimeTransformed::new(
        Kepler::new(1.0).unwrap(),
        CentralDistance::new(1.5).unwrap(),
        &q0,
        &p0,
        None,
    )
    .unwrap();
    let gvi = GalerkinIntegrator::spectral(12, fictitious_period(0.99, 1.5) / 60.0).unwrap();
    let mut stepper = tt.stepper(&gvi, 0.0, &q0, &p0).unwrap();
    for _ in 0..5 {
        stepper.step().unwrap();
    }
    let kepler = count(&mut || {
        for _ in 0..200 {
            stepper.step().unwrap();
        }
    });
    assert_eq!(kepler, 0, "Kepler: {kepler} allocations in 200 steps");
    let (nb, q0, p0) = pythagorean();
    let monitor = PairDistances::new(3, 2, 1.5, Combine::Softmin).unwrap();
    let tt = TimeTransformed::new(nb, monitor, &q0, &p0, None).unwrap();
    let gvi = GalerkinIntegrator::spectral(10, 0.01).unwrap();
    let mut stepper = tt.stepper(&gvi, 0.0, &q0, &p0).unwrap();
    for _ in 0..5 {
        stepper.step().unwrap();
    }
    let nbody = count(&mut || {
        for _ in 0..400 {
            stepper.step().unwrap();
        }
    });
    assert_eq!(nbody, 0, "N-body: {nbody} allocations in 400 steps");
    assert!(stepper.time() > 1.8, "{}", stepper.time());
    // Negative control: the same monitor behind a Vec in its value allocates per node.
    struct Allocating(PairDistances);
    impl Monitor for Allocating {
        fn name(&self) -> String {
            "allocating".into()
        }
        fn value<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
            let copy: Vec<T> = q.to_vec();
            self.0.value(&copy)
        }
        fn gradient(&self, q: &[f64], grad: &mut [f64]) -> f64 {
            self.0.gradient(q, grad)
        }
        fn hessian(&self, q: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
            self.0.hessian(q, grad, hess)
        }
    }
    let (nb, q0, p0) = pythagorean();
    let tt = TimeTransformed::new(nb, Allocating(monitor), &q0, &p0, None).unwrap();
    let mut stepper = tt.stepper(&gvi, 0.0, &q0, &p0).unwrap();
    stepper.step().unwrap();
    let control = count(&mut || {
        stepper.step().unwrap();
    });
    assert!(control > 0, "the allocating monitor was not counted");
}
