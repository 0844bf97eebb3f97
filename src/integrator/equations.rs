//! Pluggable stage solvers: the stage equations of one step as a problem
//! ([`StageEquations`]) and a solver of them ([`StageSolve`]), separate pieces as the cost
//! functions and solvers of argmin are.
//!
//! The built-in solvers are the values of [`StageSolver`] (exact Newton, the Kronecker
//! frozen-Hessian iteration, Newton–Krylov, fixed point, and `auto`), chosen by name on the
//! command line and in scene files. A researcher who wants another iteration — a different
//! forcing term, a line search, a quasi-Newton update — implements [`StageSolve`] and hands it
//! to [`GalerkinIntegrator::with_stage_solver`]; it then sees the same operations the built-in
//! solvers are made of:
//!
//! - the residual F(ΔQ) of the stage equations (the Legendre-transform row and the
//!   u-weighted stage rows; paper eqs. (3)–(4)) at the current iterate, negated, in
//!   [`correction`](StageEquations::correction);
//! - exact products J x with the Newton matrix, matrix-free
//!   ([`jacobian_product`](StageEquations::jacobian_product));
//! - three linear solves in place on the correction: dense LU of the exact Jacobian, the
//!   Kronecker solve of the frozen-Hessian Jacobian K ⊗ M + h² B ⊗ H̄, and GMRES on the exact
//!   Jacobian preconditioned by it;
//! - the compensated update ΔQ ← ΔQ + δ ([`apply_correction`](StageEquations::apply_correction));
//! - and any built-in solver from the current iterate ([`solve_with`](StageEquations::solve_with)),
//!   as a fallback.
//!
//! Evaluations are counted into the step's [`StepStats`] as for the built-in solvers. The
//! integrator re-evaluates the residual at the iterate a solver returns, so the step's
//! momentum and statistics always describe the final iterate.

use super::node_model::node_hessian;
use super::stage::Mode;
use super::{GalerkinIntegrator, NewtonOptions, StageSolver, StepFailure, StepStats, Workspace};
use crate::basis::Basis;
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

/// A solver of the stage equations of one step.
///
/// `solve` starts from the iterate the integrator's initial guess left in the equations and
/// returns `Ok` once it considers them solved, or a [`StepFailure`] (the integrator then
/// retries from its other initial guesses, and reports the failure with the step number and
/// the trajectory so far if none succeeds).
///
/// A damped Newton iteration with the dense exact Jacobian, written with the public
/// operations only, gives the built-in exact solver's map:
///
/// ```
/// use galerkin_vi::prelude::*;
/// use galerkin_vi::integrator::{StageEquations, StageSolve, StageSolver, StepFailure};
///
/// #[derive(Debug)]
/// struct PlainNewton;
///
/// impl StageSolve for PlainNewton {
///     fn name(&self) -> &str {
///         "plain-newton"
///     }
///     fn solve(&self, eq: &mut dyn StageEquations) -> Result<(), StepFailure> {
///         for it in 0..eq.options().max_iterations {
///             let residual = eq.residual();
///             if !residual.is_finite() {
///                 return Err(StepFailure { residual, iterations: it, reason: "diverged".into() });
///             }
///             eq.solve_exact()?;
///             let step = eq.apply_correction();
///             if step.size <= 1e-15 * step.scale {
///                 return Ok(());
///             }
///         }
///         Err(StepFailure { residual: eq.residual(), iterations: 0, reason: "no convergence".into() })
///     }
/// }
///
/// let kepler = Kepler::new(1.0)?;
/// let (q0, p0) = Kepler::paper_initial_state();
/// let exact = NewtonOptions { solver: StageSolver::Exact, ..NewtonOptions::default() };
/// let builtin = GalerkinIntegrator::spectral(12, 0.5)?.with_options(exact);
/// let custom = GalerkinIntegrator::spectral(12, 0.5)?.with_stage_solver(PlainNewton);
/// let (a, b) = (builtin.integrate(&kepler, 0.0, &q0, &p0, 40)?, custom.integrate(&kepler, 0.0, &q0, &p0, 40)?);
/// assert!((a.q[40][0] - b.q[40][0]).abs() < 1e-13 && (a.p[40][1] - b.p[40][1]).abs() < 1e-13);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub trait StageSolve: std::fmt::Debug + Send + Sync {
    /// A short name for output (e.g. `plain-newton`).
    fn name(&self) -> &str;
    /// Solve the stage equations from their current iterate.
    fn solve(&self, equations: &mut dyn StageEquations) -> Result<(), StepFailure>;
}

