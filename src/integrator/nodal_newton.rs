//! Newton's iteration on the nodal stage equations (paper eqs. (3)–(4)), as a
//! [`NewtonIteration`] run by the crate's one Newton driver ([`crate::newton::drive`]).
//!
//! The iteration supplies the residual, the linear solve of each correction — dense LU of the
//! exact Jacobian, the Kronecker solve of the frozen-Hessian Jacobian, GMRES preconditioned by
//! it, or the fixed-point iteration's kinetic-only matrix — and how it adapts that solve when
//! the iteration contracts slowly: refactor a reused matrix, refreeze the Hessian once, hand a
//! stalled frozen Hessian to Newton–Krylov (`Auto`) or to exact Newton. The driver decides
//! termination by the [`Termination`] each linear solve names.

use super::linear::Linear;
use super::solver::StageSolver;
use super::stage::Mode;
use super::{GalerkinIntegrator, StepFailure, StepStats, Workspace};
use crate::basis::Basis;
use crate::lagrangian::Lagrangian;
use crate::newton::{Adapt, ConvergedBy, Correction, NewtonIteration, Progress, Termination};
use crate::quadrature::Quadrature;

/// Contraction per iteration above which the fixed-point iteration hands over to the frozen
/// Hessian: slower, it needs more than ~20 cheap iterations where the frozen Hessian needs a
/// few more expensive ones.
const FIXED_POINT_STALL: f64 = 0.2;

/// Relative increment below which a linearly converging (frozen-Hessian or fixed-point)
/// iteration that stops shrinking is at the round-off floor of its residual, not stalled
/// (Newton's quadratic iteration uses `NewtonOptions::floor_tolerance`, 1e-10, instead).
const LINEAR_FLOOR: f64 = 1e-13;

/// Contraction per iteration above which the Kronecker solver's frozen Hessian is refrozen
/// (once) and then abandoned for exact Newton within the step.
const KRONECKER_STALL: f64 = 0.5;

/// Contraction below which the quadratic iterations (dense, Newton–Krylov) trust the estimate
/// θ/(1 − θ)·|δ| of the remaining error, and above which a correction that stops shrinking
/// is at the floor.
const QUADRATIC_ESTIMATE: f64 = 1.0;
const QUADRATIC_FLOOR_THETA: f64 = 0.5;

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Newton's method on the stage equations of `mode`, from the iterate's
    /// increments; on success the coefficients solve them and `ws.stage.grad` holds
    /// ∂S/∂Q at the solution.
    pub(super) fn newton<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        mode: Mode,
        p_k: &[f64],
        stats: &mut StepStats,
        solver: StageSolver,
    ) -> std::result::Result<(), StepFailure> {
        let opts = self.options();
        let (n, d) = (ws.n, ws.d);
        let size = mode.count(n) * d;
        ws.iterate.clear_last_lo();
        if size == 0 {
            stats.gradient_evaluations += self.action_gradient(lag, ws, false);
            stats.residual = self.residual(ws, mode, p_k);
            return Ok(());
        }
        // Simplified Newton: keep the factorised Jacobian (from an earlier iteration or the
        // previous step) while the iteration contracts fast; refactor at the current iterate
        // (full Newton) as soon as it does not.
        let reuse = opts.dense.reuse_jacobian && mode == Mode::InitialValue;
        let have_lu = reuse && opts.dense.reuse_across_steps && ws.system.reusable(size);
        // The structured solvers (initial-value steps of separable Lagrangians): the
        // Kronecker solver freezes the Hessian per step (refrozen once if the iteration
        // contracts slowly); Newton–Krylov freezes it for its preconditioner only. Either
        // continues with exact dense Newton within the step if it stalls.
        let structured =
            mode == Mode::InitialValue && ws.system.structured() && self.tables().kron().is_some();
        let auto = matches!(solver, StageSolver::Auto | StageSolver::Modal);
        let (linear, fixed_point) = match (structured, self.resolve_solver(ws, solver)) {
            (true, StageSolver::Kronecker) => (Linear::Frozen, false),
            (true, StageSolver::FixedPoint) => (Linear::Frozen, true),
            (true, StageSolver::NewtonKrylov) => (Linear::Krylov, false),
            _ => (Linear::Dense, false),
        };
        let mut iteration = NodalNewton {
            gvi: self,
            lag,
            ws,
            mode,
            p_k,
            stats,
            size,
            u0: mode.first_unknown() * d,
            reuse,
            auto,
            linear,
            fixed_point,
            have_lu: have_lu && linear == Linear::Dense,
            fresh: false,
            refrozen: false,
            krylov_start: 0,
            residual: f64::NAN,
        };
        let first = iteration.termination();
        let solved = crate::newton::drive(&mut iteration, &first);
        if solved.is_err() {
            iteration.ws.system.invalidate();
        }
        solved.map(|_| ())
    }
}

