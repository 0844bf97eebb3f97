//! Symplectic variable steps by a Poincaré time transformation.
//!
//! A fixed step cannot follow a close encounter: the physical step has to shrink where the
//! motion is fast, and a step size chosen from the state breaks the symplecticity of the
//! one-step map. The Poincaré transformation moves the variable step into the Lagrangian.
//! For H = ½ pᵀM⁻¹p + V(q) and a positive monitor g(q), the Hamiltonian
//! H̃ = g(q)(H − E₀) in a fictitious time s has the same orbits as H on H̃ = 0, with
//! dt/ds = g(q). Its Legendre transform is the regular Lagrangian
//!
//!   L̃(q, q') = q'ᵀM q' / (2 g(q)) − g(q) (V(q) − E₀),      q' = dq/ds,
//!
//! whose momentum ∂L̃/∂q' = M q'/g = M dq/dt is the physical momentum p. [`TimeTransformed`]
//! is L̃ as a [`Lagrangian`]: the Galerkin integrator of the paper (its eqs. (1)–(4)) applied
//! to it with a *fixed* fictitious step Δs is a variational integrator in s — its one-step
//! map (q, p) ↦ (q', p') is symplectic, and the momentum maps of the symmetries L̃ shares with
//! L (those of g) are conserved exactly — while the physical step
//! Δt = ∫ g(q(s)) ds shrinks where g does. [`TimeStepper`] takes those steps and keeps the
//! physical time t(s), integrating g along each step's Galerkin curve with the step's own
//! quadrature (compensated summation over steps). [`integrate_time_transformed`] runs to a
//! physical end time, returning states at requested physical times located as zeros of
//! t(s) − t_out on the Galerkin curves (events on t(s), not interpolation after the fact),
//! with user events in physical time and a dense-output record of every step.
//!
//! E₀ is the energy of the initial state unless given: only on H̃ = 0 is s a reparametrisation
//! of the physical motion. g is divided by its initial value, so Δs is the physical step at
//! the initial state.
//!
//! **Stage solvers.** L̃ has a position-dependent kinetic term, so it is not separable
//! ([`Lagrangian::mass_matrix`] is `None`): the velocity form and the structured solvers
//! (Kronecker, Newton–Krylov with the frozen Hessian, fixed point) need a constant mass matrix
//! and do not apply. `auto` solves every step by dense exact Newton on the nodal equations
//! (docs/DESIGN.md §3.5), with the hand-written second derivatives of L̃ below; that is the
//! solver to use, and N-body systems of more than a few bodies pay O((nD)³) per step for it.
//!
//! ```
//! use galerkin_vi::prelude::*;
//! use galerkin_vi::time_transform::{CentralDistance, TimeTransformed};
//!
//! // Kepler e = 0.9 (a = 1, period 2π) from periapsis with g = (r/r_p)^{3/2}: the
//! // fictitious period is 0.26462, so Δs = 0.0044 makes 60 steps per orbit.
//! let e = 0.9;
//! let (q0, p0) = ([1.0 - e, 0.0], [0.0, ((1.0 + e) / (1.0 - e)).sqrt()]);
//! let tt = TimeTransformed::new(Kepler::new(1.0)?, CentralDistance::new(1.5)?, &q0, &p0, None)?;
//! let gvi = GalerkinIntegrator::spectral(12, 0.0044)?;
//! let mut stepper = tt.stepper(&gvi, 0.0, &q0, &p0)?;
//! while stepper.time() < 2.0 * std::f64::consts::PI {
//!     stepper.step()?;
//! }
//! // About 60 steps; the physical ones from 0.0044 at periapsis to ~0.3 at apoapsis.
//! assert!((59..=61).contains(&stepper.steps()));
//! let energy = tt.hamiltonian(stepper.position(), stepper.momentum());
//! assert!((energy + 0.5).abs() < 1e-8);
//! # Ok::<(), galerkin_vi::GviError>(())
//! ```

mod clock;
mod monitor;
mod run;
mod spec;
#[cfg(test)]
mod tests;

pub use clock::TimeStepper;
pub use monitor::{CentralDistance, Combine, Monitor, PairDistances, SOFTMIN_BETA};
pub use run::{
    OutputState, TimeTransformFailure, TimeTransformOptions, TimeTransformedRun,
    integrate_time_transformed, integrate_time_transformed_until,
};
pub use spec::{AnyMonitor, MonitorKind, TimeTransformSpec};

