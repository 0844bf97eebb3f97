//! Solutions: states at the step ends plus every step's Galerkin curve (dense output,
//! [`Trajectory::curve`] as a [`GalerkinCurveRef`]).

use crate::basis::{AnyBasis, BasisKind};
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use crate::quadrature::QuadratureKind;
use crate::stats::StepStats;
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// The result of [`GalerkinIntegrator::integrate`](crate::GalerkinIntegrator::integrate):
/// (q_k, p_k) at t_k = t0 + k h, and each step's Galerkin coefficients, so that q(t), q̇(t)
/// and p(t) = ∂L/∂v(q(t), q̇(t)) can be read at any time in [t0, t_end].
///
/// Serialises with serde; the basis used for dense output is rebuilt from its kind and n.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Trajectory {
    /// Basis of the Galerkin curves.
    pub basis: BasisKind,
    /// Number of basis functions.
    pub n: usize,
    /// Quadrature family.
    pub quadrature: QuadratureKind,
    /// Quadrature points.
    pub quad_points: usize,
    /// Step size.
    pub h: f64,
    /// Initial time.
    pub t0: f64,
    /// Configuration dimension D.
    pub dim: usize,
    /// Positions q_k (steps + 1 of them).
    pub q: Vec<Vec<f64>>,
    /// Momenta p_k.
    pub p: Vec<Vec<f64>>,
    /// Galerkin coefficients of each step, n×D row-major (row i = Q_i); read a step's curve
    /// with its n, h and start time as a [`GalerkinCurveRef`] by [`Trajectory::curve`].
    pub coefficients: Vec<Vec<f64>>,
    /// Cost of each step.
    pub stats: Vec<StepStats>,
    /// Number of basis functions of each step when it varies (tolerance-driven runs);
    /// empty when every step uses `n`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub step_n: Vec<usize>,
    #[serde(skip)]
    basis_cache: OnceLock<Option<AnyBasis>>,
}

