//! Profile harness of the multirate Galerkin integrator (issue 35) on the J2000 10-body scene,
//! T = 10 000 d, through the studies' sampled runner (100 samples), with Mercury (the shortest
//! orbit) on R micro steps: the time of `REPEATS` runs and the Picard iterations per step.
//!
//! ```text
//! cargo run --release -p galerkin-vi-lab --example multirate_fastest -- N R DIVISOR [REPEATS]
//! cargo run --release -p galerkin-vi-lab --example multirate_fastest -- 9 3 3 20
//! ```
use galerkin_vi::baselines::OneStepMethod;
use galerkin_vi::multirate::{MultirateGalerkin, MultirateShape};
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::peers::{Peer, nbody_of, run_peer};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: multirate_fastest N R DIVISOR [REPEATS]";
    let number = |i: usize| -> Result<usize, Box<dyn std::error::Error>> {
        Ok(args.get(i).ok_or(usage)?.parse()?)
    };
    let (n, micro_steps, divisor) = (number(0)?, number(1)?, number(2)?);
    let repeats = number(3).unwrap_or(10);
    let interval = 100.0;
    let scene = Scene::load("solar-system")?.build()?;
    let system = scene.euclidean()?;
    let peer = Peer::Multirate { n, micro_steps };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let start = Instant::now();
        let run = run_peer(system, &scene.initial, peer, interval, divisor, 100)?;
        times.push(start.elapsed().as_secs_f64());
        last = Some(run);
    }
    times.sort_by(f64::total_cmp);
    let run = last.ok_or("no run")?;
    if let Some(failure) = &run.failure {
        return Err(failure.clone().into());
    }
    // The iterations per step, from one run of the integrator itself.
    let nbody = nbody_of(system).ok_or("not an N-body scene")?;
    let (q0, p0) = (&scene.initial.q, &scene.initial.p);
    let fast = MultirateGalerkin::shortest_period_body(nbody, q0, p0).ok_or("no fast body")?;
    let h = interval / divisor as f64;
    let mut m = MultirateGalerkin::new(
        nbody,
        &[fast],
        MultirateShape::collocation(n, micro_steps),
        h,
    )?;
    let steps = 100 * divisor;
    let (mut q, mut p) = (q0.clone(), p0.clone());
    let (mut q1, mut p1) = (q.clone(), p.clone());
    for k in 0..steps {
        m.step(k as f64 * h, &q, &p, &mut q1, &mut p1)?;
        std::mem::swap(&mut q, &mut q1);
        std::mem::swap(&mut p, &mut p1);
    }
    println!(
        "n = {n}, R = {micro_steps}, H = {h:.3}: median {:.3} ms (min {:.3}), {:.2} Picard \
         sweeps and {:.1} force evaluations (quadrature points) per step, fast body {fast}",
        times[times.len() / 2] * 1e3,
        times[0] * 1e3,
        m.iterations() as f64 / steps as f64,
        m.force_evaluations() as f64 / steps as f64,
    );
    Ok(())
}
