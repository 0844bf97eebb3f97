//! Newton settings ([`NewtonOptions`]). How each step's iteration starts ([`InitialGuess`])
//! and what a step cost ([`StepStats`]) live in [`crate::stats`], which the trajectory shares.

use super::solver::StageSolver;
pub use crate::stats::{InitialGuess, StepFailure, StepStats};
use serde::{Deserialize, Serialize};

/// Newton iteration settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NewtonOptions {
    /// Iteration limit per step.
    pub max_iterations: usize,
    /// Stop when the estimated remaining error of the Newton unknowns (the increments
    /// ΔQ_i = Q_i − u_i q_k) is below `tolerance · max|ΔQ|` (error estimated from the
    /// contraction of successive Newton increments). The default 1e-16 is just below ε: with
    /// 1e-15 the Hermite and Chebyshev flows of `tests/bases.rs` drift apart by 1.1e-10 in
    /// 10 steps at n = 22 (the solve error, not the basis); 1e-16 costs 2.61 linear solves per
    /// step at n = 32, h = 2 with the exactly summed residuals of
    /// [`exact_kinetic`](Self::exact_kinetic) (2.96 with rounded ones; `tests/counts.rs`). The
    /// long-run results of `tests/roundoff.rs` are measured with the default.
    pub tolerance: f64,
    /// Also stop, as converged at the round-off floor, once increments below
    /// `floor_tolerance · max|ΔQ|` stop shrinking (iterating further only stirs noise).
    pub floor_tolerance: f64,
    /// How each step's iteration starts.
    pub initial_guess: InitialGuess,
    /// Substeps of the RK4 predictor guess (`None`: max(n, 8)).
    pub predictor_substeps: Option<usize>,
    /// Accumulate q and p across steps with compensated (Kahan–Babuška/TwoSum) summation of
    /// the step increments, in [`integrate`](crate::integrator::GalerkinIntegrator::integrate) and the
    /// [`GalerkinMethod`](crate::baselines::GalerkinMethod) adapter (docs/DESIGN.md §4). Costs 2D
    /// extra additions per step; removes the O(√N ε) (or O(N ε)) round-off drift of the
    /// naive sums over N steps.
    #[serde(default = "default_true")]
    pub compensated: bool,
    /// Sum the kinetic part (1/h) Σ_b K_ab M ΔQ_b of the stage rows in Newton's residuals in
    /// double-double (exact products by FMA, TwoSum) instead of one rounded matrix product
    /// (default true; the residuals that only rank initial guesses stay rounded). Rounded,
    /// those products leave an error ≈ ε·|K|·|ΔQ|/h in the stage rows, which the Newton matrix
    /// (condition up to 1e8 with nodal bases) turns into a solution error along directions the
    /// residual barely sees, and which carries a one-signed bias when K's entries are not
    /// short binary fractions (the Chebyshev–Lagrange basis; the Legendre basis's entries are
    /// snapped to exact values). Measured, rounded → exact: the symmetric two-body problem
    /// (Chebyshev n = 24, h = 2, 100 steps) keeps its barycentre to 2.8e-16 instead of 4.5e-13
    /// and its relative motion within 5.8e-12 of the Kepler run instead of 2.6e-10; Kepler
    /// e = 0.6 over T = 20,000 with Chebyshev n = 24, h = 0.5 reaches 1.8e-8 instead of
    /// 1.9e-7; Newton needs 2.61 instead of 2.96 solves per step (n = 32, h = 2). Costs
    /// ≈ n² D TwoProds per residual (≈ 7 % of the step at n = 10, nothing measurable at
    /// n = 24). Concerns the nodal stage equations only: the velocity form
    /// ([`StageSolver::Modal`], `auto`'s choice where it exists) has no kinetic sums.
    #[serde(default = "default_true")]
    pub exact_kinetic: bool,
    /// How the linear systems of the iteration are solved ([`StageSolver`]): the dense exact
    /// Jacobian, or the Kronecker-structured frozen-Hessian Jacobian.
    #[serde(default)]
    pub solver: StageSolver,
    /// Options of the dense exact-Newton solve: the `exact` solver, `auto` up to a Newton system
    /// of 64 unknowns, and every dense fallback.
    #[serde(default)]
    pub dense: DenseOptions,
    /// Options of the structured solves: `kronecker`, `newton-krylov`, `fixed-point` and `auto`
    /// above 64 unknowns.
    #[serde(default)]
    pub structured: StructuredOptions,
}

fn default_self_block_rate() -> f64 {
    super::self_blocks::FAST_RATE
}

fn default_velocity_self_block_rate() -> f64 {
    super::self_blocks::VELOCITY_FAST_RATE
}

fn default_velocity_fixed_point_handover() -> f64 {
    super::velocity::FIXED_POINT_HANDOVER
}

