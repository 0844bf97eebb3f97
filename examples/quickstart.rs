//! Quickstart, quoted verbatim in README.md: `cargo run --release --example quickstart`
use galerkin_vi::prelude::*;

/// A particle in a double well: L = v²/2 − (q² − 1)²/4. Derivatives come from AD.
struct DoubleWell;

impl Lagrangian for DoubleWell {
    fn dim(&self) -> usize {
        1
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        let w = q[0] * q[0] - 1.0;
        v[0] * v[0] * 0.5 - w * w * 0.25
    }
}

fn main() -> Result<(), GviError> {
    let gvi = GalerkinIntegrator::spectral(16, 1.0)?; // n = 16, h = 1, 32 Gauss points
    let traj = gvi.integrate(&DoubleWell, 0.0, &[0.0], &[0.75], 200)?;
    let energy = |k: usize| DoubleWell.energy(&traj.q[k], &traj.p[k]);
    let drift = (0..=200).map(|k| (energy(k) - energy(0)).abs());
    println!("q(200) = {:.12}", traj.q[200][0]);
    println!("q(0.5) on the curve = {:.12}", traj.position_at(0.5)?[0]);
    println!("max energy error: {:.1e}", drift.fold(0.0, f64::max));
    Ok(())
}
