//! The linear algebra of one Newton iteration: the Newton matrix and its LU factorisation
//! (which may outlive a step, when reused across steps), the right-hand side that becomes the
//! correction, and the structured solvers' buffers (Kronecker, Newton–Krylov).
//!
//! Fields are private: whether the factorisation belongs to the current Newton matrix, and
//! may be reused by the next step, is decided by [`NewtonSystem::factor`] and
//! [`NewtonSystem::invalidate`] only.

use super::kronecker::KroneckerWork;
use super::krylov::KrylovWork;
use crate::linalg::Lu;

/// The Newton matrix, its factorisation, the right-hand side and the structured solvers'
/// buffers, for (n−1)D unknowns.
#[derive(Debug, Clone)]
pub(crate) struct NewtonSystem {
    /// The Newton matrix ((n−1)D)², leading `size`² entries used.
    jac: Vec<f64>,
    /// Its factorisation.
    lu: Lu,
    /// Whether `lu` factorises a Newton matrix of the initial-value step (reusable).
    reusable: bool,
    /// Right-hand side, then the correction ((n−1)D).
    rhs: Vec<f64>,
    /// Scratch of the LU solve ((n−1)D).
    scratch: Vec<f64>,
    /// Buffers of the Kronecker solver (separable Lagrangians whose tables have a Schur form).
    kron: Option<KroneckerWork>,
    /// Buffers of the Newton–Krylov solver (present with `kron`).
    krylov: Option<KrylovWork>,
}

impl NewtonSystem {
    /// Buffers for n basis functions and D coordinates, with the structured solvers' buffers
    /// when available.
    pub(crate) fn new(
        n: usize,
        d: usize,
        kron: Option<KroneckerWork>,
        krylov: Option<KrylovWork>,
    ) -> Self {
        let nu = (n - 1) * d;
        NewtonSystem {
            jac: vec![0.0; nu * nu],
            lu: Lu::with_capacity(nu),
            reusable: false,
            rhs: vec![0.0; nu],
            scratch: vec![0.0; nu],
            kron,
            krylov,
        }
    }

    /// The Newton matrix of `size` unknowns (row-major), to be assembled.
    pub(crate) fn jacobian_mut(&mut self, size: usize) -> &mut [f64] {
        &mut self.jac[..size * size]
    }

    /// The assembled Newton matrix of `size` unknowns.
    pub(crate) fn jacobian(&self, size: usize) -> &[f64] {
        &self.jac[..size * size]
    }

    /// The right-hand side (the negated residual), or after a solve the correction.
    pub(crate) fn rhs(&self, size: usize) -> &[f64] {
        &self.rhs[..size]
    }

    /// See [`rhs`](Self::rhs).
    pub(crate) fn rhs_mut(&mut self, size: usize) -> &mut [f64] {
        &mut self.rhs[..size]
    }

    /// Factorise the Newton matrix of `size` unknowns; `reusable`: it belongs to an
    /// initial-value step, so a later step may reuse it. Err: singular.
    pub(crate) fn factor(&mut self, size: usize, reusable: bool) -> Result<(), ()> {
        if self.lu.dim() != size {
            self.lu = Lu::with_capacity(size);
        }
        self.reusable = false;
        self.lu.refactor(&self.jac[..size * size]).map_err(|_| ())?;
        self.reusable = reusable;
        Ok(())
    }

    /// Whether a factorisation of `size` unknowns from an earlier initial-value step is there
    /// to be reused.
    pub(crate) fn reusable(&self, size: usize) -> bool {
        self.reusable && self.lu.dim() == size
    }

    /// The factorisation no longer belongs to the step's Newton matrix (a failed solve, a
    /// reset): the next step refactors.
    pub(crate) fn invalidate(&mut self) {
        self.reusable = false;
    }

    /// rhs ← J⁻¹ rhs with the last factorisation.
    pub(crate) fn solve(&mut self, size: usize) {
        self.lu
            .solve_in_place(&mut self.rhs[..size], &mut self.scratch[..size]);
    }

    /// Whether the structured solvers' buffers exist (Kronecker and Newton–Krylov).
    pub(crate) fn structured(&self) -> bool {
        self.kron.is_some() && self.krylov.is_some()
    }

    /// The Kronecker solver's buffers, if any.
    pub(crate) fn kronecker_mut(&mut self) -> Option<&mut KroneckerWork> {
        self.kron.as_mut()
    }

    /// The Kronecker solve of the right-hand side, if the buffers exist.
    pub(crate) fn kronecker_solve(
        &mut self,
        t: &super::kronecker::KroneckerTables,
        h: f64,
        size: usize,
    ) -> bool {
        match self.kron.as_mut() {
            Some(kw) => {
                kw.solve(t, h, &mut self.rhs[..size]);
                true
            }
            None => false,
        }
    }

    /// The Newton–Krylov buffers and the right-hand side, if the buffers exist.
    pub(crate) fn krylov_mut(
        &mut self,
    ) -> Option<(&mut KroneckerWork, &mut KrylovWork, &mut [f64])> {
        Some((self.kron.as_mut()?, self.krylov.as_mut()?, &mut self.rhs))
    }
}
