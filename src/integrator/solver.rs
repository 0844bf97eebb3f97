//! The stage-solver layer: how the nonlinear stage equations of each step are solved.
//!
//! Every solver returns the same one-step map (the exact-Newton solution of the stage
//! equations, to their round-off); they differ in cost. Chosen by value, like bases and
//! quadratures: `NewtonOptions::solver`, `--solver` on the command line, `solver = "…"` in a
//! scene's `[method]` table.

use crate::error::GviError;
use serde::{Deserialize, Serialize};

/// A stage solver.
///
/// ```
/// use galerkin_vi::prelude::*;
/// use galerkin_vi::integrator::{NewtonOptions, StageSolver};
///
/// let kepler = Kepler::new(1.0)?;
/// let (q0, p0) = Kepler::paper_initial_state();
/// let run = |solver| -> Result<Vec<f64>, Box<dyn std::error::Error>> {
///     let options = NewtonOptions { solver, ..NewtonOptions::default() };
///     let gvi = GalerkinIntegrator::spectral(16, 1.0)?.with_options(options);
///     let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 20)?;
///     Ok(traj.q[20].clone())
/// };
/// let (exact, kron) = (run(StageSolver::Exact)?, run(StageSolver::Kronecker)?);
/// assert!((exact[0] - kron[0]).abs() < 1e-12 && (exact[1] - kron[1]).abs() < 1e-12);
/// assert_eq!("kronecker".parse::<StageSolver>()?, StageSolver::Kronecker);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum StageSolver {
    /// Choose per system: dense exact Newton up to a Newton-system size (n − 1)·D of 64; above
    /// it the frozen-Hessian solver, refrozen once when it stalls, then Newton–Krylov (kept for
    /// the next 32 solves), then dense — escalating within a step. Non-separable Lagrangians
    /// always use exact Newton.
    #[default]
    Auto,
    /// Newton's method with the exact Jacobian, assembled and LU-factorised densely
    /// (O((nD)³) per factorisation): the reference.
    Exact,
    /// Simplified Newton with the force Jacobian frozen at its quadrature-weighted mean over
    /// the step, solved through the Kronecker structure of the stage Jacobian
    /// (O(n²D + nD²) per iteration, O(nD³) per step; separable Lagrangians). For systems with
    /// coordinate blocks (N-body) the fastest bodies, those with h² |μ| above
    /// [`StructuredOptions::self_block_rate`](super::StructuredOptions::self_block_rate), are solved
    /// with their exact time-varying self-blocks instead of the frozen mean (at most eight;
    /// Mercury and Venus in the paper's 10-body run). A step it fails is retried with exact
    /// Newton, as for every structured solver.
    Kronecker,
    /// Matrix-free Newton–Krylov: GMRES on the exact Newton matrix (products from force
    /// Jacobians at the nodes, never the (nD)² matrix), right-preconditioned by the
    /// Kronecker solve (separable Lagrangians).
    NewtonKrylov,
    /// Fixed-point iteration with no force Jacobian: the kinetic part of the stage equations
    /// is solved exactly (the Kronecker solve with H̄ = 0) and the forces are taken from the
    /// previous iterate, as IAS15's predictor–corrector and fixed-point IRK codes do. No
    /// Hessian is ever evaluated; it contracts by about (hω)² per iteration, so it suits small
    /// h·ω, and a step that does not contract continues with the frozen-Hessian solver
    /// (separable Lagrangians).
    FixedPoint,
    /// Newton on the stage equations written in the Legendre modes of the velocity, where the
    /// kinetic matrix is the identity and the Newton matrix is M plus an O(h²) term: no
    /// kinetic sums in the residual, a factorisation kept across steps (dense up to
    /// (n − 1)·D = 64, the frozen-Hessian Kronecker solve above). The same map as the nodal
    /// equations (polynomial bases with a rule exact for the kinetic term; otherwise, and
    /// for a step it does not solve, the nodal `auto` solvers run).
    Modal,
}

impl StageSolver {
    /// All solvers, for sweeps.
    pub const ALL: [StageSolver; 6] = [
        StageSolver::Auto,
        StageSolver::Exact,
        StageSolver::Kronecker,
        StageSolver::NewtonKrylov,
        StageSolver::FixedPoint,
        StageSolver::Modal,
    ];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            StageSolver::Auto => "auto",
            StageSolver::Exact => "exact",
            StageSolver::Kronecker => "kronecker",
            StageSolver::NewtonKrylov => "newton-krylov",
            StageSolver::FixedPoint => "fixed-point",
            StageSolver::Modal => "modal",
        }
    }
}

impl std::fmt::Display for StageSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for StageSolver {
    type Err = GviError;
    fn from_str(s: &str) -> Result<Self, GviError> {
        StageSolver::ALL
            .into_iter()
            .find(|k| k.as_str().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| GviError::InvalidInput {
                name: "solver".into(),
                reason: format!(
                    "unknown stage solver '{s}' (expected one of: {})",
                    StageSolver::ALL.map(|k| k.as_str()).join(", ")
                ),
            })
    }
}
