//! Measures the Kepler-adapted Galerkin integrator (Gauss collocation in the interaction
//! picture of the Jacobi splitting) on the N-body scenes of issue 35: for each stage count and
//! steps per sample interval, the median wall time of REPEATS runs through the studies' own
//! sampled runner, the work–precision study's error (the largest position error at the sample
//! times against the study's reference) and the fixed-point iterations per step.
//!
//! ```text
//! cargo run --release -p galerkin-vi-lab --example kepler_adapted -- j2000 4,6,8 1,2,4 5
//! ```
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::peers::{Peer, run_peer};
use galerkin_vi_lab::studies::work_precision::{WorkPrecisionConfig, reference_csv};
use std::time::Instant;

fn list(arg: Option<&String>, default: &str) -> Result<Vec<usize>, std::num::ParseIntError> {
    arg.map_or(default, String::as_str)
        .split(',')
        .map(str::parse)
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let scene = match args.get(1).map_or("j2000", String::as_str) {
        "outer" => "outer-solar-system",
        "j2000" => "solar-system",
        other => return Err(format!("unknown scene {other} (outer or j2000)").into()),
    };
    let stages = list(args.get(2), "4,6,8")?;
    let divisors = list(args.get(3), "1,2,4")?;
    let repeats: usize = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(5);
    let scene = Scene::load(scene)?.build()?;
    let reference = reference_csv(&scene, &WorkPrecisionConfig::full())?;
    let dt = scene.method.h;
    let samples = reference.q.len() - 1;
    let system = scene.euclidean()?;
    for &s in &stages {
        for &m in &divisors {
            let mut times = Vec::new();
            let mut last = None;
            for _ in 0..repeats.max(1) {
                let start = Instant::now();
                let run = run_peer(
                    system,
                    &scene.initial,
                    Peer::KeplerAdapted { s },
                    dt,
                    m,
                    samples,
                )?;
                times.push(start.elapsed().as_secs_f64());
                last = Some(run);
            }
            times.sort_by(f64::total_cmp);
            let run = last.ok_or("no run")?;
            if let Some(f) = &run.failure {
                println!("s = {s}, h = Δ/{m}: failed: {f}");
                continue;
            }
            let error = run
                .q
                .iter()
                .zip(&reference.q)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
                .fold(0.0, f64::max);
            if std::env::var_os("PER_BODY").is_some() {
                let per: Vec<String> = (0..run.q[0].len() / 3)
                    .map(|b| {
                        let e = run
                            .q
                            .iter()
                            .zip(&reference.q)
                            .flat_map(|(a, r)| (3 * b..3 * b + 3).map(move |i| (a[i] - r[i]).abs()))
                            .fold(0.0, f64::max);
                        format!("{e:.1e}")
                    })
                    .collect();
                println!("  per body: {}", per.join(" "));
            }
            let steps = (samples * m) as f64;
            println!(
                "s = {s:2}, h = {:8.3} (Δ/{m}): median {:8.3} ms (min {:8.3}), error {error:.2e}, \
                 {:.2} iterations per step",
                dt / m as f64,
                times[times.len() / 2] * 1e3,
                times[0] * 1e3,
                run.force_evaluations as f64 / (steps * s as f64),
            );
        }
    }
    Ok(())
}
