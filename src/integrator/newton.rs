//! The one-step map: the step (plain and compensated), its initial guesses and fallbacks, and
//! the hand-over to a stage solver. Newton's iteration on the nodal stage equations is in
//! `nodal_newton`, the stage equations and their Jacobian in `stage`, the initial guesses in
//! `guess`.

pub use super::options::{
    DenseOptions, InitialGuess, NewtonOptions, StepFailure, StepStats, StructuredOptions,
};
use super::solver::StageSolver;
use super::{GalerkinIntegrator, Workspace};
use crate::basis::Basis;
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
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
        for r in 0..d {
            // Correctly rounded sums of the state and the double-double increments.
            let [(qn, _), (pn, _)] = ws.iterate.advance(r, (q[r], 0.0), (p[r], 0.0));
            (q_next[r], p_next[r]) = (qn, pn);
        }
        self.finish_step(ws, q_next);
        self.advance_time(ws);
        Ok(stats)
    }

    /// t_k ← t_k + h after a completed step (the node times are set when a step starts).
    fn advance_time(&self, ws: &mut Workspace) {
        let t = ws.stage.step_start() + self.step_size();
        ws.stage.set_step_start(t, 0.0, &[]);
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
        ws.iterate.set_compensation(q_err, p_err);
        let solved = self.solve_step(lag, ws, q, p);
        ws.iterate.clear_compensation();
        let stats = solved?;
        let d = ws.d;
        for r in 0..d {
            [(q[r], q_err[r]), (p[r], p_err[r])] =
                ws.iterate.advance(r, (q[r], q_err[r]), (p[r], p_err[r]));
        }
        self.finish_step(ws, q);
        self.advance_time(ws);
        Ok(stats)
    }

    /// Absolute coefficients for [`Workspace::coefficients`] (Q_i = u_i q_k + ΔQ_i, with the
    /// ends exactly q_k and the returned q_{k+1}), and the increments kept for the next guess.
    pub(super) fn finish_step(&self, ws: &mut Workspace, q_next: &[f64]) {
        let t = self.tables();
        let (n, d) = (t.n, ws.d);
        let (origin, increments) = (ws.iterate.origin(), ws.iterate.increments());
        let last = ws.last.coefficients_mut();
        for i in 1..n - 1 {
            for r in 0..d {
                last[i * d + r] = t.unit[i] * origin[r] + increments[i * d + r];
            }
        }
        last[..d].copy_from_slice(origin);
        last[(n - 1) * d..].copy_from_slice(q_next);
        ws.guess.remember(increments);
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

    /// Solve the stage equations of one step from (q, p): on success the iterate holds the
    /// increments ΔQ and the total impulse h Σ_j b_j L_q(c_j).
    fn solve_step<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
    ) -> std::result::Result<StepStats, StepFailure> {
        ws.iterate.set_origin(q);
        if ws.stage.timed() {
            let t0 = ws.stage.step_start();
            ws.stage
                .set_step_start(t0, self.step_size(), &self.rule().nodes);
        }
        let mut stats = StepStats::default();
        if self.velocity_form_applies(ws) {
            let solved = self.solve_velocity_form(lag, ws, q, p, &mut stats);
            if solved {
                ws.auto.velocity_gives_up.calm_solve();
            } else {
                ws.auto.velocity_gives_up.failure();
                if let Some(v) = ws.velocity.as_mut() {
                    v.forget_previous();
                }
            }
            if solved {
                stats.gradient_evaluations += ws.guess.take_force_evaluations();
                return Ok(stats);
            }
            // Not solved (a stall, a non-finite residual): the nodal solvers take the step
            // from their own guesses.
            stats.fallbacks += 1;
        }
        let (guess, evals) = self.initial_guess(lag, ws, q, p);
        stats.guess = guess;
        stats.gradient_evaluations += evals;
        ws.iterate.save_start();
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
                ws.iterate.restore_start();
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
                ws.iterate
                    .increments_mut()
                    .copy_from_slice(ws.guess.candidate());
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
                ws.guess.forget_previous();
                ws.guess.take_force_evaluations();
                return Err(StepFailure {
                    iterations: stats.iterations,
                    ..first
                });
            }
        }
        // The RK4 predictor's force evaluations are right-hand-side evaluations too.
        stats.gradient_evaluations += ws.guess.take_force_evaluations();
        // The total impulse h Σ_j b_j L_q(c_j) at the solution is left in the iterate by the
        // last residual evaluation.
        Ok(stats)
    }

    /// The stage equations of an initial-value step from the iterate in the workspace,
    /// through the public solver interface: the integrator's custom [`StageSolve`] if it has
    /// one, else the built-in `solver` (itself a `StageSolve`), each given the same
    /// [`StageEquations`]. A custom solver's result is re-evaluated here, so the impulse and
    /// ∂S/∂Q in the workspace belong to the iterate it returns; the built-in solvers end on
    /// that evaluation already.
    fn solve_stage_equations<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        p: &[f64],
        stats: &mut StepStats,
        solver: StageSolver,
    ) -> std::result::Result<(), StepFailure> {
        use super::equations::{StageEquations, StageSolve, StepEquations};
        let custom = self.stage_solver.as_deref();
        if custom.is_some() {
            // A custom solver evaluates its own residuals: the guess's is not reused.
            ws.iterate.set_ready_residual(None);
        }
        let chosen: &dyn StageSolve = match custom {
            Some(c) => c,
            None => &solver,
        };
        let mut equations = StepEquations::new(self, lag, ws, p, stats);
        chosen.solve(&mut equations)?;
        let Some(custom) = custom else {
            return Ok(());
        };
        let residual = equations.residual();
        if !residual.is_finite() {
            ws.system.invalidate();
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
