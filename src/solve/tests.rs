//! Tests of [`super`].
use super::*;
use crate::adaptive::{AdaptiveOptions, integrate_adaptive};
use crate::lagrangian::Mechanical;
use crate::lie::FreeRigidBody;
use crate::systems::{HarmonicOscillator, Kepler};
use nalgebra::DMatrix;
use num_dual::DualNum;

fn kepler() -> (Kepler, InitialState) {
    let (q, p) = Kepler::paper_initial_state();
    (
        Kepler::new(1.0).unwrap(),
        InitialState {
            t0: 0.5,
            q: q.to_vec(),
            p: p.to_vec(),
        },
    )
}

/// The same states, curves, per-step n and step size, bit for bit.
fn assert_same(a: &Trajectory, b: &Trajectory) {
    assert_eq!(a.q, b.q);
    assert_eq!(a.p, b.p);
    assert_eq!(a.coefficients, b.coefficients);
    assert_eq!(a.step_n, b.step_n);
    assert_eq!((a.h, a.t0, a.n), (b.h, b.t0, b.n));
    assert_eq!(a.gradient_evaluations(), b.gradient_evaluations());
}

/// A free particle that meets a wall of non-finite force at q = 1: from q = 0 with unit
/// speed, the steps reaching past t = 1 fail.
struct Wall;

impl Mechanical for Wall {
    fn degrees_of_freedom(&self) -> usize {
        1
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::identity(1, 1)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        if q[0].re() < 1.0 {
            q[0] * 0.0
        } else {
            T::from(f64::NAN)
        }
    }
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        out[0] = if q[0] < 1.0 { 0.0 } else { f64::NAN };
    }
    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        out[0] = if q[0] < 1.0 { 0.0 } else { f64::NAN };
    }
}

impl System for Wall {
    fn name(&self) -> &'static str {
        "wall"
    }
    fn invariant_names(&self) -> &'static [&'static str] {
        &[]
    }
    fn invariants(&self, _q: &[f64], _p: &[f64], _out: &mut [f64]) {}
}

fn wall_start() -> InitialState {
    InitialState {
        t0: 0.0,
        q: vec![0.0],
        p: vec![1.0],
    }
}

#[test]
fn a_fixed_n_solve_is_integrate_bit_for_bit() {
    let (kepler, init) = kepler();
    for solver in [StageSolverKind::Auto, StageSolverKind::Exact] {
        let mut method = MethodSpec::spectral(14, 0.75, 12);
        method.solver = solver;
        let reference = method
            .integrator()
            .unwrap()
            .integrate(&kepler, init.t0, &init.q, &init.p, method.steps)
            .unwrap();
        let solution = solve(&kepler, &init, &method).unwrap();
        assert_same(&solution.trajectory, &reference);
        assert!(solution.adaptive.is_none() && solution.step_choice.is_none());
        assert!(solution.warnings().is_empty());
        assert_eq!(
            solution.gradient_evaluations(),
            reference.gradient_evaluations()
        );
        // The retraction is the Lie group integrator's: a Euclidean solve ignores it.
        method.retraction = Some(Retraction::Cayley);
        assert_same(
            &solve(&kepler, &init, &method).unwrap().trajectory,
            &reference,
        );
    }
}

use crate::integrator::StageSolver as StageSolverKind;

