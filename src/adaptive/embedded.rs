//! The embedded error control ([`ErrorControl::Embedded`](super::ErrorControl::Embedded)):
//! a step solved at two rungs, the difference of the step-end positions as the lower rung's
//! error estimate, climbs by jumps predicted from the coefficient decay, unchecked steps
//! between checks, and the round-off floor of the estimates.

use super::AdaptiveOptions;
use super::ladder::{Accepted, Ladder, Start, decay_rate};
use crate::lagrangian::Lagrangian;

/// [`ErrorControl::Embedded`](super::ErrorControl::Embedded): an unchecked step is allowed while the indicator is at most
/// this factor above that of the last check.
const GROWTH: f64 = 1.0;
/// Ratio of the decay rate (per unit n) of the embedded estimate to that of the Chebyshev
/// coefficients of the curve, measured 1.5–1.7 on Kepler e = 0.6 (h = 1, n = 4…24).
const DECAY_RATIO: f64 = 1.5;
/// [`ErrorControl::Embedded`](super::ErrorControl::Embedded): a climb whose estimate is not below this fraction of the
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
pub(super) const NOISE_MARGIN: f64 = 2.0;
/// The last embedded check of [`ErrorControl::Embedded`](super::ErrorControl::Embedded): at step `step`, rung `rung` had
/// the estimate `est` and the indicator `ind`.
#[derive(Debug, Clone, Copy)]
pub(super) struct LastCheck {
    pub(super) rung: usize,
    pub(super) est: f64,
    pub(super) ind: f64,
    pub(super) step: usize,
}

/// The embedded control from rung `lo`: climb until |q_lo − q_{lo+1}| meets the budget.
/// Within [`AdaptiveOptions::check_every`](super::AdaptiveOptions::check_every) steps of a check at the same rung, a step whose
/// indicator has not grown since that check is solved at that rung alone, its error predicted
/// as est · ind / ind_check (see the module docs).
#[allow(clippy::too_many_arguments)]
pub(super) fn embedded_step<L: Lagrangian>(
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
    if let Some(c) = last.filter(|c| c.rung == lo && k < c.step + opts.check_every)
        && ladder.solve(lag, lo, start, false, q, p)
    {
        let ind = ladder.rungs[lo].ind;
        let predicted = c.est * ind / c.ind;
        if ind <= GROWTH * c.ind && predicted <= budget {
            ladder.passed = Some((lo, k));
            ladder.note_rung(lo);
            let next = ladder.next_rung(lo, predicted, budget, k);
            let next = ladder.swing_start(lo, next);
            return Some(Accepted {
                keep: lo,
                next,
                estimate: None,
                missed: None,
            });
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
        if let Some((b, best_est)) = best
            && est >= STALL * best_est
            && best_est <= floor
        {
            // Best effort at the round-off floor: keep the pair with the smallest
            // estimate instead of climbing to rungs whose own round-off is larger, and
            // take that estimate as the floor of later steps' budgets.
            ladder.noise = ladder.noise.max(best_est);
            lo = b;
            break (best_est, best_est);
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
        if let Some((r, s)) = ladder.passed
            && r > from
            && r < lo
            && k < s + ladder.horizon
        {
            lo = r;
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
    let next = ladder.swing_start(lo, next);
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
pub(super) fn jump(ladder: &Ladder, lo: usize, est: f64, budget: f64) -> usize {
    let top = ladder.rungs.len() - 1;
    let sigma = DECAY_RATIO * decay_rate(&ladder.rungs[lo + 1], ladder.d);
    let n0 = ladder.rungs[lo].gvi.n() as f64;
    (lo + 1..top)
        .find(|&j| est * (-sigma * (ladder.rungs[j].gvi.n() as f64 - n0)).exp() <= budget)
        .unwrap_or(top - 1)
}
