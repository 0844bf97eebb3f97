//! Newton's method on the stage equations in the velocity form ([`super`];
//! the equations themselves are in [`super::equations`]).
//!
//! Each step starts with fixed-point iterations: the Newton matrix without its force term,
//! I ⊗ M, whose correction is M⁻¹(−F) — no force Jacobian, no factorisation. They contract at
//! about h² ρ(C) max|M⁻¹H| (C the velocity pencil's matrix below), which at the step sizes
//! of the spectral method is small: ρ(C) = 5.9e-3 at n = 10, 4.1e-3 at n = 12. Where they
//! contract by less than [`FIXED_POINT_HANDOVER`] (`StructuredOptions::
//! velocity_fixed_point_handover`), the step continues with the frozen Hessian below.
//!
//! The frozen-Hessian iteration freezes the force Jacobian at H̄ (the quadrature-weighted mean
//! over the curve of the initial guess) and iterates with the Kronecker solve of I ⊗ M + h² C ⊗ H̄: the Newton
//! matrix is the mass matrix plus an O(h²) term, so the frozen matrix contracts fast wherever
//! the force Jacobian varies little over a step. Where it does not (θ > 0.5), H̄ is refrozen
//! once at the current iterate, then small systems continue with the dense exact matrix of the
//! same form; a step that still does not converge returns `false`, and the caller hands it to
//! the nodal solvers, which start again from their own guesses — so the velocity form never
//! loses a step the nodal equations would have solved. `Auto` remembers both escalations for
//! the next steps ([`VelocityState::record`]).

use super::VelocityTables;
use super::equations::assemble_dense;
use super::freeze::{correct_on_blocks, correct_on_rows};
use super::momentum::MomentumRow;
use crate::basis::Basis;
use crate::integrator::dd::max_abs;
use crate::integrator::kronecker::KroneckerWorkParts;
use crate::integrator::linear::Linear;
use crate::integrator::{GalerkinIntegrator, InitialGuess, StepStats, Workspace};
use crate::lagrangian::Lagrangian;
use crate::newton::{
    Adapt, ConvergedBy, Correction, NewtonFailure, NewtonIteration, Progress, Termination,
};
use crate::quadrature::Quadrature;

/// Contraction per iteration above which the frozen Hessian is refrozen at the current
/// iterate (once per step; a second stall continues with the dense matrix in small systems and
/// hands the step to the nodal solvers otherwise).
const VELOCITY_STALL: f64 = 0.5;

/// Relative residual of the extrapolated guess above which the RK4 predictor is tried too.
/// Measured on Kepler e = 0.6, T = 200 (Legendre n = 10, h = 0.25; n = 18, h = 0.5;
/// n = 12, h = 0.5): trusting every extrapolation is fastest but lets periapsis steps start
/// from residuals of O(10), where the frozen Hessian (taken at that guess) contracts slowly and
/// one step stopped at its noise floor with an angular-momentum error of 2e-15; 1e-6 tries
/// the predictor too often (+13 % time); 1e-3 costs +4 % and had no such step.
///
/// The residual is max |F|, in momentum units, against max |c| in velocity units: for
/// Kepler (M = I) the two agree, but an N-body system with small masses (J2000 in GM units,
/// 1e-10 … 3e-4) passes the test on almost every step, so its steps keep their
/// extrapolations even where a fast planet's is far off (Mercury at h = 25 d: 10² relative,
/// mostly in the top modes, which the first correction removes). Measured there (issue 35,
/// docs/solvers.md), a closer guess saves about two corrections and the RK4 predictor costs
/// about four residuals, so the test is left as it is.
const EXTRAPOLATION_TRUST: f64 = 1e-3;

/// Contraction per iteration above which the fixed-point start hands the step over to the
/// frozen Hessian (the default of `StructuredOptions::velocity_fixed_point_handover`, where
/// the measurements are).
pub(crate) const FIXED_POINT_HANDOVER: f64 = 0.5;

/// Relative correction up to which the fixed-point iteration converges, once it confirmed its
/// frozen blocks ([`super::freeze`]), when a correction is no smaller than half the one
/// before: the round-off floor of the whole residual. Measured on J2000 (Legendre n = 12,
/// h = 20 d): the confirmations' corrections are 1–3e-16 of the iterate where the frozen
/// blocks kept still (the slowest block's floor), and up to 2.5e-15 where a block frozen
/// early drifted with the Sun's later corrections (the iteration then continues with every
/// block).
const CONFIRMATION_FLOOR: f64 = 1e-15;

