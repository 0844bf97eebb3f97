//! Profile harness for issue 35's N-body targets: the fastest Galerkin configurations at 1e-9
//! of the work-precision studies, through the studies' own sampled runner (100 samples).
//!
//! - `outer`: the outer solar system, 500 years (Δ = 1825 d), Chebyshev n = 10, h = 912.5 d,
//!   15 Gauss points (the economical rule);
//! - `j2000`: the J2000 10-body scene, T = 10 000 d (Δ = 100 d), Chebyshev n = 10,
//!   h = 12.5 d, 10 Gauss points (the compact rule);
//! - `j2000-12`: the same scene at the frontier of the study of 2026-11-27 04:11, Legendre
//!   n = 12, h = 20 d, 12 Gauss points;
//! - `j2000-9`: the same scene, Legendre n = 9, h = 11.1 d, 8 Gauss points (the collocation
//!   rule: one vector of eight nodes in the force kernel);
//! - `j2000-11`: the same scene at the frontier of the study of 2026-11-27 09:27, Legendre
//!   n = 11, h = 16.7 d, 10 Gauss points (the collocation rule);
//! - `j2000-14`: the same scene at the frontier of the study of 2026-11-27, Legendre n = 14,
//!   h = 25 d, 14 Gauss points.
//!
//! ```text
//! cargo run --release -p galerkin-vi-lab --example nbody_fastest [outer|j2000|j2000-9|j2000-11|j2000-12|j2000-14] [REPEATS]
//! valgrind --tool=callgrind target/release/examples/nbody_fastest outer 1
//! ```
use galerkin_vi::basis::BasisKind;
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::peers::{Peer, QuadPoints, run_peer};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("outer");
    let repeats: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(10);
    let (scene, interval, divisor, points, basis, n) = match which {
        "outer" => (
            "outer-solar-system",
            1825.0,
            2,
            QuadPoints::Economical,
            BasisKind::Chebyshev,
            10,
        ),
        "j2000" => (
            "solar-system",
            100.0,
            8,
            QuadPoints::Compact,
            BasisKind::Chebyshev,
            10,
        ),
        "j2000-12" => (
            "solar-system",
            100.0,
            5,
            QuadPoints::Compact,
            BasisKind::Legendre,
            12,
        ),
        "j2000-9" => (
            "solar-system",
            100.0,
            9,
            QuadPoints::Collocation,
            BasisKind::Legendre,
            9,
        ),
        "j2000-11" => (
            "solar-system",
            100.0,
            6,
            QuadPoints::Collocation,
            BasisKind::Legendre,
            11,
        ),
        "j2000-14" => (
            "solar-system",
            100.0,
            4,
            QuadPoints::Compact,
            BasisKind::Legendre,
            14,
        ),
        other => {
            return Err(format!(
                "unknown configuration {other} (outer, j2000, j2000-9, j2000-11, j2000-12 or j2000-14)"
            )
            .into());
        }
    };
    let scene = Scene::load(scene)?.build()?;
    let peer = Peer::Galerkin { basis, n, points };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let start = Instant::now();
        let run = run_peer(
            scene.euclidean()?,
            &scene.initial,
            peer,
            interval,
            divisor,
            100,
        )?;
        times.push(start.elapsed().as_secs_f64());
        last = Some(run);
    }
    times.sort_by(f64::total_cmp);
    let run = last.ok_or("no run")?;
    if let Some(failure) = &run.failure {
        return Err(failure.clone().into());
    }
    println!(
        "{which}: median {:.3} ms (min {:.3}), {} force evaluations, q(T)[..3] = {:?}",
        times[times.len() / 2] * 1e3,
        times[0] * 1e3,
        run.force_evaluations,
        run.q.last().map(|q| q[..3].to_vec())
    );
    Ok(())
}
