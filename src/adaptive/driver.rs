//! The stepping loop of [`integrate_adaptive`]: a ladder of integrators ("rungs"), each with
//! its own workspace and step-end buffers, and the three error controls.

use super::{AdaptiveOptions, AdaptiveRun, ErrorControl, INDICATOR_EXPONENT};
use crate::basis::{AnyBasis, Basis};
use crate::error::GviError;
use crate::integrator::{
    GalerkinIntegrator, IntegrationFailure, StepFailure, StepStats, Workspace,
};
use crate::lagrangian::Lagrangian;
use crate::quadrature::QuadratureRule;
use crate::trajectory::Trajectory;

/// Round-off floor warning: tol below FLOOR_FACTOR · ε · max|q0| · steps.
const FLOOR_FACTOR: f64 = 1000.0;
/// [`ErrorControl::Embedded`]: an unchecked step is allowed while the indicator is at most
/// this factor above that of the last check.
const GROWTH: f64 = 1.0;
/// Step down one rung per factor DOWN that the estimate lies below the budget (at most
/// [`MAX_DOWN`]), unless staying is predicted cheaper ([`Ladder::next_rung`]).
const DOWN: f64 = 0.05;
/// A continued start keeps the Chebyshev modes j with |a_j| T_j(3) ≤ this fraction of the
/// curve's size (|a_0| + |a_1|), up to the first that exceeds it.
const CONTINUE_TRUNCATION: f64 = 1.0;
/// Ratio of the decay rate (per unit n) of the embedded estimate to that of the Chebyshev
/// coefficients of the curve, measured 1.5–1.7 on Kepler e = 0.6 (h = 1, n = 4…24).
const DECAY_RATIO: f64 = 1.5;
/// Newton tolerance of the lower member of an embedded pair (never kept): this fraction of
/// the per-step budget, relative to max|q0| (but never tighter than the default).
const LOOSE_NEWTON: f64 = 0.1;
/// A warm-started solve to be kept is redone cold when its stage residual exceeds this
/// fraction of max|p_k| (converged solves measured at 1e-16 relative on Kepler, 1e-14 on
/// the outer solar system).
const WARM_RESIDUAL: f64 = 1e-8;
/// [`ErrorControl::Embedded`]: a climb whose estimate is not below this fraction of the
/// smallest estimate of the step so far stops there, when that smallest estimate is at the
/// round-off level [`STALL_FLOOR`]·ε·max|q| (measured: outer solar system at tol = 1e-10,
/// the per-step budget 5e-13 AU is below what any pair resolves, and climbing to n = 64 left
/// an error of 5.6e-9 where n = 16 alone reaches 6.5e-11).
const STALL: f64 = 0.5;
/// See [`STALL`].
const STALL_FLOOR: f64 = 1e4;
/// After a stall (see [`STALL`]) the per-step budget is raised to this multiple of the
/// stalled estimate (the measured floor of the embedded estimates), and a check whose
/// estimate lies at that floor lets the next check probe one rung lower (measured: outer
/// solar system, h = 1825 days, one-step differences between solves at n ≥ 14 are
/// 3e-13…1e-12 AU whatever n, so without the probe a run that climbed to n = 24 stayed
/// there).
const NOISE_MARGIN: f64 = 2.0;
/// Weight of the latest run of steps at one rung in [`Ladder::streak_ema`].
const STREAK_EMA: f64 = 0.25;
/// Weight of the latest first solve in the moving averages of [`Ladder::first_start`].
const START_EMA: f64 = 0.25;
/// [`Ladder::first_start`] tries the start not chosen at least every this many steps; the
/// spacing doubles (up to [`START_RETRY_MAX`]) each time the retried start loses again.
const START_RETRY: usize = 8;
/// See [`START_RETRY`].
const START_RETRY_MAX: usize = 64;
/// At most this many rungs down from one step to the next.
const MAX_DOWN: usize = 5;
/// [`ErrorControl::Calibrated`]: a check is forced when the indicator grows by this factor
/// from one step to the next.
const JUMP: f64 = 10.0;
/// [`ErrorControl::Calibrated`]: the calibrated ratio of a rung is the largest of this many
/// latest ratios (error estimate / indicator) measured there.
const WINDOW: usize = 4;
/// [`ErrorControl::Calibrated`]: the ratio assumed where none has been measured (the stated
/// bound of the indicator, see the module docs).
const UNCALIBRATED_RATIO: f64 = 4.0;