/// Relative increment below which an iteration that stops contracting is at the round-off
/// floor of its residual (converged, not stalled).
const VELOCITY_FLOOR: f64 = 1e-13;

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Solve the step from (q_k, p_k) = (the iterate's origin, `p`) in the velocity form. On
    /// success the increments ΔQ (with the low part of ΔQ_{n−1}) and the impulse are in
    /// the iterate, as the nodal solve leaves them.
    pub(in crate::integrator) fn solve_velocity_form<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
        stats: &mut StepStats,
    ) -> bool {
        let (Some(vt), Some(_)) = (self.tables().velocity.as_ref(), ws.velocity.as_ref()) else {
            return false;
        };
        stats.guess = self.velocity_guess(lag, ws, vt, q, p, true);
        if let Some(vs) = ws.velocity.as_mut() {
            vs.c0_lo.iter_mut().for_each(|x| *x = 0.0);
            if let Some(f) = vs.freeze.as_mut() {
                f.start(false);
            }
        }
        // The guess's residual (and the predictor's, to choose between them) with the momentum
        // row rounded: its double-double sum matters only near the solution.
        let mut res = self.velocity_residual(lag, ws, vt, p, MomentumRow::Rounded);
        stats.gradient_evaluations += self.tables().m;
        if stats.guess == InitialGuess::Extrapolate
            && let Some(vs) = ws.velocity.as_mut()
            && (res > EXTRAPOLATION_TRUST * max_abs(&vs.c) || res.is_nan())
        {
            // Continuing a high-degree polynomial a full step ahead amplifies its top modes
            // (near Kepler's periapsis the extrapolated residual reaches O(1)): try the RK4
            // predictor and keep the better of the two.
            vs.prev.copy_from_slice(&vs.c);
            let predicted = self.velocity_guess(lag, ws, vt, q, p, false);
            let r = self.velocity_residual(lag, ws, vt, p, MomentumRow::Rounded);
            stats.gradient_evaluations += self.tables().m;
            if r < res || !res.is_finite() {
                (stats.guess, res) = (predicted, r);
            } else if let Some(vs) = ws.velocity.as_mut() {
                vs.c.copy_from_slice(&vs.prev);
                res = self.velocity_residual(lag, ws, vt, p, MomentumRow::Rounded);
                stats.gradient_evaluations += self.tables().m;
            }
        }
        ws.iterate.clear_last_lo();
        // `Auto`'s memory (every solver that reaches the velocity form keeps it): start with the
        // dense matrix for the steps after two stalls of the frozen Hessian.
        let start_dense = ws.velocity.as_ref().is_some_and(|v| v.dense.is_some())
            && ws.auto.velocity_dense.holding();
        // The fixed-point start, unless it is off, the step starts dense, or it handed over
        // twice within the last few steps (then the frozen Hessian starts, for a while).
        let handover = self.options().structured.velocity_fixed_point_handover;
        let fixed_point = handover > 0.0
            && ws.separable.is_some()
            && !start_dense
            && !ws.auto.velocity_frozen.holding();
        if fixed_point && let Some(vs) = ws.velocity.as_mut() {
            vs.start.copy_from_slice(&vs.c);
            if let Some(f) = vs.freeze.as_mut() {
                f.start(self.options().structured.velocity_freeze_converged_blocks);
            }
        }
        let mut iteration = VelocityNewton {
            gvi: self,
            lag,
            ws,
            vt,
            p,
            stats,
            initial_residual: res,
            start_dense,
            linear: if start_dense {
                Linear::Dense
            } else {
                Linear::Frozen
            },
            fixed_point,
            handover,
            factored: false,
            fresh: false,
            refrozen: false,
            confirmation: false,
            confirmed: false,
        };
        let first = iteration.termination();
        // A step the velocity form does not solve goes to the nodal solvers: an outcome, not an
        // error, so `converges` (which builds no failure message: no allocation per step).
        crate::newton::converges(&mut iteration, &first)
    }
}

