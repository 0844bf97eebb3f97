//! The measurements of docs/guide/time-transformations.md (ignored by default: they take a
//! few minutes). Regenerate with
//!
//! ```sh
//! cargo test -j 1 -p galerkin-vi-lab --test integration timetransform_study -- --ignored --nocapture --test-threads 1
//! ```
//!
//! Kepler e = 0.99 over 100 orbits — the time-transformed Galerkin method, the fixed-step one
//! and DOP853, error against the exact solution at 16 times per orbit and cost — and the
//! Pythagorean three-body problem to t = 70 against tight DOP853 and a second, independent
//! tight integration (the time-transformed method at another n and Δs).

use crate::common::kepler_periapsis::{fictitious_period, kepler_at_periapsis};
use galerkin_vi::baselines::OneStepMethod;
use galerkin_vi::prelude::*;
use galerkin_vi::systems::kepler_orbit::KeplerOrbit;
use galerkin_vi::time_transform::{
    CentralDistance, Combine, PairDistances, TimeTransformOptions, TimeTransformed,
    integrate_time_transformed,
};
use galerkin_vi_lab::dop853::Dop853Baseline;
use std::f64::consts::TAU;
use std::time::Instant;

const ORBITS: usize = 100;
const PER_ORBIT_OUTPUTS: usize = 16;

fn max_error(exact: &KeplerOrbit, times: &[f64], states: &[Vec<f64>]) -> f64 {
    times
        .iter()
        .zip(states)
        .map(|(&t, q)| {
            let (qe, _) = exact.state_at(t);
            (q[0] - qe[0]).abs().max((q[1] - qe[1]).abs())
        })
        .fold(0.0, galerkin_vi::reduce::nan_max)
}

#[test]
#[ignore = "a study of a few minutes: docs/guide/time-transformations.md"]
fn kepler_e099_error_and_cost() {
    for e in [0.99, 0.9] {
        let (q0, p0) = kepler_at_periapsis(e);
        let kepler = Kepler::new(1.0).unwrap();
        let exact = KeplerOrbit::from_state(1.0, q0, p0, 0.0).unwrap();
        let t_end = TAU * ORBITS as f64;
        println!(
            "\nKepler e = {e}, {ORBITS} orbits, max position error at {PER_ORBIT_OUTPUTS} times per orbit"
        );
        println!("| method | steps | force evaluations | max error | seconds |");
        println!("|---|---|---|---|---|");
        let tt = TimeTransformed::new(kepler, CentralDistance::new(1.5).unwrap(), &q0, &p0, None)
            .unwrap();
        for (n, per_orbit) in [(8, 30), (8, 60), (12, 30), (12, 60), (16, 60), (16, 120)] {
            let ds = fictitious_period(e, 1.5) / per_orbit as f64;
            let gvi = GalerkinIntegrator::spectral(n, ds).unwrap();
            let options = TimeTransformOptions {
                t_end: Some(t_end),
                max_steps: 4 * per_orbit * ORBITS,
                every: Some(TAU / PER_ORBIT_OUTPUTS as f64),
                keep_steps: false,
                ..TimeTransformOptions::default()
            };
            let clock = Instant::now();
            let run = integrate_time_transformed(&gvi, &tt, 0.0, &q0, &p0, &mut [], &options);
            let seconds = clock.elapsed().as_secs_f64();
            match run {
                Ok(run) => {
                    let times: Vec<f64> = run.outputs.iter().map(|o| o.t).collect();
                    let qs: Vec<Vec<f64>> = run.outputs.iter().map(|o| o.q.clone()).collect();
                    println!(
                        "| time-transformed n = {n}, {per_orbit} steps/orbit | {} | {} | {:.2e} | {seconds:.3} |",
                        run.steps(),
                        run.gradient_evaluations,
                        max_error(&exact, &times, &qs)
                    );
                }
                Err(f) => println!(
                    "| time-transformed n = {n}, {per_orbit} steps/orbit | failed: {} | | | |",
                    f.error
                ),
            }
        }
        // Fixed physical steps, n = 12 and 16: a step count per orbit (h = 2π/steps) whose
        // outputs fall on the step ends.
        for (n, per_orbit) in [
            (12, 1024),
            (12, 2048),
            (12, 4096),
            (16, 1024),
            (16, 2048),
            (16, 4096),
        ] {
            let steps = per_orbit * ORBITS;
            let gvi = GalerkinIntegrator::spectral(n, TAU / per_orbit as f64).unwrap();
            let clock = Instant::now();
            let run = gvi.integrate(&kepler, 0.0, &q0, &p0, steps);
            let seconds = clock.elapsed().as_secs_f64();
            match run {
                Ok(traj) => {
                    let stride = per_orbit / PER_ORBIT_OUTPUTS;
                    let ks: Vec<usize> = (0..=steps).step_by(stride).collect();
                    let times: Vec<f64> = ks.iter().map(|&k| traj.time(k)).collect();
                    let qs: Vec<Vec<f64>> = ks.iter().map(|&k| traj.q[k].clone()).collect();
                    println!(
                        "| fixed step n = {n}, {per_orbit} steps/orbit | {steps} | {} | {:.2e} | {seconds:.3} |",
                        traj.gradient_evaluations(),
                        max_error(&exact, &times, &qs)
                    );
                }
                Err(f) => println!(
                    "| fixed step n = {n}, {per_orbit} steps/orbit | failed: {} | | | {seconds:.3} |",
                    f.error
                ),
            }
        }
        for tol in [1e-8, 1e-10, 1e-12, 1e-14] {
            let h = TAU / PER_ORBIT_OUTPUTS as f64;
            let mut dop = Dop853Baseline::new(&kepler, h, tol).unwrap();
            let clock = Instant::now();
            let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
            let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
            let mut times = vec![0.0];
            let mut qs = vec![q.clone()];
            for k in 0..PER_ORBIT_OUTPUTS * ORBITS {
                dop.step(k as f64 * h, &q, &p, &mut qn, &mut pn).unwrap();
                std::mem::swap(&mut q, &mut qn);
                std::mem::swap(&mut p, &mut pn);
                times.push((k + 1) as f64 * h);
                qs.push(q.clone());
            }
            let seconds = clock.elapsed().as_secs_f64();
            println!(
                "| DOP853 tol = {tol:e} | {} | {} | {:.2e} | {seconds:.3} |",
                dop.adaptive_steps(),
                dop.force_evaluations(),
                max_error(&exact, &times, &qs)
            );
        }
    }
}

