//! The ladder of integrators ("rungs") of a tolerance-driven run: each rung's integrator,
//! workspace and step-end buffers, where each solve's Newton iteration starts (warm starts,
//! continuation, the integrator's own guesses), the transfer matrices between rungs, and the
//! bookkeeping the error controls share (costs per start, streaks, the round-off floor).

use super::descent::rungs_down;
use crate::basis::{AnyBasis, Basis};
use crate::curve::GalerkinCurve;
use crate::integrator::{GalerkinIntegrator, StepFailure, StepStats, Workspace};
use crate::lagrangian::Lagrangian;
use crate::quadrature::QuadratureRule;

/// Steps remembered by [`Ladder::swing_start`].
const SWING_WINDOW: usize = 3;
/// [`Ladder::swing_start`]: the largest over the smallest n of the last [`SWING_WINDOW`] lower
/// rungs from which the need counts as swinging.
const SWING: f64 = 1.5;

/// A continued start keeps the Chebyshev modes j with |a_j| T_j(3) ≤ this fraction of the
/// curve's size (|a_0| + |a_1|), up to the first that exceeds it.
const CONTINUE_TRUNCATION: f64 = 1.0;
/// A warm-started solve to be kept is redone cold when its stage residual exceeds this
/// fraction of max|p_k| (converged solves measured at 1e-16 relative on Kepler, 1e-14 on
/// the outer solar system).
const WARM_RESIDUAL: f64 = 1e-8;
/// Weight of the latest run of steps at one rung in [`Ladder::streak_ema`].
const STREAK_EMA: f64 = 0.25;
/// Weight of the latest first solve in the moving averages of [`Ladder::first_start`].
const START_EMA: f64 = 0.25;
/// [`Ladder::first_start`] tries the start not chosen at least every this many steps; the
/// spacing doubles (up to [`START_RETRY_MAX`]) each time the retried start loses again.
pub(super) const START_RETRY: usize = 8;
/// See [`START_RETRY`].
const START_RETRY_MAX: usize = 64;

/// One rung of the ladder: an integrator at one n with its workspace and this step's result.
pub(super) struct Rung {
    pub(super) gvi: GalerkinIntegrator<AnyBasis, QuadratureRule>,
    /// The same integrator with a Newton tolerance loosened to the error budget, for solves
    /// that only serve as the lower member of an embedded pair (never kept).
    pub(super) loose: GalerkinIntegrator<AnyBasis, QuadratureRule>,
    /// The current step's solution came from `loose`.
    pub(super) is_loose: bool,
    pub(super) ws: Workspace,
    pub(super) q: Vec<f64>,
    pub(super) p: Vec<f64>,
    pub(super) stats: StepStats,
    pub(super) ind: f64,
    /// Solved for the current step: Some(true) converged, Some(false) failed.
    pub(super) solved: Option<bool>,
}

/// The rungs of a run and the state the error controls share across steps.
pub(super) struct Ladder {
    /// The start time t_k of the step being solved (time-dependent and forced systems).
    pub(super) t: f64,
    pub(super) rungs: Vec<Rung>,
    pub(super) evaluations: usize,
    pub(super) last_failure: Option<StepFailure>,
    pub(super) d: usize,
    /// Warm-start the solves (see [`Start`]); off: every solve chooses its own guess.
    pub(super) warm: bool,
    /// Solve the lower member of an embedded pair with the loose Newton tolerance (only when
    /// the upper one is kept: [`ErrorControl::Embedded`](super::ErrorControl::Embedded) with local extrapolation).
    pub(super) loose_ok: bool,
    /// The measured floor of the embedded estimates (0: no stall seen), and the last climb
    /// (rung it started from, step) of the embedded control.
    pub(super) noise: f64,
    pub(super) climbed_from: Option<(usize, usize)>,
    /// The last step down whose first estimate missed the budget: (rung, step).
    pub(super) failed: Option<(usize, usize)>,
    /// The lower rung of the last embedded step.
    pub(super) last_lo: Option<usize>,
    /// Steps in a row at the current lower rung, and their moving average over past runs
    /// of steps (how long a rung stays right: the amortisation horizon of a step down).
    pub(super) streak: usize,
    pub(super) streak_ema: f64,
    /// The last rung accepted within the budget (checked or predicted), and the step.
    pub(super) passed: Option<(usize, usize)>,
    /// Memory of [`Ladder::failed`], steps ([`AdaptiveOptions::check_every`](super::AdaptiveOptions::check_every)).
    pub(super) horizon: usize,
    /// The lower rungs of the last [`SWING_WINDOW`] steps (ring buffer) and how many are set.
    pub(super) recent: [usize; SWING_WINDOW],
    pub(super) recent_len: usize,
    /// [`AdaptiveOptions::follow_swings`](super::AdaptiveOptions::follow_swings).
    pub(super) follow_swings: bool,
    pub(super) transfers: Transfers,
    /// The last accepted step's curve (solved at rung `prev_rung`; room for the largest n).
    pub(super) prev: GalerkinCurve,
    pub(super) prev_rung: Option<usize>,
    /// Force evaluations and quadrature nodes of the solves so far, by start: first solves of
    /// a step (continued or cold) and refitted ones.
    pub(super) first_cost: (usize, usize),
    pub(super) refit_cost: (usize, usize),
    /// Recent force evaluations per quadrature node of first solves started cold and
    /// continued (exponential moving averages; NaN: not measured yet), and the steps since
    /// the start not chosen was last tried.
    pub(super) start_cost: [f64; 2],
    pub(super) since_other: usize,
    /// Current spacing of the retries, and the start being retried (measured by the next
    /// solve to round-off that used it).
    pub(super) retry_every: usize,
    pub(super) retrying: Option<Start>,
    /// Warm-start coefficients being assembled (max n × D), Chebyshev coefficients of the
    /// last accepted curve (max n × D) and scratch for fitting (2 max n).
    pub(super) buf: Vec<f64>,
    pub(super) cheb: Vec<f64>,
    pub(super) fit_scratch: Vec<f64>,
}