struct Rung {
    gvi: GalerkinIntegrator<AnyBasis, QuadratureRule>,
    /// The same integrator with a Newton tolerance loosened to the error budget, for solves
    /// that only serve as the lower member of an embedded pair (never kept).
    loose: GalerkinIntegrator<AnyBasis, QuadratureRule>,
    /// The current step's solution came from `loose`.
    is_loose: bool,
    ws: Workspace,
    q: Vec<f64>,
    p: Vec<f64>,
    stats: StepStats,
    ind: f64,
    /// Solved for the current step: Some(true) converged, Some(false) failed.
    solved: Option<bool>,
}

struct Ladder {
    rungs: Vec<Rung>,
    evaluations: usize,
    last_failure: Option<StepFailure>,
    d: usize,
    /// Warm-start the solves (see [`Start`]); off: every solve chooses its own guess.
    warm: bool,
    /// Solve the lower member of an embedded pair with the loose Newton tolerance (only when
    /// the upper one is kept: [`ErrorControl::Embedded`] with local extrapolation).
    loose_ok: bool,
    /// The measured floor of the embedded estimates (0: no stall seen), and the last climb
    /// (rung it started from, step) of the embedded control.
    noise: f64,
    climbed_from: Option<(usize, usize)>,
    /// The last step down whose first estimate missed the budget: (rung, step).
    failed: Option<(usize, usize)>,
    /// The lower rung of the last embedded step.
    last_lo: Option<usize>,
    /// Steps in a row at the current lower rung, and their moving average over past runs
    /// of steps (how long a rung stays right: the amortisation horizon of a step down).
    streak: usize,
    streak_ema: f64,
    /// The last rung accepted within the budget (checked or predicted), and the step.
    passed: Option<(usize, usize)>,
    /// Memory of [`Ladder::failed`], steps ([`AdaptiveOptions::check_every`]).
    horizon: usize,
    transfers: Transfers,
    /// The last accepted step's curve (coefficients of rung `prev_rung`).
    prev: Vec<f64>,
    prev_rung: Option<usize>,
    /// Force evaluations and quadrature nodes of the solves so far, by start: first solves of
    /// a step (continued or cold) and refitted ones.
    first_cost: (usize, usize),
    refit_cost: (usize, usize),
    /// Recent force evaluations per quadrature node of first solves started cold and
    /// continued (exponential moving averages; NaN: not measured yet), and the steps since
    /// the start not chosen was last tried.
    start_cost: [f64; 2],
    since_other: usize,
    /// Current spacing of the retries, and the start being retried (measured by the next
    /// solve to round-off that used it).
    retry_every: usize,
    retrying: Option<Start>,
    /// Warm-start coefficients being assembled (max n × D), Chebyshev coefficients of the
    /// last accepted curve (max n × D) and scratch for fitting (2 max n).
    buf: Vec<f64>,
    cheb: Vec<f64>,
    fit_scratch: Vec<f64>,
}

/// Where a solve's Newton iteration starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Start {
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
struct Transfers {
    rungs: usize,
    refit: Vec<Option<Vec<f64>>>,
    cheb: Vec<Option<Vec<f64>>>,
}

impl Transfers {
    fn new(rungs: usize) -> Self {
        Transfers {
            rungs,
            refit: vec![None; rungs * rungs],
            cheb: vec![None; rungs * rungs],
        }
    }

