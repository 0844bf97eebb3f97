//! [`TimeStepper`]: fixed fictitious steps of the time-transformed Lagrangian, with the
//! physical time t(s) = t₀ + ∫ g(q(s)) ds kept along the way.
//!
//! The increment of one step is the integral of g along the step's Galerkin curve by the
//! step's own quadrature, Δt_k = Δs Σ_j b_j g(q(c_j)) — the rule that already integrates the
//! action (paper eq. (1)), so t(s) is as accurate as the curve. The increments are summed
//! with compensation (Kahan), so the physical time of a long run does not random-walk with
//! the round-off of its many steps. Within a step, t(τ) = t_k + τ Δs Σ_j b_j g(q(c_j τ)) is the
//! same rule on [0, τ], which is t_{k+1} at τ = 1: output and events in physical time are
//! located on it.

use super::{Monitor, TimeTransformed};
use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result};
use crate::integrator::{GalerkinIntegrator, Stepper};
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;
use crate::stats::StepStats;

/// Buffers and node tables for integrating g along one step's curve without allocating.
#[derive(Debug, Clone)]
pub(crate) struct CurveClock {
    nodes: Vec<f64>,
    weights: Vec<f64>,
    /// φ_i(c_j), row j (the nodes of the full step).
    phi_nodes: Vec<f64>,
    phi: Vec<f64>,
    dphi: Vec<f64>,
    q: Vec<f64>,
    v: Vec<f64>,
    n: usize,
}

impl CurveClock {
    pub(crate) fn new<B: Basis, Q: Quadrature>(gvi: &GalerkinIntegrator<B, Q>, d: usize) -> Self {
        let rule = gvi.rule();
        let n = gvi.n();
        let (mut phi, mut dphi) = (vec![0.0; n], vec![0.0; n]);
        let mut phi_nodes = Vec::with_capacity(rule.nodes.len() * n);
        for &c in &rule.nodes {
            gvi.basis().eval(c, &mut phi, &mut dphi);
            phi_nodes.extend_from_slice(&phi);
        }
        CurveClock {
            nodes: rule.nodes.clone(),
            weights: rule.weights.clone(),
            phi_nodes,
            phi,
            dphi,
            q: vec![0.0; d],
            v: vec![0.0; d],
            n,
        }
    }

    /// Δs Σ_j b_j g(q(c_j)) over the whole step (the tabulated nodes).
    pub(crate) fn increment<S: Lagrangian, M: Monitor>(
        &mut self,
        curve: &GalerkinCurveRef<'_>,
        tt: &TimeTransformed<S, M>,
    ) -> f64 {
        let (n, d) = (self.n, curve.dim());
        let c = curve.coefficients();
        let mut sum = 0.0;
        for (j, &b) in self.weights.iter().enumerate() {
            let phi = &self.phi_nodes[j * n..(j + 1) * n];
            self.q.iter_mut().for_each(|x| *x = 0.0);
            for i in 0..n {
                for r in 0..d {
                    self.q[r] += phi[i] * c[i * d + r];
                }
            }
            sum += b * tt.rate(&self.q);
        }
        curve.h() * sum
    }

    /// τ Δs Σ_j b_j g(q(c_j τ)): the physical time elapsed from the step's start to local
    /// time τ ∈ [0, 1] (the same rule on [0, τ]; at τ = 1 bit for bit [`increment`]).
    ///
    /// [`increment`]: Self::increment
    pub(crate) fn partial<B: Basis + ?Sized, S: Lagrangian, M: Monitor>(
        &mut self,
        curve: &GalerkinCurveRef<'_>,
        basis: &B,
        tt: &TimeTransformed<S, M>,
        tau: f64,
    ) -> f64 {
        if tau == 1.0 {
            return self.increment(curve, tt);
        }
        let mut sum = 0.0;
        for j in 0..self.nodes.len() {
            curve.state_into(
                basis,
                self.nodes[j] * tau,
                &mut self.phi,
                &mut self.dphi,
                &mut self.q,
                &mut self.v,
            );
            sum += self.weights[j] * tt.rate(&self.q);
        }
        tau * curve.h() * sum
    }
}

/// Fixed fictitious steps Δs of a [`TimeTransformed`] Lagrangian, keeping the physical time.
///
/// Its one-step map is the Galerkin variational integrator of L̃ (a [`Stepper`]), so it is
/// symplectic in s; [`time`](Self::time) is the physical time of the current state and
/// [`last_step`](Self::last_step) the physical length of the last step. Allocates nothing
/// per step.
#[derive(Debug)]
pub struct TimeStepper<'a, B: Basis, Q: Quadrature, S: Lagrangian, M: Monitor> {
    stepper: Stepper<'a, B, Q, TimeTransformed<S, M>>,
    tt: &'a TimeTransformed<S, M>,
    clock: CurveClock,
    /// Physical time of the current state and its compensation term.
    t: f64,
    t_err: f64,
    /// Physical time at the start of the last step.
    t_previous: f64,
    last: f64,
}

