//! Profile harness for issue 35: the fastest Galerkin configurations at 1e-9 on Kepler T = 200
//! (n = 12, h = 1/3 with the compact rule's 12 Gauss points and with Gauss collocation's 11; the
//! work-precision study's rows of 2026-11-26 and 2026-11-27) beside DOP853 at the tolerance that
//! reaches 1e-9 there, all through the study's own sampled runner, interleaved.
//!
//!     cargo run --release -p galerkin-vi-lab --example kepler_fastest [galerkin|dop853|both] [REPEATS]
use galerkin_vi::basis::BasisKind;
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::peers::{Peer, QuadPoints, run_peer};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(String::as_str).unwrap_or("both");
    let repeats: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(20);
    let scene = Scene::load("kepler")?.build()?;
    let galerkin = |points| Peer::Galerkin {
        basis: BasisKind::Legendre,
        n: 12,
        points,
    };
    let dop = Peer::Dop853 {
        tolerance: 10f64.powf(-13.5),
    };
    let mut peers = Vec::new();
    if which != "dop853" {
        peers.push(("galerkin n=12 h=1/3 m=12", galerkin(QuadPoints::Compact), 6));
        peers.push((
            "galerkin n=12 h=1/3 m=11",
            galerkin(QuadPoints::Collocation),
            6,
        ));
    }
    if which != "galerkin" {
        peers.push(("dop853 tol=10^-13.5", dop, 1));
    }
    // Interleaved: one run of each per round, so that a change in the machine's load
    // affects both alike.
    let mut times = vec![Vec::new(); peers.len()];
    let mut last = vec![None; peers.len()];
    for _ in 0..repeats {
        for (i, &(_, peer, divisor)) in peers.iter().enumerate() {
            let start = Instant::now();
            let run = run_peer(scene.euclidean()?, &scene.initial, peer, 2.0, divisor, 100)?;
            times[i].push(start.elapsed().as_secs_f64());
            last[i] = Some(run);
        }
    }
    let mut medians = Vec::new();
    for (i, (label, _, _)) in peers.iter().enumerate() {
        times[i].sort_by(f64::total_cmp);
        let median = times[i][times[i].len() / 2];
        let run = last[i].take().ok_or("no run")?;
        println!(
            "{label}: median {:.3} ms, {} force evaluations, q(T) = {:?}",
            median * 1e3,
            run.force_evaluations,
            run.q.last()
        );
        medians.push(median);
    }
    if let (Some(&dop853), true) = (medians.last(), which == "both") {
        for ((label, _, _), median) in peers.iter().zip(&medians).take(medians.len() - 1) {
            println!("ratio {label} / dop853: {:.3}", median / dop853);
        }
    }
    Ok(())
}
