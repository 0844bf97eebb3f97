use galerkin_vi::integrator::{GalerkinIntegrator, NewtonOptions, StageSolver};
use galerkin_vi::prelude::*;
use galerkin_vi::scene::Scene;
use std::time::Instant;

fn report<L: Lagrangian>(
    name: &str,
    lag: &L,
    q0: &[f64],
    p0: &[f64],
    n: usize,
    h: f64,
    steps: usize,
    solver: StageSolver,
) -> Vec<f64> {
    if let Ok(only) = std::env::var("ONLY") {
        if only != solver.as_str() {
            return q0.to_vec();
        }
    }
    let opts = NewtonOptions {
        solver,
        ..NewtonOptions::default()
    };
    let gvi = GalerkinIntegrator::spectral(n, h)
        .unwrap()
        .with_options(opts);
    let t = Instant::now();
    let traj = gvi.integrate(lag, 0.0, q0, p0, steps).unwrap();
    let el = t.elapsed().as_secs_f64();
    if std::env::var("STEPS").is_ok() {
        for (k, st) in traj.stats.iter().enumerate() {
            if st.fallbacks > 0 || st.factorizations > 1 {
                println!(
                    "  step {k}: it {} fact {} fb {} inner {} guess {:?}",
                    st.iterations, st.factorizations, st.fallbacks, st.inner_iterations, st.guess
                );
            }
        }
    }
    let it: usize = traj.stats.iter().map(|s| s.iterations).sum();
    let fb: usize = traj.stats.iter().map(|s| s.fallbacks).sum();
    let fa: usize = traj.stats.iter().map(|s| s.factorizations).sum();
    let inner: usize = traj.stats.iter().map(|s| s.inner_iterations).sum();
    println!(
        "{name} {solver}: n={n} h={h}: it/step {:.2} fallbacks {fb} fact {fa} inner/step {:.1} evals {} time {el:.4}",
        it as f64 / steps as f64,
        inner as f64 / steps as f64,
        traj.gradient_evaluations()
    );
    traj.q[steps].clone()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let which = args.get(1).map(|s| s.as_str()).unwrap_or("kepler");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(16);
    let h: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(2.0);
    let steps: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(100);
    if which == "kepler" {
        let k = Kepler::new(1.0).unwrap();
        let (q0, p0) = Kepler::paper_initial_state();
        let a = report("kepler", &k, &q0, &p0, n, h, steps, StageSolver::Exact);
        let b = report("kepler", &k, &q0, &p0, n, h, steps, StageSolver::Kronecker);
        report("kepler", &k, &q0, &p0, n, h, steps, StageSolver::Auto);
        report("kepler", &k, &q0, &p0, n, h, steps, StageSolver::FixedPoint);
        let c = report(
            "kepler",
            &k,
            &q0,
            &p0,
            n,
            h,
            steps,
            StageSolver::NewtonKrylov,
        );
        println!(
            "diff {:e}",
            a.iter()
                .zip(&c)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        );
        println!(
            "diff {:e}",
            a.iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        );
    } else {
        let scene = Scene::load(which).unwrap();
        let (nb, _) = scene.system.nbody().unwrap().unwrap();
        let init = scene.initial.clone();
        let a = report(
            which,
            &nb,
            &init.q,
            &init.p,
            n,
            h,
            steps,
            StageSolver::Exact,
        );
        let b = report(
            which,
            &nb,
            &init.q,
            &init.p,
            n,
            h,
            steps,
            StageSolver::Kronecker,
        );
        report(which, &nb, &init.q, &init.p, n, h, steps, StageSolver::Auto);
        report(
            which,
            &nb,
            &init.q,
            &init.p,
            n,
            h,
            steps,
            StageSolver::FixedPoint,
        );
        let c = report(
            which,
            &nb,
            &init.q,
            &init.p,
            n,
            h,
            steps,
            StageSolver::NewtonKrylov,
        );
        println!(
            "diff {:e}",
            a.iter()
                .zip(&c)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        );
        println!(
            "diff {:e}",
            a.iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max)
        );
    }
}
