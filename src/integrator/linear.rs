//! The linear solve inside one Newton iteration, shared by the nodal equations and the
//! velocity form.

/// Which matrix a Newton iteration's correction is solved with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Linear {
    /// Dense LU of the exact Jacobian (kept while it contracts by
    /// `DenseOptions::reuse_contraction`): quadratic convergence.
    Dense,
    /// The Kronecker solve of the frozen-Hessian Jacobian (simplified Newton): linear
    /// convergence.
    Frozen,
    /// GMRES on the exact Jacobian, preconditioned by the Kronecker solve (nodal equations
    /// only).
    Krylov,
}
