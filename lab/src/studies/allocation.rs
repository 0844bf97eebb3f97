//! The best any per-step choice of n could do: an oracle bound for tolerance-driven runs.
//!
//! A tolerance-driven run ([`galerkin_vi::adaptive`]) saves work only where the n a step needs
//! varies along the trajectory. How much it *could* save on a scene is measured here, with
//! no estimator at all: every step k of a run is solved from the same state (q_k, p_k) at
//! every n of a range, its one-step position error e_k(n) is measured against a solve at a
//! high n from that state, and the cheapest allocation n_0, n_1, … whose summed one-step
//! error does not exceed that of the cheapest fixed n meeting the tolerance is found
//! (Lagrangian relaxation: each step minimises c(n) + λ e_k(n), λ bisected). The cost c(n)
//! of a step at n is the measured mean force evaluations per step of the fixed-n run.
//!
//! The result is a lower bound on the cost of any run whose error accounting is the sum of
//! local errors (as the per-step budget tol/steps of [`galerkin_vi::adaptive`] is): it knows every
//! step's error exactly and pays nothing to learn it. Where it lies close to the fixed-n
//! cost, no error control can beat the cheapest fixed n on that scene — its checks cost more
//! than the variation of the need can return.

use crate::error::Result;
use crate::scene::BuiltScene;
use galerkin_vi::integrator::GalerkinIntegrator;
use galerkin_vi::systems::System;
use serde::Serialize;

/// One-step errors e_k(n) along a run and the per-step cost of each n.
#[derive(Debug, Clone)]
pub struct OneStepErrors {
    /// The values of n.
    pub ns: Vec<usize>,
    /// Mean force evaluations per step at each n (same order as `ns`).
    pub cost: Vec<f64>,
    /// `error[k][i]`: max-norm position error of step k solved at `ns[i]` from the state of
    /// the high-n run at step k (infinite where the solve failed).
    pub error: Vec<Vec<f64>>,
}

/// The cheapest allocation of n per step within an error budget.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Allocation {
    /// Total force evaluations (sum of the per-step costs of the chosen n).
    pub cost: f64,
    /// Sum of the one-step errors of the chosen n.
    pub error_sum: f64,
    /// Smallest and largest n chosen.
    pub n_range: (usize, usize),
}

/// Measure the one-step errors of `scene` (its basis, quadrature, h and steps) for every n in
/// `ns`, from the states of a run at `n_ref` (which also supplies the reference one-step
/// results). `cost[i]` is the per-step cost of `ns[i]`.
pub fn one_step_errors<S: System>(
    system: &S,
    scene: &BuiltScene,
    ns: &[usize],
    cost: &[f64],
    n_ref: usize,
) -> Result<OneStepErrors> {
    let (m, init) = (&scene.method, &scene.initial);
    let reference = GalerkinIntegrator::from_kinds(m.basis, n_ref, m.quadrature, None, m.h)?;
    let run = reference
        .integrate(system, init.t0, &init.q, &init.p, m.steps)
        .map_err(|f| f.error)?;
    let d = system.dim();
    let mut error = vec![vec![f64::INFINITY; ns.len()]; m.steps];
    let (mut q1, mut p1) = (vec![0.0; d], vec![0.0; d]);
    for (i, &n) in ns.iter().enumerate() {
        let gvi = GalerkinIntegrator::from_kinds(m.basis, n, m.quadrature, None, m.h)?;
        for (k, row) in error.iter_mut().enumerate() {
            // A fresh workspace per step: every solve starts from the integrator's own
            // guesses at that state, as the first step of a run would.
            let mut ws = gvi.workspace(system)?;
            if gvi
                .step(system, &mut ws, &run.q[k], &run.p[k], &mut q1, &mut p1)
                .is_ok()
            {
                row[i] = super::max_norm_diff(&q1, &run.q[k + 1]);
            }
        }
    }
    Ok(OneStepErrors {
        ns: ns.to_vec(),
        cost: cost.to_vec(),
        error,
    })
}

impl OneStepErrors {
    /// The per-step choice minimising c(n) + λ e_k(n).
    fn choose(&self, lambda: f64) -> Allocation {
        let (mut cost, mut error_sum) = (0.0, 0.0);
        let mut n_range = (usize::MAX, 0);
        for row in &self.error {
            let best = (0..self.ns.len())
                .filter(|&i| row[i].is_finite() && self.cost[i].is_finite())
                .min_by(|&a, &b| {
                    let f = |i: usize| self.cost[i] + lambda * row[i];
                    f(a).total_cmp(&f(b))
                });
            match best {
                Some(i) => {
                    cost += self.cost[i];
                    error_sum += row[i];
                    n_range = (n_range.0.min(self.ns[i]), n_range.1.max(self.ns[i]));
                }
                None => {
                    cost = f64::INFINITY;
                    error_sum = f64::INFINITY;
                }
            }
        }
        Allocation {
            cost,
            error_sum,
            n_range,
        }
    }

    /// Sum of the one-step errors of the fixed choice `n` (None if `n` was not measured).
    pub fn fixed_error_sum(&self, n: usize) -> Option<f64> {
        let i = self.ns.iter().position(|&x| x == n)?;
        Some(self.error.iter().map(|row| row[i]).sum())
    }

    /// The cheapest allocation whose summed one-step error is at most `budget` (None when
    /// even the most accurate choice at every step exceeds it). Lagrangian relaxation with λ
    /// bisected on a log scale: exact for the relaxed problem, and within one step's cost
    /// difference of the discrete optimum.
    pub fn cheapest_within(&self, budget: f64) -> Option<Allocation> {
        let (mut lo, mut hi) = (-60.0f64, 60.0f64);
        let most_accurate = self.choose(10f64.powf(hi));
        if most_accurate.error_sum.is_nan() || most_accurate.error_sum > budget {
            return None;
        }
        let cheapest = self.choose(10f64.powf(lo));
        if cheapest.error_sum <= budget {
            return Some(cheapest);
        }
        let mut best = most_accurate;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            let a = self.choose(10f64.powf(mid));
            if a.error_sum <= budget {
                best = a;
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two steps, two choices of n: the allocation spends accuracy where it is cheap.
    #[test]
    fn allocation_spends_accuracy_where_it_is_cheap() {
        let e = OneStepErrors {
            ns: vec![4, 6],
            cost: vec![1.0, 2.0],
            // Step 0 is easy (n = 4 already accurate), step 1 is hard.
            error: vec![vec![1e-9, 1e-12], vec![1e-6, 1e-9]],
        };
        assert_eq!(e.fixed_error_sum(6), Some(1e-12 + 1e-9));
        let a = e.cheapest_within(2e-9).expect("feasible");
        assert_eq!(a.n_range, (4, 6));
        assert_eq!(a.cost, 3.0);
        assert!((a.error_sum - 2e-9).abs() < 1e-20);
        // Below the most accurate choice: infeasible.
        assert!(e.cheapest_within(1e-10).is_none());
        // A generous budget: n = 4 everywhere.
        assert_eq!(e.cheapest_within(1.0).map(|a| a.cost), Some(2.0));
    }
}
