//! What forcing and events cost: Kepler e = 0.6, n = 12, h = 0.5, 100 steps per run.
//!
//! - `separable`: the unforced run on the structured path of separable Lagrangians;
//! - `general`: the same Lagrangian through the general stage path (no mass matrix offered,
//!   the hand-written derivatives kept), which a forced or time-dependent system takes;
//! - `general+drag`: that with a linear drag −γv: the cost of the force's evaluations alone;
//! - `stepper`: `separable` as a bare `Stepper` loop (no trajectory kept);
//! - `events`: that loop through `integrate_with_events` with one event that never fires
//!   (the curve sampled 8 times per step): the O(1)-per-step cost of watching.
//!
//! Run: `cargo bench --bench forcing` (ratios in docs/guide/forcing.md).

use criterion::{Criterion, criterion_group, criterion_main};
use galerkin_vi::events::{Event, EventOptions, integrate_with_events};
use galerkin_vi::prelude::*;
use galerkin_vi::{Forced, LinearDamping};
use std::hint::black_box;

/// Kepler without its mass matrix: the general stage path, same derivatives.
struct General(Kepler);
impl Lagrangian for General {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        self.0.lagrangian(q, v)
    }
    fn gradient(&self, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        self.0.gradient(q, v, lq, lv)
    }
    fn hessian(&self, q: &[f64], v: &[f64], a: &mut [f64], b: &mut [f64], c: &mut [f64]) {
        self.0.hessian(q, v, a, b, c)
    }
}

fn forcing(c: &mut Criterion) {
    let kepler = Kepler::new(1.0).expect("mu > 0");
    let (q0, p0) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::spectral(12, 0.5).expect("valid method");
    let general = General(kepler);
    let drag = Forced::new(
        General(kepler),
        LinearDamping::uniform(2, 1e-3).expect("γ ≥ 0"),
    )
    .expect("same dimension");
    let steps = 100;
    let mut group = c.benchmark_group("kepler_100_steps");
    group.bench_function("separable", |b| {
        b.iter(|| black_box(gvi.integrate(&kepler, 0.0, &q0, &p0, steps).is_ok()))
    });
    group.bench_function("general", |b| {
        b.iter(|| black_box(gvi.integrate(&general, 0.0, &q0, &p0, steps).is_ok()))
    });
    group.bench_function("general+drag", |b| {
        b.iter(|| black_box(gvi.integrate(&drag, 0.0, &q0, &p0, steps).is_ok()))
    });
    group.bench_function("stepper", |b| {
        b.iter(|| {
            // The loop `events` runs, without the scan: its baseline.
            let Ok(mut stepper) = gvi.stepper(&kepler, 0.0, &q0, &p0) else {
                return black_box(false);
            };
            for _ in 0..steps {
                if stepper.step().is_err() {
                    return black_box(false);
                }
            }
            black_box(true)
        })
    });
    group.bench_function("events", |b| {
        b.iter(|| {
            // |q| < 2 on this orbit: g never changes sign.
            let mut events = [Event::new("never", |_t: f64, q: &[f64], _p: &[f64]| {
                q[0] - 10.0
            })];
            let t_end = steps as f64 * 0.5;
            let run = integrate_with_events(
                &gvi,
                &kepler,
                0.0,
                &q0,
                &p0,
                t_end,
                &mut events,
                &EventOptions::default(),
            );
            black_box(run.is_ok())
        })
    });
    group.finish();
}

criterion_group!(benches, forcing);
criterion_main!(benches);
