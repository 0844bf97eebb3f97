//! The evidence of docs/guide/enriched-bases.md: the Fermi–Pasta–Ulam problem (Hairer, Lubich
//! & Wanner, GNI §I.5.1; m = 3, ω = 50) with the enriched basis, polynomial Galerkin,
//! Störmer–Verlet, Gauss collocation and DOP853, and a scene with a position-dependent fast
//! frequency. Prints every number the guide quotes and writes the charts to
//! docs/figures/enriched/.
//!
//! Run: `cargo run --release -p galerkin-vi-lab --example enriched_fpu`

use galerkin_vi::GalerkinIntegrator;
use galerkin_vi::Result;
use galerkin_vi::baselines::{
    GalerkinMethod, GaussCollocationBaseline, OneStepMethod, StormerVerlet, integrate_one_step,
};
use galerkin_vi::basis::{Basis, ChebyshevLagrange, Enriched};
use galerkin_vi::quadrature::GaussLegendre;
use galerkin_vi::systems::{Fpu, System};
use galerkin_vi_lab::dop853::Dop853Baseline;
use galerkin_vi_lab::plot::{Chart, Series, thin};
use std::time::Instant;

type States = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// One run: the states at every step end, its cost.
struct Run {
    label: String,
    h: f64,
    states: States,
    forces: usize,
    seconds: f64,
}

fn run<M: OneStepMethod>(
    label: &str,
    mut m: M,
    q0: &[f64],
    p0: &[f64],
    horizon: f64,
) -> Result<Run> {
    let h = m.step_size();
    let steps = (horizon / h).round() as usize;
    let clock = Instant::now();
    let states = integrate_one_step(&mut m, q0, p0, steps)?;
    Ok(Run {
        label: label.to_string(),
        h,
        states,
        forces: m.force_evaluations(),
        seconds: clock.elapsed().as_secs_f64(),
    })
}

fn enriched(p: usize, omega: f64, h: f64) -> Result<GalerkinIntegrator<Enriched, GaussLegendre>> {
    let basis = Enriched::new(p, omega, h)?;
    let points = basis.gauss_points().max(2 * basis.len());
    GalerkinIntegrator::new(basis, GaussLegendre::new(points)?, h)
}

fn chebyshev(n: usize, h: f64) -> Result<GalerkinIntegrator<ChebyshevLagrange, GaussLegendre>> {
    GalerkinIntegrator::new(ChebyshevLagrange::new(n)?, GaussLegendre::new(2 * n)?, h)
}

/// The state of `r` at time t (a multiple of its h).
fn at(r: &Run, t: f64) -> (&[f64], &[f64]) {
    let k = (t / r.h).round() as usize;
    (&r.states.0[k], &r.states.1[k])
}

/// Max over the sample times of the slow-variable error (‖x₀ − x₀,ref‖∞) and of |I − I_ref|.
fn errors(fpu: &Fpu, r: &Run, reference: &Run, times: &[f64]) -> (f64, f64) {
    let m = fpu.springs();
    let mut inv = vec![0.0; fpu.invariant_names().len()];
    let mut inv_ref = inv.clone();
    let (mut slow, mut osc) = (0.0f64, 0.0f64);
    for &t in times {
        let (q, p) = at(r, t);
        let (qr, pr) = at(reference, t);
        fpu.invariants(q, p, &mut inv);
        fpu.invariants(qr, pr, &mut inv_ref);
        let e = q[..m]
            .iter()
            .zip(&qr[..m])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        slow = if e.is_finite() {
            slow.max(e)
        } else {
            f64::INFINITY
        };
        let ei = (inv[1] - inv_ref[1]).abs();
        osc = if ei.is_finite() {
            osc.max(ei)
        } else {
            f64::INFINITY
        };
    }
    (slow, osc)
}

