//! Extending the framework: a basis (Bernstein), a quadrature (Gauss–Radau), a stage solver
//! (capped Newton) and a Lagrangian (a charged particle in a non-uniform magnetic field),
//! all written outside the crate, and what the library gives them: the step map, dense
//! output, the tangent map, refinement studies and serialisation.
//!
//! Run: `cargo run --release --example extending`. The four pieces are in `user.rs`, which
//! `tests/extension.rs` includes and tests with negative controls; the walk-through is
//! docs/guide/extending.md.

use galerkin_vi::basis::ChebyshevLagrange;
use galerkin_vi::geometry::relative_symplecticity_defect;
use galerkin_vi::refinement::{
    ErrorMeasure, Problem, RefineBy, fitted_rate, h_refinement, n_refinement,
};
use galerkin_vi::systems::{Kepler, System};
use galerkin_vi::{GalerkinIntegrator, GviError, Result, Trajectory};

mod user;
use user::{Bernstein, CappedNewton, GaussRadau, MAGNETIC};

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn main() -> Result<()> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = kepler
        .exact_solution(0.0, &q0, &p0)?
        .ok_or_else(|| GviError::Unsupported("exact Kepler solution".into()))?;

    // 1. The user's basis, rule and solver in the integrator; the same map as Chebyshev's.
    let radau = GaussRadau::new(12)?;
    let bern = GalerkinIntegrator::new(Bernstein::new(12)?, radau, 0.5)?
        .with_stage_solver(CappedNewton { cap: 10.0 });
    let cheb = GalerkinIntegrator::new(ChebyshevLagrange::new(12)?, radau, 0.5)?;
    let tb = bern.integrate(&kepler, 0.0, &q0, &p0, 40)?;
    let tc = cheb.integrate(&kepler, 0.0, &q0, &p0, 40)?;
    let map = (0..=40)
        .map(|k| max_diff(&tb.q[k], &tc.q[k]))
        .fold(0.0, f64::max);
    let dense = [0.25, 3.3, 10.1]
        .iter()
        .map(|&t| Ok(max_diff(&tb.velocity_at(t)?, &tc.velocity_at(t)?)))
        .collect::<Result<Vec<f64>>>()?
        .into_iter()
        .fold(0.0, f64::max);
    let error = max_diff(&tb.position_at(20.0)?, &exact.position(20.0));
    println!("Bernstein n = 12 + Gauss–Radau(12) + capped Newton, Kepler h = 0.5, T = 20:");
    println!("  step ends vs Chebyshev (same rule)   {map:.1e}");
    println!("  dense q̇(t) vs Chebyshev at 0.25, 3.3, 10.1   {dense:.1e}");
    println!("  error vs the exact orbit at T        {error:.1e}");
    let misread = tb.curve(6)?.state_at(&ChebyshevLagrange::new(12)?, 3.3)?.0;
    let wrong = max_diff(&misread, &tc.position_at(3.3)?);
    println!("  (its coefficients read as Chebyshev's: off by {wrong:.1e})");

    // 2. The user's Lagrangian: exact tangent map, symplecticity, Noether momentum.
    let (qm, pm) = ([0.8, 0.1], [0.2, 0.9]);
    let gm = GalerkinIntegrator::new(Bernstein::new(10)?, GaussRadau::new(10)?, 0.5)?
        .with_stage_solver(CappedNewton { cap: 10.0 });
    let maps = gm.tangent_map(&MAGNETIC, &qm, &pm, 20)?;
    let defect = relative_symplecticity_defect(&maps[19]);
    let run = gm.integrate(&MAGNETIC, 0.0, &qm, &pm, 200)?;
    let ang = |k: usize| run.q[k][0] * run.p[k][1] - run.q[k][1] * run.p[k][0];
    let drift = (0..=200)
        .map(|k| (ang(k) - ang(0)).abs())
        .fold(0.0, f64::max);
    println!("Magnetic Lagrangian, Bernstein 10 + Radau(10), h = 0.5:");
    println!("  20-step tangent map, relative symplecticity defect   {defect:.1e}");
    let energy = |k: usize| MAGNETIC.energy(&run.q[k], &run.p[k]);
    let wobble = (0..=200)
        .map(|k| (energy(k) - energy(0)).abs())
        .fold(0.0, f64::max);
    println!("  canonical angular momentum drift over 200 steps      {drift:.1e}");
    println!("  energy error over 200 steps (bounded, not drifting)   {wobble:.1e}");

    // 3. Studies over the user's family.
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, 20.0)?;
    let ns: Vec<usize> = (6..=20).step_by(2).collect();
    let points = n_refinement(
        |n| GalerkinIntegrator::new(Bernstein::new(n)?, GaussRadau::new(n + 1)?, 1.0),
        &ns,
        &problem,
        |t| exact.position(t),
        8,
    )?;
    println!("n-refinement, Bernstein(n) + Radau(n + 1), Kepler h = 1, T = 20:");
    for p in &points {
        println!(
            "  n = {:2}  map error {:.2e}  curve error {:.2e}  {:5} gradient evaluations",
            p.n, p.map_error, p.error, p.gradient_evaluations
        );
    }
    let fit = fitted_rate(&points, RefineBy::N, ErrorMeasure::Map)?;
    println!(
        "  fitted: error ≈ C·{:.3}ⁿ (ρ = {:.2})",
        fit.rate,
        fit.rho().unwrap_or(f64::NAN)
    );
    let period = std::f64::consts::TAU;
    let one_period = Problem::new(&kepler, 0.0, &q0, &p0, period)?;
    let hs: Vec<f64> = [128.0, 192.0, 256.0, 384.0, 512.0]
        .iter()
        .map(|s| period / s)
        .collect();
    for m in [3, 4] {
        let points = h_refinement(
            |h| GalerkinIntegrator::new(Bernstein::new(4)?, GaussRadau::new(m)?, h),
            &hs,
            &one_period,
            |t| exact.position(t),
            4,
        )?;
        let fit = fitted_rate(&points, RefineBy::H, ErrorMeasure::Map)?;
        println!(
            "h-refinement, Bernstein 4 + Radau({m}): order {:.2} (expected min(2(n − 1), 2m − 1) = {})",
            fit.rate,
            6.min(2 * m - 1)
        );
    }

    // 4. Serialisation: JSON records the basis by name; the user's basis must be attached
    // again before dense output.
    let json = serde_json::to_string(&tb).map_err(|e| GviError::Unsupported(e.to_string()))?;
    let mut back: Trajectory =
        serde_json::from_str(&json).map_err(|e| GviError::Unsupported(e.to_string()))?;
    println!("Serialisation (JSON, {} bytes):", json.len());
    let describe = |r: Result<()>| match r {
        Ok(()) => "accepted (unexpected)".to_string(),
        Err(e) => e.to_string(),
    };
    println!(
        "  before attach_basis: {}",
        describe(back.position_at(3.3).map(|_| ()))
    );
    println!(
        "  attaching Chebyshev: {}",
        describe(back.attach_basis(ChebyshevLagrange::new))
    );
    back.attach_basis(Bernstein::new)?;
    let after = max_diff(&back.position_at(3.3)?, &tb.position_at(3.3)?);
    println!("  after attach_basis(Bernstein::new): q(3.3) within {after:.1e} of the original");
    Ok(())
}