#[test]
fn a_tolerance_driven_solve_is_integrate_adaptive_bit_for_bit() {
    let (kepler, init) = kepler();
    for control in [ErrorControl::Embedded, ErrorControl::Indicator] {
        let mut method = MethodSpec::spectral(99, 0.5, 16);
        method.tol = Some(1e-8);
        method.ladder = Some(vec![6, 8, 10, 12, 16, 20, 24]);
        method.control = Some(control);
        // n and quad_points are the fixed-n method's: ignored here.
        method.quad_points = Some(7);
        let mut opts = AdaptiveOptions::new(1e-8, method.basis, method.quadrature, 0.5);
        opts.ladder = vec![6, 8, 10, 12, 16, 20, 24];
        opts.control = control;
        assert_eq!(method.adaptive_options(), Some(opts.clone()));
        let run = integrate_adaptive(&kepler, &opts, init.t0, &init.q, &init.p, 16).unwrap();
        let solution = solve(&kepler, &init, &method).unwrap();
        assert_same(&solution.trajectory, &run.trajectory);
        let report = solution.adaptive.as_ref().unwrap();
        assert_eq!(report.tol, 1e-8);
        assert_eq!(report.control, control);
        assert_eq!(report.indicators, run.indicators);
        assert_eq!(report.estimates, run.estimates);
        assert_eq!(report.checks, run.checks);
        assert_eq!(report.local_tol, run.local_tol);
        assert_eq!(report.rejected, run.rejected);
        assert_eq!(report.warnings, run.warnings);
        assert_eq!(solution.gradient_evaluations(), run.gradient_evaluations);
        assert!(solution.step_choice.is_none());
        assert!(solution.trajectory.step_n.len() == 16);
    }
}

#[test]
fn auto_h_solves_at_the_step_choose_step_picks() {
    let system = HarmonicOscillator::new(1.0, 1.0).unwrap();
    let init = InitialState {
        t0: 0.0,
        q: vec![1.0],
        p: vec![0.0],
    };
    let mut method = MethodSpec::spectral(12, 1.0, 40);
    method.tol = Some(1e-8);
    method.auto_h = true;
    let mut opts = method.adaptive_options().unwrap();
    let choice = choose_step(&system, &opts, 0.0, &init.q, &init.p, 40.0).unwrap();
    opts.h = choice.h;
    let run = integrate_adaptive(&system, &opts, 0.0, &init.q, &init.p, choice.steps).unwrap();
    let solution = solve(&system, &init, &method).unwrap();
    assert_eq!(solution.step_choice.as_ref(), Some(&choice));
    assert_same(&solution.trajectory, &run.trajectory);
    assert_eq!(solution.trajectory.h, choice.h);
    assert_eq!(solution.trajectory.steps(), choice.steps);
}

#[test]
fn auto_h_without_tol_is_refused_by_every_entry_point() {
    let (kepler, init) = kepler();
    let mut method = MethodSpec::spectral(12, 1.0, 10);
    method.auto_h = true;
    let is_auto_h =
        |e: &GviError| matches!(e, GviError::InvalidInput { name, .. } if name == "auto_h");
    let f = solve(&kepler, &init, &method).unwrap_err();
    assert!(is_auto_h(&f.error), "{}", f.error);
    assert!(f.partial.is_none());
    let f = solve_streaming(&kepler, &init, &method, |_| Ok::<(), ()>(())).unwrap_err();
    assert!(is_auto_h(&f.error) && f.partial.is_none());
    let body = FreeRigidBody::new([1.0, 2.0, 3.0]).unwrap();
    let rb = InitialState {
        t0: 0.0,
        q: vec![0.0; 3],
        p: vec![0.1, 1.0, 0.2],
    };
    assert!(is_auto_h(
        &solve_rigid_body(&body, &rb, &method).unwrap_err()
    ));
    // The same method with a tolerance: refused where n cannot vary, with the reason.
    method.auto_h = false;
    method.tol = Some(1e-8);
    let f = solve_streaming(&kepler, &init, &method, |_| Ok::<(), ()>(())).unwrap_err();
    assert!(matches!(f.error, GviError::Unsupported(ref m) if m.contains("not streamed")));
    let e = solve_rigid_body(&body, &rb, &method).unwrap_err();
    assert!(
        matches!(e, GviError::Unsupported(ref m) if m.contains("needs a fixed n")),
        "{e}"
    );
}

