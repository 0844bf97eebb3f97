//! Locating a zero of g(t, q(t), p(t)) on one step's Galerkin curve: sample the curve at
//! equally spaced local times, and refine a sign change by the Illinois variant of regula
//! falsi (superlinear, and bracketing, so it never leaves the step).
//!
//! The state on the curve is (q(τ), p(τ)) with p = ∂L/∂v(q(τ), q̇(τ)), the continuous Legendre
//! transform of the curve — the dense output the step has already computed; nothing is
//! re-integrated. Every buffer is owned by [`CurveProbe`] and sized once, so scanning a step
//! allocates nothing.

use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::lagrangian::Lagrangian;

use super::EventFunction;

/// Buffers for evaluating a state on a Galerkin curve without allocating.
#[derive(Debug, Clone)]
pub(crate) struct CurveProbe {
    phi: Vec<f64>,
    dphi: Vec<f64>,
    /// q(τ) (D).
    pub(crate) q: Vec<f64>,
    v: Vec<f64>,
    /// p(τ) = ∂L/∂v (D).
    pub(crate) p: Vec<f64>,
    /// Function evaluations so far (for the cost accounting of a run).
    pub(crate) evaluations: usize,
}

impl CurveProbe {
    /// Buffers for curves of up to `n` basis functions in dimension `d`.
    pub(crate) fn new(n: usize, d: usize) -> Self {
        CurveProbe {
            phi: vec![0.0; n],
            dphi: vec![0.0; n],
            q: vec![0.0; d],
            v: vec![0.0; d],
            p: vec![0.0; d],
            evaluations: 0,
        }
    }

    /// The state (q, p) at local time τ of `curve` into `self.q`, `self.p`; returns its time.
    pub(crate) fn state<B: Basis + ?Sized, L: Lagrangian>(
        &mut self,
        curve: &GalerkinCurveRef<'_>,
        basis: &B,
        lag: &L,
        tau: f64,
    ) -> f64 {
        let n = curve.n();
        if self.phi.len() < n {
            self.phi.resize(n, 0.0);
            self.dphi.resize(n, 0.0);
        }
        curve.state_into(
            basis,
            tau,
            &mut self.phi,
            &mut self.dphi,
            &mut self.q,
            &mut self.v,
        );
        let t = curve.start_time() + tau * curve.h();
        lag.legendre_transform_at(t, &self.q, &self.v, &mut self.p);
        t
    }

    /// g at local time τ of `curve` (counted), with the state left in `self.q`, `self.p`.
    pub(crate) fn value<B: Basis + ?Sized, L: Lagrangian>(
        &mut self,
        curve: &GalerkinCurveRef<'_>,
        basis: &B,
        lag: &L,
        g: &dyn EventFunction,
        tau: f64,
    ) -> f64 {
        let t = self.state(curve, basis, lag, tau);
        self.evaluations += 1;
        g.value(t, &self.q, &self.p)
    }
}

/// The root of g on [a, b] ⊂ [0, 1] (local times) given g(a) = ga and g(b) = gb of opposite
/// signs (or one of them zero), by [`illinois`] to a bracket below `tau_tol`. Returns the local
/// time, with the state there left in `probe`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn refine<B: Basis + ?Sized, L: Lagrangian>(
    probe: &mut CurveProbe,
    curve: &GalerkinCurveRef<'_>,
    basis: &B,
    lag: &L,
    g: &dyn EventFunction,
    (a, ga): (f64, f64),
    (b, gb): (f64, f64),
    tau_tol: f64,
) -> f64 {
    // The iterate where g vanished, if the search stopped there: the probe already holds its
    // state, and evaluating it again would count one evaluation too many
    // (`EventRun::curve_evaluations`).
    let mut zero_at = None;
    let g_at = |x: f64| {
        let gx = probe.value(curve, basis, lag, g, x);
        if gx == 0.0 {
            zero_at = Some(x);
        }
        gx
    };
    let x = illinois(g_at, (a, ga), (b, gb), tau_tol);
    if zero_at != Some(x) {
        probe.value(curve, basis, lag, g, x);
    }
    x
}

/// The root of f on [a, b] given f(a) = fa and f(b) = fb of opposite signs (or fa zero):
/// Illinois regula falsi, stopped when the bracket is below `tol` or f vanishes; at most 200
/// iterations (each halves the bracket's worst case within a few steps). Returns a when fa is
/// zero, the iterate where f vanished, or else the final bracket's midpoint.
///
/// The one root finder of the crate's located times: the events on a step's curve
/// ([`refine`]) and, on the curve's physical time t(τ), the output times, events and dense
/// output of time-transformed runs (`time_transform::run`).
pub(crate) fn illinois(
    mut f: impl FnMut(f64) -> f64,
    (mut a, mut fa): (f64, f64),
    (mut b, mut fb): (f64, f64),
    tol: f64,
) -> f64 {
    if fa == 0.0 {
        return a;
    }
    // Which end the last iterate replaced, to halve the other's weight when one end sticks.
    let mut side = 0i8;
    for _ in 0..200 {
        if (b - a).abs() <= tol {
            break;
        }
        let mut x = (a * fb - b * fa) / (fb - fa);
        if !(x > a.min(b) && x < a.max(b)) {
            x = 0.5 * (a + b);
        }
        let fx = f(x);
        if fx == 0.0 {
            return x;
        }
        if (fx > 0.0) == (fb > 0.0) {
            (b, fb) = (x, fx);
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            (a, fa) = (x, fx);
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
    }
    // The bracket is below the tolerance (or the iterations ran out): its midpoint.
    0.5 * (a + b)
}