fn pythagorean() -> (NBody, Vec<f64>, Vec<f64>) {
    let nb = NBody::new(vec![3.0, 4.0, 5.0], 1.0, 2).unwrap();
    (nb, vec![1.0, 3.0, -2.0, -1.0, 1.0, -1.0], vec![0.0; 6])
}

/// States at t = 0, 0.1, …, 70 of the time-transformed run, its energy error over the run,
/// steps, force evaluations and seconds.
fn pythagorean_tt(
    n: usize,
    ds: f64,
    combine: Combine,
) -> (Vec<Vec<f64>>, f64, usize, usize, f64, f64) {
    let (nb, q0, p0) = pythagorean();
    let monitor = PairDistances::new(3, 2, 1.5, combine).unwrap();
    let tt = TimeTransformed::new(nb.clone(), monitor, &q0, &p0, None).unwrap();
    let gvi = GalerkinIntegrator::spectral(n, ds).unwrap();
    let options = TimeTransformOptions {
        t_end: Some(70.0),
        max_steps: 10_000_000,
        every: Some(0.1),
        keep_steps: true,
        ..TimeTransformOptions::default()
    };
    let clock = Instant::now();
    let run = integrate_time_transformed(&gvi, &tt, 0.0, &q0, &p0, &mut [], &options).unwrap();
    let seconds = clock.elapsed().as_secs_f64();
    let e0 = tt.hamiltonian(&q0, &p0);
    let energy = run
        .step_ends
        .iter()
        .map(|o| ((tt.hamiltonian(&o.q, &o.p) - e0) / e0).abs())
        .fold(0.0, galerkin_vi::reduce::nan_max);
    let min_dt = run.step_ends[1..]
        .iter()
        .map(|o| o.dt)
        .fold(f64::INFINITY, f64::min);
    (
        run.outputs.iter().map(|o| o.q.clone()).collect(),
        energy,
        run.steps(),
        run.gradient_evaluations,
        seconds,
        min_dt,
    )
}