#[test]
fn a_failed_step_keeps_the_run_before_it() {
    let init = wall_start();
    // Fixed n: the steps before the wall are kept, as `integrate` keeps them.
    let method = MethodSpec::spectral(6, 0.25, 12);
    let reference = method
        .integrator()
        .unwrap()
        .integrate(&Wall, 0.0, &init.q, &init.p, 12)
        .unwrap_err();
    let f = solve(&Wall, &init, &method).unwrap_err();
    assert!(
        matches!(f.error, GviError::NewtonFailure { .. }),
        "{}",
        f.error
    );
    let partial = f.partial.as_ref().expect("the steps before the failure");
    let kept = reference.partial.as_ref().unwrap();
    assert!(kept.steps() >= 2 && kept.steps() < 12, "{}", kept.steps());
    assert_same(&partial.trajectory, kept);
    assert!(partial.adaptive.is_none());
    assert!(f.to_string().contains("steps completed before it"), "{f}");
    // Tolerance-driven: the same, with a report of the kept steps.
    let mut method = method;
    method.tol = Some(1e-6);
    let f = solve(&Wall, &init, &method).unwrap_err();
    assert!(
        matches!(f.error, GviError::NewtonFailure { .. }),
        "{}",
        f.error
    );
    let partial = f.partial.expect("the steps before the failure");
    assert!(
        partial.trajectory.steps() >= 2,
        "{}",
        partial.trajectory.steps()
    );
    assert_eq!(partial.trajectory.step_n.len(), partial.trajectory.steps());
    let report = partial
        .adaptive
        .as_ref()
        .expect("a tolerance-driven partial run");
    assert_eq!(report.tol, 1e-6);
    assert_eq!(
        report.gradient_evaluations,
        partial.trajectory.gradient_evaluations()
    );
    // Streamed: every step before the failure was shown.
    let mut shown = 0;
    let method = MethodSpec::spectral(6, 0.25, 12);
    let f = solve_streaming(&Wall, &init, &method, |s| {
        shown = s.step;
        Ok::<(), ()>(())
    })
    .unwrap_err();
    assert_eq!(f.partial.unwrap().steps, kept.steps());
    assert_eq!(shown, kept.steps());
}

#[test]
fn a_streamed_solve_shows_integrates_states_and_curves() {
    let (kepler, init) = kepler();
    let method = MethodSpec::spectral(12, 0.5, 9);
    let reference = solve(&kepler, &init, &method).unwrap().trajectory;
    let mut seen = 0;
    let end = solve_streaming(&kepler, &init, &method, |s| {
        assert_eq!(s.t, reference.time(s.step));
        assert_eq!(s.q, &reference.q[s.step][..]);
        assert_eq!(s.p, &reference.p[s.step][..]);
        match (s.step, s.curve, s.stats) {
            (0, None, None) => {}
            (k, Some(c), Some(st)) => {
                assert_eq!(c.coefficients(), &reference.coefficients[k - 1][..]);
                assert_eq!(c.start_time(), reference.time(k - 1));
                assert_eq!(st, reference.stats[k - 1]);
            }
            _ => panic!("curve and cost go together"),
        }
        seen += 1;
        Ok::<(), ()>(())
    })
    .unwrap();
    assert_eq!((end.steps, end.stopped, seen), (9, None, 10));
    // The visitor stops the run.
    let end = solve_streaming(&kepler, &init, &method, |s| match s.step {
        3 => Err("enough"),
        _ => Ok(()),
    })
    .unwrap();
    assert_eq!((end.steps, end.stopped), (3, Some("enough")));
}

