//! Measures the Kepler-adapted Galerkin integrator (Gauss collocation in the interaction
//! picture of the Jacobi splitting) on the N-body scenes of issue 35: for each stage count and
//! steps per sample interval, the median wall time of REPEATS runs through the studies' own
//! sampled runner, the work–precision study's error (the largest position error at the sample
//! times against the study's reference) and the fixed-point iterations per step.
//!
//! With `PER_BODY=1` in the environment it also prints each body's largest position error;
//! `PERTURB=f` scales the initial momenta by 1 + f (the scene's sensitivity to round-off);
//! `KEPLER_BODIES=1` adapts the integrator to the listed bodies' Kepler motion only
//! (`KeplerAdaptedGalerkin::with_kepler_bodies`; on J2000 body 1 is Mercury), the others'
//! curves polynomials; `INNER=k` runs `InnerKeplerGalerkin` with the innermost k planets on
//! their Kepler orbits (the same map as `KEPLER_BODIES=1,…,k`, solved slot by slot with the
//! converged slots frozen) and prints its iterations per step.
//!
//! `eccentric` is its favourable case, built here: a unit star, a planet of 1e-5 at a = 1,
//! e = 0.7 and a companion of 1e-3 on a circular orbit at a = 6, over 20 of the planet's
//! orbits, against the Chebyshev–Lagrange Galerkin integrator (n Gauss points), errors at the
//! end against 8-stage Gauss collocation with 40 000 steps.
//!
//! ```text
//! cargo run --release -p galerkin-vi-lab --example kepler_adapted -- j2000 4,6,8 1,2,4 5
//! cargo run --release -p galerkin-vi-lab --example kepler_adapted -- eccentric 4,6,8 50,100,200,400 5
//! ```
use galerkin_vi::kepler_adapted::{InnerKeplerGalerkin, KeplerAdaptedGalerkin};
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::peers::{KeplerBodies, Peer, nbody_of, run_peer, sampled};
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
    let stages = list(args.get(2), "4,6,8")?;
    let divisors = list(args.get(3), "1,2,4")?;
    let repeats: usize = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(5);
    let scene = match args.get(1).map_or("j2000", String::as_str) {
        "outer" => "outer-solar-system",
        "j2000" => "solar-system",
        "eccentric" => return eccentric(&stages, &divisors, repeats),
        other => return Err(format!("unknown scene {other} (outer, j2000, eccentric)").into()),
    };
    let scene = Scene::load(scene)?.build()?;
    let reference = reference_csv(&scene, &WorkPrecisionConfig::full())?;
    let dt = scene.method.h;
    let samples = reference.q.len() - 1;
    let system = scene.euclidean()?;
    // PERTURB=f scales the initial momenta by 1 + f: the scene's sensitivity to round-off.
    let mut initial = scene.initial.clone();
    if let Ok(f) = std::env::var("PERTURB") {
        let f: f64 = f.parse()?;
        initial.p.iter_mut().for_each(|x| *x *= 1.0 + f);
    }
    let kepler_bodies: Option<Vec<usize>> = match std::env::var("KEPLER_BODIES") {
        Ok(v) => Some(
            v.split(',')
                .filter(|x| !x.is_empty())
                .map(str::parse)
                .collect::<Result<_, _>>()?,
        ),
        Err(_) => None,
    };
    // INNER=k: the innermost k planets Kepler-adapted, solved slot by slot with freezing
    // (`InnerKeplerGalerkin`).
    let inner: Option<usize> = std::env::var("INNER").ok().map(|v| v.parse()).transpose()?;
    for &s in &stages {
        for &m in &divisors {
            let mut times = Vec::new();
            let mut last = None;
            let mut extra = String::new();
            for _ in 0..repeats.max(1) {
                let start = Instant::now();
                let run = match (&kepler_bodies, inner) {
                    (_, Some(k)) => {
                        let nbody = nbody_of(system).ok_or("not an N-body scene")?;
                        let h = dt / m as f64;
                        let mut method = InnerKeplerGalerkin::new(nbody, s, h, k)?;
                        let run = sampled(&mut method, &initial, m, samples);
                        let steps = (samples * m) as f64;
                        extra = format!(
                            ", {:.2} iterations per step ({:.2} of them partial)",
                            method.iterations() as f64 / steps,
                            method.partial_force_evaluations() as f64 / (steps * s as f64)
                        );
                        run
                    }
                    (Some(bodies), None) => {
                        let nbody = nbody_of(system).ok_or("not an N-body scene")?;
                        let h = dt / m as f64;
                        let mut method =
                            KeplerAdaptedGalerkin::with_kepler_bodies(nbody, s, h, bodies)?;
                        sampled(&mut method, &initial, m, samples)
                    }
                    (None, None) => run_peer(
                        system,
                        &initial,
                        Peer::KeplerAdapted {
                            s,
                            bodies: KeplerBodies::All,
                        },
                        dt,
                        m,
                        samples,
                    )?,
                };
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
                 {:.2} iterations per step{extra}",
                dt / m as f64,
                times[times.len() / 2] * 1e3,
                times[0] * 1e3,
                run.force_evaluations as f64 / (steps * s as f64),
            );
        }
    }
    Ok(())
}