impl<'a, B: Basis, Q: Quadrature, S: Lagrangian, M: Monitor> TimeStepper<'a, B, Q, S, M> {
    /// See [`TimeTransformed::stepper`].
    pub(crate) fn new(
        gvi: &'a GalerkinIntegrator<B, Q>,
        tt: &'a TimeTransformed<S, M>,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
    ) -> Result<Self> {
        let stepper = gvi.stepper(tt, 0.0, q0, p0)?;
        if !t0.is_finite() {
            return Err(GviError::NonFinite {
                what: "initial time t0".into(),
                value: t0,
            });
        }
        let g0 = tt.rate(q0);
        if !(g0.is_finite() && g0 > 0.0) {
            return Err(GviError::InvalidParameter {
                name: format!("time-transform monitor {} at q0", tt.monitor().name()),
                value: g0,
                reason: "must be finite and positive (dt/ds = g(q))".into(),
            });
        }
        Ok(TimeStepper {
            stepper,
            tt,
            clock: CurveClock::new(gvi, tt.dim()),
            t: t0,
            t_err: 0.0,
            t_previous: t0,
            last: 0.0,
        })
    }

    /// One fictitious step Δs; returns its cost.
    ///
    /// Errors: the step's solver failure ([`GviError::NewtonFailure`], naming the step and
    /// its fictitious time); a physical step that is not finite and positive (the monitor
    /// left its domain along the curve: [`GviError::NonFinite`]). The state is then the last
    /// completed step's.
    pub fn step(&mut self) -> Result<StepStats> {
        let stats = self.stepper.step()?;
        let dt = self.clock.increment(&self.stepper.curve(), self.tt);
        if !(dt.is_finite() && dt > 0.0) {
            return Err(GviError::NonFinite {
                what: format!(
                    "physical step of fictitious step {} (the integral of the monitor {} along \
                     its curve must be finite and positive)",
                    self.stepper.steps() - 1,
                    self.tt.monitor().name()
                ),
                value: dt,
            });
        }
        self.t_previous = self.t;
        // Kahan summation of t += dt.
        let y = dt - self.t_err;
        let t = self.t + y;
        self.t_err = (t - self.t) - y;
        self.t = t;
        self.last = dt;
        Ok(stats)
    }

    /// The physical time t of the current state.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The physical time at the start of the last step.
    pub fn previous_time(&self) -> f64 {
        self.t_previous
    }

    /// The fictitious time s = k Δs of the current state.
    pub fn fictitious_time(&self) -> f64 {
        self.stepper.time()
    }

    /// The physical length of the last step (0 before the first).
    pub fn last_step(&self) -> f64 {
        self.last
    }

    /// Fictitious steps completed.
    pub fn steps(&self) -> usize {
        self.stepper.steps()
    }

    /// The current position q.
    pub fn position(&self) -> &[f64] {
        self.stepper.position()
    }

    /// The current momentum p (physical: ∂L̃/∂q' = M dq/dt).
    pub fn momentum(&self) -> &[f64] {
        self.stepper.momentum()
    }

    /// The last step's Galerkin curve, in fictitious time (its `start_time` is s_k).
    pub fn curve(&self) -> GalerkinCurveRef<'_> {
        self.stepper.curve()
    }

    /// The time-transformed Lagrangian.
    pub fn lagrangian(&self) -> &'a TimeTransformed<S, M> {
        self.tt
    }

    /// The integrator (its step size is Δs).
    pub fn integrator(&self) -> &GalerkinIntegrator<B, Q> {
        self.stepper.integrator()
    }

    /// The physical time at local time τ ∈ [0, 1] of the last step's curve.
    pub fn time_on_curve(&mut self, tau: f64) -> f64 {
        let curve = self.stepper.curve();
        let basis = self.stepper.integrator().basis();
        self.t_previous + self.clock.partial(&curve, basis, self.tt, tau)
    }

    /// The underlying [`Stepper`] of L̃ and the clock, for the run driver.
    pub(crate) fn parts(
        &mut self,
    ) -> (
        &Stepper<'a, B, Q, TimeTransformed<S, M>>,
        &mut CurveClock,
        f64,
    ) {
        (&self.stepper, &mut self.clock, self.t_previous)
    }
}