#[test]
fn a_rigid_body_solve_is_the_lie_integrators_run() {
    let body = FreeRigidBody::new([1.0, 2.0, 3.0]).unwrap();
    let init = InitialState {
        t0: 0.25,
        q: vec![0.1, -0.2, 0.3],
        p: vec![0.1, 1.0, 0.2],
    };
    let mut method = MethodSpec::spectral(6, 0.25, 8);
    method.retraction = Some(Retraction::Cayley);
    let gvi = LieGalerkin::spectral(6, 0.25)
        .unwrap()
        .with_retraction(Retraction::Cayley);
    let r0 = Retraction::Exp.map(&[0.1, -0.2, 0.3]);
    let reference = gvi
        .integrate(&body, 0.25, &r0, &[0.1, 1.0, 0.2], 8)
        .unwrap();
    let solution = solve_rigid_body(&body, &init, &method).unwrap();
    assert_eq!(solution.trajectory, reference);
    assert_eq!(solution.integrator.describe(), gvi.describe());
    let short = InitialState {
        q: vec![0.0; 2],
        ..init
    };
    assert!(matches!(
        solve_rigid_body(&body, &short, &method),
        Err(GviError::DimensionMismatch { .. })
    ));
}

/// `solve_until` with a `stop` that never says yes is `solve`, fixed n and tolerance-driven;
/// a `stop` that says yes before step 7 keeps exactly the 7 steps before it, which are
/// `solve`'s first 7 (negative control: the full runs differ from the partial ones).
#[test]
fn solve_until_stops_before_the_asked_step_and_otherwise_is_solve() {
    let (kepler, initial) = kepler();
    let mut fixed = MethodSpec::spectral(12, 0.5, 20);
    let mut tolerance = fixed.clone();
    tolerance.tol = Some(1e-8);
    for method in [&mut fixed, &mut tolerance] {
        let whole = solve(&kepler, &initial, method).unwrap();
        let never = solve_until(&kepler, &initial, method, &|| false).unwrap();
        assert_same(&whole.trajectory, &never.trajectory);
        let asked = std::cell::Cell::new(0usize);
        let stop = || {
            asked.set(asked.get() + 1);
            asked.get() > 7
        };
        let failure = solve_until(&kepler, &initial, method, &stop).unwrap_err();
        let GviError::Interrupted { step, t } = failure.error else {
            panic!("expected Interrupted, got {}", failure.error);
        };
        assert_eq!((step, t), (7, initial.t0 + 7.0 * 0.5));
        let partial = failure.partial.unwrap().trajectory;
        assert_eq!(partial.steps(), 7);
        assert_eq!(partial.q[..], whole.trajectory.q[..8]);
        assert_eq!(partial.coefficients[..], whole.trajectory.coefficients[..7]);
        assert_ne!(partial.q.len(), whole.trajectory.q.len());
    }
}

/// The fixed-n run has one step loop: `integrate`, `solve` and `solve_until` with a `stop`
/// that never fires give the same trajectory bit for bit, and `solve_until` refuses what
/// `integrate` refuses (a non-finite t0, which its former copy of the loop let through;
/// negative control: the same call with a finite t0 succeeds).
#[test]
fn integrate_solve_and_solve_until_share_one_step_loop() {
    let (kepler, initial) = kepler();
    let method = MethodSpec::spectral(12, 0.5, 15);
    let gvi = method.integrator().unwrap();
    let direct = gvi
        .integrate(&kepler, initial.t0, &initial.q, &initial.p, method.steps)
        .unwrap();
    let solved = solve(&kepler, &initial, &method).unwrap();
    let never = solve_until(&kepler, &initial, &method, &|| false).unwrap();
    assert_same(&direct, &solved.trajectory);
    assert_same(&direct, &never.trajectory);
    for t0 in [f64::NAN, f64::INFINITY] {
        let bad = InitialState {
            t0,
            ..initial.clone()
        };
        let failure = solve_until(&kepler, &bad, &method, &|| false).unwrap_err();
        assert!(
            matches!(failure.error, GviError::NonFinite { .. }),
            "{}",
            failure.error
        );
        assert!(failure.partial.is_none());
    }
    assert!(solve_until(&kepler, &initial, &method, &|| false).is_ok());
}
