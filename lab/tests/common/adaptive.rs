//! Helpers of the tolerance-driven-n tests (`adaptive.rs`, `adaptive_embedded.rs`). Include
//! with `#[path = "common/adaptive.rs"] mod adaptive_common;`.
#![allow(dead_code)]

use galerkin_vi::prelude::*;
use galerkin_vi::systems::ExactSolution;

pub fn max_norm(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// One step from the exact state at each t0: (true one-step error, indicator).
pub fn one_step_errors<S: System>(
    sys: &S,
    exact: &ExactSolution,
    n: usize,
    h: f64,
    starts: &[f64],
) -> Vec<(f64, f64)> {
    let gvi = GalerkinIntegrator::spectral(n, h).unwrap();
    starts
        .iter()
        .map(|&t0| {
            let (q0, p0) = exact.state(t0);
            let tr = gvi.integrate(sys, t0, &q0, &p0, 1).unwrap();
            let err = max_norm(&tr.q[1], &exact.position(t0 + h));
            (err, gvi.modal_indicator(&tr.coefficients[0], q0.len()))
        })
        .collect()
}

pub fn kepler_state(e: f64) -> ([f64; 2], [f64; 2]) {
    ([1.0 - e, 0.0], [0.0, ((1.0 + e) / (1.0 - e)).sqrt()])
}
