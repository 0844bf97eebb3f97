//! Events located on the Galerkin curve, against exact event times.

use super::*;
use crate::prelude::*;
use std::f64::consts::PI;

fn spectral(n: usize, h: f64) -> GalerkinIntegrator {
    GalerkinIntegrator::spectral(n, h).unwrap()
}

/// q = cos t: every zero crossing, each direction, at π/2 + kπ, to the method's accuracy
/// (n = 14 at h = 1 is at round-off for the oscillator), with the state on the curve there.
#[test]
fn zero_crossings_of_the_oscillator_are_located_on_the_curve() {
    let ho = HarmonicOscillator::unit();
    let gvi = spectral(14, 1.0);
    let q = |_t: f64, q: &[f64], _p: &[f64]| q[0];
    let mut events = [
        Event::new("down", q).falling(),
        Event::new("up", q).rising(),
    ];
    let run = integrate_with_events(
        &gvi,
        &ho,
        0.0,
        &[1.0],
        &[0.0],
        20.0,
        &mut events,
        &EventOptions::default(),
    )
    .unwrap();
    assert_eq!(run.crossings.len(), 6, "{:?}", run.crossings);
    for (k, c) in run.crossings.iter().enumerate() {
        let exact = PI / 2.0 + k as f64 * PI;
        assert!((c.t - exact).abs() < 1e-12, "{k}: {} vs {exact}", c.t);
        assert_eq!(c.rising, k % 2 == 1);
        assert_eq!(c.name, if c.rising { "up" } else { "down" });
        assert!(c.q[0].abs() < 1e-12);
        // p = −sin t there: ∓1.
        assert!((c.p[0] - if c.rising { 1.0 } else { -1.0 }).abs() < 1e-12);
        assert_eq!(c.step, c.t.floor() as usize);
    }
    assert!(!run.stopped);
    assert_eq!((run.steps, run.t), (20, 20.0));
}

/// An event that comes and goes within one step — q = cos t above 0.99 for |t − 2π| < 0.1415,
/// inside the step [5.5, 6.5] at h = 1 — is found on the curve, both crossings, to 1e-10.
/// Negative control: looking at step ends only (samples_per_step = 1) misses it, because
/// q(5.5) and q(6.5) are both below 0.99.
#[test]
fn the_curve_finds_an_event_that_step_ends_miss() {
    let ho = HarmonicOscillator::unit();
    let gvi = spectral(14, 1.0);
    let level = |_t: f64, q: &[f64], _p: &[f64]| q[0] - 0.99;
    let (t0, q0, p0) = (0.5, [0.5f64.cos()], [-(0.5f64.sin())]);
    let run_with = |samples: usize| {
        let mut events = [Event::new("q = 0.99", level)];
        let options = EventOptions {
            samples_per_step: samples,
            ..EventOptions::default()
        };
        integrate_with_events(&gvi, &ho, t0, &q0, &p0, 6.5, &mut events, &options).unwrap()
    };
    let curve = run_with(8);
    let half_width = 0.99f64.acos();
    let exact = [2.0 * PI - half_width, 2.0 * PI + half_width];
    assert_eq!(curve.crossings.len(), 2, "{:?}", curve.crossings);
    for (c, e) in curve.crossings.iter().zip(exact) {
        assert!((c.t - e).abs() < 1e-10, "{} vs {e}", c.t);
        assert_eq!(c.step, 5);
    }
    assert!(curve.crossings[0].rising && !curve.crossings[1].rising);
    let ends = run_with(1);
    assert!(ends.crossings.is_empty(), "{:?}", ends.crossings);
    // Nothing crosses elsewhere: the samples and the root finding are all it cost.
    assert_eq!(ends.curve_evaluations, 6);
    assert!(curve.curve_evaluations >= 6 * 8 && curve.curve_evaluations < 6 * 8 + 2 * 60);
}

/// Stop: the run ends at the first counted crossing, with the state on the curve there.
#[test]
fn a_stopping_event_ends_the_run_at_its_time() {
    let ho = HarmonicOscillator::unit();
    let gvi = spectral(14, 1.0);
    let mut events = [
        Event::new("q = -0.5", |_t: f64, q: &[f64], _p: &[f64]| q[0] + 0.5)
            .falling()
            .stop(),
    ];
    let run = integrate_with_events(
        &gvi,
        &ho,
        0.0,
        &[1.0],
        &[0.0],
        100.0,
        &mut events,
        &EventOptions::default(),
    )
    .unwrap();
    let exact = 2.0 * PI / 3.0;
    assert!(run.stopped);
    assert_eq!(run.crossings.len(), 1);
    assert!((run.t - exact).abs() < 1e-12, "{}", run.t);
    assert!((run.q[0] + 0.5).abs() < 1e-12 && (run.p[0] + exact.sin()).abs() < 1e-12);
    assert_eq!(run.steps, 3);
}