impl Trajectory {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        basis: BasisKind,
        n: usize,
        quadrature: QuadratureKind,
        quad_points: usize,
        h: f64,
        t0: f64,
        dim: usize,
        capacity: usize,
    ) -> Self {
        let cap = capacity.min(1 << 20);
        Trajectory {
            basis,
            n,
            quadrature,
            quad_points,
            h,
            t0,
            dim,
            q: Vec::with_capacity(cap + 1),
            p: Vec::with_capacity(cap + 1),
            coefficients: Vec::with_capacity(cap),
            stats: Vec::with_capacity(cap),
            step_n: Vec::new(),
            basis_cache: OnceLock::new(),
        }
    }

    pub(crate) fn push_state(&mut self, q: &[f64], p: &[f64]) {
        self.q.push(q.to_vec());
        self.p.push(p.to_vec());
    }

    /// Append a step whose curve's n may differ from the trajectory's (tolerance-driven runs:
    /// every step's n is then recorded).
    pub(crate) fn push_step_with_n(
        &mut self,
        curve: GalerkinCurveRef<'_>,
        q: &[f64],
        p: &[f64],
        stats: StepStats,
    ) {
        if self.step_n.capacity() == 0 {
            self.step_n.reserve(self.coefficients.capacity());
        }
        while self.step_n.len() < self.coefficients.len() {
            self.step_n.push(self.n);
        }
        self.step_n.push(curve.n());
        self.push_step(curve, q, p, stats);
    }

    /// Append a step: its curve, the state at its end and its cost.
    pub(crate) fn push_step(
        &mut self,
        curve: GalerkinCurveRef<'_>,
        q: &[f64],
        p: &[f64],
        stats: StepStats,
    ) {
        debug_assert_eq!(curve.dim(), self.dim);
        self.coefficients.push(curve.coefficients().to_vec());
        self.stats.push(stats);
        self.push_state(q, p);
    }

    /// Number of completed steps.
    pub fn steps(&self) -> usize {
        self.coefficients.len()
    }

    /// Time of step end k.
    pub fn time(&self, k: usize) -> f64 {
        self.t0 + k as f64 * self.h
    }

    /// All step-end times.
    pub fn times(&self) -> Vec<f64> {
        (0..self.q.len()).map(|k| self.time(k)).collect()
    }

    /// Final time.
    pub fn end_time(&self) -> f64 {
        self.time(self.steps())
    }

    /// Total Newton iterations over all steps.
    pub fn newton_iterations(&self) -> usize {
        self.stats.iter().map(|s| s.iterations).sum()
    }

    /// Total first-derivative (force) evaluations over all steps.
    pub fn gradient_evaluations(&self) -> usize {
        self.stats.iter().map(|s| s.gradient_evaluations).sum()
    }

    fn basis(&self) -> Result<&AnyBasis> {
        self.basis_cache
            .get_or_init(|| self.basis.build(self.n).ok())
            .as_ref()
            .ok_or_else(|| GviError::InvalidBasisSize {
                n: self.n,
                basis: self.basis.to_string(),
                reason: "cannot rebuild the basis of this trajectory".into(),
            })
    }

    /// Locate t: (step index, τ ∈ [0, 1]).
    fn locate(&self, t: f64) -> Result<(usize, f64)> {
        let steps = self.steps();
        let end = self.end_time();
        let tol = 1e-12 * self.h.max(end.abs());
        if steps == 0 || !t.is_finite() || t < self.t0 - tol || t > end + tol {
            return Err(GviError::InvalidInput {
                name: "t".into(),
                reason: format!(
                    "{t} is outside the trajectory's time span [{}, {end}]",
                    self.t0
                ),
            });
        }
        let x = (t - self.t0) / self.h;
        let k = (x.floor().max(0.0) as usize).min(steps - 1);
        let tau = (x - k as f64).clamp(0.0, 1.0);
        Ok((k, tau))
    }

    /// Number of basis functions of step k.
    pub fn n_of_step(&self, k: usize) -> usize {
        self.step_n.get(k).copied().unwrap_or(self.n)
    }

    /// The Galerkin curve of step k (from t_k to t_{k+1}).
    ///
    /// Errors: k is not a completed step.
    pub fn curve(&self, k: usize) -> Result<GalerkinCurveRef<'_>> {
        let c = self
            .coefficients
            .get(k)
            .ok_or_else(|| GviError::InvalidInput {
                name: "step".into(),
                reason: format!("{k} is not a completed step (0 ≤ k < {})", self.steps()),
            })?;
        Ok(GalerkinCurveRef::from_parts(
            c,
            self.n_of_step(k),
            self.dim,
            self.h,
            self.time(k),
        ))
    }

    /// Galerkin curve position q(t) and velocity q̇(t) at any t in [t0, t_end].
    pub fn state_on_curve(&self, t: f64) -> Result<(Vec<f64>, Vec<f64>)> {
        let (k, tau) = self.locate(t)?;
        let curve = self.curve(k)?;
        let (n, d) = (curve.n(), self.dim);
        let (mut phi, mut dphi) = (vec![0.0; n], vec![0.0; n]);
        let (mut q, mut v) = (vec![0.0; d], vec![0.0; d]);
        if n == self.n {
            curve.state_into(self.basis()?, tau, &mut phi, &mut dphi, &mut q, &mut v);
        } else {
            let basis = self.basis.build(n)?;
            curve.state_into(&basis, tau, &mut phi, &mut dphi, &mut q, &mut v);
        }
        Ok((q, v))
    }

    /// Position q(t) on the Galerkin curves.
    pub fn position_at(&self, t: f64) -> Result<Vec<f64>> {
        Ok(self.state_on_curve(t)?.0)
    }

    /// Velocity q̇(t) on the Galerkin curves.
    pub fn velocity_at(&self, t: f64) -> Result<Vec<f64>> {
        Ok(self.state_on_curve(t)?.1)
    }

    /// Momentum along the Galerkin curves, p(t) = ∂L/∂v(q(t), q̇(t)) (the continuous Legendre
    /// transform of the curve; at step ends it differs from p_k by the method's error).
    pub fn momentum_at<L: Lagrangian>(&self, lagrangian: &L, t: f64) -> Result<Vec<f64>> {
        crate::error::ensure_len("Lagrangian dimension", self.dim, lagrangian.dim())?;
        let (q, v) = self.state_on_curve(t)?;
        let mut p = vec![0.0; self.dim];
        lagrangian.legendre_transform(&q, &v, &mut p);
        Ok(p)
    }

    /// Sample times: `per_step` equally spaced points inside every step plus the final time,
    /// for measuring errors along the curves (max over t).
    pub fn sample_times(&self, per_step: usize) -> Vec<f64> {
        let per = per_step.max(1);
        let mut ts = Vec::with_capacity(self.steps() * per + 1);
        for k in 0..self.steps() {
            for s in 0..per {
                ts.push(self.time(k) + self.h * s as f64 / per as f64);
            }
        }
        ts.push(self.end_time());
        ts
    }
}
