//! What one step of the Galerkin integrator did: how its Newton iteration started
//! ([`InitialGuess`]), what it cost ([`StepStats`]) and, if it failed, why ([`StepFailure`]).
//!
//! These are plain records shared by the integrator (which fills them) and the
//! [`Trajectory`](crate::trajectory::Trajectory) (which stores one per step); they live here,
//! outside both, so that neither module imports the other's internals. The integrator
//! re-exports them (`galerkin_vi::integrator::StepStats` and so on).

use serde::{Deserialize, Serialize};

/// How the Newton iteration of each step is started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum InitialGuess {
    /// The constant curve q(t) = q_k.
    Constant,
    /// The straight line q_k + (t − t_k) v_k, with v_k the end velocity of the previous curve
    /// (or the inverse Legendre transform of p_k on the first step).
    Linear,
    /// The previous step's Galerkin curve continued over the new step.
    Extrapolate,
    /// A cheap explicit predictor: classical Runge–Kutta 4 on the Euler–Lagrange equations
    /// q̈ = M⁻¹ L_q(q) over the step (separable Lagrangians only), sampled at the basis's
    /// interpolation nodes by cubic Hermite interpolation and fitted in the basis.
    Predictor,
    /// Whichever of the three has the smallest stage residual (with very large steps
    /// extrapolation can be worse than a constant guess, so it is measured, not assumed).
    #[default]
    BestResidual,
    /// Coefficients supplied for one step by [`Workspace::warm_start`](crate::integrator::Workspace::warm_start) (reported in
    /// [`StepStats::guess`]; as an option it behaves like `BestResidual`).
    Warm,
}

/// What one step cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct StepStats {
    /// Newton iterations (Jacobian factorisations) taken.
    pub iterations: usize,
    /// Max-norm of the stage residual at the accepted coefficients.
    pub residual: f64,
    /// Evaluations of the Lagrangian's first derivatives (or force), counted per quadrature
    /// point, plus the force evaluations of the RK4 predictor guess: the "right-hand-side
    /// evaluations" of the step.
    pub gradient_evaluations: usize,
    /// Evaluations of the forces on some coordinate blocks only, per quadrature point: the
    /// velocity form's fixed-point iterations after some blocks converged
    /// (`StructuredOptions::velocity_freeze_converged_blocks`); not counted in
    /// `gradient_evaluations`.
    #[serde(default)]
    pub partial_gradient_evaluations: usize,
    /// Evaluations of second derivatives, per quadrature point.
    pub hessian_evaluations: usize,
    /// LU factorisations of the Newton matrix (for the Kronecker solver: freezes of the
    /// Hessian, each factorising the n − 1 small diagonal blocks).
    pub factorizations: usize,
    /// Iterations of the structured (Kronecker) solver that stalled and were continued with
    /// the exact Jacobian.
    #[serde(default)]
    pub fallbacks: usize,
    /// Krylov (GMRES) iterations of the Newton–Krylov solver.
    #[serde(default)]
    pub inner_iterations: usize,
    /// The initial guess that was used.
    pub guess: InitialGuess,
}

/// A step's Newton failure, as returned by [`GalerkinIntegrator::step`](crate::integrator::GalerkinIntegrator::step) (and turned into
/// [`GviError::NewtonFailure`](crate::GviError::NewtonFailure) by `integrate`).
#[derive(Debug, Clone, PartialEq)]
pub struct StepFailure {
    /// Max-norm of the stage residual at the last iterate.
    pub residual: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// Why it stopped.
    pub reason: String,
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Newton's iteration failed after {} iterations (stage residual {:.3e}): {}",
            self.iterations, self.residual, self.reason
        )
    }
}

impl std::error::Error for StepFailure {}