/// I₁, I₂, I₃ and I of a run against t, as an SVG chart.
fn energy_chart(
    fpu: &Fpu,
    r: &Run,
    title: &str,
    path: &str,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let mut inv = vec![0.0; fpu.invariant_names().len()];
    let mut series: Vec<Vec<(f64, f64)>> = vec![Vec::new(); 4];
    for (k, (q, p)) in r.states.0.iter().zip(&r.states.1).enumerate() {
        fpu.invariants(q, p, &mut inv);
        let t = k as f64 * r.h;
        series[0].push((t, inv[1]));
        for j in 0..3 {
            series[j + 1].push((t, inv[2 + j]));
        }
    }
    let labels = ["I", "I1", "I2", "I3"];
    let mut chart = Chart::new(title, "time t", "oscillatory energy").size(900, 420);
    for (s, label) in series.iter().zip(labels) {
        chart.push(Series::line(label, thin(s, 4000)));
    }
    chart.save_svg(path)?;
    println!("wrote {path}");
    Ok(())
}

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let fpu = Fpu::hlw();
    let (q0, p0) = fpu.hlw_initial_state();
    let omega = fpu.omega();

    // 1. Energy exchange over T = 200 at h = 0.025 (ωh = 1.25 ≥ 1: Störmer–Verlet is stable
    //    for ωh < 2), against DOP853 at 1e-13.
    let horizon = 200.0;
    let h = 0.025;
    let reference = run(
        "DOP853 1e-13",
        Dop853Baseline::new(&fpu, h, 1e-13)?,
        &q0,
        &p0,
        horizon,
    )?;
    let check = {
        let gvi = chebyshev(16, 0.005)?;
        run(
            "Chebyshev n = 16, h = 0.005",
            GalerkinMethod::new(&gvi, &fpu)?,
            &q0,
            &p0,
            horizon,
        )?
    };
    let e_gvi = enriched(4, omega, h)?;
    let c_gvi = chebyshev(7, h)?;
    let runs = vec![
        run(
            "enriched p = 4 (n = 7)",
            GalerkinMethod::new(&e_gvi, &fpu)?,
            &q0,
            &p0,
            horizon,
        )?,
        run(
            "Chebyshev n = 7",
            GalerkinMethod::new(&c_gvi, &fpu)?,
            &q0,
            &p0,
            horizon,
        )?,
        run(
            "Störmer–Verlet",
            StormerVerlet::new(&fpu, h)?,
            &q0,
            &p0,
            horizon,
        )?,
    ];
    let grid: Vec<f64> = (0..=1000).map(|k| 0.2 * k as f64).collect();
    let short: Vec<f64> = (0..=50).map(|k| 0.2 * k as f64).collect();
    let (s, i) = errors(&fpu, &check, &reference, &grid);
    println!(
        "reference check (Chebyshev 16, h = 0.005 vs DOP853 1e-13), T = 200: slow {s:.1e}, I {i:.1e}"
    );
    println!("T = 200, h = {h} (ωh = {}):", omega * h);
    println!(
        "{:<26} {:>12} {:>12} {:>12} {:>12} {:>10}",
        "method", "slow T≤10", "slow T≤200", "|ΔI| vs ref", "max|I−I(0)|", "forces"
    );
    let mut inv = vec![0.0; 5];
    for r in &runs {
        let (s10, _) = errors(&fpu, r, &reference, &short);
        let (s200, i200) = errors(&fpu, r, &reference, &grid);
        let drift = r
            .states
            .0
            .iter()
            .zip(&r.states.1)
            .fold(0.0f64, |m, (q, p)| {
                fpu.invariants(q, p, &mut inv);
                m.max((inv[1] - 1.0).abs())
            });
        println!(
            "{:<26} {s10:>12.2e} {s200:>12.2e} {i200:>12.2e} {drift:>12.2e} {:>10}",
            r.label, r.forces
        );
    }
    println!("reference I, I1, I2, I3 at t = 0, 25, …, 200:");
    for k in 0..=8 {
        let t = 25.0 * k as f64;
        let (q, p) = at(&reference, t);
        fpu.invariants(q, p, &mut inv);
        println!(
            "  t = {t:>5}: I = {:.4}, I1 = {:.4}, I2 = {:.4}, I3 = {:.4}",
            inv[1], inv[2], inv[3], inv[4]
        );
    }
    std::fs::create_dir_all("docs/figures/enriched")?;
    energy_chart(
        &fpu,
        &reference,
        "FPU, DOP853 (tol 1e-13): I1, I2, I3 and I",
        "docs/figures/enriched/fpu-reference.svg",
    )?;
    let names = ["enriched", "polynomial", "verlet"];
    for (r, name) in runs.iter().zip(names) {
        let title = format!("FPU, {} at h = {h} (ωh = 1.25): I1, I2, I3 and I", r.label);
        energy_chart(
            &fpu,
            r,
            &title,
            &format!("docs/figures/enriched/fpu-{name}.svg"),
        )?;
    }

    // 2. Work–precision over T = 20, errors at t = 0.4 k against the same reference.
    let horizon = 20.0;
    let times: Vec<f64> = (0..=50).map(|k| 0.4 * k as f64).collect();
    let reference = run(
        "DOP853 1e-13",
        Dop853Baseline::new(&fpu, 0.4, 1e-13)?,
        &q0,
        &p0,
        horizon,
    )?;
    let mut points: Vec<(String, f64, f64, usize, f64)> = Vec::new();
    let mut record = |family: &str, r: Run| {
        let (s, i) = errors(&fpu, &r, &reference, &times);
        println!(
            "{family:<22} {:<28} {s:>10.2e} {i:>10.2e} {:>10} {:>8.3}",
            r.label, r.forces, r.seconds
        );
        points.push((family.to_string(), s, i, r.forces, r.seconds));
    };
    println!("work–precision, T = 20:");
    println!(
        "{:<22} {:<28} {:>10} {:>10} {:>10} {:>8}",
        "family", "run", "slow err", "I err", "forces", "seconds"
    );
    for p in [4usize, 6, 8] {
        for h in [0.4, 0.2, 0.1, 0.05] {
            let gvi = enriched(p, omega, h)?;
            let label = format!("p = {p}, h = {h} (ωh = {})", omega * h);
            match run(&label, GalerkinMethod::new(&gvi, &fpu)?, &q0, &p0, horizon) {
                Ok(r) => record(&format!("enriched p = {p}"), r),
                Err(e) => println!("enriched {label}: {e}"),
            }
        }
    }
    for n in [7usize, 9, 11] {
        for h in [0.2, 0.1, 0.05, 0.025, 0.0125] {
            let gvi = chebyshev(n, h)?;
            let label = format!("n = {n}, h = {h}");
            match run(&label, GalerkinMethod::new(&gvi, &fpu)?, &q0, &p0, horizon) {
                Ok(r) => record(&format!("Chebyshev n = {n}"), r),
                Err(e) => println!("Chebyshev {label}: {e}"),
            }
        }
    }
    for h in [0.025, 0.0125, 0.00625, 0.003125, 0.0015625] {
        record(
            "Störmer–Verlet",
            run(
                &format!("h = {h}"),
                StormerVerlet::new(&fpu, h)?,
                &q0,
                &p0,
                horizon,
            )?,
        );
    }
    for h in [0.05, 0.025, 0.0125, 0.00625] {
        record(
            "Gauss s = 3",
            run(
                &format!("h = {h}"),
                GaussCollocationBaseline::new(&fpu, 3, h)?,
                &q0,
                &p0,
                horizon,
            )?,
        );
    }
    for tol in [1e-5, 1e-7, 1e-9, 1e-11] {
        record(
            "DOP853",
            run(
                &format!("tol = {tol:e}"),
                Dop853Baseline::new(&fpu, 0.4, tol)?,
                &q0,
                &p0,
                horizon,
            )?,
        );
    }
    for (measure, title, file) in [
        (
            1usize,
            "FPU work-precision, T = 20: slow variables",
            "wp-slow",
        ),
        (
            2,
            "FPU work-precision, T = 20: oscillatory energy I",
            "wp-oscillatory",
        ),
    ] {
        let mut chart = Chart::new(title, "force evaluations", "max error")
            .log_x()
            .log_y()
            .size(900, 560);
        let mut families: Vec<String> = points.iter().map(|p| p.0.clone()).collect();
        families.dedup();
        for f in &families {
            let pts: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| &p.0 == f)
                .map(|p| (p.3 as f64, if measure == 1 { p.1 } else { p.2 }))
                .collect();
            chart.push(Series::line_markers(f.as_str(), pts));
        }
        let path = format!("docs/figures/enriched/{file}.svg");
        chart.save_svg(&path)?;
        println!("wrote {path}");
    }

    // 2b. What more Gauss points buy: the quartic springs put up to 4ωh into the integrand,
    //     beyond the products `gauss_points` resolves.
    println!("quadrature, enriched p = 4, T = 20 (slow-variable error):");
    for h in [0.2, 0.4] {
        let basis = Enriched::new(4, omega, h)?;
        let base = basis.gauss_points();
        for m in [base, base + base / 2, 2 * base, 3 * base] {
            let gvi = GalerkinIntegrator::new(basis.clone(), GaussLegendre::new(m)?, h)?;
            let r = run("", GalerkinMethod::new(&gvi, &fpu)?, &q0, &p0, horizon)?;
            let (s, i) = errors(&fpu, &r, &reference, &times);
            println!(
                "  ωh = {:>4}: {m:>3} points{} slow {s:.2e}, I {i:.2e}, {} forces",
                omega * h,
                if m == base { " (gauss_points)" } else { "" },
                r.forces
            );
        }
    }

    // 3. A position-dependent fast frequency: ω(y) = ω √(1 + y²) (scene varying-frequency).
    varying_frequency()?;
    Ok(())
}

