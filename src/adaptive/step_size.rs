//! Choosing one fixed h for a tolerance-driven run from the tolerance and the system's time
//! scale.
//!
//! The run keeps one h throughout (a variational integrator with a varying step is no
//! longer symplectic in the usual sense), so h is chosen once, before the run, by short pilot
//! runs: for candidates h = τ/2, τ/4, … (τ = [`System::shortest_time_scale`] at the initial
//! state), a tolerance-driven run over one time scale (or the whole horizon if shorter) with
//! the per-step budget the full run would have, ESTIMATE_SAFETY · tol · h / T. The candidate
//! with the fewest force evaluations per unit time wins; the scan stops once the cost has
//! risen at two candidates in a row (it is unimodal in h: large steps need large n and many
//! Newton iterations, small steps many steps). Candidates whose pilot misses its budget
//! (warnings) or fails are skipped. The pilots cost about as much as integrating a few time
//! scales: worth it for horizons of many time scales, and reported
//! ([`StepChoice::pilot_evaluations`]).

use super::{AdaptiveOptions, integrate_adaptive};
use crate::error::{GviError, Result};
use crate::systems::System;
use serde::Serialize;

/// The candidates: τ / 2^j for j = 1 … MAX_HALVINGS.
const MAX_HALVINGS: i32 = 8;

/// One pilot run of [`choose_step`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pilot {
    /// Candidate step size.
    pub h: f64,
    /// Force evaluations per unit time of the pilot (infinite: it failed or missed its
    /// budget).
    pub cost_per_time: f64,
}

/// The h chosen by [`choose_step`], with the evidence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepChoice {
    /// The chosen step, adjusted so that a whole number of steps spans the horizon.
    pub h: f64,
    /// Steps of the full run.
    pub steps: usize,
    /// The system's shortest time scale at the initial state.
    pub time_scale: f64,
    /// Every pilot, in the order run.
    pub pilots: Vec<Pilot>,
    /// Force evaluations spent on the pilots.
    pub pilot_evaluations: usize,
}

/// Choose h for a tolerance-driven run of `system` over `horizon` from (q0, p0) at t0 with
/// the tolerance, basis, ladder and control of `opts` (its `h` is ignored). See the module
/// docs.
///
/// Errors: a non-positive or non-finite horizon, a system without a time scale, or no
/// candidate whose pilot met its budget.
///
/// ```
/// use galerkin_vi::adaptive::{AdaptiveOptions, choose_step};
/// use galerkin_vi::prelude::*;
///
/// let kepler = Kepler::new(1.0)?;
/// let (q0, p0) = Kepler::paper_initial_state();
/// let opts = AdaptiveOptions::new(1e-8, BasisKind::Legendre, QuadratureKind::GaussLegendre, 1.0);
/// let choice = choose_step(&kepler, &opts, 0.0, &q0, &p0, 100.0)?;
/// assert!(choice.h > 0.0 && (choice.h * choice.steps as f64 - 100.0).abs() < 1e-9);
/// # Ok::<(), GviError>(())
/// ```
pub fn choose_step<S: System>(
    system: &S,
    opts: &AdaptiveOptions,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    horizon: f64,
) -> Result<StepChoice> {
    if !(horizon.is_finite() && horizon > 0.0) {
        return Err(GviError::InvalidInput {
            name: "horizon".into(),
            reason: format!("{horizon} must be finite and positive"),
        });
    }
    let tau = system
        .shortest_time_scale(q0, p0)
        .filter(|t| t.is_finite() && *t > 0.0)
        .ok_or_else(|| {
            GviError::Unsupported(format!(
                "choosing h needs a time scale, which the {} system does not provide",
                system.name()
            ))
        })?;
    let window = horizon.min(tau);
    let mut pilots = Vec::new();
    let mut pilot_evaluations = 0;
    let mut best: Option<Pilot> = None;
    let mut rises = 0;
    for j in 1..=MAX_HALVINGS {
        let h = tau / 2f64.powi(j);
        if h > horizon {
            continue;
        }
        let steps = (window / h).ceil().max(1.0) as usize;
        // Same per-step budget as the full run: ESTIMATE_SAFETY · tol · h / horizon.
        let mut o = opts.clone();
        o.h = h;
        o.tol = opts.tol * steps as f64 * h / horizon;
        let cost_per_time = match integrate_adaptive(system, &o, t0, q0, p0, steps) {
            Ok(run) => {
                pilot_evaluations += run.gradient_evaluations;
                if run.warnings.is_empty() {
                    run.gradient_evaluations as f64 / (steps as f64 * h)
                } else {
                    f64::INFINITY
                }
            }
            Err(_) => f64::INFINITY,
        };
        let pilot = Pilot { h, cost_per_time };
        pilots.push(pilot);
        match best {
            Some(b) if cost_per_time >= b.cost_per_time => {
                rises += 1;
                if rises >= 2 {
                    break;
                }
            }
            _ if cost_per_time.is_finite() => {
                best = Some(pilot);
                rises = 0;
            }
            _ => {}
        }
    }
    let best = best.ok_or_else(|| GviError::InvalidInput {
        name: "tol".into(),
        reason: format!(
            "no step size from τ/2 to τ/{} (τ = {tau:e}) met the per-step budget in its \
             pilot run",
            1 << MAX_HALVINGS
        ),
    })?;
    let steps = (horizon / best.h).round().max(1.0) as usize;
    Ok(StepChoice {
        h: horizon / steps as f64,
        steps,
        time_scale: tau,
        pilots,
        pilot_evaluations,
    })
}