/// One velocity-form Newton solve: the problem and its current linear solve.
struct VelocityNewton<'a, B: Basis, Q: Quadrature, L: Lagrangian> {
    gvi: &'a GalerkinIntegrator<B, Q>,
    lag: &'a L,
    ws: &'a mut Workspace,
    vt: &'a VelocityTables,
    p: &'a [f64],
    stats: &'a mut StepStats,
    /// The residual of the chosen guess (iteration 0).
    initial_residual: f64,
    /// The step started with the dense matrix (`Auto`'s memory; not recorded again).
    start_dense: bool,
    /// The iteration is the fixed-point one (J̃ = I ⊗ M) …
    fixed_point: bool,
    /// … until it contracts by less than this.
    handover: f64,
    linear: Linear,
    /// The current linear solve's matrix belongs to this step …
    factored: bool,
    /// … and was built at the last iterate.
    fresh: bool,
    /// The frozen Hessian was refrozen once.
    refrozen: bool,
    /// The last correction confirmed the frozen blocks ([`super::freeze`]) …
    confirmation: bool,
    /// … or one did, earlier in the step.
    confirmed: bool,
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> VelocityNewton<'_, B, Q, L> {
    /// Exact Newton converges quadratically: a slow contraction at small increments is its
    /// round-off floor (the nodal solver's `floor_tolerance`); the frozen Hessian's linear
    /// iteration gets the floor only much closer to round-off. Both trust the contraction
    /// estimate below [`VELOCITY_STALL`] (a frozen Hessian that contracts that fast is near
    /// Newton's own rate here, the Newton matrix being M plus an O(h²) term).
    fn termination(&self) -> Termination {
        let opts = self.gvi.options();
        let floor = match self.linear {
            // No floor for the fixed-point iteration: one that stops contracting hands the step
            // over to the frozen Hessian (`adapt`) rather than stopping where it stands (at
            // θ > 0.5 the error left is at least the last increment).
            //
            // After a confirmation of frozen blocks ([`super::freeze`]) the slowest block has
            // already reached its round-off floor, and so do the corrections from there on:
            // they end the iteration at [`CONFIRMATION_FLOOR`].
            Linear::Frozen if self.fixed_point && self.confirmed => CONFIRMATION_FLOOR,
            Linear::Frozen if self.fixed_point => 0.0,
            Linear::Frozen => VELOCITY_FLOOR,
            Linear::Dense | Linear::Krylov => opts.floor_tolerance,
        };
        Termination::new(
            opts.max_iterations,
            opts.tolerance,
            Some(VELOCITY_STALL),
            floor,
            VELOCITY_STALL,
        )
    }
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> NewtonIteration for VelocityNewton<'_, B, Q, L> {
    fn residual(&mut self, iteration: usize) -> f64 {
        let res = if iteration == 0 {
            self.initial_residual
        } else {
            let masked = self.ws.velocity.as_ref().and_then(|v| v.freeze.as_ref());
            if masked.is_some_and(|f| f.masked()) {
                self.stats.partial_gradient_evaluations += self.gvi.tables().m;
            } else {
                self.stats.gradient_evaluations += self.gvi.tables().m;
            }
            self.gvi
                .velocity_residual(self.lag, self.ws, self.vt, self.p, MomentumRow::Compensated)
        };
        self.stats.residual = res;
        res
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        let (gvi, lag, vt) = (self.gvi, self.lag, self.vt);
        let h = gvi.step_size();
        let ws = &mut *self.ws;
        // The caller only learns whether the velocity form solved the step (`converges`), so
        // a failure carries no message (and allocates nothing).
        let fail = |_why: &str| NewtonFailure {
            residual: self.stats.residual,
            iterations: iteration,
            reason: String::new(),
        };
        let Some(vs) = ws.velocity.as_mut() else {
            return Err(fail("no velocity form"));
        };
        if self.fixed_point
            && let Some(sep) = ws.separable.as_ref()
        {
            let d = ws.d;
            let opts = gvi.options();
            let (size, scale, masked, confirmation) =
                match (vs.freeze.as_mut(), vs.mass_tiled.as_deref()) {
                    (Some(f), Some(tiled)) if f.freezing() => {
                        let (size, active_scale) = match vs.masked.as_ref() {
                            // The masked residual's −F, by coordinate.
                            Some(rows) if rows.holds_residual() => correct_on_rows(
                                &mut vs.c,
                                &mut vs.c0_lo,
                                rows.residual(),
                                (vt.k, rows.kstride()),
                                tiled,
                                !vs.unit_mass,
                                d,
                                f.maxima_mut(),
                            ),
                            _ => correct_on_blocks(
                                &mut vs.c,
                                &mut vs.c0_lo,
                                &mut vs.delta,
                                tiled,
                                !vs.unit_mass,
                                d,
                                f.maxima_mut(),
                            ),
                        };
                        let scale = f.scale(active_scale).max(f64::MIN_POSITIVE);
                        // A confirmation of every block ends freezing; otherwise the blocks
                        // that pass the test are frozen, and while any is, this correction
                        // cannot end the iteration.
                        let confirmation = f.confirmed();
                        let masked =
                            !confirmation && f.update(opts.tolerance, scale, VELOCITY_STALL);
                        (size, scale, masked, confirmation)
                    }
                    _ => {
                        let (size, scale) = vs.correct_fixed_point(sep, d);
                        (size, scale.max(f64::MIN_POSITIVE), false, false)
                    }
                };
            self.confirmation = confirmation;
            self.stats.iterations += 1;
            self.confirmed |= confirmation;
            let termination = if masked {
                // Frozen blocks are not confirmed: no test may pass (but an exact zero).
                Termination::new(opts.max_iterations, 0.0, None, 0.0, VELOCITY_STALL)
            } else {
                self.termination()
            };
            return Ok((Correction { size, scale }, termination));
        }
        // The frozen Hessian's first use builds the pencil's Schur form.
        let Some(kt) = vt.kron() else {
            return Err(fail("no Schur form of the velocity pencil"));
        };
        if !self.factored {
            // At this iterate: the step's guess, or where the iteration stalled.
            self.stats.factorizations += 1;
            match (self.linear, vs.dense.as_mut()) {
                (Linear::Dense, Some(dn)) => {
                    ws.stage.evaluate_node_jacobians(lag);
                    self.stats.hessian_evaluations += gvi.tables().m;
                    let sep = ws.separable.as_ref();
                    assemble_dense(vt, &gvi.tables().weights, h, ws.d, &ws.stage.hall, sep, dn);
                    let size = vt.k * ws.d;
                    if dn.lu.refactor(&dn.jac[..size * size]).is_err() {
                        return Err(fail("singular Newton matrix"));
                    }
                }
                _ => {
                    self.stats.hessian_evaluations +=
                        gvi.mean_force_jacobian(lag, &mut ws.stage, &mut vs.kron);
                    if vs.kron.factor(kt, h).is_err() {
                        return Err(fail("singular frozen matrix"));
                    }
                    // The fast bodies' exact self-blocks beside the frozen mean (none below
                    // `StructuredOptions::velocity_self_block_rate`), from the node Jacobians
                    // the mean was taken from.
                    if let Some(sep) = ws.separable.as_ref() {
                        let (d, b) = (vs.kron.dim(), vs.kron.block());
                        let stage = &ws.stage;
                        let full = stage.node_jacobians_current();
                        let KroneckerWorkParts { exact, mu } = vs.kron.parts();
                        let weights = &gvi.tables().weights;
                        exact.factor_velocity(
                            &vt.psi,
                            &vt.iota,
                            weights,
                            h,
                            sep.mass(),
                            mu,
                            |j, r, s| {
                                if full {
                                    stage.hall[j * d * d + r * d + s]
                                } else {
                                    stage.hblocks[j * d * b + (r / b) * b * b + (r % b) * b + s % b]
                                }
                            },
                        );
                    }
                }
            }
            self.factored = true;
            self.fresh = true;
        }
        let d = ws.d;
        vs.correct(self.linear, kt, h, d);
        self.stats.iterations += 1;
        let delta = max_abs(&vs.delta);
        let scale = max_abs(&vs.c).max(f64::MIN_POSITIVE);
        Ok((Correction { size: delta, scale }, self.termination()))
    }

    fn adapt(&mut self, progress: &Progress) -> Adapt {
        let theta = progress.theta;
        let stalled = theta.is_finite() && theta > VELOCITY_STALL;
        let has_dense = self.ws.velocity.as_ref().is_some_and(|v| v.dense.is_some());
        let opts = self.gvi.options();
        let fresh = std::mem::replace(&mut self.fresh, false);
        if std::mem::replace(&mut self.confirmation, false) {
            // The confirmation's ratio to the last masked correction measures a frozen block's
            // drift against the slowest block's last step, not a contraction: the iteration
            // continues (no hand-over), and the next ratio is between two full corrections.
            return Adapt::Continue;
        }
        if self.fixed_point {
            if !(theta.is_finite() && theta > self.handover) {
                return Adapt::Continue;
            }
            // Too slow for the fixed-point iteration: the frozen Hessian from here — or from
            // the step's guess, if the fixed-point iterations moved away from it.
            self.fixed_point = false;
            if let Some(f) = self.ws.velocity.as_mut().and_then(|v| v.freeze.as_mut()) {
                f.stop();
            }
            self.stats.fallbacks += 1;
            self.ws.auto.velocity_frozen.failure();
            if theta >= 1.0
                && let Some(vs) = self.ws.velocity.as_mut()
            {
                vs.c.copy_from_slice(&vs.start);
                vs.c0_lo.iter_mut().for_each(|x| *x = 0.0);
            }
            return Adapt::Restart;
        }
        match self.linear {
            Linear::Frozen if stalled && !self.refrozen => {
                self.factored = false;
                self.refrozen = true;
                Adapt::Restart
            }
            // The frozen Hessian is too far from the step's even when refrozen: exact Newton
            // in the same form, where the system is small enough; otherwise the nodal solvers
            // take the step.
            Linear::Frozen if stalled && !has_dense => Adapt::GiveUp,
            Linear::Frozen if stalled => {
                self.linear = Linear::Dense;
                self.factored = false;
                self.stats.fallbacks += 1;
                Adapt::Restart
            }
            Linear::Dense if stalled && fresh => Adapt::GiveUp,
            // A matrix from an earlier iterate that no longer contracts fast: rebuild it.
            Linear::Dense if theta.is_finite() && theta > opts.dense.reuse_contraction => {
                self.factored = false;
                Adapt::Restart
            }
            _ => Adapt::Continue,
        }
    }

    fn finish(&mut self, _: ConvergedBy) -> Result<(), NewtonFailure> {
        // The forces at the solution: the impulse and the step's residual. Its correction
        // costs no force evaluation and is applied too: a linear iteration stopped on its
        // contraction estimate leaves a remainder of one sign along the orbit (measured:
        // Kepler, Legendre n = 24, h = 0.5, T = 20 000 drifts to 1.5e-8 and ΔE = −2.8e-13
        // without it), the correction shrinks it by the contraction factor. The impulse keeps
        // the forces before it (they differ by O(h²|H|) times a correction at the round-off
        // level).
        //
        // Ending on the confirmation of frozen blocks ([`super::freeze`]), that confirmation
        // is this final pass: its residual is of every block, its forces are in the stage for
        // the impulse, and its correction is applied — the same structure, one residual fewer.
        let (gvi, vt) = (self.gvi, self.vt);
        if let Some(f) = self.ws.velocity.as_mut().and_then(|v| v.freeze.as_mut()) {
            f.stop();
        }
        if !self.confirmation {
            self.stats.residual =
                gvi.velocity_residual(self.lag, self.ws, vt, self.p, MomentumRow::Compensated);
            self.stats.gradient_evaluations += gvi.tables().m;
        }
        let (h, d) = (gvi.step_size(), self.ws.d);
        let fixed_point = self.ws.separable.as_ref().filter(|_| self.fixed_point);
        if let Some(vs) = self.ws.velocity.as_mut().filter(|_| !self.confirmation) {
            match (fixed_point, vt.kron()) {
                (Some(sep), _) => {
                    vs.correct_fixed_point(sep, d);
                }
                (None, Some(kt)) => vs.correct(self.linear, kt, h, d),
                (None, None) => {}
            }
        }
        if self.fixed_point {
            self.ws.auto.velocity_frozen.calm_solve();
        }
        if !self.start_dense {
            if self.linear == Linear::Dense {
                self.ws.auto.velocity_dense.failure();
            } else {
                self.ws.auto.velocity_dense.calm_solve();
            }
        }
        gvi.finish_velocity_form(self.ws, vt);
        Ok(())
    }
}