fn default_true() -> bool {
    true
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            max_iterations: 40,
            tolerance: 1e-16,
            floor_tolerance: 1e-10,
            initial_guess: InitialGuess::BestResidual,
            predictor_substeps: None,
            exact_kinetic: true,
            compensated: true,
            solver: StageSolver::Auto,
            dense: DenseOptions::default(),
            structured: StructuredOptions::default(),
        }
    }
}

/// Options of the dense exact-Newton solve (the `exact` solver and every dense fallback).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DenseOptions {
    /// Simplified Newton: reuse the factorised Jacobian across iterations and steps while
    /// the iteration contracts by at least `reuse_contraction` per iteration.
    pub reuse_jacobian: bool,
    /// Contraction factor above which a reused Jacobian is refactorised (full Newton).
    pub reuse_contraction: f64,
    /// Also start each step with the previous step's factorisation (pays off when h is small
    /// compared with the time scale, so that the Newton matrix changes little per step).
    pub reuse_across_steps: bool,
}

impl Default for DenseOptions {
    fn default() -> Self {
        DenseOptions {
            reuse_jacobian: true,
            reuse_contraction: 0.1,
            reuse_across_steps: false,
        }
    }
}

/// Options of the structured solves (`kronecker`, `newton-krylov`, `fixed-point`, and `auto`
/// above 64 unknowns).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StructuredOptions {
    /// The structured solvers' preconditioner treats a block of coordinates (a body of an
    /// N-body system) exactly, with its time-varying self-block instead of the frozen mean,
    /// when h² max |μ| exceeds this rate, μ the eigenvalues of the block's mean force Jacobian
    /// relative to its mass (h² |μ| ≈ (h ω)² for a body of orbital frequency ω). Default 4:
    /// at the paper's h = 100 d that is Mercury and Venus ((h ω)² ≈ 50 and 8), which makes the
    /// frozen iteration contract where the frozen mean stalls (docs/solvers.md). At most
    /// eight blocks, the fastest, are treated exactly. Set to
    /// `f64::MAX` to turn it off. Concerns the nodal stage equations of systems with
    /// coordinate blocks only (N-body); the map does not change.
    pub self_block_rate: f64,
    /// The same threshold for the frozen iteration of the velocity form (the default route of
    /// separable systems, docs/solvers.md), whose exact self-blocks are those of its own
    /// Newton matrix. Default 1: measured on the outer solar system (h = 912.5 d, Chebyshev
    /// n = 10, 15 points: Jupiter alone, 31 % fewer force evaluations, 8.6 % fewer instructions)
    /// and the J2000 10-body scene (h = 12.5 d, n = 10, 10 points: 27 % fewer force
    /// evaluations, 11 % fewer instructions); at 0.5 more bodies are treated exactly and the
    /// factorisations cost what the iterations save on the outer solar system. The map
    /// does not change beyond round-off (the iteration stops at the same tolerance).
    #[serde(default = "default_velocity_self_block_rate")]
    pub velocity_self_block_rate: f64,
    /// The velocity form starts each step with fixed-point iterations — its Newton matrix
    /// without the force term, I ⊗ M: no force Jacobian, no factorisation, a correction that
    /// costs a division — and hands the step over to the frozen Hessian when they contract by
    /// less than this per iteration. The fixed-point iteration contracts at about
    /// h² ρ(C) max|M⁻¹H|, ρ(C) = 5.9e-3 at n = 10 (docs/solvers.md), which is small at the
    /// step sizes of the spectral method's n-refinement. Two hand-overs within 8 steps start
    /// the next 32 with the frozen Hessian. Default 0.5, measured in instructions against 0.05,
    /// 0.1, 0.2, 0.3, 0.7 and 0.9 (Kepler e = 0.6 at h = 0.4, n = 13: the higher the better up
    /// to 0.5, then within 2 %; the N-body configurations of issue 35: flat from 0.1). 0 turns
    /// the fixed-point start off (every step starts with the frozen Hessian, as before this
    /// option). The map does not change beyond round-off (the iteration stops at the same
    /// tolerance).
    #[serde(default = "default_velocity_fixed_point_handover")]
    pub velocity_fixed_point_handover: f64,
    /// In the fixed-point iteration, stop iterating the coordinate blocks
    /// (`Lagrangian::coordinate_blocks`: the bodies of an N-body system) whose corrections
    /// pass the iteration's own convergence test, and evaluate the residual and the forces
    /// (`Lagrangian::force_at_points_on_blocks`) on the others only; once every block is
    /// frozen, one correction of all of them decides convergence as usual. For a diagonal
    /// mass matrix and at least two blocks. The map does not change beyond round-off (the
    /// iteration stops at the same tolerance, on a correction of every block). Default on.
    #[serde(default = "default_true")]
    pub velocity_freeze_converged_blocks: bool,
}

impl Default for StructuredOptions {
    fn default() -> Self {
        StructuredOptions {
            self_block_rate: default_self_block_rate(),
            velocity_self_block_rate: default_velocity_self_block_rate(),
            velocity_fixed_point_handover: default_velocity_fixed_point_handover(),
            velocity_freeze_converged_blocks: true,
        }
    }
}
