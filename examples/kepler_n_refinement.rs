//! The paper's Kepler experiment (Figure 5): e = 0.6, h = 2, 100 steps; max error of the
//! one-step map (step ends) and of the Galerkin curves (max over t) for n = 4…44.
//!
//! Run: `cargo run --release --example kepler_n_refinement`

use galerkin_vi::prelude::*;

fn main() -> Result<(), GviError> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = kepler
        .exact_solution(0.0, &q0, &p0)?
        .ok_or_else(|| GviError::Unsupported("no exact solution".into()))?;
    println!(
        "{:>3} {:>12} {:>12} {:>12} {:>10}",
        "n", "map error", "curve error", "energy err", "newton/step"
    );
    for n in (4..=44).step_by(2) {
        let gvi = GalerkinIntegrator::spectral(n, 2.0)?;
        let traj = match gvi.integrate(&kepler, 0.0, &q0, &p0, 100) {
            Ok(traj) => traj,
            Err(failure) => {
                println!("{n:>3} failed: {failure}");
                continue;
            }
        };
        let map_err = (0..=traj.steps())
            .map(|k| dist(&traj.q[k], &exact.position(traj.time(k))))
            .fold(0.0, f64::max);
        let curve_err = traj
            .sample_times(16)
            .into_iter()
            .map(|t| dist(&traj.position_at(t).unwrap_or_default(), &exact.position(t)))
            .fold(0.0, f64::max);
        let mut e0 = [0.0; 2];
        kepler.invariants(&traj.q[0], &traj.p[0], &mut e0);
        let energy_err = (0..=traj.steps())
            .map(|k| {
                let mut e = [0.0; 2];
                kepler.invariants(&traj.q[k], &traj.p[k], &mut e);
                (e[0] - e0[0]).abs()
            })
            .fold(0.0, f64::max);
        println!(
            "{n:>3} {map_err:>12.3e} {curve_err:>12.3e} {energy_err:>12.3e} {:>10.2}",
            traj.newton_iterations() as f64 / traj.steps() as f64
        );
    }
    Ok(())
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(
        if a.len() == b.len() {
            0.0
        } else {
            f64::INFINITY
        },
        f64::max,
    )
}
