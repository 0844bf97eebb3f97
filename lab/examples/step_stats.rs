//! Per-step solver statistics of one Galerkin configuration over a scene's horizon: how many
//! residuals (force evaluations / quadrature points) each step takes, with which guess, and the
//! wall time — issue 35's measurement of where a step's iterations go (docs/solvers.md).
//!
//! ```text
//! cargo run --release -p galerkin-vi-lab --example step_stats -- SCENE N H [M] [HANDOVER] [SELF_BLOCK_RATE]
//! cargo run --release -p galerkin-vi-lab --example step_stats -- solar-system 10 12.5
//! cargo run --release -p galerkin-vi-lab --example step_stats -- solar-system 11 16.666666666666668 11 0 1
//! ```
//!
//! Chebyshev–Lagrange basis, M Gauss points (default N), `T = h · steps` of the scene. HANDOVER
//! and SELF_BLOCK_RATE set `StructuredOptions::velocity_fixed_point_handover` (0: the frozen
//! Hessian from the first iteration) and `velocity_self_block_rate`.
use galerkin_vi::basis::BasisKind;
use galerkin_vi::prelude::*;
use galerkin_vi::quadrature::QuadratureKind;
use galerkin_vi_lab::scene::Scene;
use std::collections::BTreeMap;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: step_stats SCENE N H [M] [HANDOVER] [SELF_BLOCK_RATE]";
    let (Some(name), Some(n), Some(h)) = (args.first(), args.get(1), args.get(2)) else {
        return Err(usage.into());
    };
    let (n, h): (usize, f64) = (n.parse()?, h.parse()?);
    let m: usize = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(n);
    let scene = Scene::load(name)?.build()?;
    let system = scene.euclidean()?;
    let gvi = GalerkinIntegrator::from_kinds(
        BasisKind::Chebyshev,
        n,
        QuadratureKind::default(),
        Some(m),
        h,
    )?;
    let mut options = *gvi.options();
    if let Some(x) = args.get(4) {
        options.structured.velocity_fixed_point_handover = x.parse()?;
    }
    if let Some(x) = args.get(5) {
        options.structured.velocity_self_block_rate = x.parse()?;
    }
    let gvi = gvi.with_options(options);
    let horizon = scene.method.h * scene.method.steps as f64;
    let steps = (horizon / h).round() as usize;
    let mut ws = gvi.workspace(system)?;
    let (mut q, mut p) = (scene.initial.q.clone(), scene.initial.p.clone());
    let (mut q_next, mut p_next) = (q.clone(), p.clone());
    // (residuals of the step, its guess and counts) → steps.
    let mut histogram: BTreeMap<(usize, String), usize> = BTreeMap::new();
    let (mut evaluations, mut partial) = (0, 0);
    let start = Instant::now();
    for k in 0..steps {
        let stats = gvi
            .step(system, &mut ws, &q, &p, &mut q_next, &mut p_next)
            .map_err(|e| format!("step {k}: {e}"))?;
        evaluations += stats.gradient_evaluations;
        partial += stats.partial_gradient_evaluations;
        let kind = format!(
            "{:?}, {} iterations, {} Hessians, {} factorisations",
            stats.guess, stats.iterations, stats.hessian_evaluations, stats.factorizations
        );
        *histogram
            .entry((stats.gradient_evaluations / m.max(1), kind))
            .or_default() += 1;
        std::mem::swap(&mut q, &mut q_next);
        std::mem::swap(&mut p, &mut p_next);
    }
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{name}: Chebyshev n = {n}, h = {h}, {m} points, {steps} steps in {:.2} ms; {evaluations} force evaluations, {:.2} residuals per step (and {:.2} masked: only the unconverged bodies' forces)",
        seconds * 1e3,
        evaluations as f64 / (steps.max(1) * m.max(1)) as f64,
        partial as f64 / (steps.max(1) * m.max(1)) as f64
    );
    println!("residuals  steps  kind");
    for ((residuals, kind), count) in histogram {
        println!("{residuals:9}  {count:5}  {kind}");
    }
    Ok(())
}
