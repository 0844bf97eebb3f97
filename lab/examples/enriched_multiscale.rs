//! The evidence of docs/guide/enriched-bases.md beyond one fixed frequency: the enriched basis
//! with two frequencies on the Fermi–Pasta–Ulam chain whose stiff springs have ω = 50 and
//! ω = 20 (scene fpu-two-frequency), and the enriched basis with the fixed rest frequency on
//! the stiff spring pendulum (scene spring-pendulum), whose fast frequency √(ω² + 3φ̇²) depends
//! on the state. Prints every number the guide quotes from it and writes the charts to
//! docs/figures/enriched/.
//!
//! Run: `cargo run --release -p galerkin-vi-lab --example enriched_multiscale`

use galerkin_vi::GalerkinIntegrator;
use galerkin_vi::Lagrangian;
use galerkin_vi::Result;
use galerkin_vi::baselines::{GalerkinMethod, OneStepMethod, integrate_one_step};
use galerkin_vi::basis::{Basis, ChebyshevLagrange, Enriched};
use galerkin_vi::quadrature::GaussLegendre;
use galerkin_vi::systems::{Fpu, SpringPendulum};
use galerkin_vi_lab::dop853::Dop853Baseline;
use galerkin_vi_lab::plot::{Chart, Series};

type States = (Vec<Vec<f64>>, Vec<Vec<f64>>);
type Failure = Box<dyn std::error::Error>;

fn states<M: OneStepMethod>(mut m: M, q0: &[f64], p0: &[f64], horizon: f64) -> Result<States> {
    let steps = (horizon / m.step_size()).round() as usize;
    integrate_one_step(&mut m, q0, p0, steps)
}

fn enriched(
    p: usize,
    omegas: &[f64],
    h: f64,
) -> Result<GalerkinIntegrator<Enriched, GaussLegendre>> {
    let basis = Enriched::with_frequencies(p, 1, omegas, h)?;
    let points = basis.gauss_points().max(2 * basis.len());
    GalerkinIntegrator::new(basis, GaussLegendre::new(points)?, h)
}

fn chebyshev(n: usize, h: f64) -> Result<GalerkinIntegrator<ChebyshevLagrange, GaussLegendre>> {
    GalerkinIntegrator::new(ChebyshevLagrange::new(n)?, GaussLegendre::new(2 * n)?, h)
}

/// Max position error of a run with step h at the sample times t = k·every, against a
/// reference sampled every `every`; a failed run is infinitely wrong.
fn max_error(run: Result<States>, h: f64, reference: &States, every: f64) -> f64 {
    let Ok((q, _)) = run else {
        return f64::INFINITY;
    };
    let stride = (every / h).round() as usize;
    reference
        .0
        .iter()
        .enumerate()
        .filter_map(|(k, qr)| q.get(k * stride).map(|qk| (qk, qr)))
        .fold(0.0f64, |m, (a, b)| {
            a.iter().zip(b).fold(m, |m, (x, y)| m.max((x - y).abs()))
        })
}

fn galerkin<B, L>(
    gvi: Result<GalerkinIntegrator<B, GaussLegendre>>,
    sys: &L,
    q0: &[f64],
    p0: &[f64],
    t: f64,
) -> Result<States>
where
    B: Basis,
    L: Lagrangian,
{
    let gvi = gvi?;
    states(GalerkinMethod::new(&gvi, sys)?, q0, p0, t)
}

/// The spring pendulum's two methods at step h from (q0, p0), both with the same n = 7: the
/// max position errors of the enriched basis at the fixed rest frequency (p = 4) and of
/// Chebyshev, against `reference` sampled every `every` (the (a) and (b) sweeps compare them
/// alike).
fn pendulum_errors(
    sp: &SpringPendulum,
    q0: &[f64],
    p0: &[f64],
    h: f64,
    horizon: f64,
    reference: &States,
    every: f64,
) -> (f64, f64) {
    let enriched_run = galerkin(enriched(4, &[sp.omega()], h), sp, q0, p0, horizon);
    let chebyshev_run = galerkin(chebyshev(7, h), sp, q0, p0, horizon);
    (
        max_error(enriched_run, h, reference, every),
        max_error(chebyshev_run, h, reference, every),
    )
}

/// Add the point (x, error) to an error curve of a log-log chart: a failed run (infinite
/// error) has no point, and an exact zero is drawn at 1e-16 so the log axis can show it.
fn push_error(curve: &mut Vec<(f64, f64)>, x: f64, error: f64) {
    if error.is_finite() {
        curve.push((x, error.max(1e-16)));
    }
}

fn log_chart(
    title: &str,
    x: &str,
    y: &str,
    series: Vec<Series>,
    path: &str,
) -> std::result::Result<(), Failure> {
    let mut chart = Chart::new(title, x, y).log_x().log_y().size(900, 480);
    for s in series {
        chart.push(s);
    }
    chart.save_svg(path)?;
    println!("wrote {path}");
    Ok(())
}

fn main() -> std::result::Result<(), Failure> {
    std::fs::create_dir_all("docs/figures/enriched")?;
    two_frequency_fpu()?;
    spring_pendulum()?;
    Ok(())
}