/// States at t = 0, 0.1, …, 70 by DOP853 at `tol`, its energy error, steps, force
/// evaluations, seconds.
fn pythagorean_dop(tol: f64) -> (Vec<Vec<f64>>, f64, usize, usize, f64) {
    let (nb, q0, p0) = pythagorean();
    let h = 0.1;
    let mut dop = Dop853Baseline::new(&nb, h, tol).unwrap();
    let clock = Instant::now();
    let (mut q, mut p) = (q0.clone(), p0.clone());
    let (mut qn, mut pn) = (vec![0.0; 6], vec![0.0; 6]);
    let mut qs = vec![q.clone()];
    let mut inv = [0.0; 4];
    nb.invariants(&q0, &p0, &mut inv);
    let e0 = inv[0];
    let mut energy: f64 = 0.0;
    for k in 0..700 {
        dop.step(k as f64 * h, &q, &p, &mut qn, &mut pn).unwrap();
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
        nb.invariants(&q, &p, &mut inv);
        energy = energy.max(((inv[0] - e0) / e0).abs());
        qs.push(q.clone());
    }
    let seconds = clock.elapsed().as_secs_f64();
    (
        qs,
        energy,
        dop.adaptive_steps(),
        dop.force_evaluations(),
        seconds,
    )
}

/// The first output time at which two runs differ by more than `tol` in position (max norm).
fn agree_until(a: &[Vec<f64>], b: &[Vec<f64>], tol: f64) -> f64 {
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let d = x
            .iter()
            .zip(y)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max);
        if d > tol || d.is_nan() {
            return 0.1 * k as f64;
        }
    }
    0.1 * (a.len().min(b.len()) - 1) as f64
}

#[test]
#[ignore = "a study of a few minutes: docs/guide/time-transformations.md"]
fn pythagorean_against_tight_integrations() {
    let (reference, e_ref, s_ref, f_ref, t_ref) = pythagorean_dop(1e-15);
    println!("\nPythagorean problem to t = 70");
    println!(
        "| run | steps | force evaluations | max relative energy error | seconds | smallest Δt | agrees with DOP853 1e-15 to 1e-6 until | to 1e-2 until |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    println!("| DOP853 tol = 1e-15 | {s_ref} | {f_ref} | {e_ref:.1e} | {t_ref:.3} | | | |");
    for tol in [1e-13, 1e-11] {
        let (qs, e, s, f, t) = pythagorean_dop(tol);
        println!(
            "| DOP853 tol = {tol:e} | {s} | {f} | {e:.1e} | {t:.3} | | {:.1} | {:.1} |",
            agree_until(&qs, &reference, 1e-6),
            agree_until(&qs, &reference, 1e-2)
        );
    }
    let mut tt_runs = Vec::new();
    for (n, ds, combine) in [
        (10, 0.01, Combine::Min),
        (10, 0.005, Combine::Min),
        (14, 0.01, Combine::Min),
        (10, 0.01, Combine::Softmin),
        (8, 0.01, Combine::Softmin),
    ] {
        let (qs, e, s, f, t, min_dt) = pythagorean_tt(n, ds, combine);
        println!(
            "| time-transformed n = {n}, Δs = {ds}, {combine:?} | {s} | {f} | {e:.1e} | {t:.3} | {min_dt:.1e} | {:.1} | {:.1} |",
            agree_until(&qs, &reference, 1e-6),
            agree_until(&qs, &reference, 1e-2)
        );
        tt_runs.push(qs);
    }
    println!(
        "time-transformed n = 10 against n = 14 (independent of DOP853): to 1e-6 until {:.1}, to 1e-2 until {:.1}",
        agree_until(&tt_runs[0], &tt_runs[2], 1e-6),
        agree_until(&tt_runs[0], &tt_runs[2], 1e-2)
    );
    let last = reference.last().unwrap();
    println!("DOP853 1e-15 at t = 70: {last:?}");
}