/// Where a solve's Newton iteration starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Start {
    /// The integrator's own guesses (best residual of predictor, extrapolation, line, constant).
    Cold,
    /// The curve of another rung solved at this step, refitted at this rung's nodes.
    Refit(usize),
    /// The last accepted step's curve continued over this step, fitted at this rung's nodes.
    Continue,
}

/// Lazily built matrices between the rungs (n_to × n_from each, built on first use of a pair:
/// the only allocations of the stepping loop). `refit`: the curve Σ_l Q_l φ_l^{from}(τ) of
/// one step fitted at rung `to`'s interpolation nodes (coefficients to coefficients).
/// `cheb`: T_j(1 + 2x_k), the Chebyshev polynomial j continued to the next step's
/// interpolation node x_k of rung `to` (τ = 1 + x_k, i.e. 2τ − 1 = 1 + 2x_k).
pub(super) struct Transfers {
    pub(super) rungs: usize,
    pub(super) refit: Vec<Option<Vec<f64>>>,
    pub(super) cheb: Vec<Option<Vec<f64>>>,
}

impl Transfers {
    pub(super) fn new(rungs: usize) -> Self {
        Transfers {
            rungs,
            refit: vec![None; rungs * rungs],
            cheb: vec![None; rungs * rungs],
        }
    }

    pub(super) fn refit(&mut self, rungs: &[Rung], from: usize, to: usize) -> &[f64] {
        self.refit[from * self.rungs + to].get_or_insert_with(|| {
            let (src, dst) = (&rungs[from].gvi, &rungs[to].gvi);
            let nf = src.n();
            let fit = dst.curve_fit();
            let mut t = vec![0.0; dst.n() * nf];
            let (mut v, mut dv) = (vec![0.0; nf], vec![0.0; nf]);
            for (k, &x) in fit.nodes().iter().enumerate() {
                src.basis().eval(x, &mut v, &mut dv);
                t[k * nf..(k + 1) * nf].copy_from_slice(&v);
            }
            fit.values_to_coefficients(&mut t, nf);
            t
        })
    }

    pub(super) fn cheb(&mut self, rungs: &[Rung], from: usize, to: usize) -> &[f64] {
        self.cheb[from * self.rungs + to].get_or_insert_with(|| {
            let nf = rungs[from].gvi.n();
            let nodes = rungs[to].gvi.curve_fit().nodes();
            let mut t = vec![0.0; nodes.len() * nf];
            for (k, &x) in nodes.iter().enumerate() {
                let y = 1.0 + 2.0 * x;
                let (mut a, mut b) = (1.0, y);
                for j in 0..nf {
                    t[k * nf + j] = a;
                    (a, b) = (b, 2.0 * y * b - a);
                }
            }
            t
        })
    }
}

