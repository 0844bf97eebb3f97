//! Every basis × quadrature on Kepler e = 0.6 at h = 2 (100 steps): one-step error and kinetic
//! condition number against n. Writes CSV/JSON/SVG to out/basis_comparison and prints a table.
//!
//! Run: `cargo run --release --example basis_comparison`

use galerkin_vi::quadrature::QuadratureKind;
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::compare_bases::compare_bases;

fn main() -> Result<(), galerkin_vi_lab::error::LabError> {
    let scene = Scene::load("kepler")?;
    let ns: Vec<usize> = (8..=64).step_by(8).collect();
    let quads = [QuadratureKind::GaussLegendre, QuadratureKind::GaussLobatto];
    let cmp = compare_bases(&scene.build()?, &ns, &quads)?;
    println!(
        "{:<11} {:<15} {:>3} {:>11} {:>11} {:>8}",
        "basis", "quadrature", "n", "map error", "condition", "newton"
    );
    for p in &cmp.points {
        let m = &p.measurement;
        match &m.failure {
            None => println!(
                "{:<11} {:<15} {:>3} {:>11.3e} {:>11.3e} {:>8.2}",
                m.basis,
                m.quadrature,
                m.n,
                m.map_error,
                p.kinetic_condition,
                m.newton_iterations as f64 / m.steps as f64
            ),
            Some(f) => println!(
                "{:<11} {:<15} {:>3} failed: {f}",
                m.basis, m.quadrature, m.n
            ),
        }
    }
    for f in cmp.write(std::path::Path::new("out/basis_comparison"))? {
        println!("wrote {}", f.display());
    }
    Ok(())
}