/// A free fall L = v²/2 − q with elastic impacts at q = 0 (map p ↦ −p): from q = 1 at rest
/// the impacts are at √2 (1 + 2k), and the energy stays 1. The restart puts the later steps
/// off the grid t0 + k h, which the exact times check. Negative control: without the map the
/// particle falls through q = 0 once and never returns.
#[test]
fn an_impact_map_restarts_the_run() {
    #[derive(Debug)]
    struct Fall;
    impl crate::lagrangian::Mechanical for Fall {
        fn degrees_of_freedom(&self) -> usize {
            1
        }
        fn mass(&self) -> nalgebra::DMatrix<f64> {
            nalgebra::DMatrix::identity(1, 1)
        }
        fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
            q[0]
        }
    }
    let gvi = spectral(6, 0.5);
    let floor = |_t: f64, q: &[f64], _p: &[f64]| q[0];
    let mut events = [Event::new("impact", floor)
        .falling()
        .apply(|_t: f64, _q: &mut [f64], p: &mut [f64]| p[0] = -p[0])];
    let options = EventOptions::default();
    let run = integrate_with_events(
        &gvi,
        &Fall,
        0.0,
        &[1.0],
        &[0.0],
        12.0,
        &mut events,
        &options,
    )
    .unwrap();
    let s2 = 2f64.sqrt();
    let times: Vec<f64> = run.crossings.iter().map(|c| c.t).collect();
    assert_eq!(times.len(), 4, "{times:?}");
    for (k, t) in times.iter().enumerate() {
        assert!((t - s2 * (1 + 2 * k) as f64).abs() < 1e-12, "{k}: {t}");
    }
    let energy = 0.5 * run.p[0] * run.p[0] + run.q[0];
    assert!((energy - 1.0).abs() < 1e-12, "{energy}");
    let mut plain = [Event::new("impact", floor).falling()];
    let through =
        integrate_with_events(&gvi, &Fall, 0.0, &[1.0], &[0.0], 12.0, &mut plain, &options)
            .unwrap();
    assert_eq!(through.crossings.len(), 1);
    assert!(through.q[0] < -50.0);
}

/// Scanning a stored trajectory finds what the online run finds, bit for bit.
#[test]
fn a_stored_trajectory_gives_the_same_crossings() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = spectral(16, 0.5);
    let y = |_t: f64, q: &[f64], _p: &[f64]| q[1];
    let mut events = [Event::new("y = 0", y)];
    let options = EventOptions::default();
    let online =
        integrate_with_events(&gvi, &kepler, 0.0, &q0, &p0, 20.0, &mut events, &options).unwrap();
    let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 40).unwrap();
    let stored = crossings_on_trajectory(&traj, &kepler, &events, &options).unwrap();
    assert_eq!(online.crossings, stored);
    // The orbit (period 2π) crosses y = 0 twice per revolution: 6 times in T = 20.
    assert_eq!(stored.len(), 6);
}