impl Ladder {
    /// Set rung i's next Newton start from `start`; false if that start is unavailable.
    pub(super) fn warm_start(&mut self, i: usize, start: Start) -> bool {
        let d = self.d;
        let nt = self.rungs[i].gvi.n();
        match start {
            Start::Cold => return false,
            Start::Refit(j) => {
                if self.rungs[j].solved != Some(true) {
                    return false;
                }
                let nf = self.rungs[j].gvi.n();
                let t = self.transfers.refit(&self.rungs, j, i);
                let src = self.rungs[j].ws.curve().coefficients();
                let out = &mut self.buf[..nt * d];
                for (k, row) in t.chunks_exact(nf).enumerate() {
                    for r in 0..d {
                        out[k * d + r] = row
                            .iter()
                            .zip(src.chunks_exact(d))
                            .map(|(a, q)| a * q[r])
                            .sum();
                    }
                }
            }
            Start::Continue => {
                let Some(j) = self.prev_rung else {
                    return false;
                };
                let nf = self.rungs[j].gvi.n();
                // Chebyshev coefficients a of the last accepted curve.
                let c = self.rungs[j].gvi.chebyshev_transform();
                let a = &mut self.cheb[..nf * d];
                for (jj, row) in c.chunks_exact(nf).enumerate() {
                    for r in 0..d {
                        a[jj * d + r] = row
                            .iter()
                            .zip(self.prev.coefficients().chunks_exact(d))
                            .map(|(w, q)| w * q[r])
                            .sum();
                    }
                }
                // Continue only the modes whose continuation stays small: |a_j| T_j(3) grows
                // like |a_j| 5.83^j, so the round-off tail of a long curve would swamp it.
                let mode = |jj: usize| {
                    a[jj * d..(jj + 1) * d]
                        .iter()
                        .fold(0.0f64, |m, x| m.max(x.abs()))
                };
                let scale = (mode(0) + if nf > 1 { mode(1) } else { 0.0 }).max(f64::MIN_POSITIVE);
                let (mut t_prev, mut t_j) = (1.0, 3.0);
                let mut keep = nf.min(2);
                for jj in 2..nf {
                    (t_prev, t_j) = (t_j, 6.0 * t_j - t_prev);
                    if mode(jj) * t_j > CONTINUE_TRUNCATION * scale {
                        break;
                    }
                    keep = jj + 1;
                }
                let t = self.transfers.cheb(&self.rungs, j, i);
                let out = &mut self.buf[..nt * d];
                for (k, row) in t.chunks_exact(nf).enumerate() {
                    for r in 0..d {
                        out[k * d + r] = (0..keep).map(|jj| row[jj] * a[jj * d + r]).sum();
                    }
                }
                let (col, scratch) = self.fit_scratch.split_at_mut(nt);
                self.rungs[i].gvi.curve_fit().values_to_coefficients_with(
                    out,
                    d,
                    col,
                    &mut scratch[..nt],
                );
            }
        }
        self.rungs[i].ws.warm_start(&self.buf[..nt * d]).is_ok()
    }