/// Two stiff blocks (ω = 50, ω = 20): both frequencies, either one, polynomials; equal n = 9.
fn two_frequency_fpu() -> std::result::Result<(), Failure> {
    let fpu = Fpu::with_frequencies(&[50.0, 50.0, 20.0, 20.0])?;
    let (q0, p0) = fpu.excited_initial_state(&[2]);
    let (horizon, every) = (20.0, 0.4);
    let reference = states(Dop853Baseline::new(&fpu, every, 1e-13)?, &q0, &p0, horizon)?;
    println!(
        "two-frequency FPU (ω = 50, 20), T = {horizon}, n = 9, max position error at t = 0.4k:"
    );
    println!(
        "{:>5} {:>8} {:>12} {:>12} {:>12} {:>12}",
        "h", "20h", "ω = 50, 20", "ω = 50", "ω = 20", "Chebyshev"
    );
    let labels = [
        "enriched ω = 50, 20 (p = 4)",
        "enriched ω = 50 (p = 6)",
        "enriched ω = 20 (p = 6)",
        "Chebyshev n = 9",
    ];
    let mut curves: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 4];
    for h in [0.05, 0.1, 0.2, 0.4] {
        let run = |i: usize| match i {
            0 => galerkin(enriched(4, &[50.0, 20.0], h), &fpu, &q0, &p0, horizon),
            1 => galerkin(enriched(6, &[50.0], h), &fpu, &q0, &p0, horizon),
            2 => galerkin(enriched(6, &[20.0], h), &fpu, &q0, &p0, horizon),
            _ => galerkin(chebyshev(9, h), &fpu, &q0, &p0, horizon),
        };
        let e: Vec<f64> = (0..4)
            .map(|i| max_error(run(i), h, &reference, every))
            .collect();
        println!(
            "{h:>5} {:>8} {:>12.2e} {:>12.2e} {:>12.2e} {:>12.2e}",
            20.0 * h,
            e[0],
            e[1],
            e[2],
            e[3]
        );
        for (c, &e) in curves.iter_mut().zip(&e) {
            push_error(c, 20.0 * h, e);
        }
    }
    let series = curves
        .into_iter()
        .zip(labels)
        .map(|(c, l)| Series::line_markers(l, c))
        .collect();
    log_chart(
        "FPU with stiff springs of ω = 50 and ω = 20, T = 20, n = 9",
        "ω_min h = 20 h",
        "max position error",
        series,
        "docs/figures/enriched/two-frequency.svg",
    )
}

/// The stiff spring pendulum: error against hω at the scene's swing, and the enriched
/// advantage as the spin (and with it ω_fast) grows.
fn spring_pendulum() -> std::result::Result<(), Failure> {
    let sp = SpringPendulum::new(50.0, 1.0, 1.0)?;
    let omega = sp.omega();
    let (horizon, every) = (6.4, 0.32);
    // (a) Error against hω at spin 1 (the scene's: a swing to ±60°).
    let (q0, p0) = sp.initial_state(1.0 / omega, 1.0);
    let reference = states(Dop853Baseline::new(&sp, every, 1e-13)?, &q0, &p0, horizon)?;
    println!("spring pendulum, spin 1, T = {horizon}, n = 7, max position error at t = 0.32k:");
    println!(
        "{:>6} {:>6} {:>12} {:>12}",
        "h", "ωh", "enriched", "Chebyshev"
    );
    let (mut e_curve, mut c_curve) = (Vec::new(), Vec::new());
    for h in [0.01, 0.02, 0.04, 0.08, 0.16, 0.32] {
        let (e, c) = pendulum_errors(&sp, &q0, &p0, h, horizon, &reference, every);
        println!("{h:>6} {:>6} {e:>12.2e} {c:>12.2e}", omega * h);
        push_error(&mut e_curve, omega * h, e);
        push_error(&mut c_curve, omega * h, c);
    }
    log_chart(
        "Stiff spring pendulum (ω = 50, swing ±60°), T = 6.4, n = 7",
        "ωh",
        "max position error",
        vec![
            Series::line_markers("enriched, fixed ω = 50 (p = 4)", e_curve),
            Series::line_markers("Chebyshev n = 7", c_curve),
        ],
        "docs/figures/enriched/spring-pendulum-h.svg",
    )?;

    // (b) The spin sweeps ω_fast = √(ω² + 3φ̇²) away from the enrichment's ω.
    println!("spring pendulum, T = {horizon}, n = 7, enriched (fixed ω = 50) / Chebyshev:");
    println!(
        "{:>5} {:>16} {:>6} {:>12} {:>12} {:>10}",
        "spin", "ω_fast range", "ωh", "enriched", "Chebyshev", "ratio"
    );
    let mut ratio_curves: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 2];
    for spin in [0.5, 1.0, 2.5, 5.0, 10.0, 20.0] {
        let (q0, p0) = sp.initial_state(1.0 / omega, spin);
        let reference = states(Dop853Baseline::new(&sp, every, 1e-13)?, &q0, &p0, horizon)?;
        let (lo, hi) = reference
            .0
            .iter()
            .zip(&reference.1)
            .map(|(q, p)| sp.fast_frequency(q, p))
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
                (lo.min(w), hi.max(w))
            });
        for (curve, h) in ratio_curves.iter_mut().zip([0.04, 0.08]) {
            let (e, c) = pendulum_errors(&sp, &q0, &p0, h, horizon, &reference, every);
            println!(
                "{spin:>5} {lo:>7.2}–{hi:<8.2} {:>6} {e:>12.2e} {c:>12.2e} {:>10.2e}",
                omega * h,
                e / c
            );
            if (e / c).is_finite() {
                curve.push(((hi - omega) / omega, e / c));
            }
        }
    }
    log_chart(
        "Stiff spring pendulum: where a fixed ω stops helping (T = 6.4, n = 7)",
        "(max ω_fast − ω)/ω",
        "enriched error / Chebyshev error",
        vec![
            Series::line_markers("ωh = 2 (h = 0.04)", ratio_curves[0].clone()),
            Series::line_markers("ωh = 4 (h = 0.08)", ratio_curves[1].clone()),
        ],
        "docs/figures/enriched/spring-pendulum-spin.svg",
    )
}