use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::systems::System;
use num_dual::DualNum;

/// The Poincaré time-transformed Lagrangian L̃(q, q') = q'ᵀMq'/(2g) − g(V − E₀) of a
/// separable system L = ½ q̇ᵀMq̇ − V(q) and a [`Monitor`] g (see the [module](self) docs).
///
/// Its derivatives are hand-written from the system's force, force Jacobian and mass matrix
/// and the monitor's gradient and Hessian (automatic differentiation of the generic
/// [`Lagrangian::lagrangian`] is used only to test them), and they allocate nothing.
#[derive(Debug, Clone)]
pub struct TimeTransformed<S, M> {
    system: S,
    monitor: M,
    /// E₀.
    energy: f64,
    /// 1 / g_raw(q₀): g = scale · monitor(q).
    scale: f64,
    d: usize,
    /// M (row-major D×D) and M⁻¹.
    mass: Vec<f64>,
    mass_inverse: Vec<f64>,
    /// D zeros: V(q) = −L(q, 0).
    zeros: Vec<f64>,
}

impl<S: Lagrangian, M: Monitor> TimeTransformed<S, M> {
    /// L̃ for `system` with monitor `monitor`, normalised so that g(q₀) = 1, at the energy
    /// `energy` (default: H(q₀, p₀), the only value on which s reparametrises the physical
    /// motion).
    ///
    /// Errors ([`GviError::Unsupported`]): a system without a constant mass matrix, or a
    /// time-dependent or forced one; ([`GviError::InvalidParameter`]) the monitor not finite
    /// or not positive at q₀, E₀ not finite; ([`GviError::DimensionMismatch`],
    /// [`GviError::NonFinite`]) q₀, p₀ of the wrong length or not finite, a monitor made for
    /// another dimension; a singular mass matrix.
    pub fn new(system: S, monitor: M, q0: &[f64], p0: &[f64], energy: Option<f64>) -> Result<Self> {
        let d = system.dim();
        if !system.is_autonomous() || system.is_forced() {
            return Err(GviError::Unsupported(
                "a time transformation needs an autonomous, unforced system (H − E₀ must be \
                 conserved)"
                    .into(),
            ));
        }
        let Some(m) = system.mass_matrix() else {
            return Err(GviError::Unsupported(
                "a time transformation needs a separable Lagrangian ½ q̇ᵀMq̇ − V(q) with a \
                 constant mass matrix"
                    .into(),
            ));
        };
        ensure_len("time-transform q0", d, q0.len())?;
        ensure_len("time-transform p0", d, p0.len())?;
        ensure_finite("time-transform q0", q0)?;
        ensure_finite("time-transform p0", p0)?;
        if let Some(md) = monitor.dim() {
            ensure_len("monitor dimension", d, md)?;
        }
        let inverse = m
            .clone()
            .try_inverse()
            .ok_or_else(|| GviError::InvalidInput {
                name: "mass matrix".into(),
                reason: "is singular".into(),
            })?;
        let g0 = monitor.value_f64(q0);
        if !(g0.is_finite() && g0 > 0.0) {
            return Err(GviError::InvalidParameter {
                name: format!("time-transform monitor {} at q0", monitor.name()),
                value: g0,
                reason: "must be finite and positive (dt/ds = g(q))".into(),
            });
        }
        let mut tt = TimeTransformed {
            system,
            monitor,
            energy: 0.0,
            scale: 1.0 / g0,
            d,
            mass: (0..d * d).map(|i| m[(i / d, i % d)]).collect(),
            mass_inverse: (0..d * d).map(|i| inverse[(i / d, i % d)]).collect(),
            zeros: vec![0.0; d],
        };
        let e0 = energy.unwrap_or_else(|| tt.hamiltonian(q0, p0));
        if !e0.is_finite() {
            return Err(GviError::InvalidParameter {
                name: "time-transform energy E0".into(),
                value: e0,
                reason: "must be finite".into(),
            });
        }
        tt.energy = e0;
        Ok(tt)
    }

    /// The physical system.
    pub fn system(&self) -> &S {
        &self.system
    }

    /// The monitor.
    pub fn monitor(&self) -> &M {
        &self.monitor
    }

    /// E₀.
    pub fn energy_level(&self) -> f64 {
        self.energy
    }