    fn refit(&mut self, rungs: &[Rung], from: usize, to: usize) -> &[f64] {
        self.refit[from * self.rungs + to].get_or_insert_with(|| {
            let (src, dst) = (&rungs[from].gvi, &rungs[to].gvi);
            let nf = src.n();
            let fit = &dst.tables().fit;
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

    fn cheb(&mut self, rungs: &[Rung], from: usize, to: usize) -> &[f64] {
        self.cheb[from * self.rungs + to].get_or_insert_with(|| {
            let nf = rungs[from].gvi.n();
            let nodes = rungs[to].gvi.tables().fit.nodes();
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
    fn warm_start(&mut self, i: usize, start: Start) -> bool {
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
                let src = self.rungs[j].ws.coefficients();
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
                let c = &self.rungs[j].gvi.tables().chebyshev;
                let a = &mut self.cheb[..nf * d];
                for (jj, row) in c.chunks_exact(nf).enumerate() {
                    for r in 0..d {
                        a[jj * d + r] = row
                            .iter()
                            .zip(self.prev.chunks_exact(d))
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
                self.rungs[i].gvi.tables().fit.values_to_coefficients_with(
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
    fn solve<L: Lagrangian>(
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
        let mut result = gvi.step(lag, &mut r.ws, q, p, &mut r.q, &mut r.p);
        if warmed && !loose {
            // Guard: a warm start must not yield a kept step that is not solved to round-off
            // (Newton's increment test is relative to the size of the iterate, which a poor
            // start can inflate). Redo it from the integrator's own guesses.
            let pscale = p
                .iter()
                .fold(0.0f64, |m, x| m.max(x.abs()))
                .max(f64::MIN_POSITIVE);
            if let Ok(stats) = &result {
                if stats.residual.is_nan() || stats.residual > WARM_RESIDUAL * pscale {
                    self.evaluations += stats.gradient_evaluations;
                    r.ws.reset();
                    result = gvi.step(lag, &mut r.ws, q, p, &mut r.q, &mut r.p);
                }
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
    fn estimate<L: Lagrangian>(
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
    fn first_start(&mut self) -> Start {
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
    fn next_rung(&self, lo: usize, e: f64, budget: f64, k: usize) -> usize {
        let mut j = lo.saturating_sub(rungs_down(e, budget));
        // Not below the middle between a rung that missed the budget within the last
        // `horizon` steps and lo: bisection where the decay model cannot tell (measured: the
        // oscillator at h = 20 stepped from n = 28 down to 14 where 24 was needed).
        if let Some((f, s)) = self.failed {
            if f < lo && k < s + self.horizon {
                j = j.max((f + 1 + lo).div_ceil(2));
            }
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

    /// Re-solve rung i to round-off if its solution of this step came from the loose solver
    /// (before it is kept), starting from that solution; whether it converged.
    fn tighten<L: Lagrangian>(&mut self, lag: &L, i: usize, q: &[f64], p: &[f64]) -> bool {
        if !(self.ok(i) && self.rungs[i].is_loose) {
            return self.ok(i);
        }
        self.warm_start(i, Start::Refit(i));
        self.rungs[i].solved = None;
        self.solve(lag, i, Start::Refit(i), false, q, p)
    }

    /// Record that a step of the embedded control had lower rung `lo` (for the streaks).
    fn note_rung(&mut self, lo: usize) {
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

    fn ok(&self, i: usize) -> bool {
        self.rungs[i].solved == Some(true)
    }
}

/// What one step accepted.
struct Accepted {
    /// The rung whose solution is kept.
    keep: usize,
    /// The rung to start the next step from.
    next: usize,
    estimate: Option<f64>,
    /// The estimate (or scaled indicator) exceeded the budget at the top rung.
    missed: Option<f64>,
}

/// Integrate `steps` steps choosing n per step from the ladder (see the module docs).
pub fn integrate_adaptive<L: Lagrangian>(
    lag: &L,
    opts: &AdaptiveOptions,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
) -> std::result::Result<AdaptiveRun, IntegrationFailure> {
    opts.validate()?;
    if steps == 0 || steps > crate::integrator::MAX_STEPS {
        return Err(GviError::InvalidStepCount {
            steps,
            reason: format!("need 1 ≤ steps ≤ {}", crate::integrator::MAX_STEPS),
        }
        .into());
    }
    let d = lag.dim();
    crate::error::ensure_len("initial position q0", d, q0.len())?;
    crate::error::ensure_len("initial momentum p0", d, p0.len())?;
    crate::error::ensure_finite("initial position q0", q0)?;
    crate::error::ensure_finite("initial momentum p0", p0)?;
    let mut ladder = Ladder {
        rungs: Vec::with_capacity(opts.ladder.len()),
        evaluations: 0,
        last_failure: None,
        d,
        warm: opts.warm_start,
        loose_ok: opts.extrapolate && opts.control == ErrorControl::Embedded,
        noise: 0.0,
        climbed_from: None,
        failed: None,
        last_lo: None,
        streak: 0,
        streak_ema: 1.0,
        passed: None,
        horizon: opts.check_every,
        transfers: Transfers::new(opts.ladder.len()),
        prev: vec![0.0; opts.ladder.last().copied().unwrap_or(0) * d],
        prev_rung: None,
        first_cost: (0, 0),
        refit_cost: (0, 0),
        start_cost: [f64::NAN; 2],
        since_other: 0,
        retry_every: START_RETRY,
        retrying: None,
        buf: vec![0.0; opts.ladder.last().copied().unwrap_or(0) * d],
        cheb: vec![0.0; opts.ladder.last().copied().unwrap_or(0) * d],
        fit_scratch: vec![0.0; 2 * opts.ladder.last().copied().unwrap_or(0)],
    };
    for &n in &opts.ladder {
        let gvi = GalerkinIntegrator::from_kinds(opts.basis, n, opts.quadrature, None, opts.h)?;
        let ws = gvi.workspace(lag)?;
        let mut o = *gvi.options();
        let scale = q0
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(f64::MIN_POSITIVE);
        o.tolerance = (LOOSE_NEWTON * opts.step_budget(steps) / scale).clamp(o.tolerance, 1e-6);
        let loose = gvi.clone().with_options(o);
        ladder.rungs.push(Rung {
            gvi,
            loose,
            is_loose: false,
            ws,
            q: vec![0.0; d],
            p: vec![0.0; d],
            stats: StepStats::default(),
            ind: f64::NAN,
            solved: None,
        });
    }
    let budget = opts.step_budget(steps);
    // One rung only: nothing to compare with, the indicator control is the only option.
    let control = if ladder.rungs.len() < 2 {
        ErrorControl::Indicator
    } else {
        opts.control
    };
    let local_tol = match control {
        ErrorControl::Indicator => budget.powf(1.0 / INDICATOR_EXPONENT),
        _ => budget,
    };
    let mut traj = Trajectory::new(
        opts.basis,
        opts.ladder[0],
        opts.quadrature,
        opts.quadrature.default_points(opts.ladder[0]),
        opts.h,
        t0,
        d,
        steps,
    );
    traj.push_state(q0, p0);
    let mut run = AdaptiveRun {
        trajectory: Trajectory::new(opts.basis, 0, opts.quadrature, 0, opts.h, t0, d, 0),
        indicators: Vec::with_capacity(steps),
        estimates: Vec::with_capacity(steps),
        control,
        checks: 0,
        local_tol,
        rejected: 0,
        gradient_evaluations: 0,
        warnings: Vec::new(),
    };
    // Round-off floor of the accumulated step-end positions: the per-step estimates cannot
    // see it (measured: outer solar system, h = 1825 days, no n reaches below 2.3e-10 AU,
    // while the estimates met a 1e-10 budget: a silent 49× miss without this warning).
    let scale = q0.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let floor = FLOOR_FACTOR * f64::EPSILON * scale * steps as f64;
    if opts.tol < floor {
        run.warnings.push(format!(
            "tol = {:e} is below {FLOOR_FACTOR}·ε·max|q0|·steps = {floor:.1e}: round-off in the \
             step-end positions may keep the achieved error above tol",
            opts.tol
        ));
    }
    let (mut q, mut p) = (q0.to_vec(), p0.to_vec());
    let mut idx = 0usize;
    let mut ctl = Calibration::new(ladder.rungs.len());
    let mut last_check = None;
    for k in 0..steps {
        let t = t0 + k as f64 * opts.h;
        for r in ladder.rungs.iter_mut() {
            r.solved = None;
        }
        let acc = match control {
            ErrorControl::Indicator => indicator_step(&mut ladder, lag, idx, &q, &p, local_tol),
            ErrorControl::Embedded => embedded_step(
                &mut ladder,
                &mut last_check,
                lag,
                idx,
                k,
                &q,
                &p,
                budget,
                opts,
            ),
            ErrorControl::Calibrated => {
                calibrated_step(&mut ladder, &mut ctl, lag, idx, k, &q, &p, budget, opts)
            }
        };
        let Some(acc) = acc else {
            let f = ladder.last_failure.take().unwrap_or(StepFailure {
                residual: f64::NAN,
                iterations: 0,
                reason: "no rung converged".into(),
            });
            run.gradient_evaluations = ladder.evaluations;
            run.trajectory = traj;
            return Err(IntegrationFailure {
                error: GviError::NewtonFailure {
                    step: k,
                    t,
                    residual: f.residual,
                    iterations: f.iterations,
                    reason: f.reason,
                },
                partial: Some(Box::new(run.trajectory)),
            });
        };
        if acc.estimate.is_some() {
            run.checks += 1;
        }
        let solved_above = ladder
            .rungs
            .iter()
            .skip(acc.keep.min(idx) + 1)
            .filter(|r| r.solved.is_some())
            .count();
        run.rejected += solved_above.saturating_sub(usize::from(acc.estimate.is_some()));
        if let Some(e) = acc.missed {
            run.warnings.push(format!(
                "step {k} (t = {t}): error estimate {e:.2e} exceeds the per-step budget \
                 {local_tol:.2e} even at the largest n = {}; kept as best effort",
                opts.ladder[acc.keep]
            ));
        }
        let r = &ladder.rungs[acc.keep];
        traj.push_step_with_n(
            opts.ladder[acc.keep],
            r.ws.coefficients(),
            &r.q,
            &r.p,
            r.stats,
        );
        run.indicators.push(r.ind);
        run.estimates.push(acc.estimate);
        q.copy_from_slice(&r.q);
        p.copy_from_slice(&r.p);
        let c = r.ws.coefficients();
        ladder.prev[..c.len()].copy_from_slice(c);
        ladder.prev_rung = Some(acc.keep);
        // Rungs not solved at this step remember a stale curve.
        for r in ladder.rungs.iter_mut() {
            if r.solved != Some(true) {
                r.ws.reset();
            }
        }
        idx = acc.next;
    }
    if NOISE_MARGIN * ladder.noise > budget {
        run.warnings.insert(
            0,
            format!(
                "the per-step budget {budget:.2e} lies below the round-off floor of the \
                 embedded estimates ({:.2e}, where a higher n no longer lowers them): later \
                 steps used {:.2e} instead (best effort)",
                ladder.noise,
                NOISE_MARGIN * ladder.noise
            ),
        );
    }
    if run.warnings.len() > 10 {
        let extra = run.warnings.len() - 10;
        run.warnings.truncate(10);
        run.warnings
            .push(format!("… and {extra} more steps above the tolerance"));
    }
    run.gradient_evaluations = ladder.evaluations;
    run.trajectory = traj;
    Ok(run)
}

/// The indicator control: the smallest rung from `idx` up whose indicator meets `ind_tol`.
fn indicator_step<L: Lagrangian>(
    ladder: &mut Ladder,
    lag: &L,
    mut idx: usize,
    q: &[f64],
    p: &[f64],
    ind_tol: f64,
) -> Option<Accepted> {
    let top = ladder.rungs.len() - 1;
    let mut start = ladder.first_start();
    loop {
        if ladder.solve(lag, idx, start, false, q, p) {
            let ind = ladder.rungs[idx].ind;
            if ind <= ind_tol || idx == top {
                let next = if idx > 0 && ind < 1e-2 * ind_tol {
                    idx - 1
                } else {
                    idx
                };
                return Some(Accepted {
                    keep: idx,
                    next,
                    estimate: None,
                    missed: (ind > ind_tol).then_some(ind),
                });
            }
        } else if idx == top {
            return None;
        }
        start = Start::Refit(idx);
        idx += 1;
    }
}

/// The last embedded check of [`ErrorControl::Embedded`]: at step `step`, rung `rung` had
/// the estimate `est` and the indicator `ind`.
#[derive(Debug, Clone, Copy)]
struct LastCheck {
    rung: usize,
    est: f64,
    ind: f64,
    step: usize,
}

/// The embedded control from rung `lo`: climb until |q_lo − q_{lo+1}| meets the budget.
/// Within [`AdaptiveOptions::check_every`] steps of a check at the same rung, a step whose
/// indicator has not grown since that check is solved at that rung alone, its error predicted
/// as est · ind / ind_check (see the module docs).
#[allow(clippy::too_many_arguments)]
fn embedded_step<L: Lagrangian>(
    ladder: &mut Ladder,
    last: &mut Option<LastCheck>,
    lag: &L,
    lo: usize,
    k: usize,
    q: &[f64],
    p: &[f64],
    budget: f64,
    opts: &AdaptiveOptions,
) -> Option<Accepted> {
    let top = ladder.rungs.len() - 1;
    let mut lo = lo.min(top - 1);
    let first = lo;
    let budget = budget.max(NOISE_MARGIN * ladder.noise);
    let mut start = ladder.first_start();
    if let Some(c) = last.filter(|c| c.rung == lo && k < c.step + opts.check_every) {
        if ladder.solve(lag, lo, start, false, q, p) {
            let ind = ladder.rungs[lo].ind;
            let predicted = c.est * ind / c.ind;
            if ind <= GROWTH * c.ind && predicted <= budget {
                ladder.passed = Some((lo, k));
                ladder.note_rung(lo);
                let next = ladder.next_rung(lo, predicted, budget, k);
                return Some(Accepted {
                    keep: lo,
                    next,
                    estimate: None,
                    missed: None,
                });
            }
        }
    }
    // Round-off level of an estimate at this state: a climb that no longer lowers an
    // estimate this small has reached the floor of the solves (see [`STALL`]).
    let floor = STALL_FLOOR * f64::EPSILON * q.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut best: Option<(usize, f64)> = None;
    let (est, crit) = loop {
        let est = ladder.estimate(lag, lo, start, q, p);
        // The criterion is the measured difference itself. Measured and rejected: scaling it
        // by ind_{lo+1}/ind_lo to predict the kept rung's error saved 10–15 % but missed
        // tol by up to 18× on Kepler e = 0.9.
        let crit = est;
        if crit <= budget {
            break (est, crit);
        }
        if lo + 1 == top {
            // The largest pair misses a budget at the round-off level: nothing resolves
            // more, so its estimate is the floor for later steps (measured: the oscillator
            // at h = 20, tol = 1e-12, stayed at n = 48–64 with a 5e-15 budget where the
            // pairs from n = 24 up differ by 1e-15…9e-14).
            if est <= floor {
                ladder.noise = ladder.noise.max(est);
            }
            break (est, crit);
        }
        if lo == first && ladder.last_lo.is_some_and(|l| first < l) {
            // A step down that failed.
            ladder.failed = Some((lo, k));
        }
        if let Some((b, best_est)) = best {
            if est >= STALL * best_est && best_est <= floor {
                // Best effort at the round-off floor: keep the pair with the smallest
                // estimate instead of climbing to rungs whose own round-off is larger, and
                // take that estimate as the floor of later steps' budgets.
                ladder.noise = ladder.noise.max(best_est);
                lo = b;
                break (best_est, best_est);
            }
        }
        if best.is_none_or(|(_, b)| est < b) {
            best = Some((lo, est));
        }
        start = Start::Refit(lo + 1);
        let from = lo;
        lo = jump(ladder, lo, est, budget);
        // Not past a rung that met the budget within the last `horizon` steps (measured:
        // the decay model fitted on an unresolved curve overshoots, e.g. the oscillator at
        // h = 20 jumped from n = 20 to 32 where 24 had just passed).
        if let Some((r, s)) = ladder.passed {
            if r > from && r < lo && k < s + ladder.horizon {
                lo = r;
            }
        }
    };
    let keep = match (opts.extrapolate, ladder.ok(lo), ladder.ok(lo + 1)) {
        (_, _, false) if ladder.tighten(lag, lo, q, p) => lo,
        (_, _, false) => return None,
        (true, _, true) | (false, false, true) => lo + 1,
        (false, true, true) => lo,
    };
    if lo > first {
        ladder.climbed_from = Some((first, k));
    }
    if crit <= budget {
        ladder.passed = Some((lo, k));
    }
    ladder.note_rung(lo);
    let mut next = ladder.next_rung(lo, crit, budget, k);
    // At the floor the estimate says nothing about lower rungs: probe one rung down, unless
    // a climb from there happened within the last check_every steps.
    let at_floor = ladder.noise > 0.0 && crit <= NOISE_MARGIN * ladder.noise;
    let failed_recently = ladder
        .climbed_from
        .is_some_and(|(r, s)| r + 1 == lo && k < s + opts.check_every);
    if at_floor && next == lo && lo > 0 && !failed_recently {
        next = lo - 1;
    }
    let ind = ladder.rungs[lo].ind;
    *last = (est.is_finite() && est <= budget && ind > 0.0).then_some(LastCheck {
        rung: lo,
        est,
        ind,
        step: k,
    });
    Some(Accepted {
        keep,
        next,
        estimate: est.is_finite().then_some(est),
        missed: (crit > budget).then_some(crit),
    })
}

/// The next rung to try after rung `lo` missed the budget with the estimate `est`: the
/// smallest rung j > lo, below the top, with est · exp(−κσ (n_j − n_lo)) ≤ budget, where σ
/// is the geometric decay rate of the Chebyshev coefficients of rung lo + 1's curve and κ =
/// [`DECAY_RATIO`] the measured ratio of the estimate's decay rate to σ.
fn jump(ladder: &Ladder, lo: usize, est: f64, budget: f64) -> usize {
    let top = ladder.rungs.len() - 1;
    let sigma = DECAY_RATIO * decay_rate(&ladder.rungs[lo + 1], ladder.d);
    let n0 = ladder.rungs[lo].gvi.n() as f64;
    (lo + 1..top)
        .find(|&j| est * (-sigma * (ladder.rungs[j].gvi.n() as f64 - n0)).exp() <= budget)
        .unwrap_or(top - 1)
}

/// How many rungs to step down after an estimate `e`: one per factor [`DOWN`] below the
/// budget, at most [`MAX_DOWN`].
fn rungs_down(e: f64, budget: f64) -> usize {
    let mut k = 0;
    let mut level = DOWN * budget;
    while e < level && k < MAX_DOWN {
        k += 1;
        level *= DOWN;
    }
    k
}

/// State of the online calibration: per rung, the latest measured ratios
/// (embedded estimate / indicator) and the step of the last measurement.
struct Calibration {
    ratios: Vec<Vec<f64>>,
    measured_at: Vec<Option<usize>>,
    last_ind: f64,
}

impl Calibration {
    fn new(rungs: usize) -> Self {
        Calibration {
            ratios: vec![Vec::new(); rungs],
            measured_at: vec![None; rungs],
            last_ind: f64::INFINITY,
        }
    }

    /// The calibrated ratio of rung i: the largest recent one measured there; for a rung not
    /// measured yet, that of the nearest measured rung below (the ratio falls with n) but at
    /// most [`UNCALIBRATED_RATIO`].
    fn ratio(&self, i: usize) -> Option<f64> {
        let max = |v: &Vec<f64>| v.iter().copied().reduce(f64::max);
        max(&self.ratios[i]).or_else(|| {
            (0..i)
                .rev()
                .find_map(|j| max(&self.ratios[j]))
                .map(|r| r.min(UNCALIBRATED_RATIO))
        })
    }

    fn measured(&self, i: usize) -> bool {
        !self.ratios[i].is_empty()
    }

    fn record(&mut self, i: usize, est: f64, ind: f64, k: usize) {
        if est.is_finite() && ind > 0.0 {
            let r = &mut self.ratios[i];
            if r.len() == WINDOW {
                r.remove(0);
            }
            r.push(est / ind);
            self.measured_at[i] = Some(k);
        }
    }

    fn stale(&self, i: usize, k: usize, every: usize) -> bool {
        self.measured_at[i].is_none_or(|m| k >= m + every)
    }
}

/// Geometric decay rate σ per mode of the step's Chebyshev coefficients, from the envelope at
/// n/2 and at the last pair: the indicator at n' is predicted as ind · exp(−σ (n' − n)).
fn decay_rate(r: &Rung, d: usize) -> f64 {
    let n = r.gvi.n();
    if n < 6 {
        return 0.3;
    }
    let a = r.gvi.chebyshev_coefficients(r.ws.coefficients(), d);
    let env = |j: usize| {
        a[j * d..(j + 2).min(n) * d]
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()))
    };
    let (j1, j2) = (n / 2, n - 2);
    let (e1, e2) = (env(j1), env(j2).max(1e-300));
    ((e1 / e2).ln() / (j2 - j1) as f64).clamp(0.05, 5.0)
}

/// The smallest rung at or above `from` whose predicted scaled indicator, extrapolated from
/// rung `base` (solved), meets `target`.
fn predict(ladder: &Ladder, ctl: &Calibration, base: usize, from: usize, target: f64) -> usize {
    let r = &ladder.rungs[base];
    let sigma = decay_rate(r, ladder.d);
    let n0 = r.gvi.n() as f64;
    let top = ladder.rungs.len() - 1;
    (from..=top)
        .find(|&j| {
            let n = ladder.rungs[j].gvi.n() as f64;
            let ratio = ctl.ratio(j).unwrap_or(UNCALIBRATED_RATIO);
            ratio * r.ind * (-sigma * (n - n0)).exp() <= target
        })
        .unwrap_or(top)
}

/// The calibrated control (see [`ErrorControl::Calibrated`]).
#[allow(clippy::too_many_arguments)]
fn calibrated_step<L: Lagrangian>(
    ladder: &mut Ladder,
    ctl: &mut Calibration,
    lag: &L,
    idx: usize,
    k: usize,
    q: &[f64],
    p: &[f64],
    budget: f64,
    opts: &AdaptiveOptions,
) -> Option<Accepted> {
    let top = ladder.rungs.len() - 1;
    let mut i = idx;
    let mut estimate = None;
    let mut start = ladder.first_start();
    let keep = loop {
        let ok = ladder.solve(lag, i, start, false, q, p);
        if !ok {
            if i == top {
                return None;
            }
            i += 1;
            continue;
        }
        let ind = ladder.rungs[i].ind;
        let check = i < top
            && (!ctl.measured(i) || ctl.stale(i, k, opts.check_every) || ind > JUMP * ctl.last_ind);
        if check {
            let est = ladder.estimate(lag, i, Start::Continue, q, p);
            ctl.record(i, est, ind, k);
            if est <= budget {
                estimate = Some(est);
                break if opts.extrapolate && ladder.ok(i + 1) {
                    i + 1
                } else {
                    i
                };
            }
        } else {
            let scaled = ctl.ratio(i).unwrap_or(UNCALIBRATED_RATIO) * ind;
            if scaled <= budget || i == top {
                break i;
            }
        }
        if i == top || (check && i + 1 == top) {
            estimate = None;
            break top;
        }
        start = Start::Refit(i);
        i = predict(ladder, ctl, i, i + 1, budget);
    };
    // Calibrate on every other pair of neighbouring rungs solved at this step.
    for j in 0..top {
        if ladder.ok(j) && ladder.ok(j + 1) && ctl.measured_at[j] != Some(k) {
            let est = ladder.estimate(lag, j, Start::Continue, q, p);
            ctl.record(j, est, ladder.rungs[j].ind, k);
        }
    }
    let lo = if estimate.is_some() && keep > i {
        i
    } else {
        keep
    };
    let r = ctl.ratio(lo).unwrap_or(UNCALIBRATED_RATIO);
    let scaled = estimate.unwrap_or(r * ladder.rungs[keep].ind);
    let missed = (scaled > budget && keep == top).then_some(scaled);
    // Next step: the smallest rung predicted to meet half the budget (at most two rungs down).
    let next = predict(ladder, ctl, keep, 0, 0.5 * budget).min(lo);
    ctl.last_ind = ladder.rungs[lo].ind.max(f64::MIN_POSITIVE);
    Some(Accepted {
        keep,
        next,
        estimate,
        missed,
    })
}