/// One nodal Newton solve: the problem, its current linear solve and what it remembers.
struct NodalNewton<'a, B: Basis, Q: Quadrature, L: Lagrangian> {
    gvi: &'a GalerkinIntegrator<B, Q>,
    lag: &'a L,
    ws: &'a mut Workspace,
    mode: Mode,
    p_k: &'a [f64],
    stats: &'a mut StepStats,
    /// Unknowns, and the offset of the first in the iterate's increments.
    size: usize,
    u0: usize,
    /// Simplified Newton with the dense matrix (initial-value steps).
    reuse: bool,
    /// `Auto` (or `Modal`'s nodal fallback): a stalled frozen Hessian goes to Newton–Krylov.
    auto: bool,
    linear: Linear,
    /// The frozen iteration is the fixed-point one (kinetic-only matrix).
    fixed_point: bool,
    /// A factorisation (or frozen matrix) for the current linear solve exists …
    have_lu: bool,
    /// … and one was made in this solve.
    fresh: bool,
    /// The frozen Hessian was refrozen once.
    refrozen: bool,
    /// The iteration at which Newton–Krylov took over (its growth test starts there).
    krylov_start: usize,
    /// The last residual's norm.
    residual: f64,
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> NodalNewton<'_, B, Q, L> {
    /// The termination of the current linear solve: the quadratic iterations trust the
    /// contraction estimate; the linearly converging frozen-Hessian and fixed-point iterations
    /// do not (near round-off it is noisy and leaves a one-signed remainder that drifts over
    /// long runs: measured, Kepler, Legendre n = 24, h = 0.5, T = 20 000 at 1.6e-8 instead of
    /// 2.4e-10), so they iterate until the increment itself is below the tolerance or stalls
    /// at [`LINEAR_FLOOR`].
    fn termination(&self) -> Termination {
        let opts = self.gvi.options();
        match self.linear {
            Linear::Frozen => Termination::new(
                opts.max_iterations,
                opts.tolerance,
                None,
                LINEAR_FLOOR,
                if self.fixed_point {
                    FIXED_POINT_STALL
                } else {
                    KRONECKER_STALL
                },
            ),
            Linear::Dense | Linear::Krylov => Termination::new(
                opts.max_iterations,
                opts.tolerance,
                Some(QUADRATIC_ESTIMATE),
                opts.floor_tolerance,
                QUADRATIC_FLOOR_THETA,
            ),
        }
    }

    fn failure(&self, reason: &str, iterations: usize) -> StepFailure {
        StepFailure {
            residual: self.residual,
            iterations,
            reason: reason.to_string(),
        }
    }
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> NewtonIteration for NodalNewton<'_, B, Q, L> {
    fn residual(&mut self, iteration: usize) -> f64 {
        // The initial guess's residual may already be in the workspace (same point).
        let res = match self
            .ws
            .iterate
            .take_ready_residual()
            .filter(|_| iteration == 0)
        {
            Some(r) => r,
            None => {
                self.stats.gradient_evaluations +=
                    self.gvi.action_gradient(self.lag, self.ws, false);
                self.gvi.residual(self.ws, self.mode, self.p_k)
            }
        };
        self.stats.residual = res;
        self.residual = res;
        res
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), StepFailure> {
        let (gvi, lag, size) = (self.gvi, self.lag, self.size);
        let ws = &mut *self.ws;
        let stats = &mut *self.stats;
        if self.linear == Linear::Krylov && self.have_lu {
            // Exact node Hessians at the current iterate for the products J x.
            stats.hessian_evaluations += gvi.node_force_jacobians(lag, ws);
        }
        if !self.have_lu && self.linear != Linear::Dense {
            stats.factorizations += 1;
            match gvi.freeze_hessian(lag, ws, self.fixed_point) {
                Ok(evals) => {
                    stats.hessian_evaluations += evals;
                    self.have_lu = true;
                    self.fresh = true;
                    if self.linear == Linear::Krylov && !ws.stage.node_jacobians_current() {
                        // The freeze formed only the diagonal blocks; GMRES needs the node
                        // Jacobians at this iterate.
                        stats.hessian_evaluations += gvi.node_force_jacobians(lag, ws);
                    }
                }
                Err(_) => {
                    self.linear = Linear::Dense;
                    stats.fallbacks += 1;
                }
            }
        }
        if !self.have_lu {
            stats.hessian_evaluations += gvi.jacobian(lag, ws, self.mode);
            stats.factorizations += 1;
            if ws
                .system
                .factor(size, self.mode == Mode::InitialValue)
                .is_err()
            {
                return Err(self.failure("singular Jacobian", iteration));
            }
            self.have_lu = true;
            self.fresh = true;
        }
        let h = gvi.step_size();
        let kt = gvi.tables().kron();
        match (self.linear, kt) {
            (Linear::Frozen, Some(kt)) => {
                ws.system.kronecker_solve(kt, h, size);
            }
            (Linear::Krylov, Some(kt)) => {
                let d = ws.d;
                if let Some((kw, kv, parts, rhs)) = ws.krylov_parts() {
                    let apply = |q: &[f64], x: &[f64], out: &mut [f64]| {
                        lag.force_jacobian_products_at_points(q, x, out)
                    };
                    let op = parts.operator(gvi.tables(), h, d, &apply);
                    stats.inner_iterations += super::krylov::gmres(&op, kt, kw, kv, rhs);
                }
            }
            _ => ws.system.solve(size),
        }
        stats.iterations += 1;
        // ΔQ_{n−1} (the increment of q) is kept as hi + lo.
        let (delta, scale) =
            ws.iterate
                .apply_correction(ws.system.rhs(size), self.u0, ws.separable.is_some());
        Ok((Correction { size: delta, scale }, self.termination()))
    }

    fn adapt(&mut self, progress: &Progress) -> Adapt {
        let (theta, growing, it) = (progress.theta, progress.growing, progress.iteration);
        match self.linear {
            Linear::Frozen => {
                // A frozen Hessian contracts at a rate set by how much the force Jacobian
                // varies over the step: keep it while it contracts, refreeze once at the
                // current iterate when it does not, then continue with Newton–Krylov (`Auto`)
                // or exact Newton. The fixed-point iteration (no Hessian) is kept only while
                // it contracts fast; its iterations are cheap but many.
                let limit = if self.fixed_point {
                    FIXED_POINT_STALL
                } else {
                    KRONECKER_STALL
                };
                let stalled = growing || (theta.is_finite() && theta > limit);
                if stalled && self.fixed_point {
                    // Continue with a frozen Hessian.
                    self.fixed_point = false;
                    self.have_lu = false;
                    self.stats.fallbacks += 1;
                } else if stalled && !self.refrozen {
                    self.have_lu = false;
                    self.refrozen = true;
                } else if stalled && self.auto {
                    // `Auto`: the frozen Hessian is too far from the step's even when
                    // refrozen; continue with Newton–Krylov, and start the next solves with it
                    // too when the frozen Hessian fails repeatedly, not at an occasional hard
                    // step (Kepler's periapsis).
                    self.linear = Linear::Krylov;
                    self.have_lu = true;
                    self.krylov_start = it;
                    self.stats.fallbacks += 1;
                    self.ws.auto.krylov.failure();
                    return Adapt::Restart;
                } else if stalled {
                    self.have_lu = false;
                    self.linear = Linear::Dense;
                    self.stats.fallbacks += 1;
                }
            }
            Linear::Krylov => {
                // Exact Newton directions (to the forcing term): an iteration that grows after
                // the first has left the basin the dense solver would keep.
                if growing && it >= self.krylov_start + 3 {
                    self.have_lu = false;
                    self.linear = Linear::Dense;
                    self.stats.fallbacks += 1;
                }
            }
            Linear::Dense => {
                // A reused (stale) Jacobian that does not contract quickly is replaced.
                let slow = theta.is_finite() && theta > self.gvi.options().dense.reuse_contraction;
                if !self.reuse || slow || growing || (!self.fresh && it >= 2 && !theta.is_finite())
                {
                    self.have_lu = false;
                }
            }
        }
        Adapt::Continue
    }

    fn finish(&mut self, _: ConvergedBy) -> Result<(), StepFailure> {
        self.stats.gradient_evaluations += self.gvi.action_gradient(self.lag, self.ws, false);
        self.stats.residual = self.gvi.residual(self.ws, self.mode, self.p_k);
        Ok(())
    }
}