    /// The normalised monitor g(q) = monitor(q)/monitor(q₀) = dt/ds.
    pub fn rate(&self, q: &[f64]) -> f64 {
        self.scale * self.monitor.value_f64(q)
    }

    /// V(q) of the physical system: [`Lagrangian::potential_energy`], or −L(q, 0) for a
    /// system that does not give it.
    pub fn potential(&self, q: &[f64]) -> f64 {
        self.system
            .potential_energy(q)
            .unwrap_or_else(|| -self.system.value(q, &self.zeros))
    }

    /// ½ pᵀM⁻¹p.
    fn kinetic_of_momentum(&self, p: &[f64]) -> f64 {
        let d = self.d;
        let mut t = 0.0;
        for r in 0..d {
            for c in 0..d {
                t += p[r] * self.mass_inverse[r * d + c] * p[c];
            }
        }
        0.5 * t
    }

    /// ½ vᵀMv.
    fn kinetic_of_velocity(&self, v: &[f64]) -> f64 {
        let d = self.d;
        let mut t = 0.0;
        for r in 0..d {
            for c in 0..d {
                t += v[r] * self.mass[r * d + c] * v[c];
            }
        }
        0.5 * t
    }

    /// The physical energy H(q, p) = ½ pᵀM⁻¹p + V(q).
    pub fn hamiltonian(&self, q: &[f64], p: &[f64]) -> f64 {
        self.kinetic_of_momentum(p) + self.potential(q)
    }

    /// The transformed Hamiltonian H̃ = g (H − E₀), conserved (zero) by the s-flow.
    pub fn transformed_hamiltonian(&self, q: &[f64], p: &[f64]) -> f64 {
        self.rate(q) * (self.hamiltonian(q, p) - self.energy)
    }

    /// The vector field of the s-flow, dq/ds = g M⁻¹p and dp/ds = −∇g (H − E₀) − g ∇V, into
    /// `dq` and `dp` (for reference integrations and tests; allocates two D-vectors).
    pub fn vector_field(&self, q: &[f64], p: &[f64], dq: &mut [f64], dp: &mut [f64]) {
        let d = self.d;
        let mut grad_g = vec![0.0; d];
        let g = self.scale * self.monitor.gradient(q, &mut grad_g);
        let shift = self.hamiltonian(q, p) - self.energy;
        self.system.force(q, dp); // −∇V
        for r in 0..d {
            dq[r] = g
                * (0..d)
                    .map(|c| self.mass_inverse[r * d + c] * p[c])
                    .sum::<f64>();
            dp[r] = g * dp[r] - self.scale * grad_g[r] * shift;
        }
    }
}

