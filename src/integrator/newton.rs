//! The one-step map: Newton settings and statistics, Newton's method on the stage equations,
//! the step (plain and compensated) and the discrete Lagrangian. The stage equations and
//! their Jacobian are in `stage`, the initial guesses in `guess`.

use super::dd::{dd_add, max_abs, two_sum};
pub use super::options::{InitialGuess, NewtonOptions, StepFailure, StepStats};
use super::solver::StageSolver;
use super::stage::Mode;
use super::{GalerkinIntegrator, Workspace};
use crate::basis::Basis;
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

use super::linear::Linear;

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

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Newton's method on the stage equations of `mode`, from the coefficients in
    /// `ws.newton.coeffs`; on success the coefficients solve them and `ws.stage.grad` holds ∂S/∂Q at the
    /// solution.
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
        let u0 = mode.first_unknown() * d;
        let mut previous_increment = f64::INFINITY;
        ws.newton.last_lo.iter_mut().for_each(|x| *x = 0.0);
        let fail = |residual: f64, iterations, reason: &str| StepFailure {
            residual,
            iterations,
            reason: reason.to_string(),
        };
        if size == 0 {
            stats.gradient_evaluations += self.action_gradient(lag, ws, false);
            stats.residual = self.residual(ws, mode, p_k);
            return Ok(());
        }
        // Simplified Newton: keep the factorised Jacobian (from an earlier iteration or the
        // previous step) while the iteration contracts fast; refactor at the current iterate
        // (full Newton) as soon as it does not.
        let reuse = opts.reuse_jacobian && mode == Mode::InitialValue;
        let mut have_lu =
            reuse && opts.reuse_across_steps && ws.newton.lu_valid && ws.newton.lu.dim() == size;
        let mut fresh = false;
        // The structured solvers (initial-value steps of separable Lagrangians): the
        // Kronecker solver freezes the Hessian per step (refrozen once if the iteration
        // contracts slowly); Newton–Krylov freezes it for its preconditioner only. Either
        // continues with exact dense Newton within the step if it stalls.
        let structured = mode == Mode::InitialValue
            && ws.newton.kron.is_some()
            && ws.newton.krylov.is_some()
            && self.tables().kron.is_some();
        let auto = matches!(solver, StageSolver::Auto | StageSolver::Modal);
        let mut fixed_point = false;
        let mut linear = match (structured, self.resolve_solver(ws, solver)) {
            (true, StageSolver::Kronecker) => Linear::Frozen,
            (true, StageSolver::FixedPoint) => {
                fixed_point = true;
                Linear::Frozen
            }
            (true, StageSolver::NewtonKrylov) => Linear::Krylov,
            _ => Linear::Dense,
        };
        let mut refrozen = false;
        // The iteration at which Newton–Krylov took over (its growth test starts there).
        let mut krylov_start = 0;
        if linear != Linear::Dense {
            have_lu = false;
        }
        let mut it = 0;
        loop {
            // The initial guess's residual may already be in the workspace (same point).
            let res = match ws.newton.residual_ready.take().filter(|_| it == 0) {
                Some(r) => r,
                None => {
                    stats.gradient_evaluations += self.action_gradient(lag, ws, false);
                    self.residual(ws, mode, p_k)
                }
            };
            stats.residual = res;
            if !res.is_finite() {
                ws.newton.lu_valid = false;
                return Err(fail(
                    res,
                    it,
                    "non-finite residual (the iteration diverged)",
                ));
            }
            if it >= opts.max_iterations {
                ws.newton.lu_valid = false;
                return Err(fail(res, it, "iteration limit reached"));
            }
            if linear == Linear::Krylov && have_lu {
                // Exact node Hessians at the current iterate for the products J x.
                stats.hessian_evaluations += self.node_force_jacobians(lag, ws);
            }
            if !have_lu && linear != Linear::Dense {
                stats.factorizations += 1;
                match self.freeze_hessian(lag, ws, fixed_point) {
                    Ok(evals) => {
                        stats.hessian_evaluations += evals;
                        have_lu = true;
                        fresh = true;
                        if linear == Linear::Krylov && ws.stage.hall_stale {
                            // The freeze formed only the diagonal blocks; GMRES needs the
                            // node Jacobians at this iterate.
                            stats.hessian_evaluations += self.node_force_jacobians(lag, ws);
                        }
                    }
                    Err(_) => {
                        linear = Linear::Dense;
                        stats.fallbacks += 1;
                    }
                }
            }
            if !have_lu {
                stats.hessian_evaluations += self.jacobian(lag, ws, mode);
                if ws.newton.lu.dim() != size {
                    ws.newton.lu = crate::linalg::Lu::with_capacity(size);
                }
                stats.factorizations += 1;
                if ws
                    .newton
                    .lu
                    .refactor(&ws.newton.jac[..size * size])
                    .is_err()
                {
                    ws.newton.lu_valid = false;
                    return Err(fail(res, it, "singular Jacobian"));
                }
                ws.newton.lu_valid = mode == Mode::InitialValue;
                have_lu = true;
                fresh = true;
            }
            let h = self.step_size();
            let kt = self.tables().kron.as_ref();
            match (linear, kt) {
                (Linear::Frozen, Some(kt)) => {
                    if let Some(kw) = ws.newton.kron.as_mut() {
                        kw.solve(kt, h, &mut ws.newton.rhs[..size]);
                    }
                }
                (Linear::Krylov, Some(kt)) => {
                    let d = ws.d;
                    if let Some((kw, kv, parts, rhs)) = ws.krylov_parts() {
                        let apply = |q: &[f64], x: &[f64], out: &mut [f64]| {
                            lag.force_jacobian_products_at_points(q, x, out)
                        };
                        let op = parts.operator(self.tables(), h, d, &apply);
                        stats.inner_iterations += super::krylov::gmres(&op, kt, kw, kv, rhs);
                    }
                }
                _ => ws
                    .newton
                    .lu
                    .solve_in_place(&mut ws.newton.rhs[..size], &mut ws.newton.scratch[..size]),
            }
            it += 1;
            stats.iterations += 1;
            let delta = max_abs(&ws.newton.rhs[..size]);
            // ΔQ_{n−1} (the increment of q) is kept as hi + lo: the corrections of the last
            // iterations lie below its ulp, and the compensated Legendre-transform row resolves
            // them.
            let last = (n - 1) * d;
            for i in 0..size {
                let k = u0 + i;
                if k >= last && ws.separable.is_some() {
                    let (s, e) = two_sum(ws.newton.coeffs[k], ws.newton.rhs[i]);
                    ws.newton.coeffs[k] = s;
                    ws.newton.last_lo[k - last] += e;
                } else {
                    ws.newton.coeffs[k] += ws.newton.rhs[i];
                }
            }
            // The scale of the unknowns, the increments ΔQ (which the stage equations determine
            // to a relative accuracy far better than ε|q_k| when h is small).
            let scale = max_abs(&ws.newton.coeffs).max(f64::MIN_POSITIVE);
            if !delta.is_finite() || !scale.is_finite() {
                ws.newton.lu_valid = false;
                return Err(fail(f64::INFINITY, it, "non-finite Newton update"));
            }
            // θ estimates the contraction; undefined on the first iteration. A slow contraction
            // at small increments means the round-off floor for Newton's quadratic iteration,
            // but only a stall for the linearly converging frozen-Hessian and fixed-point
            // iterations (they escalate instead).
            let theta = if previous_increment.is_finite() {
                delta / previous_increment
            } else {
                f64::INFINITY
            };
            let converged = delta == 0.0
                || delta <= opts.tolerance * scale
                // The linearly converging frozen-Hessian and fixed-point iterations may not
                // stop on the contraction estimate: near round-off it is noisy and leaves a
                // one-signed remainder that drifts over long runs (measured: Kepler, Legendre
                // n = 24, h = 0.5, T = 20 000 at 1.6e-8 instead of 2.4e-10), so they iterate
                // until the increment itself is below the tolerance or stalls at the floor.
                || (theta < 1.0
                    && linear != Linear::Frozen
                    && theta / (1.0 - theta) * delta <= opts.tolerance * scale)
                || (theta.is_finite()
                    && theta >= 0.5
                    && linear != Linear::Frozen
                    && delta <= opts.floor_tolerance * scale);
            if converged {
                stats.gradient_evaluations += self.action_gradient(lag, ws, false);
                stats.residual = self.residual(ws, mode, p_k);
                return Ok(());
            }
            let growing = delta > previous_increment;
            match linear {
                Linear::Frozen => {
                    // A frozen Hessian contracts at a rate set by how much the force Jacobian
                    // varies over the step: keep it while it contracts, refreeze once at the
                    // current iterate when it does not, then continue with Newton–Krylov
                    // (`Auto`) or exact Newton. The fixed-point iteration (no Hessian) is
                    // kept only while it contracts fast; its iterations are cheap but many.
                    let limit = if fixed_point {
                        FIXED_POINT_STALL
                    } else {
                        KRONECKER_STALL
                    };
                    let stalled = growing || (theta.is_finite() && theta > limit);
                    if stalled && delta <= LINEAR_FLOOR * scale {
                        // Increments at the noise level of the residual no longer shrink:
                        // converged to round-off, not stalled.
                        stats.gradient_evaluations += self.action_gradient(lag, ws, false);
                        stats.residual = self.residual(ws, mode, p_k);
                        return Ok(());
                    }
                    if stalled && fixed_point {
                        // Continue with a frozen Hessian.
                        fixed_point = false;
                        have_lu = false;
                        stats.fallbacks += 1;
                    } else if stalled && !refrozen {
                        have_lu = false;
                        refrozen = true;
                    } else if stalled && auto {
                        // `Auto`: the frozen Hessian is too far from the step's even when
                        // refrozen; continue with Newton–Krylov, and start the next steps
                        // with it too.
                        linear = Linear::Krylov;
                        have_lu = true;
                        krylov_start = it;
                        stats.fallbacks += 1;
                        // Start the next solves with Newton–Krylov only when the frozen
                        // Hessian fails repeatedly, not at an occasional hard step (Kepler's
                        // periapsis).
                        ws.auto.krylov.failure();
                        previous_increment = f64::INFINITY;
                        continue;
                    } else if stalled {
                        have_lu = false;
                        linear = Linear::Dense;
                        stats.fallbacks += 1;
                    }
                    previous_increment = delta;
                    continue;
                }
                Linear::Krylov => {
                    // Exact Newton directions (to the forcing term): an iteration that grows
                    // after the first has left the basin the dense solver would keep.
                    if growing && it >= krylov_start + 3 {
                        have_lu = false;
                        linear = Linear::Dense;
                        stats.fallbacks += 1;
                    }
                    previous_increment = delta;
                    continue;
                }
                Linear::Dense => {}
            }
            // A reused (stale) Jacobian that does not contract quickly is replaced.
            let slow = theta.is_finite() && theta > opts.reuse_contraction;
            if !reuse || slow || growing || (!fresh && it >= 2 && !theta.is_finite()) {
                have_lu = false;
            }
            previous_increment = delta;
        }
    }

    /// One step of the discrete flow: (q_k, p_k) ↦ (q_{k+1}, p_{k+1}). The step's Galerkin
    /// coefficients are left in [`Workspace::coefficients`] and remembered for the next
    /// step's extrapolated guess.
    ///
    /// The Newton unknowns are the increments ΔQ_i = Q_i − u_i q_k (u: the coefficients of
    /// the constant curve), so the curve is q_k + Σ ΔQ_i φ_i and q_{k+1} = q_k + ΔQ_{n−1}
    /// with ΔQ_{n−1} computed to full relative accuracy. p_{k+1} is computed as
    /// p_k + h Σ_j b_j L_q(c_j), which equals ∂S/∂Q_{n−1} once the stage equations hold (the
    /// basis reproduces constants, so Σ_a u_a ∂S/∂Q_a is the total impulse) but avoids the
    /// cancellation of large kinetic terms when h is small. See
    /// [`step_compensated`](Self::step_compensated) for the variant that also carries the
    /// rounding errors of these two sums across steps.
    pub fn step<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> std::result::Result<StepStats, StepFailure> {
        self.check_workspace(lag, ws, q, p, [q_next.len(), p_next.len()])?;
        let stats = self.solve_step(lag, ws, q, p)?;
        let d = ws.d;
        let last = (ws.n - 1) * d;
        for r in 0..d {
            // Correctly rounded sums of the state and the double-double increments.
            q_next[r] = dd_add(q[r], 0.0, ws.newton.coeffs[last + r], ws.newton.last_lo[r]).0;
            p_next[r] = dd_add(p[r], 0.0, ws.newton.impulse[r], ws.newton.impulse_lo[r]).0;
        }
        self.finish_step(ws, q_next);
        Ok(stats)
    }

    /// [`step`](Self::step) with compensated summation of the state, in place: (q, p) is
    /// advanced by one step and `q_err`, `p_err` carry the rounding errors of the sums
    /// q_{k+1} = q_k + ΔQ_{n−1} and p_{k+1} = p_k + impulse (Kahan–Babuška with Knuth's
    /// TwoSum), so that q + q_err and p + p_err represent the state to about twice the
    /// working precision over any number of steps. Start with `q_err = p_err = 0`. The step
    /// itself is solved at the rounded (q, p); only the increments are compensated, as in
    /// IAS15. On failure the state is unchanged.
    pub fn step_compensated<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &mut [f64],
        q_err: &mut [f64],
        p: &mut [f64],
        p_err: &mut [f64],
    ) -> std::result::Result<StepStats, StepFailure> {
        self.check_workspace(lag, ws, q, p, [q_err.len(), p_err.len()])?;
        ws.newton.base_err.copy_from_slice(q_err);
        ws.newton.p_err.copy_from_slice(p_err);
        let solved = self.solve_step(lag, ws, q, p);
        ws.newton.base_err.iter_mut().for_each(|x| *x = 0.0);
        ws.newton.p_err.iter_mut().for_each(|x| *x = 0.0);
        let stats = solved?;
        let d = ws.d;
        let last = (ws.n - 1) * d;
        for r in 0..d {
            (q[r], q_err[r]) = dd_add(
                q[r],
                q_err[r],
                ws.newton.coeffs[last + r],
                ws.newton.last_lo[r],
            );
            (p[r], p_err[r]) = dd_add(
                p[r],
                p_err[r],
                ws.newton.impulse[r],
                ws.newton.impulse_lo[r],
            );
        }
        self.finish_step(ws, q);
        Ok(stats)
    }

    /// Absolute coefficients for [`Workspace::coefficients`] (Q_i = u_i q_k + ΔQ_i, with the
    /// ends exactly q_k and the returned q_{k+1}), and the increments kept for the next guess.
    pub(super) fn finish_step(&self, ws: &mut Workspace, q_next: &[f64]) {
        let t = self.tables();
        let (n, d) = (t.n, ws.d);
        let last = ws.last.coefficients_mut();
        for i in 1..n - 1 {
            for r in 0..d {
                last[i * d + r] = t.unit[i] * ws.newton.base[r] + ws.newton.coeffs[i * d + r];
            }
        }
        last[..d].copy_from_slice(&ws.newton.base);
        last[(n - 1) * d..].copy_from_slice(q_next);
        ws.guess.prev.copy_from_slice(&ws.newton.coeffs);
        ws.guess.has_prev = true;
    }

    /// Refuse a workspace made for another integrator or dimension, and states of the wrong
    /// length, before anything is indexed (a workspace's tables are laid out for one basis,
    /// quadrature, h and D). [`Stepper`](super::Stepper) owns its workspace, so there this
    /// cannot happen.
    fn check_workspace<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &Workspace,
        q: &[f64],
        p: &[f64],
        outputs: [usize; 2],
    ) -> std::result::Result<(), StepFailure> {
        let d = ws.d;
        let reason = if !ws.made_for.matches(self) {
            format!(
                "the workspace was made for {} but the integrator is {}",
                ws.made_for,
                super::workspace::MadeFor::of(self, lag.dim())
            )
        } else if lag.dim() != d || q.len() != d || p.len() != d || outputs != [d, d] {
            format!(
                "the workspace was made for dimension D = {d}; the Lagrangian has {}, the \
                 state {} and {}, the outputs {} and {}",
                lag.dim(),
                q.len(),
                p.len(),
                outputs[0],
                outputs[1]
            )
        } else {
            return Ok(());
        };
        Err(StepFailure {
            residual: f64::NAN,
            iterations: 0,
            reason,
        })
    }

    /// Solve the stage equations of one step from (q, p): on success `ws.newton.coeffs` holds the
    /// increments ΔQ and `ws.newton.impulse` the total impulse h Σ_j b_j L_q(c_j).
    fn solve_step<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
    ) -> std::result::Result<StepStats, StepFailure> {
        ws.newton.base.copy_from_slice(q);
        let mut stats = StepStats::default();
        if self.velocity_form_applies(ws) {
            let solved = self.solve_velocity_form(lag, ws, q, p, &mut stats);
            if solved {
                ws.auto.velocity_gives_up.calm_solve();
            } else {
                ws.auto.velocity_gives_up.failure();
                if let Some(v) = ws.velocity.as_mut() {
                    v.has_prev = false;
                }
            }
            if solved {
                stats.gradient_evaluations += std::mem::take(&mut ws.guess.guess_force_evaluations);
                return Ok(stats);
            }
            // Not solved (a stall, a non-finite residual): the nodal solvers take the step
            // from their own guesses.
            stats.fallbacks += 1;
        }
        let (guess, evals) = self.initial_guess(lag, ws, q, p);
        stats.guess = guess;
        stats.gradient_evaluations += evals;
        ws.newton.start.copy_from_slice(&ws.newton.coeffs);
        let solver = self.options().solver;
        if let Err(first) = self.solve_stage_equations(lag, ws, p, &mut stats, solver) {
            // Fallbacks before giving up. A structured solver that failed hands the step to
            // exact Newton, first from the same guess (its iterations can leave the basin the
            // dense solver keeps when the step is hard, e.g. an under-resolved Mercury), so
            // that no solver fails where `exact` succeeds. Then Newton from each of the other
            // guesses (with very large steps the residual-best guess can lie in the basin of
            // no root, or of another).
            let mut solved = false;
            let retry = if self.stage_solver.is_none() && solver != StageSolver::Exact {
                stats.fallbacks += 1;
                ws.newton.coeffs.copy_from_slice(&ws.newton.start);
                ws.newton.residual_ready = None;
                solved = self
                    .solve_stage_equations(lag, ws, p, &mut stats, StageSolver::Exact)
                    .is_ok();
                StageSolver::Exact
            } else {
                solver
            };
            for g in [
                InitialGuess::Predictor,
                InitialGuess::Extrapolate,
                InitialGuess::Linear,
                InitialGuess::Constant,
            ] {
                if solved || g == guess || !self.make_guess(lag, ws, g, q, p) {
                    continue;
                }
                ws.newton.coeffs.copy_from_slice(&ws.guess.cand);
                if self
                    .solve_stage_equations(lag, ws, p, &mut stats, retry)
                    .is_ok()
                {
                    stats.guess = g;
                    solved = true;
                    break;
                }
            }
            if !solved {
                ws.guess.has_prev = false;
                ws.guess.guess_force_evaluations = 0;
                return Err(StepFailure {
                    iterations: stats.iterations,
                    ..first
                });
            }
        }
        // The RK4 predictor's force evaluations are right-hand-side evaluations too.
        stats.gradient_evaluations += std::mem::take(&mut ws.guess.guess_force_evaluations);
        // The total impulse h Σ_j b_j L_q(c_j) at the solution is left in ws.newton.impulse by the
        // last residual evaluation.
        Ok(stats)
    }

    /// The stage equations of an initial-value step from the iterate in `ws.newton.coeffs`, by the
    /// integrator's custom stage solver if it has one, else by the built-in `solver`. A custom solver's result is re-evaluated here, so the impulse and ∂S/∂Q in the
    /// workspace belong to the iterate it returns.
    fn solve_stage_equations<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        p: &[f64],
        stats: &mut StepStats,
        solver: StageSolver,
    ) -> std::result::Result<(), StepFailure> {
        let Some(custom) = self.stage_solver.clone() else {
            return self.newton(lag, ws, Mode::InitialValue, p, stats, solver);
        };
        use super::equations::{StageEquations, StepEquations};
        let mut equations = StepEquations::new(self, lag, ws, p, stats);
        custom.solve(&mut equations)?;
        let residual = equations.residual();
        if !residual.is_finite() {
            ws.newton.lu_valid = false;
            return Err(StepFailure {
                residual,
                iterations: stats.iterations,
                reason: format!(
                    "stage solver '{}' returned a non-finite residual",
                    custom.name()
                ),
            });
        }
        Ok(())
    }
}