/// The built-in solvers are stage solvers too (so a custom solver can wrap one).
impl StageSolve for StageSolver {
    fn name(&self) -> &str {
        self.as_str()
    }
    fn solve(&self, equations: &mut dyn StageEquations) -> Result<(), StepFailure> {
        equations.solve_with(*self)
    }
}

pub use crate::newton::Correction;

/// The stage equations of one initial-value step, F(ΔQ) = 0 in the increments
/// ΔQ_1 … ΔQ_{n−1} of the Galerkin curve's coefficients, as a stage solver sees them.
///
/// Vectors of unknowns are (n − 1)·D long, block a − 1 holding ΔQ_a; residual rows are in
/// the same layout, row block 0 being the discrete Legendre transform p_k = −D₁L_d combined
/// with the stage rows (the form the built-in solvers use).
pub trait StageEquations {
    /// Configuration dimension D.
    fn dim(&self) -> usize;
    /// Number of unknowns (n − 1)·D.
    fn unknowns(&self) -> usize;
    /// The integrator's Newton options (tolerances, iteration limit).
    fn options(&self) -> &NewtonOptions;
    /// The current iterate ΔQ_1 … ΔQ_{n−1} (its high parts; the last block also carries a
    /// low part below its ulp, which the equations keep).
    fn iterate(&self) -> &[f64];
    /// Evaluate the residual at the current iterate: −F is left in
    /// [`correction`](Self::correction) and max |F| returned (∞ if any entry is non-finite).
    fn residual(&mut self) -> f64;
    /// The correction vector: −F after [`residual`](Self::residual), overwritten by the
    /// linear solves with the correction δ, and read by
    /// [`apply_correction`](Self::apply_correction). A solver may also write its own δ here.
    fn correction(&mut self) -> &mut [f64];
    /// ΔQ ← ΔQ + δ (the last block compensated), counted as one iteration.
    fn apply_correction(&mut self) -> Correction;
    /// δ ← J⁻¹ δ in place, with the exact Jacobian at the current iterate assembled densely
    /// and LU-factorised (O((nD)³)).
    fn solve_exact(&mut self) -> Result<(), StepFailure>;
    /// δ ← J⁻¹ δ in place with the last LU factorisation (from `solve_exact` in this step,
    /// at an earlier iterate: a simplified Newton step). Returns `false`, leaving δ as it
    /// was, when there is none.
    fn solve_reused(&mut self) -> bool;
    /// Freeze the force Jacobian at its quadrature-weighted mean over the curve of the current
    /// iterate and factorise the Kronecker-structured matrix K ⊗ M / h + h B ⊗ H̄ (separable
    /// Lagrangians). With `kinetic_only`, H̄ = 0 (the fixed-point iteration's matrix).
    fn freeze_hessian(&mut self, kinetic_only: bool) -> Result<(), StepFailure>;
    /// δ ← P⁻¹ δ in place with the frozen matrix of [`freeze_hessian`](Self::freeze_hessian).
    fn solve_frozen(&mut self) -> Result<(), StepFailure>;
    /// δ ← J⁻¹ δ in place, approximately (relative residual 1e-5), by GMRES on the exact
    /// Jacobian at the current iterate, preconditioned by the frozen matrix. Returns the GMRES
    /// iterations.
    fn solve_krylov(&mut self) -> Result<usize, StepFailure>;
    /// y = J x with the exact Jacobian at the current iterate, matrix-free: from the node
    /// force Jacobians for separable Lagrangians (pairwise for large N-body systems), from the
    /// node Hessians L_qq, L_qv, L_vv (AD) for the others; O(mnD + mD²) either way.
    fn jacobian_product(&mut self, x: &[f64], y: &mut [f64]);
    /// Run a built-in solver from the current iterate.
    fn solve_with(&mut self, solver: StageSolver) -> Result<(), StepFailure>;
}

