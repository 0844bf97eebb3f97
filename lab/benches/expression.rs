//! The double pendulum as an expression Lagrangian (scene `double-pendulum`, parsed and
//! compiled once; gradient and Hessian in one tape pass) against the same Lagrangian written
//! in Rust (default AD derivatives): the time of 40 steps of the
//! scene's method (n = 16, h = 0.5) and of one AD Hessian, and their ratios, measured in the
//! same process with the two interleaved (median of 15 rounds), printed before criterion's
//! own measurements.
//!
//! Run: `cargo bench --bench expression`

use criterion::{Criterion, criterion_group, criterion_main};
use galerkin_vi::prelude::*;
use galerkin_vi::systems::ExpressionLagrangian;
use galerkin_vi_lab::scene::{Scene, SystemSpec};
use std::hint::black_box;
use std::time::Instant;

/// The scene's Lagrangian written in Rust (m1 = m2 = l1 = l2 = g = 1).
struct DoublePendulum;
impl Lagrangian for DoublePendulum {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        v[0] * v[0]
            + v[1] * v[1] * 0.5
            + v[0] * v[1] * (q[0] - q[1]).cos()
            + q[0].cos() * 2.0
            + q[1].cos()
    }
}

fn expression() -> (ExpressionLagrangian, Vec<f64>, Vec<f64>) {
    let scene = Scene::load("double-pendulum").expect("built-in scene");
    let SystemSpec::Lagrangian(spec) = &scene.system else {
        panic!("double-pendulum is an expression scene")
    };
    let lag = spec.build().expect("valid scene");
    (lag, scene.initial.q.clone(), scene.initial.p.clone())
}

const STEPS: usize = 40;

fn run<L: Lagrangian>(lag: &L, gvi: &GalerkinIntegrator, q0: &[f64], p0: &[f64]) -> f64 {
    let traj = gvi.integrate(lag, 0.0, q0, p0, STEPS).expect("integrates");
    traj.q[STEPS][0]
}

fn hessians<L: Lagrangian>(lag: &L, reps: usize) -> f64 {
    let (mut a, mut b, mut c) = ([0.0; 4], [0.0; 4], [0.0; 4]);
    let mut acc = 0.0;
    for k in 0..reps {
        let x = 0.1 + 1e-4 * k as f64;
        lag.hessian(
            black_box(&[x, 0.5]),
            black_box(&[0.3, -0.2]),
            &mut a,
            &mut b,
            &mut c,
        );
        acc += c[1];
    }
    acc
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Interleaved timing of `f(expression)` against `f(rust)`: median seconds of each.
fn ratio(mut expr: impl FnMut() -> f64, mut rust: impl FnMut() -> f64) -> (f64, f64) {
    let (mut te, mut tr) = (Vec::new(), Vec::new());
    for _ in 0..15 {
        let s = Instant::now();
        black_box(expr());
        te.push(s.elapsed().as_secs_f64());
        let s = Instant::now();
        black_box(rust());
        tr.push(s.elapsed().as_secs_f64());
    }
    (median(te), median(tr))
}

fn double_pendulum(c: &mut Criterion) {
    let (lag, q0, p0) = expression();
    let gvi = GalerkinIntegrator::spectral(16, 0.5).expect("valid method");
    // Same map: the two trajectories agree to round-off.
    let (a, b) = (
        run(&lag, &gvi, &q0, &p0),
        run(&DoublePendulum, &gvi, &q0, &p0),
    );
    assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    let (te, tr) = ratio(
        || run(&lag, &gvi, &q0, &p0),
        || run(&DoublePendulum, &gvi, &q0, &p0),
    );
    eprintln!(
        "double pendulum, {STEPS} steps (n = 16, h = 0.5): expression {:.3} ms, Rust {:.3} ms, \
         ratio expression/Rust = {:.2} (tape of {} instructions)",
        te * 1e3,
        tr * 1e3,
        te / tr,
        lag.tape().len()
    );
    let (he, hr) = ratio(
        || hessians(&lag, 20_000),
        || hessians(&DoublePendulum, 20_000),
    );
    eprintln!(
        "double pendulum, one AD Hessian: expression {:.0} ns, Rust {:.0} ns, ratio = {:.2}",
        he / 20_000.0 * 1e9,
        hr / 20_000.0 * 1e9,
        he / hr
    );
    let mut group = c.benchmark_group("double_pendulum_40_steps");
    group.sample_size(20);
    group.bench_function("expression", |b| b.iter(|| run(&lag, &gvi, &q0, &p0)));
    group.bench_function("rust", |b| b.iter(|| run(&DoublePendulum, &gvi, &q0, &p0)));
    group.finish();
}

criterion_group!(benches, double_pendulum);
criterion_main!(benches);
