//! Solutions: states at the step ends plus every step's Galerkin curve (dense output,
//! [`Trajectory::curve`] as a [`GalerkinCurveRef`]).

use crate::basis::{Basis, BasisKind};
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use crate::stats::StepStats;
use serde::{Deserialize, Serialize};
use std::sync::{Arc, OnceLock};

/// A basis shared by a trajectory and the integrator that made it.
pub type SharedBasis = Arc<dyn Basis>;

/// The bases a trajectory evaluates its curves with, one per distinct n.
type BasisTable = Vec<(usize, SharedBasis)>;

/// The result of [`GalerkinIntegrator::integrate`](crate::GalerkinIntegrator::integrate):
/// (q_k, p_k) at t_k = t0 + k h, and each step's Galerkin coefficients, so that q(t), q̇(t)
/// and p(t) = ∂L/∂v(q(t), q̇(t)) can be read at any time in [t0, t_end].
///
/// The trajectory holds the basis its curves were computed in (the integrator's own value, a
/// user's basis as much as a built-in one), so dense output never depends on a name.
///
/// Serialises with serde. The basis is recorded by name and n: a deserialised trajectory of a
/// built-in basis rebuilds it; one of a user's basis
/// ([`user_basis`](Trajectory::user_basis)) answers dense-output queries with
/// [`GviError::BasisNotAttached`] until the basis is attached again with
/// [`attach_basis`](Trajectory::attach_basis) — never with a silently different curve.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Trajectory {
    /// Name of the basis of the Galerkin curves ([`Basis::name`]).
    pub basis: String,
    /// The basis is not one of the crate's ([`BasisKind::of`] is `None`): a deserialised
    /// trajectory needs it attached for dense output.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub user_basis: bool,
    /// Number of basis functions.
    pub n: usize,
    /// Name of the quadrature family ([`QuadratureRule::family`](crate::quadrature::QuadratureRule::family)).
    pub quadrature: String,
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
    /// The bases of the curves, set by the integrator (or by
    /// [`attach_basis`](Trajectory::attach_basis)), else rebuilt once from a built-in name.
    #[serde(skip)]
    bases: OnceLock<BasisTable>,
}

impl Trajectory {
    /// An empty trajectory whose curves are in `basis` (n = `basis.len()`), computed with a
    /// quadrature of family `quadrature` and `quad_points` points.
    pub(crate) fn new(
        basis: SharedBasis,
        quadrature: &str,
        quad_points: usize,
        h: f64,
        t0: f64,
        dim: usize,
        capacity: usize,
    ) -> Self {
        let n = basis.len();
        let traj = Trajectory::of_kind_name(
            basis.name(),
            n,
            quadrature,
            quad_points,
            h,
            t0,
            dim,
            capacity,
        );
        let _ = traj.bases.set(vec![(n, basis)]);
        traj
    }

    #[allow(clippy::too_many_arguments)]
    /// An empty trajectory for a built-in basis kind whose n may vary from step to step
    /// (tolerance-driven runs): the bases are built on first use.
    pub(crate) fn of_kind(
        kind: BasisKind,
        n: usize,
        quadrature: &str,
        quad_points: usize,
        h: f64,
        t0: f64,
        dim: usize,
        capacity: usize,
    ) -> Self {
        Trajectory::of_kind_name(
            kind.as_str(),
            n,
            quadrature,
            quad_points,
            h,
            t0,
            dim,
            capacity,
        )
    }

    /// An empty trajectory with room for `capacity` steps (at most 2²⁰ reserved up front) and
    /// no basis attached yet.
    #[allow(clippy::too_many_arguments)]
    fn of_kind_name(
        basis: &str,
        n: usize,
        quadrature: &str,
        quad_points: usize,
        h: f64,
        t0: f64,
        dim: usize,
        capacity: usize,
    ) -> Self {
        let cap = capacity.min(1 << 20);
        Trajectory {
            basis: basis.to_string(),
            user_basis: false,
            n,
            quadrature: quadrature.to_string(),
            quad_points,
            h,
            t0,
            dim,
            q: Vec::with_capacity(cap + 1),
            p: Vec::with_capacity(cap + 1),
            coefficients: Vec::with_capacity(cap),
            stats: Vec::with_capacity(cap),
            step_n: Vec::new(),
            bases: OnceLock::new(),
        }
    }

    /// Mark the trajectory's basis as one written outside the crate (set by the integrator
    /// from the basis's type).
    pub(crate) fn set_user_basis(&mut self, user: bool) {
        self.user_basis = user;
    }

    /// Attach the basis of a deserialised trajectory's curves, so that dense output works
    /// again: needed for a user's basis ([`user_basis`](Trajectory::user_basis)), allowed for
    /// any. `family` builds the basis for a given n (every distinct n of the trajectory's
    /// steps is built once).
    ///
    /// Errors: [`GviError::Mismatch`] when the basis's name is not the recorded one or
    /// it does not have the n asked for; the error of `family`.
    pub fn attach_basis<B: Basis>(
        &mut self,
        mut family: impl FnMut(usize) -> Result<B>,
    ) -> Result<()> {
        let mut table: BasisTable = Vec::new();
        for n in self.distinct_n() {
            let b = family(n)?;
            if b.name() != self.basis || b.len() != n {
                return Err(GviError::Mismatch {
                    expected: format!("{} with n = {n}", self.basis),
                    got: format!("{} with n = {}", b.name(), b.len()),
                });
            }
            table.push((n, Arc::new(b)));
        }
        self.bases = OnceLock::new();
        let _ = self.bases.set(table);
        Ok(())
    }

    /// Every n the trajectory's steps use, in increasing order.
    fn distinct_n(&self) -> Vec<usize> {
        let mut ns: Vec<usize> = self.step_n.clone();
        ns.push(self.n);
        ns.sort_unstable();
        ns.dedup();
        ns
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

    /// The basis of the curves with n functions: the one the integrator used or the user
    /// attached, else (deserialised, built-in) rebuilt from the recorded name.
    pub(crate) fn basis_with(&self, n: usize) -> Result<&dyn Basis> {
        if self.bases.get().is_none() {
            if self.user_basis {
                return Err(GviError::BasisNotAttached {
                    basis: self.basis.clone(),
                });
            }
            let kind: BasisKind = self.basis.parse()?;
            let mut table: BasisTable = Vec::new();
            for m in self.distinct_n() {
                if m >= 2 {
                    table.push((m, Arc::new(kind.build(m)?)));
                }
            }
            let _ = self.bases.set(table);
        }
        let found = self
            .bases
            .get()
            .and_then(|t| t.iter().find(|(m, _)| *m == n))
            .map(|(_, b)| &**b);
        match found {
            Some(b) => Ok(b),
            None if self.user_basis => Err(GviError::BasisNotAttached {
                basis: self.basis.clone(),
            }),
            None => {
                // A built-in basis at an n the table does not hold (not expected: every n of
                // the steps is in it).
                Err(GviError::InvalidBasisSize {
                    n,
                    basis: self.basis.clone(),
                    reason: "no basis of this size is attached to the trajectory".into(),
                })
            }
        }
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
        curve.state_into(
            self.basis_with(n)?,
            tau,
            &mut phi,
            &mut dphi,
            &mut q,
            &mut v,
        );
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
        lagrangian.legendre_transform_at(t, &q, &v, &mut p);
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
