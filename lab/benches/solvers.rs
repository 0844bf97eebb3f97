//! Time of a short integration with each stage solver (exact, kronecker, newton-krylov, modal,
//! auto)
//! at a few sizes: 10 steps of Kepler e = 0.6 at h = 1 with n = 16, 32, 64 and of the outer
//! solar system (h = 1825 days) with n = 12 and of the paper's 10-body run (J2000, n = 25,
//! h = 100 days); 2 steps of the synthetic planetesimal ring
//! (h = 1/8 of the innermost period) with N = 16 and 32 bodies at n = 16 (the exact solver's
//! (15·96)² LU makes longer ring runs slow). Asserts nothing about time; the scaling
//! study with fitted exponents is `gvi solver-scaling` (docs/studies/solver-scaling/).
//!
//! Run: `cargo bench --bench solvers` (about a minute after compiling).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use galerkin_vi::prelude::*;
use galerkin_vi_lab::ring::{RingConfig, planetesimal_ring};
use galerkin_vi_lab::scene::{InitialState, Scene};
use std::hint::black_box;
use std::time::Duration;

fn bench_case<L: Lagrangian>(
    c: &mut Criterion,
    group_name: &str,
    lag: &L,
    init: &InitialState,
    n: usize,
    h: f64,
    steps: usize,
) {
    let mut group = c.benchmark_group(group_name);
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_millis(1200));
    for solver in [
        StageSolver::Exact,
        StageSolver::Kronecker,
        StageSolver::NewtonKrylov,
        StageSolver::Modal,
        StageSolver::Auto,
    ] {
        let options = NewtonOptions {
            solver,
            ..NewtonOptions::default()
        };
        let Ok(gvi) = GalerkinIntegrator::spectral(n, h).map(|g| g.with_options(options)) else {
            eprintln!("{group_name}: cannot build n = {n}, h = {h}");
            continue;
        };
        if gvi
            .integrate(lag, init.t0, &init.q, &init.p, steps)
            .is_err()
        {
            eprintln!("{group_name}: {solver} fails; skipped");
            continue;
        }
        group.bench_with_input(BenchmarkId::from_parameter(solver), &solver, |b, _| {
            b.iter(|| black_box(gvi.integrate(lag, init.t0, &init.q, &init.p, steps).is_ok()))
        });
    }
    group.finish();
}

fn solvers(c: &mut Criterion) {
    let kepler = Kepler::new(1.0).expect("mu > 0");
    let kepler_init = Scene::load("kepler").expect("built-in scene").initial;
    for n in [16, 32, 64] {
        bench_case(
            c,
            &format!("kepler_n{n}"),
            &kepler,
            &kepler_init,
            n,
            1.0,
            10,
        );
    }
    // The outer solar system at its scene's h = 1825 d, and the paper's 10-body
    // configuration (J2000, n = 25, h = 100 d), where Mercury and Venus get exact self-blocks
    // in the frozen iteration's preconditioner (docs/solvers.md).
    for (name, group, n, h) in [
        ("outer-solar-system", "outer_solar_system_n12", 12, None),
        ("solar-system", "solar_system_n25_h100", 25, Some(100.0)),
    ] {
        let scene = Scene::load(name).expect("built-in scene");
        if let Ok(built) = scene.build()
            && let Some(system) = built.euclidean().ok().and_then(|s| s.as_nbody())
        {
            let h = h.unwrap_or(scene.method.h);
            bench_case(c, group, system, &built.initial, n, h, 10);
        }
    }
    for bodies in [16, 32] {
        let config = RingConfig::with_bodies(bodies);
        let (system, init) = planetesimal_ring(&config).expect("valid ring");
        bench_case(
            c,
            &format!("ring_N{bodies}_n16"),
            &system,
            &init,
            16,
            config.step(),
            2,
        );
    }
}

criterion_group!(benches, solvers);
criterion_main!(benches);
