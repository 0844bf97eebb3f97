//! Built-in mechanical systems: the harmonic oscillator and the planar Kepler problem of the
//! paper's §5 (with exact solutions), the gravitational N-body problem of its §5.2.2, and the
//! simple pendulum, the Fermi–Pasta–Ulam chain of stiff and soft springs ([`Fpu`], Hairer,
//! Lubich and Wanner's multiscale test problem), and the stiff spring pendulum
//! ([`SpringPendulum`], a fast frequency that depends on the state).
//!
//! Each implements [`Mechanical`](crate::Mechanical) with hand-written gradient and Hessian
//! (the AD defaults are checked against them in tests) and [`System`], which adds the
//! invariants reported in output and, where known, the exact solution. [`AnySystem`] holds any
//! of them chosen at run time (a scene file) and implements both traits by dispatch.
//!
//! Also here: [`ExpressionLagrangian`] (a Lagrangian parsed from text and compiled to a tape,
//! differentiated by AD), and [`kepler_orbit`] (Kepler's equation solved to round-off, the
//! reference for every Kepler study). The scene files of the `gvi` tool name these systems by
//! their `type`; the N-body page of the guide (docs/guide/nbody.md) describes the solar-system
//! scenes and their sources.

mod any;
pub mod expression;
mod fpu;
mod harmonic;
mod kepler;
pub mod kepler_orbit;
mod nbody;
mod pendulum;
mod spring_pendulum;

pub use any::AnySystem;
pub use expression::ExpressionLagrangian;
pub use fpu::Fpu;
pub use harmonic::HarmonicOscillator;
pub use kepler::Kepler;
pub use nbody::NBody;
pub use pendulum::Pendulum;
pub use spring_pendulum::SpringPendulum;

use crate::error::Result;
use crate::lagrangian::Lagrangian;

/// A Lagrangian system with named invariants and, possibly, an exact solution.
pub trait System: Lagrangian {
    /// Short name, e.g. "kepler".
    fn name(&self) -> &'static str;

    /// Names of the invariants [`invariants`](System::invariants) returns, in order; used as
    /// CSV column names (e.g. `energy`, `angular_momentum`).
    fn invariant_names(&self) -> &'static [&'static str];

    /// The invariants at the phase-space point (q, p), into `out`
    /// (length `invariant_names().len()`).
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]);

    /// The continuous symmetries of the Lagrangian as momentum maps (discrete Noether: the
    /// integrator conserves them at step ends). Default: none.
    fn symmetries(&self) -> Vec<crate::symmetries::NamedMomentumMap> {
        Vec::new()
    }

    /// For systems of point masses: the body names, in the order of the (body-major)
    /// configuration vector. Charts draw one orbit per body. Default: `None`.
    fn body_names(&self) -> Option<Vec<String>> {
        None
    }

    /// The shortest dynamical time scale at (q, p) — for N bodies the shortest two-body
    /// period — used to choose the step of numerical reference solutions. Default: unknown.
    fn shortest_time_scale(&self, q: &[f64], p: &[f64]) -> Option<f64> {
        let _ = (q, p);
        None
    }

    /// The exact solution through (q0, p0) at t0, if this system has one in closed form.
    /// `Ok(None)` when none is known for this system or this initial state.
    fn exact_solution(&self, t0: f64, q0: &[f64], p0: &[f64]) -> Result<Option<ExactSolution>> {
        let _ = (t0, q0, p0);
        Ok(None)
    }
}

/// A closed-form solution t ↦ (q(t), p(t)).
pub struct ExactSolution {
    state: Box<StateFn>,
}

type StateFn = dyn Fn(f64) -> (Vec<f64>, Vec<f64>) + Send + Sync;

impl ExactSolution {
    /// Wrap a closed-form state function.
    pub fn new(state: impl Fn(f64) -> (Vec<f64>, Vec<f64>) + Send + Sync + 'static) -> Self {
        ExactSolution {
            state: Box::new(state),
        }
    }

    /// (q(t), p(t)).
    pub fn state(&self, t: f64) -> (Vec<f64>, Vec<f64>) {
        (self.state)(t)
    }

    /// q(t).
    pub fn position(&self, t: f64) -> Vec<f64> {
        self.state(t).0
    }
}

impl std::fmt::Debug for ExactSolution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ExactSolution")
    }
}

/// Check that a physical parameter is finite and positive.
pub(crate) fn positive(name: &str, value: f64) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(crate::GviError::InvalidParameter {
            name: name.into(),
            value,
            reason: "must be finite and positive".into(),
        })
    }
}

#[cfg(test)]
pub(crate) mod derivative_tests {
    use crate::Mechanical;

    /// Compare hand-written ∇V and ∇²V with AD (through `potential`) and central differences.
    pub fn check_against_ad<S: Mechanical>(s: &S, q: &[f64]) {
        let d = s.degrees_of_freedom();
        let mut g = vec![0.0; d];
        let mut h = vec![0.0; d * d];
        s.potential_gradient(q, &mut g);
        s.potential_hessian(q, &mut h);
        let mut g_ad = vec![0.0; d];
        crate::ad::gradient(|y| s.potential(y), q, &mut g_ad);
        let mut g2 = vec![0.0; d];
        let mut h_ad = vec![0.0; d * d];
        crate::ad::hessian(|y| s.potential(y), q, &mut g2, &mut h_ad);
        let gs = g.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        let hs = h.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        for i in 0..d {
            assert!((g[i] - g_ad[i]).abs() <= 1e-13 * gs, "gradient {i}");
        }
        for i in 0..d * d {
            assert!((h[i] - h_ad[i]).abs() <= 1e-13 * hs, "hessian {i}");
        }
        // Central differences of the hand-written gradient.
        let eps = 1e-6;
        for c in 0..d {
            let mut qp = q.to_vec();
            let mut qm = q.to_vec();
            qp[c] += eps;
            qm[c] -= eps;
            let (mut gp, mut gm) = (vec![0.0; d], vec![0.0; d]);
            s.potential_gradient(&qp, &mut gp);
            s.potential_gradient(&qm, &mut gm);
            for r in 0..d {
                let fd = (gp[r] - gm[r]) / (2.0 * eps);
                assert!(
                    (fd - h[r * d + c]).abs() <= 1e-6 * hs,
                    "FD hessian ({r},{c})"
                );
            }
        }
    }
}