/// [`StageEquations`] of one step of a [`GalerkinIntegrator`].
pub(crate) struct StepEquations<'a, B: Basis, Q: Quadrature, L: Lagrangian> {
    pub gvi: &'a GalerkinIntegrator<B, Q>,
    pub lag: &'a L,
    pub ws: &'a mut Workspace,
    pub p_k: &'a [f64],
    pub stats: &'a mut StepStats,
    /// The curve at the nodes, the node force Jacobians and the dense Jacobian are at the
    /// current iterate.
    curve_fresh: bool,
    hessians_fresh: bool,
    jacobian_fresh: bool,
    /// A frozen matrix and an LU factorisation exist in this step.
    frozen: bool,
    factored: bool,
}

impl<'a, B: Basis, Q: Quadrature, L: Lagrangian> StepEquations<'a, B, Q, L> {
    pub(crate) fn new(
        gvi: &'a GalerkinIntegrator<B, Q>,
        lag: &'a L,
        ws: &'a mut Workspace,
        p_k: &'a [f64],
        stats: &'a mut StepStats,
    ) -> Self {
        // The guess's residual, if the workspace has it, stays for a built-in solver's first
        // iteration (the integrator clears it before a custom solver runs).
        ws.iterate.clear_last_lo();
        StepEquations {
            gvi,
            lag,
            ws,
            p_k,
            stats,
            curve_fresh: false,
            hessians_fresh: false,
            jacobian_fresh: false,
            frozen: false,
            factored: false,
        }
    }

    fn size(&self) -> usize {
        (self.ws.n - 1) * self.ws.d
    }

    fn failure(&self, reason: &str) -> StepFailure {
        StepFailure {
            residual: self.stats.residual,
            iterations: self.stats.iterations,
            reason: reason.to_string(),
        }
    }

    /// The curve of the current iterate at the nodes, which the Jacobians are evaluated on
    /// (the residual leaves it; otherwise it is evaluated, leaving the correction alone).
    fn ensure_curve(&mut self) {
        if !self.curve_fresh {
            self.gvi.evaluate_curve(self.ws, false);
            self.curve_fresh = true;
        }
    }
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> StageEquations for StepEquations<'_, B, Q, L> {
    fn dim(&self) -> usize {
        self.ws.d
    }

    fn unknowns(&self) -> usize {
        self.size()
    }

    fn options(&self) -> &NewtonOptions {
        self.gvi.options()
    }

    fn iterate(&self) -> &[f64] {
        &self.ws.iterate.increments()[self.ws.d..]
    }

    fn residual(&mut self) -> f64 {
        self.stats.gradient_evaluations += self.gvi.action_gradient(self.lag, self.ws, false);
        let r = self.gvi.residual(self.ws, Mode::InitialValue, self.p_k);
        self.curve_fresh = true;
        self.stats.residual = r;
        r
    }

    fn correction(&mut self) -> &mut [f64] {
        let size = self.size();
        self.ws.system.rhs_mut(size)
    }

    fn apply_correction(&mut self) -> Correction {
        let size = self.size();
        let ws = &mut *self.ws;
        let (size, scale) =
            ws.iterate
                .apply_correction(ws.system.rhs(size), ws.d, ws.separable.is_some());
        self.stats.iterations += 1;
        self.curve_fresh = false;
        self.hessians_fresh = false;
        self.jacobian_fresh = false;
        Correction { size, scale }
    }

    fn solve_exact(&mut self) -> Result<(), StepFailure> {
        let size = self.size();
        self.ensure_curve();
        if !self.jacobian_fresh {
            self.stats.hessian_evaluations +=
                self.gvi.jacobian(self.lag, self.ws, Mode::InitialValue);
            self.jacobian_fresh = true;
        }
        self.stats.factorizations += 1;
        if self.ws.system.factor(size, false).is_err() {
            self.factored = false;
            return Err(self.failure("singular Jacobian"));
        }
        self.factored = true;
        self.ws.system.solve(size);
        Ok(())
    }

