//! Issue 35's force-kernel timing: the J2000 10-body forces at 10 quadrature nodes (the
//! positions of the scene's initial state, scaled slightly from node to node), evaluated
//! point by point for every body (`force_at_points`), for the Sun and Mercury only
//! (`force_at_points_on_blocks`, the masked residual's kernel before the by-coordinate layout),
//! and for the Sun and Mercury from rows laid out by coordinate
//! (`force_at_points_by_coordinate_on_blocks`, rows of 16), 200 000 calls each, three rounds.
//!
//! ```text
//! cargo run --release -p galerkin-vi-lab --example force_kernel
//! ```
use galerkin_vi::Lagrangian;
use galerkin_vi::lagrangian::ByCoordinate;
use galerkin_vi_lab::scene::Scene;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = Scene::load("solar-system")?.build()?;
    let sys = scene.euclidean()?;
    let q0 = scene.initial.q.clone();
    let d = q0.len();
    let m = 10;
    let stride = 16;
    let mut qp = vec![0.0; m * d];
    for j in 0..m {
        for r in 0..d {
            qp[j * d + r] = q0[r] * (1.0 + 1e-3 * j as f64);
        }
    }
    let mut qt = vec![0.0; d * stride];
    for r in 0..d {
        for j in 0..stride {
            qt[r * stride + j] = qp[j.min(m - 1) * d + r];
        }
    }
    let mut active = vec![false; d / 3];
    active[0] = true;
    active[1] = true;
    let mut out = vec![0.0; m * d];
    let mut outt = vec![0.0; d * stride];
    let n = 200_000;
    for round in 0..3 {
        let t = Instant::now();
        for _ in 0..n {
            sys.force_at_points(std::hint::black_box(&qp), &mut out);
        }
        let full = t.elapsed().as_secs_f64() / n as f64 * 1e9;
        let t = Instant::now();
        for _ in 0..n {
            sys.force_at_points_on_blocks(std::hint::black_box(&qp), &active, &mut out);
        }
        let masked = t.elapsed().as_secs_f64() / n as f64 * 1e9;
        let t = Instant::now();
        for _ in 0..n {
            sys.force_at_points_by_coordinate_on_blocks(
                std::hint::black_box(&qt),
                ByCoordinate::new(m, stride),
                &active,
                &mut outt,
            );
        }
        let bc = t.elapsed().as_secs_f64() / n as f64 * 1e9;
        println!(
            "round {round}: full {full:.0} ns, masked {masked:.0} ns, by coordinate {bc:.0} ns"
        );
    }
    Ok(())
}
