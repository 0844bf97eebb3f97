//! Initial guesses for each step's Newton iteration: constant, linear, extrapolated and
//! RK4-predictor curves, and the residual competition that picks among them
//! ([`InitialGuess`]).

mod state;

pub(super) use state::GuessState;

use super::stage::Mode;
use super::{GalerkinIntegrator, Workspace};
use crate::basis::Basis;
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;
use crate::stats::InitialGuess;

/// Steps between full competitions of the initial guesses.
const GUESS_RECHECK: usize = 16;
/// A remembered guess is taken without a competition if its residual is at most this multiple
/// of the residual of the last competition's winner.
const GUESS_SLACK: f64 = 4.0;

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// The RK4 predictor into the candidate guess; false when unavailable (non-separable Lagrangian) or
    /// not finite.
    fn predict<L: Lagrangian>(&self, lag: &L, ws: &mut Workspace, q: &[f64], p: &[f64]) -> bool {
        if !self.predict_values(lag, ws, q, p) {
            return false;
        }
        self.tables().fit.values_to_coefficients_with(
            &mut ws.guess.cand,
            ws.d,
            &mut ws.guess.fit_col,
            &mut ws.guess.fit_scratch,
        );
        true
    }

    /// The RK4 predictor's increments from q_k at the basis's interpolation nodes (n×D) into
    /// the candidate guess, before the fit to coefficients: the velocity form maps them to
    /// its modes with the fit folded into one table. False when unavailable (non-separable
    /// Lagrangian).
    pub(super) fn predict_values<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
    ) -> bool {
        let Some(sep) = &ws.separable else {
            return false;
        };
        let t = self.tables();
        let (d, h) = (ws.d, self.step_size());
        let sub = ws.guess.rk_substeps;
        let dt = h / sub as f64;
        let w = 2 * d;
        // State y = (q, v) at every substep end, v = M⁻¹p at the start.
        ws.guess.rk_states[..d].copy_from_slice(q);
        ws.stage.vel.copy_from_slice(p);
        sep.solve_mass(&mut ws.stage.vel, &mut ws.stage.small_scratch);
        ws.guess.rk_states[d..w].copy_from_slice(&ws.stage.vel);
        for s in 0..sub {
            let (done, rest) = ws.guess.rk_states.split_at_mut((s + 1) * w);
            let y0 = &done[s * w..];
            let y1 = &mut rest[..w];
            // k_i = f(y0 + c_i dt k_{i−1}); f(q, v) = (v, M⁻¹ L_q(q)).
            for stage in 0..4 {
                let c = match stage {
                    0 => 0.0,
                    3 => dt,
                    _ => 0.5 * dt,
                };
                for r in 0..w {
                    let prev = if stage == 0 {
                        0.0
                    } else {
                        ws.guess.rk_k[(stage - 1) * w + r]
                    };
                    ws.guess.rk_tmp[r] = y0[r] + c * prev;
                }
                let k = &mut ws.guess.rk_k[stage * w..(stage + 1) * w];
                k[..d].copy_from_slice(&ws.guess.rk_tmp[d..w]);
                lag.force(&ws.guess.rk_tmp[..d], &mut k[d..w]);
                ws.guess.guess_force_evaluations += 1;
                sep.solve_mass(&mut k[d..w], &mut ws.stage.small_scratch);
            }
            for r in 0..w {
                let k = &ws.guess.rk_k;
                y1[r] =
                    y0[r] + dt / 6.0 * (k[r] + 2.0 * k[w + r] + 2.0 * k[2 * w + r] + k[3 * w + r]);
            }
        }
        // Cubic Hermite interpolation at the interpolation nodes, then fit coefficients.
        for (k, &x) in t.fit.nodes().iter().enumerate() {
            let pos = (x * sub as f64).clamp(0.0, sub as f64);
            let i = (pos.floor() as usize).min(sub - 1);
            let s = pos - i as f64;
            let (s2, s3) = (s * s, s * s * s);
            let (h00, h10, h01, h11) = (
                2.0 * s3 - 3.0 * s2 + 1.0,
                s3 - 2.0 * s2 + s,
                -2.0 * s3 + 3.0 * s2,
                s3 - s2,
            );
            let (a, b) = (
                &ws.guess.rk_states[i * w..(i + 1) * w],
                &ws.guess.rk_states[(i + 1) * w..(i + 2) * w],
            );
            // Increments from q_k (h00 + h01 = 1).
            for r in 0..d {
                ws.guess.cand[k * d + r] = h00 * (a[r] - q[r])
                    + h10 * dt * a[d + r]
                    + h01 * (b[r] - q[r])
                    + h11 * dt * b[d + r];
            }
        }
        true
    }

    /// Fill `ws.guess.cand` with the guess of kind `g`; false if that guess is unavailable.
    pub(super) fn make_guess<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        g: InitialGuess,
        q: &[f64],
        p: &[f64],
    ) -> bool {
        let t = self.tables();
        let (n, d, h) = (t.n, ws.d, self.step_size());
        match g {
            InitialGuess::Constant | InitialGuess::BestResidual | InitialGuess::Warm => {
                ws.guess.cand.iter_mut().for_each(|x| *x = 0.0);
            }
            InitialGuess::Linear => {
                if ws.guess.has_prev {
                    // End velocity of the previous Galerkin curve.
                    for r in 0..d {
                        ws.stage.vel[r] = (0..n)
                            .map(|i| t.dphi_end[i] * ws.guess.prev[i * d + r])
                            .sum::<f64>()
                            / h;
                    }
                } else {
                    ws.stage.vel.copy_from_slice(p);
                    self.inverse_legendre(lag, ws, q, p);
                }
                for i in 0..n {
                    for r in 0..d {
                        ws.guess.cand[i * d + r] = t.ramp[i] * h * ws.stage.vel[r];
                    }
                }
            }
            InitialGuess::Predictor => {
                if !self.predict(lag, ws, q, p) {
                    return false;
                }
            }
            InitialGuess::Extrapolate => {
                let Some(e) = &t.extrapolate else {
                    return false;
                };
                if !ws.guess.has_prev {
                    return false;
                }
                // The previous curve is q_{k−1} + Σ ΔP_i φ_i and q_k = q_{k−1} + ΔP_{n−1}; E
                // maps constants to constants, so the continued curve's increments from q_k
                // are E ΔP − u ΔP_{n−1}.
                let last = (n - 1) * d;
                for i in 0..n {
                    for r in 0..d {
                        let c: f64 = (0..n)
                            .map(|k| e[i * n + k] * ws.guess.prev[k * d + r])
                            .sum();
                        ws.guess.cand[i * d + r] = c - t.unit[i] * ws.guess.prev[last + r];
                    }
                }
            }
        }
        // The start of the curve is q_k exactly: ΔQ_0 = 0.
        ws.guess.cand[..d].iter_mut().for_each(|x| *x = 0.0);
        ws.guess.cand.iter().all(|x| x.is_finite())
    }

    /// Choose the initial guess into the iterate; returns (choice, gradient evaluations).
    pub(super) fn initial_guess<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        q: &[f64],
        p: &[f64],
    ) -> (InitialGuess, usize) {
        if ws.guess.has_warm {
            ws.guess.has_warm = false;
            // Absolute coefficients to increments from q_k (ΔQ_0 = 0).
            let (t, d) = (self.tables(), ws.d);
            let increments = ws.iterate.increments_mut();
            for i in 0..t.n {
                for r in 0..d {
                    increments[i * d + r] = ws.guess.warm[i * d + r] - t.unit[i] * q[r];
                }
            }
            increments[..d].iter_mut().for_each(|x| *x = 0.0);
            return (InitialGuess::Warm, 0);
        }
        let choice = self.options().initial_guess;
        if !matches!(choice, InitialGuess::BestResidual | InitialGuess::Warm) {
            let g = if self.make_guess(lag, ws, choice, q, p) {
                choice
            } else {
                self.make_guess(lag, ws, InitialGuess::Linear, q, p);
                InitialGuess::Linear
            };
            ws.iterate.increments_mut().copy_from_slice(&ws.guess.cand);
            return (g, 0);
        }
        let mut evals = 0;
        // Between full competitions (every GUESS_RECHECK steps) the previous winner is taken
        // at once if its residual is within GUESS_SLACK of the last competition's: the ranking
        // changes slowly along a trajectory, and the competition costs three more residuals and
        // an RK4 integration (more than the Newton iteration itself at small h). Its residual
        // is Newton's first (the iterate's ready residual), so the check costs nothing when it passes.
        if let Some(winner) = ws.guess.guess_winner
            && ws.guess.guess_age < GUESS_RECHECK
            && self.make_guess(lag, ws, winner, q, p)
        {
            evals += self.action_gradient(lag, ws, true);
            let r = self.residual(ws, Mode::InitialValue, p);
            if r <= GUESS_SLACK * ws.guess.guess_reference {
                ws.guess.guess_age += 1;
                ws.iterate.increments_mut().copy_from_slice(&ws.guess.cand);
                ws.iterate.set_ready_residual(Some(r));
                return (winner, evals);
            }
        }
        let mut best = (InitialGuess::Constant, f64::INFINITY);
        for g in [
            InitialGuess::Predictor,
            InitialGuess::Extrapolate,
            InitialGuess::Linear,
            InitialGuess::Constant,
        ] {
            if !self.make_guess(lag, ws, g, q, p) {
                continue;
            }
            evals += self.action_gradient(lag, ws, true);
            let r = self.residual(ws, Mode::InitialValue, p);
            if r < best.1 {
                best = (g, r);
                ws.guess.best.copy_from_slice(&ws.guess.cand);
            }
        }
        if best.1.is_finite() {
            ws.iterate.increments_mut().copy_from_slice(&ws.guess.best);
            ws.guess.guess_winner = Some(best.0);
            ws.guess.guess_reference = best.1;
            ws.guess.guess_age = 0;
        } else {
            self.make_guess(lag, ws, InitialGuess::Constant, q, p);
            ws.iterate.increments_mut().copy_from_slice(&ws.guess.cand);
        }
        (best.0, evals)
    }
}
