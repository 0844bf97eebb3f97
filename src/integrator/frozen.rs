//! Freezing the force Jacobian for the structured solvers: H̄, the quadrature-weighted mean
//! of the node Jacobians (or only its diagonal blocks, which is all a block-diagonal
//! preconditioner uses), the node Jacobians for Newton–Krylov's products, and the choice
//! `auto` makes per workspace.

use super::kronecker::{KroneckerTables, KroneckerWorkParts};
use crate::error::{GviError, Result};

impl<B: crate::basis::Basis, Q: crate::quadrature::Quadrature> super::GalerkinIntegrator<B, Q> {
    /// Freeze the force Jacobian at its quadrature-weighted mean H̄ = Σ_j b_j L_qq(q(c_j)) over
    /// the curve last evaluated in `ws`, and factorise the Kronecker solver's diagonal blocks.
    /// Returns the Hessian evaluations. With `kinetic_only` H̄ = 0 (the fixed-point
    /// iteration) and no Hessian is evaluated.
    pub(super) fn freeze_hessian<L: crate::lagrangian::Lagrangian>(
        &self,
        lag: &L,
        ws: &mut super::Workspace,
        kinetic_only: bool,
    ) -> Result<usize> {
        let t = self.tables();
        let (m, h) = (t.m, self.step_size());
        let (Some(kt), Some(kw)) = (t.kron(), ws.system.kronecker_mut()) else {
            return Err(GviError::Unsupported(
                "the Kronecker solver needs a separable Lagrangian".into(),
            ));
        };
        if kinetic_only {
            kw.hbar.iter_mut().for_each(|x| *x = 0.0);
            kw.factor(kt, h)?;
            kw.exact.clear();
            return Ok(0);
        }
        self.mean_force_jacobian(lag, &mut ws.stage, kw);
        kw.factor(kt, h)?;
        if let Some(sep) = ws.separable.as_ref() {
            // The exact self-blocks of the fast bodies, from the node Jacobians' diagonal
            // blocks (or the full node Jacobians) at the freeze.
            let (d, b) = (kw.dim(), kw.block());
            let stage = &ws.stage;
            let KroneckerWorkParts { exact, mu } = kw.parts();
            if !stage.node_jacobians_current() {
                exact.factor(t, h, sep.mass(), mu, |j, r, s| {
                    stage.hblocks[j * d * b + (r / b) * b * b + (r % b) * b + s % b]
                });
            } else {
                exact.factor(t, h, sep.mass(), mu, |j, r, s| {
                    stage.hall[j * d * d + r * d + s]
                });
            }
        }
        Ok(m)
    }

    /// H̄ = Σ_j b_j L_qq(q(c_j)) over the nodes in `stage.qj` into `kw.hbar` (only its
    /// diagonal blocks when the system provides them and the frozen solve uses only those).
    /// Returns the Hessian evaluations.
    pub(super) fn mean_force_jacobian<L: crate::lagrangian::Lagrangian>(
        &self,
        lag: &L,
        stage: &mut super::stage_scratch::StageScratch,
        kw: &mut super::kronecker::KroneckerWork,
    ) -> usize {
        let t = self.tables();
        let d = kw.dim();
        let dd = d * d;
        kw.hbar.iter_mut().for_each(|x| *x = 0.0);
        if stage.evaluate_node_jacobian_blocks(lag) {
            // Only the diagonal blocks of H̄ are used (block-diagonal preconditioner): the
            // same weighted sums of the same entries, without forming the node Jacobians.
            let b = kw.block();
            let (bb, blocks) = (b * b, d / b);
            for (j, hj) in stage.hblocks.chunks_exact(d * b).enumerate() {
                let w = t.weights[j];
                for c in 0..blocks {
                    for r in 0..b {
                        for s in 0..b {
                            kw.hbar[(c * b + r) * d + c * b + s] += w * hj[c * bb + r * b + s];
                        }
                    }
                }
            }
        } else {
            stage.evaluate_node_jacobians(lag);
            for (j, hj) in stage.hall.chunks_exact(dd).enumerate() {
                let w = t.weights[j];
                for (x, y) in kw.hbar.iter_mut().zip(hj) {
                    *x += w * y;
                }
            }
        }
        t.m
    }
}

impl<B: crate::basis::Basis, Q: crate::quadrature::Quadrature> super::GalerkinIntegrator<B, Q> {
    /// Force Jacobians L_qq at every node of the curve last evaluated in `ws`, into
    /// `ws.stage.hall`. Returns the Hessian evaluations.
    pub(super) fn node_force_jacobians<L: crate::lagrangian::Lagrangian>(
        &self,
        lag: &L,
        ws: &mut super::Workspace,
    ) -> usize {
        if ws.matrix_free {
            // The products are evaluated pairwise by the system when GMRES needs them.
            return 0;
        }
        ws.stage.evaluate_node_jacobians(lag);
        self.tables().m
    }

    /// The eigenvalues (re, im) of the stage pencil C = K_s⁻¹ G_s that the Kronecker solver
    /// decouples (module docs of the solvers): rows 0…n−2 and columns 1…n−1 of the kinetic
    /// matrix K and of the mass Gram matrix G_ab = Σ_j b_j φ_a(c_j) φ_b(c_j). They depend on
    /// the approximation space and the quadrature only, so every polynomial basis of the same
    /// n gives the same values. `None` when the Schur form could not be computed.
    ///
    /// ```
    /// use galerkin_vi::prelude::*;
    ///
    /// let cheb = GalerkinIntegrator::from_kinds(BasisKind::Chebyshev, 8, QuadratureKind::default(), None, 1.0)?;
    /// let leg = GalerkinIntegrator::from_kinds(BasisKind::Legendre, 8, QuadratureKind::default(), None, 1.0)?;
    /// let (mut a, mut b) = (cheb.stage_pencil_eigenvalues().unwrap(), leg.stage_pencil_eigenvalues().unwrap());
    /// a.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
    /// b.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.total_cmp(&y.1)));
    /// for (x, y) in a.iter().zip(&b) {
    ///     assert!((x.0 - y.0).abs() < 1e-12 && (x.1 - y.1).abs() < 1e-12);
    /// }
    /// # Ok::<(), galerkin_vi::GviError>(())
    /// ```
    pub fn stage_pencil_eigenvalues(&self) -> Option<Vec<(f64, f64)>> {
        self.tables().kron().map(KroneckerTables::eigenvalues)
    }

    /// Whether the stage equations can be solved in their velocity form (`StageSolver::Modal`,
    /// chosen by `Auto` for separable Lagrangians): a polynomial basis and a rule that
    /// integrates the kinetic term exactly (Gauss–Legendre with at least n − 1 points), where
    /// it is the nodal map written in the Legendre modes of the velocity (docs/solvers.md).
    ///
    /// ```
    /// use galerkin_vi::prelude::*;
    ///
    /// assert!(GalerkinIntegrator::spectral(16, 1.0)?.has_velocity_form());
    /// let fourier = GalerkinIntegrator::from_kinds(BasisKind::Fourier, 9, QuadratureKind::default(), None, 1.0)?;
    /// assert!(!fourier.has_velocity_form());
    /// # Ok::<(), galerkin_vi::GviError>(())
    /// ```
    pub fn has_velocity_form(&self) -> bool {
        self.tables().velocity.is_some()
    }
}