/// L = ẋ²/2 + ẏ²/2 − ω²(1 + y²)x²/2 − y²/2: enriched with the fixed ω against Chebyshev at
/// the same n and h, for slow amplitudes y₀ that sweep the fast frequency over a growing range.
fn varying_frequency() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let scene = galerkin_vi_lab::scene::Scene::load("varying-frequency")?.build()?;
    let galerkin_vi_lab::scene::BuiltSystem::Euclidean(system) = &scene.system else {
        return Err("varying-frequency is not a Euclidean system".into());
    };
    let omega = 50.0;
    let horizon = 10.0;
    let times: Vec<f64> = (0..=25).map(|k| 0.4 * k as f64).collect();
    println!(
        "varying frequency, T = {horizon}, h = 0.04 (ωh = 2 at y = 0), n = 7, max error over t = 0.4 k:"
    );
    println!(
        "{:>5} {:>14} {:>12} {:>12} {:>12}",
        "y0", "ω(y) range", "enriched", "Chebyshev", "ratio"
    );
    for y0 in [0.1, 0.25, 0.5, 1.0, 2.0] {
        let q0 = [0.0, y0];
        let p0 = [1.0, 0.0];
        let reference = run(
            "DOP853",
            Dop853Baseline::new(system, 0.4, 1e-13)?,
            &q0,
            &p0,
            horizon,
        )?;
        let err = |r: &Run| {
            times
                .iter()
                .map(|&t| {
                    let (q, _) = at(r, t);
                    let (qr, _) = at(&reference, t);
                    q.iter()
                        .zip(qr)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max)
                })
                .fold(0.0, f64::max)
        };
        let h = 0.04;
        let e_gvi = enriched(4, omega, h)?;
        let c_gvi = chebyshev(7, h)?;
        let e = run(
            "enriched",
            GalerkinMethod::new(&e_gvi, system)?,
            &q0,
            &p0,
            horizon,
        )
        .map(|r| err(&r));
        let c = run(
            "chebyshev",
            GalerkinMethod::new(&c_gvi, system)?,
            &q0,
            &p0,
            horizon,
        )
        .map(|r| err(&r));
        let (e, c) = (e.unwrap_or(f64::NAN), c.unwrap_or(f64::NAN));
        println!(
            "{y0:>5} {:>6.1}–{:<6.1} {e:>12.2e} {c:>12.2e} {:>12.2e}",
            omega,
            omega * (1.0 + y0 * y0).sqrt(),
            e / c
        );
    }
    Ok(())
}