    /// Solve the current step at rung i (once per step) starting Newton from `start`;
    /// whether it converged.
    pub(super) fn solve<L: Lagrangian>(
        &mut self,
        lag: &L,
        i: usize,
        start: Start,
        loose: bool,
        q: &[f64],
        p: &[f64],
    ) -> bool {
        if let Some(ok) = self.rungs[i].solved {
            return ok;
        }
        let warmed = self.warm && self.warm_start(i, start);
        let d = self.d;
        let r = &mut self.rungs[i];
        let gvi = if loose { &r.loose } else { &r.gvi };
        r.ws.stage.set_step_start(self.t, 0.0, &[]);
        let mut result = gvi.step(lag, &mut r.ws, q, p, &mut r.q, &mut r.p);
        if warmed && !loose {
            // Guard: a warm start must not yield a kept step that is not solved to round-off
            // (Newton's increment test is relative to the size of the iterate, which a poor
            // start can inflate). Redo it from the integrator's own guesses.
            let pscale = p
                .iter()
                .fold(0.0f64, |m, x| m.max(x.abs()))
                .max(f64::MIN_POSITIVE);
            if let Ok(stats) = &result
                && (stats.residual.is_nan() || stats.residual > WARM_RESIDUAL * pscale)
            {
                self.evaluations += stats.gradient_evaluations;
                r.ws.reset();
                r.ws.stage.set_step_start(self.t, 0.0, &[]);
                result = gvi.step(lag, &mut r.ws, q, p, &mut r.q, &mut r.p);
            }
        }
        let ok = match result {
            Ok(stats) => {
                self.evaluations += stats.gradient_evaluations;
                let m = r.gvi.rule().nodes.len();
                let c = if matches!(start, Start::Refit(_)) {
                    &mut self.refit_cost
                } else {
                    &mut self.first_cost
                };
                c.0 += stats.gradient_evaluations;
                c.1 += m;
                // Only solves to round-off compare the starts: a loose solve stops early
                // whatever its start (measured on the outer solar system: loose continued
                // solves looked cheap and kept the continued start, which costs 8–13 Newton
                // iterations per solve to round-off there against 3 from the predictor).
                let slot = match start {
                    _ if loose => None,
                    Start::Cold => Some(0),
                    Start::Continue => Some(1),
                    Start::Refit(_) => None,
                };
                if let Some(s) = slot {
                    let x = stats.gradient_evaluations as f64 / m as f64;
                    if self.retrying.take_if(|r| *r == start).is_some() {
                        // Back off from a start that keeps losing (outer solar system: the
                        // continued start costs 1.4× the cold one per node, and retrying it
                        // every 8 steps cost 6 % of the run).
                        let other = self.start_cost[1 - s];
                        self.retry_every = if x > other {
                            (2 * self.retry_every).min(START_RETRY_MAX)
                        } else {
                            START_RETRY
                        };
                    }
                    let e = &mut self.start_cost[s];
                    *e = if e.is_nan() {
                        x
                    } else {
                        *e + START_EMA * (x - *e)
                    };
                }
                r.stats = stats;
                r.ind = r.gvi.modal_indicator(r.ws.coefficients(), d);
                r.is_loose = loose;
                true
            }
            Err(f) => {
                self.last_failure = Some(f);
                false
            }
        };
        r.solved = Some(ok);
        ok
    }

    /// Embedded estimate of rung i's error: |q_i − q_{i+1}|∞ (infinite if either failed).
    pub(super) fn estimate<L: Lagrangian>(
        &mut self,
        lag: &L,
        i: usize,
        start: Start,
        q: &[f64],
        p: &[f64],
    ) -> f64 {
        let a = self.solve(lag, i, start, self.loose_ok, q, p);
        let b = self.solve(lag, i + 1, Start::Refit(i), false, q, p);
        if !(a && b) {
            return f64::INFINITY;
        }
        let (x, y) = (&self.rungs[i].q, &self.rungs[i + 1].q);
        x.iter()
            .zip(y)
            .map(|(u, v)| (u - v).abs())
            .fold(0.0, f64::max)
    }

    /// How to start the first solve of a step: continued from the last accepted curve or cold
    /// (the integrator's guess competition), whichever has recently cost fewer force
    /// evaluations per node; each is tried at least every [`START_RETRY`] steps.
    pub(super) fn first_start(&mut self) -> Start {
        if !self.warm || self.prev_rung.is_none() {
            return Start::Cold;
        }
        let [cold, cont] = self.start_cost;
        let best = if cont.is_nan() || cont <= cold {
            Start::Continue
        } else {
            Start::Cold
        };
        self.since_other += 1;
        if self.since_other >= self.retry_every {
            self.since_other = 0;
            let other = if best == Start::Continue {
                Start::Cold
            } else {
                Start::Continue
            };
            self.retrying = Some(other);
            return other;
        }
        best
    }

    /// The rung to start the next step from after rung `lo` was accepted with the estimated
    /// error `e`: [`rungs_down`] rungs lower, unless solving rung `lo` alone (an unchecked step,
    /// possible while the indicator does not grow) is expected to cost less than a checked
    /// step lower down (first solve at j, refitted solve at j + 1), by the measured force
    /// evaluations per quadrature node of first and refitted solves.
    pub(super) fn next_rung(&self, lo: usize, e: f64, budget: f64, k: usize) -> usize {
        let mut j = lo.saturating_sub(rungs_down(e, budget));
        // Not below the middle between a rung that missed the budget within the last
        // `horizon` steps and lo: bisection where the decay model cannot tell (measured: the
        // oscillator at h = 20 stepped from n = 28 down to 14 where 24 was needed).
        if let Some((f, s)) = self.failed
            && f < lo
            && k < s + self.horizon
        {
            j = j.max((f + 1 + lo).div_ceil(2));
        }
        if j >= lo {
            return lo;
        }
        let per_node = |c: (usize, usize)| c.0 as f64 / c.1.max(1) as f64;
        let (first, refit) = (per_node(self.first_cost), per_node(self.refit_cost));
        let m = |i: usize| self.rungs[i].gvi.rule().nodes.len() as f64;
        // Over the next `horizon` steps: unchecked solves at lo, against one checked step at
        // j followed by unchecked solves there (measured: comparing single steps kept the
        // oscillator at h = 20 on n = 40 for a whole run where n = 21 meets tol).
        let horizon = self
            .streak_ema
            .max(self.streak as f64)
            .clamp(1.0, self.horizon as f64);
        if horizon * first * m(lo)
            <= first * m(j) + refit * m(j + 1) + (horizon - 1.0) * first * m(j)
        {
            lo
        } else {
            j
        }
    }

