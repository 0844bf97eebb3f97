//! Time per step against n for Kepler e = 0.6 at h = 2 (the paper's spectral setting).
//!
//! Run: `cargo bench --bench step`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use galerkin_vi::prelude::*;
use std::hint::black_box;

fn kepler_step(c: &mut Criterion) {
    let kepler = Kepler::new(1.0).expect("mu > 0");
    let (q0, p0) = Kepler::paper_initial_state();
    // The deterministic cost per step (also asserted in tests/counts.rs), printed beside the
    // times: linear solves, factorisations and force evaluations per step over 100 steps.
    for n in [8usize, 12, 16, 24, 32, 48] {
        if let Ok(gvi) = GalerkinIntegrator::spectral(n, 2.0)
            && let Ok(t) = gvi.integrate(&kepler, 0.0, &q0, &p0, 100)
        {
            let per = |f: fn(&galerkin_vi::integrator::StepStats) -> usize| {
                t.stats.iter().map(f).sum::<usize>() as f64 / t.steps() as f64
            };
            eprintln!(
                "n = {n:>2}: {:.2} linear solves, {:.2} factorisations, {:.0} force evaluations per step",
                per(|s| s.iterations),
                per(|s| s.factorizations),
                per(|s| s.gradient_evaluations)
            );
        }
    }
    let mut group = c.benchmark_group("kepler_step_h2");
    for n in [8usize, 12, 16, 24, 32, 48] {
        let gvi = GalerkinIntegrator::spectral(n, 2.0).expect("valid method");
        // Warm up along the orbit so the extrapolated guess is in use, as in a real run.
        let mut ws = gvi.workspace(&kepler).expect("workspace");
        let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
        let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                if gvi
                    .step(&kepler, &mut ws, &q, &p, &mut qn, &mut pn)
                    .is_err()
                {
                    // Restart the orbit rather than abort the benchmark.
                    q.copy_from_slice(&q0);
                    p.copy_from_slice(&p0);
                    ws.reset();
                    return;
                }
                std::mem::swap(&mut q, &mut qn);
                std::mem::swap(&mut p, &mut pn);
                black_box(&q);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, kepler_step);
criterion_main!(benches);
