//! Long-run round-off of the Galerkin integrator on Kepler e = 0.6: max position error against
//! the exact solution at the samples t = 2k, and the energy error (its max and its drift, the
//! least-squares slope against t), with and without compensated summation of the state.
//!
//! Run: `cargo run --release --example roundoff -- [T] [basis:n:h[:points]] ...`
//! (default T = 20000 and the configurations legendre:32:1, legendre:24:0.5,
//! chebyshev:32:1). Experiments with the Newton options through the environment: GVI_TOL,
//! GVI_FLOOR (tolerances), GVI_NO_REUSE (no simplified Newton), GVI_ROUNDED_KINETIC (rounded
//! kinetic products in the residuals instead of the default double-double ones).

use galerkin_vi::integrator::DenseOptions;
use galerkin_vi::prelude::*;
use std::time::Instant;

/// An f64 from the environment (for experiments with the Newton options), or `default`.
fn env_f64(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn main() -> Result<(), GviError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let horizon: f64 = args
        .first()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000.0);
    let mut configs: Vec<String> = args.iter().skip(1).cloned().collect();
    if configs.is_empty() {
        configs = ["legendre:32:1", "legendre:24:0.5", "chebyshev:32:1"]
            .map(String::from)
            .to_vec();
    }
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = kepler
        .exact_solution(0.0, &q0, &p0)?
        .expect("bound orbit has an exact solution");
    let energy = |q: &[f64], p: &[f64]| {
        0.5 * (p[0] * p[0] + p[1] * p[1]) - 1.0 / (q[0] * q[0] + q[1] * q[1]).sqrt()
    };
    let e0 = energy(&q0, &p0);
    println!(
        "{:<10} {:>3} {:>5} {:>4} {:>12} {:>12} {:>11} {:>12} {:>7} {:>6}",
        "basis",
        "n",
        "h",
        "m",
        "compensated",
        "max |q−q*|",
        "max |ΔH|",
        "dH/dt",
        "seconds",
        "it/st"
    );
    for c in &configs {
        let parts: Vec<&str> = c.split(':').collect();
        let basis: BasisKind = parts[0].parse()?;
        let n: usize = parts[1].parse().expect("n");
        let h: f64 = parts[2].parse().expect("h");
        let points: Option<usize> = parts.get(3).map(|s| s.parse().expect("points"));
        let steps = (horizon / h).round() as usize;
        let every = (2.0 / h).round().max(1.0) as usize;
        for compensated in [false, true] {
            let gvi =
                GalerkinIntegrator::from_kinds(basis, n, QuadratureKind::GaussLegendre, points, h)?
                    .with_options(NewtonOptions {
                        compensated,
                        floor_tolerance: env_f64(
                            "GVI_FLOOR",
                            NewtonOptions::default().floor_tolerance,
                        ),
                        dense: DenseOptions {
                            reuse_jacobian: std::env::var("GVI_NO_REUSE").is_err(),
                            ..DenseOptions::default()
                        },
                        exact_kinetic: std::env::var("GVI_ROUNDED_KINETIC").is_err(),
                        tolerance: env_f64("GVI_TOL", NewtonOptions::default().tolerance),
                        ..NewtonOptions::default()
                    });
            let start = Instant::now();
            let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, steps)?;
            let secs = start.elapsed().as_secs_f64();
            let mut err = 0.0f64;
            let (mut st, mut sde, mut stt, mut ste, mut cnt, mut dmax) =
                (0.0, 0.0, 0.0, 0.0, 0.0, 0.0f64);
            for k in (0..=steps).step_by(every) {
                let t = k as f64 * h;
                let q = &traj.q[k];
                let qe = exact.position(t);
                err = err.max((q[0] - qe[0]).abs().max((q[1] - qe[1]).abs()));
                let de = energy(q, &traj.p[k]) - e0;
                dmax = dmax.max(de.abs());
                st += t;
                sde += de;
                stt += t * t;
                ste += t * de;
                cnt += 1.0;
            }
            let slope = (cnt * ste - st * sde) / (cnt * stt - st * st);
            println!(
                "{:<10} {:>3} {:>5} {:>4} {:>12} {:>12.3e} {:>11.3e} {:>12.3e} {:>7.2} {:>6.2}",
                basis.as_str(),
                n,
                h,
                gvi.rule().len(),
                compensated,
                err,
                dmax,
                slope,
                secs,
                traj.newton_iterations() as f64 / steps as f64
            );
        }
    }
    Ok(())
}