impl<S: Lagrangian, M: Monitor> Lagrangian for TimeTransformed<S, M> {
    fn dim(&self) -> usize {
        self.d
    }

    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        let d = self.d;
        let mut kinetic = T::from(0.0);
        for r in 0..d {
            for c in 0..d {
                kinetic += v[r] * v[c] * self.mass[r * d + c];
            }
        }
        let zeros = vec![T::from(0.0); d];
        let potential = -self.system.lagrangian(q, &zeros);
        let g = self.monitor.value(q) * self.scale;
        kinetic * 0.5 / g - g * (potential - self.energy)
    }

    fn value(&self, q: &[f64], v: &[f64]) -> f64 {
        let g = self.rate(q);
        self.kinetic_of_velocity(v) / g - g * (self.potential(q) - self.energy)
    }

    fn gradient(&self, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        let d = self.d;
        // lq ← −∇V, lv ← ∇g (scratch until the end).
        self.system.force(q, lq);
        let g = self.scale * self.monitor.gradient(q, lv);
        let kinetic = self.kinetic_of_velocity(v);
        // L_q = −(T_v/g² + V − E₀) ∇g − g ∇V, T_v = ½ vᵀMv
        let c = kinetic / (g * g) + self.potential(q) - self.energy;
        for r in 0..d {
            lq[r] = g * lq[r] - c * self.scale * lv[r];
        }
        // L_v = M v / g
        for r in 0..d {
            lv[r] = (0..d).map(|s| self.mass[r * d + s] * v[s]).sum::<f64>() / g;
        }
    }

    fn hessian(&self, q: &[f64], v: &[f64], lqq: &mut [f64], lqv: &mut [f64], lvv: &mut [f64]) {
        let d = self.d;
        // Scratch: ∇g and ∇V in lqv (2D ≤ D² for D ≥ 2), ∇²g in lvv, −∇²V in lqq.
        let mut small = [0.0; 2];
        let (grad_g, grad_v): (&mut [f64], &mut [f64]) = if d >= 2 {
            let (a, b) = lqv.split_at_mut(d);
            (a, &mut b[..d])
        } else {
            let (a, b) = small.split_at_mut(1);
            (a, b)
        };
        let g = self.scale * self.monitor.hessian(q, grad_g, lvv);
        grad_g.iter_mut().for_each(|x| *x *= self.scale);
        lvv.iter_mut().for_each(|x| *x *= self.scale);
        self.system.force(q, grad_v);
        grad_v.iter_mut().for_each(|x| *x = -*x);
        self.system.force_jacobian(q, lqq);
        let kinetic = self.kinetic_of_velocity(v);
        let c = kinetic / (g * g) + self.potential(q) - self.energy;
        // L_qq = 2T_v/g³ ∇g∇gᵀ − (T_v/g² + V − E₀) ∇²g − ∇g∇Vᵀ − ∇V∇gᵀ − g ∇²V
        let k3 = 2.0 * kinetic / (g * g * g);
        for r in 0..d {
            for s in 0..d {
                let i = r * d + s;
                lqq[i] = g * lqq[i] + k3 * grad_g[r] * grad_g[s]
                    - c * lvv[i]
                    - grad_g[r] * grad_v[s]
                    - grad_v[r] * grad_g[s];
            }
        }
        // L_qv(r, s) = ∂²L/∂q_r∂v_s = −∇g_r (Mv)_s / g²; grad_g is read before lqv is
        // overwritten, so keep a copy of it in lvv's place first (lvv is rewritten next).
        lvv[..d].copy_from_slice(&grad_g[..d]);
        for s in 0..d {
            let mv: f64 = (0..d).map(|c| self.mass[s * d + c] * v[c]).sum();
            for r in 0..d {
                lqv[r * d + s] = -lvv[r] * mv / (g * g);
            }
        }
        // L_vv = M / g
        for i in 0..d * d {
            lvv[i] = self.mass[i] / g;
        }
    }

    fn legendre_transform(&self, q: &[f64], v: &[f64], p: &mut [f64]) {
        let (d, g) = (self.d, self.rate(q));
        for r in 0..d {
            p[r] = (0..d).map(|s| self.mass[r * d + s] * v[s]).sum::<f64>() / g;
        }
    }

    fn energy(&self, q: &[f64], v: &[f64]) -> f64 {
        // E = L_v·v − L = T_v/g + g (V − E₀) = H̃
        let g = self.rate(q);
        self.kinetic_of_velocity(v) / g + g * (self.potential(q) - self.energy)
    }
}

/// The physical system's invariants and symmetries, of (q, p) with p the physical momentum
/// (which is L̃'s). The symmetries are conserved by the s-flow when the monitor shares them
/// (the built-in [`PairDistances`] is invariant under translations and rotations,
/// [`CentralDistance`] under rotations); a user's monitor that is not breaks them.
impl<S: System, M: Monitor> System for TimeTransformed<S, M> {
    fn name(&self) -> &'static str {
        self.system.name()
    }
    fn invariant_names(&self) -> &'static [&'static str] {
        self.system.invariant_names()
    }
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        self.system.invariants(q, p, out)
    }
    fn symmetries(&self) -> Vec<crate::symmetries::NamedMomentumMap> {
        self.system.symmetries()
    }
    fn body_names(&self) -> Option<Vec<String>> {
        self.system.body_names()
    }
}

impl<S: Lagrangian, M: Monitor> TimeTransformed<S, M> {
    /// A [`TimeStepper`] of `gvi` (whose step size is the fictitious step Δs) from (q₀, p₀)
    /// at physical time t₀.
    ///
    /// Errors: those of [`crate::GalerkinIntegrator::stepper`]; the monitor not finite and
    /// positive at q₀ ([`GviError::InvalidParameter`]).
    pub fn stepper<'a, B: crate::basis::Basis, Q: crate::quadrature::Quadrature>(
        &'a self,
        gvi: &'a crate::GalerkinIntegrator<B, Q>,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
    ) -> Result<TimeStepper<'a, B, Q, S, M>> {
        TimeStepper::new(gvi, self, t0, q0, p0)
    }
}