    fn solve_reused(&mut self) -> bool {
        if !self.factored {
            return false;
        }
        let size = self.size();
        self.ws.system.solve(size);
        true
    }

    fn freeze_hessian(&mut self, kinetic_only: bool) -> Result<(), StepFailure> {
        self.ensure_curve();
        self.stats.factorizations += 1;
        match self.gvi.freeze_hessian(self.lag, self.ws, kinetic_only) {
            Ok(evals) => {
                self.stats.hessian_evaluations += evals;
                self.frozen = true;
                Ok(())
            }
            Err(e) => {
                self.frozen = false;
                Err(self.failure(&format!("no frozen-Hessian solve: {e}")))
            }
        }
    }

    fn solve_frozen(&mut self) -> Result<(), StepFailure> {
        let size = self.size();
        let h = self.gvi.step_size();
        match (self.frozen, self.gvi.tables().kron()) {
            (true, Some(kt)) if self.ws.system.kronecker_solve(kt, h, size) => Ok(()),
            _ => Err(self.failure("no frozen Hessian: call freeze_hessian first")),
        }
    }

    fn solve_krylov(&mut self) -> Result<usize, StepFailure> {
        if !self.frozen {
            return Err(self.failure("no preconditioner: call freeze_hessian first"));
        }
        self.ensure_curve();
        if !self.hessians_fresh {
            self.stats.hessian_evaluations += self.gvi.node_force_jacobians(self.lag, self.ws);
            self.hessians_fresh = true;
        }
        let (h, d) = (self.gvi.step_size(), self.ws.d);
        let tables = self.gvi.tables();
        let Some(kt) = tables.kron() else {
            return Err(self.failure("no Kronecker tables for this basis and quadrature"));
        };
        let Some((kw, kv, parts, rhs)) = self.ws.krylov_parts() else {
            return Err(self.failure("Newton–Krylov needs a separable Lagrangian"));
        };
        let lag = self.lag;
        let apply = |q: &[f64], x: &[f64], out: &mut [f64]| {
            lag.force_jacobian_products_at_points(q, x, out)
        };
        let op = parts.operator(tables, h, d, &apply);
        let inner = super::krylov::gmres(&op, kt, kw, kv, rhs);
        self.stats.inner_iterations += inner;
        Ok(inner)
    }

    fn jacobian_product(&mut self, x: &[f64], y: &mut [f64]) {
        let size = self.size();
        let (h, d) = (self.gvi.step_size(), self.ws.d);
        self.ensure_curve();
        if self.ws.system.structured() && self.ws.separable.is_some() {
            if !self.hessians_fresh {
                self.stats.hessian_evaluations += self.gvi.node_force_jacobians(self.lag, self.ws);
                self.hessians_fresh = true;
            }
            let tables = self.gvi.tables();
            if let Some((_, kv, parts, _)) = self.ws.krylov_parts() {
                let lag = self.lag;
                let apply = |q: &[f64], x: &[f64], out: &mut [f64]| {
                    lag.force_jacobian_products_at_points(q, x, out)
                };
                let op = parts.operator(tables, h, d, &apply);
                kv.product(&op, &x[..size], &mut y[..size]);
                return;
            }
        }
        if self.ws.separable.is_none() {
            // Non-separable: node Hessians by AD, applied without forming J.
            self.stats.hessian_evaluations += self.gvi.jacobian_product_general(
                self.lag,
                self.ws,
                self.hessians_fresh,
                &x[..size],
                &mut y[..size],
            );
            self.hessians_fresh = true;
            return;
        }
        if !self.jacobian_fresh {
            self.stats.hessian_evaluations +=
                self.gvi.jacobian(self.lag, self.ws, Mode::InitialValue);
            self.jacobian_fresh = true;
        }
        let jac = self.ws.system.jacobian(size);
        for (row, yi) in jac.chunks_exact(size).zip(y.iter_mut()) {
            *yi = row.iter().zip(x).map(|(a, b)| a * b).sum();
        }
    }