/// Bad input is a typed error: options, t_end, a g not finite at the start, a map that makes
/// the state non-finite (with the run before it kept); an event exactly zero at t0 is not
/// reported there.
#[test]
fn bad_events_are_typed_errors() {
    let ho = HarmonicOscillator::unit();
    let gvi = spectral(10, 1.0);
    let q = |_t: f64, q: &[f64], _p: &[f64]| q[0];
    let run = |events: &mut [Event<'_>], options: &EventOptions, t_end: f64| {
        integrate_with_events(&gvi, &ho, 0.0, &[1.0], &[0.0], t_end, events, options)
    };
    let opts = EventOptions::default();
    let zero = EventOptions {
        samples_per_step: 0,
        ..opts
    };
    assert!(run(&mut [Event::new("q", q)], &zero, 5.0).is_err());
    let bad_tol = EventOptions {
        local_time_tolerance: 0.0,
        ..opts
    };
    assert!(run(&mut [Event::new("q", q)], &bad_tol, 5.0).is_err());
    assert!(run(&mut [Event::new("q", q)], &opts, f64::NAN).is_err());
    assert!(run(&mut [Event::new("q", q)], &opts, -1.0).is_err());
    let nan = |_t: f64, _q: &[f64], _p: &[f64]| f64::NAN;
    let err = run(&mut [Event::new("nan", nan)], &opts, 5.0).unwrap_err();
    assert!(matches!(err.error, GviError::NonFinite { .. }), "{err}");
    let mut blow_up = [Event::new("q", q)
        .falling()
        .apply(|_t: f64, q: &mut [f64], _p: &mut [f64]| q[0] = f64::INFINITY)];
    let err = run(&mut blow_up, &opts, 5.0).unwrap_err();
    assert!(matches!(err.error, GviError::NonFinite { .. }), "{err}");
    assert_eq!(err.partial.crossings.len(), 1);
    assert_eq!(err.partial.steps, 2);
    // p = 0 at t0: zero there, then negative — no crossing at the start.
    let p = |_t: f64, _q: &[f64], p: &[f64]| p[0];
    let at_start = run(&mut [Event::new("p", p)], &opts, 5.0).unwrap();
    assert_eq!(at_start.crossings.len(), 1);
    assert!((at_start.crossings[0].t - PI).abs() < 1e-9);
}

/// Two equal masses on a relative Kepler orbit (a = 1, e = 0.6, μ = 2) from apoapsis: the
/// separation dips to 0.4 at periapsis, t = π/√2 ≈ 2.221, inside the step [2, 3] at h = 1,
/// where the step ends see 0.7 and more. The close-encounter event (r_min = 0.45) stops the run
/// on the curve with the pair named; the separation there is 0.45 to 1e-9. Negative control:
/// step ends only (samples_per_step = 1) run through the encounter to T = 6.
#[test]
fn a_close_encounter_between_step_ends_stops_the_run() {
    let nb = NBody::new(vec![1.0, 1.0], 1.0, 2).unwrap();
    let v = 0.25 * 2f64.sqrt();
    let (q0, p0) = ([-0.8, 0.0, 0.8, 0.0], [0.0, -v, 0.0, v]);
    let gvi = spectral(24, 1.0);
    let run_with = |samples: usize| {
        let mut events = [close_encounter(&nb, 0.45).unwrap()];
        let options = EventOptions {
            samples_per_step: samples,
            ..EventOptions::default()
        };
        integrate_with_events(&gvi, &nb, 0.0, &q0, &p0, 6.0, &mut events, &options).unwrap()
    };
    let run = run_with(8);
    assert!(run.stopped, "{run:?}");
    let c = &run.crossings[0];
    assert_eq!(c.step, 2);
    let (i, j, r) = nb.closest_pair(&c.q).unwrap();
    assert_eq!((i, j), (0, 1));
    assert!((r - 0.45).abs() < 1e-9, "{r}");
    assert!(c.t > 2.0 && c.t < std::f64::consts::PI / 2f64.sqrt());
    let ends = run_with(1);
    assert!(!ends.stopped && ends.crossings.is_empty());
    assert_eq!(ends.t, 6.0);
    assert!(close_encounter(&nb, 0.0).is_err());
    assert!(close_encounter(&NBody::new(vec![1.0], 1.0, 2).unwrap(), 0.1).is_err());
}

/// Hénon–Heiles, V = (x² + y²)/2 + x²y − y³/3, unit masses.
#[derive(Debug)]
struct HenonHeiles;

impl crate::lagrangian::Mechanical for HenonHeiles {
    fn degrees_of_freedom(&self) -> usize {
        2
    }
    fn mass(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::identity(2, 2)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let (x, y) = (q[0], q[1]);
        (x * x + y * y) * 0.5 + x * x * y - y * y * y * (1.0 / 3.0)
    }
}

/// The surface of section x = 0, p_x > 0 of Hénon–Heiles at E = 1/12 over T = 100 (a regular
/// orbit, about 16 points), on the Galerkin curve at h = 0.5, n = 16, against an independent
/// event-located integration: RK4 at h = 1e-3 (global error ~1e-12 here) with the crossing
/// found by bisection on the cubic Hermite interpolant of each step (error O(h⁴) ≈ 1e-12).
/// The points (t, y, p_y) agree to 1e-10 (measured 2.1e-12).
#[test]
fn henon_heiles_section_agrees_with_an_independent_integration() {
    let worst = henon_heiles_section_against_rk4(1.0 / 12.0, 0.1, 100.0);
    assert!(worst < 1e-10, "worst difference {worst:e}");
}

