//! The state of one step's solve: the Newton iterate (the increments ΔQ_i = Q_i − u_i q_k),
//! the compensated parts of the state and of the result, the linear solve (Newton matrix, LU,
//! right-hand side, the structured solvers' buffers).
//!
//! The iterate lives in increments from q_k so that q_{k+1} = q_k + ΔQ_{n−1} is known to full
//! relative accuracy (docs/DESIGN.md §4); its low part `last_lo` and the state's low parts
//! (`base_err`, `p_err`, from compensated stepping) are carried beside it. Some of this
//! outlives a step on purpose: the factorisation (`lu_valid`, reused across steps when asked).

use super::kronecker::KroneckerWork;
use super::krylov::KrylovWork;
use crate::linalg::Lu;

/// The Newton iterate, its compensation terms and the linear solve.
#[derive(Debug, Clone)]
pub(crate) struct NewtonState {
    /// The Newton unknowns: increments ΔQ_i = Q_i − u_i q_k, row i (n×D; ΔQ_0 = 0).
    pub coeffs: Vec<f64>,
    /// q_k, the start of the current step's curve (D).
    pub base: Vec<f64>,
    /// Low-order part of the compensated q_k (zero unless the step is taken by
    /// `step_compensated`).
    pub base_err: Vec<f64>,
    /// Low-order part of the compensated p_k (likewise).
    pub p_err: Vec<f64>,
    /// Low-order part of ΔQ_{n−1} accumulated by the Newton corrections (D).
    pub last_lo: Vec<f64>,
    /// Total impulse h Σ_j b_j L_q(c_j) of the last solved step (D) …
    pub impulse: Vec<f64>,
    /// … and its low-order part (the impulse is hi + lo to about twice the working precision).
    pub impulse_lo: Vec<f64>,
    /// The step's initial guess (n×D), kept for a retry with exact Newton when a structured
    /// solver fails from it.
    pub start: Vec<f64>,
    /// The stage residual of the iterate is already in the workspace (its norm).
    pub residual_ready: Option<f64>,
    /// The Newton matrix ((n−1)D)².
    pub jac: Vec<f64>,
    /// Its factorisation.
    pub lu: Lu,
    /// Whether `lu` factorises a Newton matrix of the initial-value step (reusable).
    pub lu_valid: bool,
    /// Right-hand side, then the correction ((n−1)D).
    pub rhs: Vec<f64>,
    /// Scratch of the LU solve ((n−1)D).
    pub scratch: Vec<f64>,
    /// Buffers of the Kronecker solver (separable Lagrangians whose tables have a Schur form).
    pub kron: Option<KroneckerWork>,
    /// Buffers of the Newton–Krylov solver (present with `kron`).
    pub krylov: Option<KrylovWork>,
}

impl NewtonState {
    /// Buffers for n basis functions and D coordinates, with the structured solvers' buffers
    /// when available.
    pub(crate) fn new(
        n: usize,
        d: usize,
        kron: Option<KroneckerWork>,
        krylov: Option<KrylovWork>,
    ) -> Self {
        let nu = (n - 1) * d;
        NewtonState {
            coeffs: vec![0.0; n * d],
            base: vec![0.0; d],
            base_err: vec![0.0; d],
            p_err: vec![0.0; d],
            last_lo: vec![0.0; d],
            impulse: vec![0.0; d],
            impulse_lo: vec![0.0; d],
            start: vec![0.0; n * d],
            residual_ready: None,
            jac: vec![0.0; nu * nu],
            lu: Lu::with_capacity(nu),
            lu_valid: false,
            rhs: vec![0.0; nu],
            scratch: vec![0.0; nu],
            kron,
            krylov,
        }
    }
}
