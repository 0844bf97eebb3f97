//! The stepping loop of [`integrate_adaptive`]: builds the ladder ([`super::ladder`]), runs
//! one of the error controls ([`super::embedded`], [`super::indicator`]) per step, and
//! collects the trajectory, the estimates and the warnings.

use super::embedded::{NOISE_MARGIN, embedded_step};
use super::indicator::{Calibration, calibrated_step, indicator_step};
use super::ladder::{Ladder, Rung, START_RETRY, Transfers};
use super::{AdaptiveOptions, AdaptiveRun, ErrorControl, INDICATOR_EXPONENT};
use crate::curve::GalerkinCurve;
use crate::error::GviError;
use crate::integrator::{GalerkinIntegrator, IntegrationFailure, StepFailure, StepStats};
use crate::lagrangian::Lagrangian;
use crate::trajectory::Trajectory;

/// Round-off floor warning: tol below FLOOR_FACTOR · ε · max|q0| · steps.
const FLOOR_FACTOR: f64 = 1000.0;
/// Newton tolerance of the lower member of an embedded pair (never kept): this fraction of
/// the per-step budget, relative to max|q0| (but never tighter than the default).
const LOOSE_NEWTON: f64 = 0.1;

/// Integrate `steps` steps choosing n per step from the ladder (see the module docs).
pub fn integrate_adaptive<L: Lagrangian>(
    lag: &L,
    opts: &AdaptiveOptions,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
) -> std::result::Result<AdaptiveRun, IntegrationFailure> {
    integrate_adaptive_until(lag, opts, t0, q0, p0, steps, &|| false)
}

/// [`integrate_adaptive`], asking `stop` before every step whether to stop there: a `true`
/// ends the run with [`GviError::Interrupted`] and the steps before it as the partial
/// trajectory ([`crate::solve::solve_until`]).
pub(crate) fn integrate_adaptive_until<L: Lagrangian>(
    lag: &L,
    opts: &AdaptiveOptions,
    t0: f64,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
    stop: &dyn Fn() -> bool,
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
        t: t0,
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
        recent: Default::default(),
        recent_len: 0,
        follow_swings: opts.follow_swings,
        transfers: Transfers::new(opts.ladder.len()),
        prev: GalerkinCurve::with_capacity(opts.ladder.last().copied().unwrap_or(0), d, opts.h),
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
        let solver = crate::integrator::NewtonOptions {
            solver: opts.solver,
            ..*gvi.options()
        };
        let gvi = gvi.with_options(solver);
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
    let mut traj = Trajectory::of_kind(
        opts.basis,
        opts.ladder[0],
        opts.quadrature.as_str(),
        opts.quadrature.default_points(opts.ladder[0]),
        opts.h,
        t0,
        d,
        steps,
    );
    traj.push_state(q0, p0);
    let mut run = AdaptiveRun {
        trajectory: Trajectory::of_kind(
            opts.basis,
            0,
            opts.quadrature.as_str(),
            0,
            opts.h,
            t0,
            d,
            0,
        ),
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
        if stop() {
            return Err(IntegrationFailure {
                error: GviError::Interrupted { step: k, t },
                partial: Some(Box::new(traj)),
            });
        }
        for r in ladder.rungs.iter_mut() {
            r.solved = None;
        }
        // Every rung's solve of this step starts at t_k (time-dependent and forced systems).
        ladder.t = t;
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
        traj.push_step_with_n(r.ws.curve().starting_at(t), &r.q, &r.p, r.stats);
        run.indicators.push(r.ind);
        run.estimates.push(acc.estimate);
        q.copy_from_slice(&r.q);
        p.copy_from_slice(&r.p);
        ladder.prev.set(r.ws.curve().starting_at(t));
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