/// The same at E = 1/6, the escape energy, from y = −0.2 on a chaotic orbit: the difference
/// grows with the orbit's Lyapunov exponent, measured 1.3e-11 over T = 50 (6 points),
/// 2.1e-10 over T = 75 and 5.8e-8 over T = 100 (13 points), so the tolerances follow it.
#[test]
fn henon_heiles_section_at_the_escape_energy_agrees_too() {
    let early = henon_heiles_section_against_rk4(1.0 / 6.0, -0.2, 50.0);
    assert!(early < 1e-10, "T = 50: worst difference {early:e}");
    let worst = henon_heiles_section_against_rk4(1.0 / 6.0, -0.2, 100.0);
    assert!(worst < 3e-7, "T = 100: worst difference {worst:e}");
}

/// Max difference in (t, y, p_y) of the section points from (0, y0) with p_y = 0 and p_x > 0
/// at energy `e`, Galerkin (n = 16, h = 0.5) against RK4 with Hermite event location; checks
/// that every point is on the plane and the energy surface.
fn henon_heiles_section_against_rk4(e: f64, y0: f64, t_end: f64) -> f64 {
    use crate::baselines::{OneStepMethod, Rk4};
    let hh = HenonHeiles;
    let py0 = 0.0;
    let v0 = 0.5 * y0 * y0 - y0 * y0 * y0 / 3.0;
    let px0 = (2.0 * (e - v0) - py0 * py0).sqrt();
    let (q0, p0) = ([0.0, y0], [px0, py0]);
    let gvi = spectral(16, 0.5);
    let mut events = [Event::new("x = 0", |_t: f64, q: &[f64], _p: &[f64]| q[0]).rising()];
    let run = integrate_with_events(
        &gvi,
        &hh,
        0.0,
        &q0,
        &p0,
        t_end,
        &mut events,
        &EventOptions::default(),
    )
    .unwrap();
    // The reference: RK4 steps, each sign change of x located on the Hermite cubic of
    // (x, ẋ = p_x), and y, p_y interpolated the same way (ṗ = −∇V).
    let h = 1e-3;
    let mut rk4 = Rk4::new(&hh, h).unwrap();
    let force = |q: &[f64]| {
        let (x, y) = (q[0], q[1]);
        [-(x + 2.0 * x * y), -(y + x * x - y * y)]
    };
    let hermite = |a: f64, da: f64, b: f64, db: f64, s: f64| {
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * a
            + (s3 - 2.0 * s2 + s) * h * da
            + (-2.0 * s3 + 3.0 * s2) * b
            + (s3 - s2) * h * db
    };
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
    let mut reference = Vec::new();
    let steps = (t_end / h).round() as usize;
    for k in 0..steps {
        let t = k as f64 * h;
        rk4.step(t, &q, &p, &mut qn, &mut pn).unwrap();
        if q[0] < 0.0 && qn[0] >= 0.0 {
            let (fa, fb) = (force(&q), force(&qn));
            let x = |s: f64| hermite(q[0], p[0], qn[0], pn[0], s);
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if x(mid) < 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let s = 0.5 * (lo + hi);
            reference.push((
                t + s * h,
                hermite(q[1], p[1], qn[1], pn[1], s),
                hermite(p[1], fa[1], pn[1], fb[1], s),
            ));
        }
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
    }
    assert!(reference.len() >= 5, "{}", reference.len());
    assert_eq!(run.crossings.len(), reference.len());
    let mut worst = 0.0f64;
    for (c, (t, y, py)) in run.crossings.iter().zip(&reference) {
        assert!(c.rising && c.q[0].abs() < 1e-12 && c.p[0] > 0.0);
        worst = worst
            .max((c.t - t).abs())
            .max((c.q[1] - y).abs())
            .max((c.p[1] - py).abs());
    }
    // Every point lies on the energy surface (p_x from x = 0).
    for c in &run.crossings {
        let ec = 0.5 * (c.p[0] * c.p[0] + c.p[1] * c.p[1]) + 0.5 * c.q[1] * c.q[1]
            - c.q[1].powi(3) / 3.0;
        assert!((ec - e).abs() < 1e-12, "{ec}");
    }
    worst
}
