//! Time-dependent Lagrangians and non-conservative forces: the discrete
//! Lagrange–d'Alembert principle on Galerkin curves (guide: docs/guide/forcing.md).
//!
//! - [`NonAutonomousLagrangian`] / [`NonAutonomous`]: L(t, q, v), evaluated at the quadrature
//!   times t_k + c_j h of each step.
//! - [`ExternalForce`] / [`Forced`]: a force f(t, q, v) that enters the stage equations as
//!   h Σ_j b_j f(c_j)·φ_i(c_j), where L_q enters them (Marsden & West's forced discrete
//!   Euler–Lagrange equations in Galerkin form); built in: [`LinearDamping`] and the N-body
//!   [`StokesDrag`].
//! - [`energy_balance`] and [`momentum_balance`]: what replaces conservation — the energy
//!   changes by the work of f minus ∫∂L/∂t, a momentum map by the impulse of f along its
//!   symmetry.
//!
//! Such systems take the general (non-separable) stage path with the node times, since the
//! structured solvers of separable Lagrangians rely on a time-independent L_q(q) alone;
//! autonomous, unforced systems are untouched and pay nothing.

mod balance;
mod force;
mod time;

pub use balance::{Balance, EnergyMeter, energy_balance, momentum_balance};
pub use force::{ExternalForce, Forced, LinearDamping, StokesDrag};
pub use time::{NonAutonomous, NonAutonomousLagrangian};

#[cfg(test)]
mod tests;

use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;

/// Refuse a time-dependent or forced system where `what` assumes an autonomous, conservative
/// one (a flow whose step map is symplectic in (q, p) alone, with conserved energy).
pub(crate) fn ensure_conservative<L: Lagrangian + ?Sized>(lag: &L, what: &str) -> Result<()> {
    let why = match (lag.is_autonomous(), lag.is_forced()) {
        (true, false) => return Ok(()),
        (false, false) => "depends on time explicitly",
        (true, true) => "is forced",
        (false, true) => "depends on time explicitly and is forced",
    };
    Err(GviError::Unsupported(format!(
        "{what} assumes an autonomous, unforced system, but this one {why} (the Galerkin \
         integrator steps it; its energy and momentum balances are in galerkin_vi::forcing)"
    )))
}