/// The median of `repeats` timed runs of `f` and its last result.
fn timed<T>(
    repeats: usize,
    mut f: impl FnMut() -> Result<T, galerkin_vi::GviError>,
) -> Result<(f64, T), galerkin_vi::GviError> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        last = Some(f()?);
        times.push(start.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let last = last.ok_or(galerkin_vi::GviError::Unsupported("no run".into()))?;
    Ok((times[times.len() / 2], last))
}

/// The eccentric planet with a distant companion (see the file's documentation).
fn eccentric(
    stages: &[usize],
    step_counts: &[usize],
    repeats: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    use galerkin_vi::baselines::{GalerkinMethod, GaussCollocationBaseline, integrate_one_step};
    use galerkin_vi::basis::BasisKind;
    use galerkin_vi::kepler_adapted::KeplerAdaptedGalerkin;
    use galerkin_vi::quadrature::QuadratureKind;
    use galerkin_vi::systems::NBody;
    let nb = NBody::new(vec![1.0, 1e-5, 1e-3], 1.0, 3)?;
    let (apo, v_apo, v_circ) = (1.7, (2.0f64 / 1.7 - 1.0).sqrt(), (1.0f64 / 6.0).sqrt());
    let mut q = vec![0.0, 0.0, 0.0, apo, 0.0, 0.0, 0.0, 6.0, 0.1];
    let mut v = vec![0.0, 0.0, 0.0, 0.0, v_apo, 0.01, -v_circ, 0.0, 0.0];
    nb.to_barycentric(&mut q, &mut v)?;
    let p = nb.momenta(&v);
    let t = 20.0 * std::f64::consts::TAU;
    let mut reference = GaussCollocationBaseline::new(&nb, 8, t / 40_000.0)?;
    let exact = integrate_one_step(&mut reference, &q, &p, 40_000)?.0[40_000].clone();
    let error = |q1: &[f64]| {
        q1.iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    for &s in stages {
        for &steps in step_counts {
            let (time, q1) = timed(repeats, || {
                let mut m = KeplerAdaptedGalerkin::new(&nb, s, t / steps as f64)?;
                Ok(integrate_one_step(&mut m, &q, &p, steps)?.0[steps].clone())
            })?;
            println!(
                "kepler-adapted s = {s:2}, {steps:5} steps: {:8.3} ms, error {:.2e}",
                time * 1e3,
                error(&q1)
            );
        }
    }
    for n in [12, 16] {
        for steps in [400, 800, 1600] {
            let (time, q1) = timed(repeats, || {
                let gvi = galerkin_vi::GalerkinIntegrator::from_kinds(
                    BasisKind::Chebyshev,
                    n,
                    QuadratureKind::default(),
                    Some(n),
                    t / steps as f64,
                )?;
                let mut m = GalerkinMethod::new(&gvi, &nb)?;
                Ok(integrate_one_step(&mut m, &q, &p, steps)?.0[steps].clone())
            })?;
            println!(
                "galerkin chebyshev n = {n:2}, {steps:5} steps: {:8.3} ms, error {:.2e}",
                time * 1e3,
                error(&q1)
            );
        }
    }
    Ok(())
}