    fn solve_with(&mut self, solver: StageSolver) -> Result<(), StepFailure> {
        self.curve_fresh = false;
        self.hessians_fresh = false;
        self.jacobian_fresh = false;
        self.frozen = false;
        self.factored = false;
        self.gvi.newton(
            self.lag,
            self.ws,
            Mode::InitialValue,
            self.p_k,
            self.stats,
            solver,
        )
    }
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// y = J x for the initial-value step of a non-separable Lagrangian without forming J:
    /// with δq_j = Σ_b φ_b(c_j) x_b and δv_j = Σ_b φ'_b(c_j) x_b at each node, row block a is
    /// Σ_j b_j [φ_a (h L_qq δq_j + L_qv δv_j) + φ'_a (L_vq δq_j + L_vv δv_j / h)] — the
    /// entries `jacobian_rows` assembles, applied to x — then row block
    /// 0 is combined as `jacobian` does. O(mnD + mD²) per product; the node
    /// Hessians (AD) are evaluated when `hessians_fresh` is false. Returns Hessian evaluations.
    pub(super) fn jacobian_product_general<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        hessians_fresh: bool,
        x: &[f64],
        y: &mut [f64],
    ) -> usize {
        let t = self.tables();
        let (n, m, d, h) = (t.n, t.m, ws.d, self.step_size());
        let dd = d * d;
        let k = n - 1;
        let mut evals = 0;
        if !hessians_fresh {
            let forced = ws.stage.forced();
            let st = &mut ws.stage;
            for j in 0..m {
                let (q, v) = (&st.qj[j * d..(j + 1) * d], &st.vj[j * d..(j + 1) * d]);
                let node = &mut st.node_hessians[4 * dd * j..4 * dd * (j + 1)];
                let (hqq, rest) = node.split_at_mut(dd);
                let (hqv, rest) = rest.split_at_mut(dd);
                let (hvq, hvv) = rest.split_at_mut(dd);
                node_hessian(
                    lag,
                    forced,
                    (st.tj[j], q, v),
                    [hqq, hqv, hvq, hvv],
                    &mut st.fq,
                    &mut st.fv,
                );
            }
            evals = m;
        }
        y[..k * d].iter_mut().for_each(|v| *v = 0.0);
        let (dq, rest) = ws.stage.jvp_scratch.split_at_mut(d);
        let (dv, rest) = rest.split_at_mut(d);
        let (fq, fv) = rest.split_at_mut(d);
        for j in 0..m {
            let w = t.weights[j];
            let (phi, dphi) = (&t.phi[j * n..(j + 1) * n], &t.dphi[j * n..(j + 1) * n]);
            dq.iter_mut().for_each(|v| *v = 0.0);
            dv.iter_mut().for_each(|v| *v = 0.0);
            for b in 1..n {
                let xb = &x[(b - 1) * d..b * d];
                for s in 0..d {
                    dq[s] += phi[b] * xb[s];
                    dv[s] += dphi[b] * xb[s];
                }
            }
            let node = &ws.stage.node_hessians[4 * dd * j..4 * dd * (j + 1)];
            let (hqq, hqv) = (&node[..dd], &node[dd..2 * dd]);
            let (hvq, hvv) = (&node[2 * dd..3 * dd], &node[3 * dd..]);
            for r in 0..d {
                let (mut a, mut c) = (0.0, 0.0);
                for s in 0..d {
                    a += h * hqq[r * d + s] * dq[s] + hqv[r * d + s] * dv[s];
                    c += hvq[r * d + s] * dq[s] + hvv[r * d + s] * dv[s] / h;
                }
                fq[r] = a;
                fv[r] = c;
            }
            for a in 0..k {
                let (pa, da) = (w * phi[a], w * dphi[a]);
                for r in 0..d {
                    y[a * d + r] += pa * fq[r] + da * fv[r];
                }
            }
        }
        let (first, rest) = y[..k * d].split_at_mut(d);
        for a in 1..k {
            let u = t.unit[a];
            if u != 0.0 {
                for (f, b) in first.iter_mut().zip(&rest[(a - 1) * d..a * d]) {
                    *f += u * b;
                }
            }
        }
        evals
    }
}