    /// The rung to start the next step from, given the lower rung `lo` of this step and the
    /// rung `next` proposed from its estimate: `next`, or the lowest lower rung of the last
    /// [`SWING_WINDOW`] steps when their n differ by a factor of at least [`SWING`] (the need
    /// swings from step to step, and the step after a hard one is usually easy). Measured
    /// (100 steps, tol 1e-6…1e-12, cost against the cheapest fixed n): Kepler e = 0.6 at h = 2
    /// (three steps per orbit needing n ≈ 45, 10 and 13 in turn; a step after the hardest one
    /// started at its rung) 1.32–1.65× → 1.09–1.34×, at h = 1 1.10–1.21× → 0.93–1.03×, e = 0.9
    /// at h = 0.25 0.28–0.35× → 0.22–0.27×; the oscillator and the outer solar system, whose
    /// need hardly varies, unchanged. Without the spread condition (always the lowest recent
    /// rung) the outer solar system at tol = 1e-6 cost 1.62× instead of 1.37×: its rare easy
    /// steps led the next ones into failed steps down.
    pub(super) fn swing_start(&mut self, lo: usize, next: usize) -> usize {
        self.recent[self.recent_len % SWING_WINDOW] = lo;
        self.recent_len += 1;
        let seen = &self.recent[..self.recent_len.min(SWING_WINDOW)];
        let (low, high) = seen
            .iter()
            .fold((usize::MAX, 0), |(a, b), &r| (a.min(r), b.max(r)));
        let n = |i: usize| self.rungs[i].gvi.n() as f64;
        if self.follow_swings && n(high) >= SWING * n(low) {
            next.min(low)
        } else {
            next
        }
    }

    /// Re-solve rung i to round-off if its solution of this step came from the loose solver
    /// (before it is kept), starting from that solution; whether it converged.
    pub(super) fn tighten<L: Lagrangian>(
        &mut self,
        lag: &L,
        i: usize,
        q: &[f64],
        p: &[f64],
    ) -> bool {
        if !(self.ok(i) && self.rungs[i].is_loose) {
            return self.ok(i);
        }
        self.warm_start(i, Start::Refit(i));
        self.rungs[i].solved = None;
        self.solve(lag, i, Start::Refit(i), false, q, p)
    }

    /// Record that a step of the embedded control had lower rung `lo` (for the streaks).
    pub(super) fn note_rung(&mut self, lo: usize) {
        if self.last_lo == Some(lo) {
            self.streak += 1;
        } else {
            if self.streak > 0 {
                self.streak_ema += STREAK_EMA * (self.streak as f64 - self.streak_ema);
            }
            self.streak = 1;
        }
        self.last_lo = Some(lo);
    }

    pub(super) fn ok(&self, i: usize) -> bool {
        self.rungs[i].solved == Some(true)
    }
}

/// What one step accepted.
pub(super) struct Accepted {
    /// The rung whose solution is kept.
    pub(super) keep: usize,
    /// The rung to start the next step from.
    pub(super) next: usize,
    pub(super) estimate: Option<f64>,
    /// The estimate (or scaled indicator) exceeded the budget at the top rung.
    pub(super) missed: Option<f64>,
}

/// Geometric decay rate σ per mode of the step's Chebyshev coefficients, from the envelope at
/// n/2 and at the last pair: the indicator at n' is predicted as ind · exp(−σ (n' − n)).
pub(super) fn decay_rate(r: &Rung, d: usize) -> f64 {
    let n = r.gvi.n();
    if n < 6 {
        return 0.3;
    }
    let mode = |j: usize| r.gvi.chebyshev_mode_size(r.ws.coefficients(), d, j);
    let env = |j: usize| (j..(j + 2).min(n)).map(mode).fold(0.0f64, f64::max);
    let (j1, j2) = (n / 2, n - 2);
    let (e1, e2) = (env(j1), env(j2).max(1e-300));
    ((e1 / e2).ln() / (j2 - j1) as f64).clamp(0.05, 5.0)
}
