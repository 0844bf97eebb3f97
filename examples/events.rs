//! Events on the Galerkin curve (docs/guide/events.md): event times located on each step's
//! curve against the exact ones, an event that step ends miss, and an impact map.
//!
//! Run: `cargo run --release --example events`

use galerkin_vi::events::{Event, EventOptions, integrate_with_events};
use galerkin_vi::lagrangian::Mechanical;
use galerkin_vi::prelude::*;
use std::f64::consts::PI;

/// Free fall L = v²/2 − q.
#[derive(Debug)]
struct Fall;

impl Mechanical for Fall {
    fn degrees_of_freedom(&self) -> usize {
        1
    }
    fn mass(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::identity(1, 1)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        q[0]
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let options = EventOptions::default();
    let ho = HarmonicOscillator::unit();

    // 1. Zero crossings of q = cos t over T = 100 at h = 1, n = 8, 10, 14.
    println!("1. q = cos t, crossings of q = 0 over T = 100 (h = 1)");
    println!("   n   crossings   max |t − (π/2 + kπ)|   curve evaluations / step");
    for n in [8, 10, 14] {
        let gvi = GalerkinIntegrator::spectral(n, 1.0)?;
        let mut events = [Event::new("q = 0", |_t: f64, q: &[f64], _p: &[f64]| q[0])];
        let run =
            integrate_with_events(&gvi, &ho, 0.0, &[1.0], &[0.0], 100.0, &mut events, &options)?;
        let err = run
            .crossings
            .iter()
            .enumerate()
            .map(|(k, c)| (c.t - (PI / 2.0 + k as f64 * PI)).abs())
            .fold(0.0, f64::max);
        let per_step = run.curve_evaluations as f64 / run.steps as f64;
        println!(
            "  {n:2}   {:9}   {err:20.1e}   {per_step:.2}",
            run.crossings.len()
        );
    }

    // 2. q > 0.99 only for |t − 2π| < 0.1415, inside the step [5.5, 6.5].
    println!("\n2. q = 0.99 crossed twice inside one step (h = 1, n = 14, from t = 0.5)");
    let gvi = GalerkinIntegrator::spectral(14, 1.0)?;
    for samples in [1, 2, 8] {
        let mut events = [Event::new("q = 0.99", |_t: f64, q: &[f64], _p: &[f64]| {
            q[0] - 0.99
        })];
        let opts = EventOptions {
            samples_per_step: samples,
            ..options
        };
        let (q0, p0) = ([0.5f64.cos()], [-(0.5f64.sin())]);
        let run = integrate_with_events(&gvi, &ho, 0.5, &q0, &p0, 6.5, &mut events, &opts)?;
        let times: Vec<String> = run
            .crossings
            .iter()
            .map(|c| format!("{:.15}", c.t))
            .collect();
        println!(
            "   samples per step {samples}: {} crossings {times:?}",
            run.crossings.len()
        );
    }
    let w = 0.99f64.acos();
    println!("   exact: [{:.15}, {:.15}]", 2.0 * PI - w, 2.0 * PI + w);

    // 3. Elastic impacts of a falling particle at q = 0 (p ↦ −p).
    println!("\n3. Free fall with impacts at q = 0 (n = 6, h = 0.5, T = 40)");
    let gvi = GalerkinIntegrator::spectral(6, 0.5)?;
    let mut events = [Event::new("impact", |_t: f64, q: &[f64], _p: &[f64]| q[0])
        .falling()
        .apply(|_t: f64, _q: &mut [f64], p: &mut [f64]| p[0] = -p[0])];
    let run = integrate_with_events(
        &gvi,
        &Fall,
        0.0,
        &[1.0],
        &[0.0],
        40.0,
        &mut events,
        &options,
    )?;
    let err = run
        .crossings
        .iter()
        .enumerate()
        .map(|(k, c)| (c.t - 2f64.sqrt() * (1 + 2 * k) as f64).abs())
        .fold(0.0, f64::max);
    let energy = 0.5 * run.p[0] * run.p[0] + run.q[0];
    println!(
        "   {} impacts, max |t − √2 (2k + 1)| = {err:.1e}, energy at T: {energy:.15}",
        run.crossings.len()
    );
    Ok(())
}
