//! Time per Galerkin step of the N-body problem against the number n of basis functions and
//! the number N of bodies (3-D, so (n − 1)·3N unknowns and an O((3nN)³) dense solve).
//!
//! The configuration is a planetary system: a central mass 1 and N − 1 planets of mass 1e-3 on
//! near-circular, slightly inclined orbits of radii 1, 1.5, 2, … (G = 1), step h = 1 (the
//! innermost period is 2π). Each sample continues the orbit, so the extrapolated initial guess
//! is in use as in a real run.
//!
//! Run: `cargo bench --bench nbody`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use galerkin_vi::prelude::*;
use std::hint::black_box;
use std::time::Duration;

fn planetary_system(bodies: usize) -> (NBody, Vec<f64>, Vec<f64>) {
    let mut masses = vec![1.0];
    let (mut q, mut v) = (vec![0.0; 3], vec![0.0; 3]);
    for k in 1..bodies {
        let r = 1.0 + 0.5 * (k - 1) as f64;
        let phase = 2.399963 * k as f64; // golden angle: spread the planets around
        let (c, s) = (phase.cos(), phase.sin());
        let speed = (1.0 / r).sqrt();
        let tilt = 0.02 * k as f64;
        masses.push(1e-3);
        q.extend_from_slice(&[r * c, r * s, 0.0]);
        v.extend_from_slice(&[-speed * s, speed * c * tilt.cos(), speed * tilt.sin()]);
    }
    let system = NBody::new(masses, 1.0, 3).expect("valid masses");
    let p = system.momenta(&v);
    (system, q, p)
}

fn bench_steps(c: &mut Criterion, group_name: &str, cases: &[(usize, usize)], by_n: bool) {
    let mut group = c.benchmark_group(group_name);
    group.sample_size(10);
    group.warm_up_time(Duration::from_secs(1));
    group.measurement_time(Duration::from_secs(4));
    for &(n, bodies) in cases {
        let (system, q0, p0) = planetary_system(bodies);
        let gvi = GalerkinIntegrator::spectral(n, 1.0).expect("valid method");
        let mut ws = gvi.workspace(&system).expect("workspace");
        let d = q0.len();
        let (mut q, mut p) = (q0.clone(), p0.clone());
        let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
        let id = if by_n { n } else { bodies };
        group.bench_with_input(BenchmarkId::from_parameter(id), &id, |b, _| {
            b.iter(|| {
                if gvi
                    .step(&system, &mut ws, &q, &p, &mut qn, &mut pn)
                    .is_err()
                {
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

fn nbody_step(c: &mut Criterion) {
    let by_n: Vec<(usize, usize)> = [8, 12, 16, 24, 32].iter().map(|&n| (n, 10)).collect();
    bench_steps(c, "nbody_step_N10_vs_n", &by_n, true);
    let by_bodies: Vec<(usize, usize)> = [2, 4, 6, 8, 10].iter().map(|&nb| (16, nb)).collect();
    bench_steps(c, "nbody_step_n16_vs_N", &by_bodies, false);
}

criterion_group!(benches, nbody_step);
criterion_main!(benches);
