//! The paper's Kepler experiment (Figure 5): e = 0.6, h = 2, 100 steps; max error of the
//! one-step map (step ends) and of the Galerkin curves (max over t) for n = 4…44. Writes the
//! table to out/kepler-n-refinement.csv and prints a short summary.
//!
//! Run: `cargo run --release --example kepler_n_refinement`

use galerkin_vi::prelude::*;
use std::fmt::Write as _;

const TABLE: &str = "out/kepler-n-refinement.csv";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = kepler
        .exact_solution(0.0, &q0, &p0)?
        .ok_or_else(|| GviError::Unsupported("no exact solution".into()))?;
    let mut csv = String::from("n,map_error,curve_error,energy_error,newton_per_step\n");
    let (mut first, mut last) = (None, None);
    for n in (4..=44).step_by(2) {
        let gvi = GalerkinIntegrator::spectral(n, 2.0)?;
        let traj = match gvi.integrate(&kepler, 0.0, &q0, &p0, 100) {
            Ok(traj) => traj,
            Err(failure) => {
                eprintln!("n = {n} failed: {failure}");
                writeln!(csv, "{n},,,,")?;
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
        writeln!(
            csv,
            "{n},{map_err:e},{curve_err:e},{energy_err:e},{}",
            traj.newton_iterations() as f64 / traj.steps() as f64
        )?;
        first = first.or(Some((n, map_err)));
        last = Some((n, map_err, curve_err));
    }
    std::fs::create_dir_all("out")?;
    std::fs::write(TABLE, csv)?;
    if let (Some((n0, e0)), Some((n1, e1, c1))) = (first, last) {
        println!(
            "Kepler e = 0.6, h = 2, 100 steps: one-step map error {e0:.1e} at n = {n0}, \
             {e1:.1e} at n = {n1} (Galerkin curves {c1:.1e})"
        );
    }
    println!("table (n, map, curve and energy errors, Newton iterations per step): {TABLE}");
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
