//! The indicator-based error controls: [`ErrorControl::Indicator`](super::ErrorControl::Indicator)
//! (the modal indicator alone) and [`ErrorControl::Calibrated`](super::ErrorControl::Calibrated)
//! (the indicator scaled by ratios measured online by embedded checks).

use super::AdaptiveOptions;
use super::ladder::{Accepted, Ladder, Start, decay_rate};
use crate::lagrangian::Lagrangian;

/// [`ErrorControl::Calibrated`](super::ErrorControl::Calibrated): a check is forced when the indicator grows by this factor
/// from one step to the next.
const JUMP: f64 = 10.0;
/// [`ErrorControl::Calibrated`](super::ErrorControl::Calibrated): the calibrated ratio of a rung is the largest of this many
/// latest ratios (error estimate / indicator) measured there.
const WINDOW: usize = 4;
/// [`ErrorControl::Calibrated`](super::ErrorControl::Calibrated): the ratio assumed where none has been measured (the stated
/// bound of the indicator, see the module docs).
const UNCALIBRATED_RATIO: f64 = 4.0;

/// The indicator control: the smallest rung from `idx` up whose indicator meets `ind_tol`.
pub(super) fn indicator_step<L: Lagrangian>(
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

/// State of the online calibration: per rung, the latest measured ratios
/// (embedded estimate / indicator) and the step of the last measurement.
pub(super) struct Calibration {
    pub(super) ratios: Vec<Vec<f64>>,
    pub(super) measured_at: Vec<Option<usize>>,
    pub(super) last_ind: f64,
}

impl Calibration {
    pub(super) fn new(rungs: usize) -> Self {
        Calibration {
            ratios: vec![Vec::new(); rungs],
            measured_at: vec![None; rungs],
            last_ind: f64::INFINITY,
        }
    }

    /// The calibrated ratio of rung i: the largest recent one measured there; for a rung not
    /// measured yet, that of the nearest measured rung below (the ratio falls with n) but at
    /// most [`UNCALIBRATED_RATIO`].
    pub(super) fn ratio(&self, i: usize) -> Option<f64> {
        let max = |v: &Vec<f64>| v.iter().copied().reduce(f64::max);
        max(&self.ratios[i]).or_else(|| {
            (0..i)
                .rev()
                .find_map(|j| max(&self.ratios[j]))
                .map(|r| r.min(UNCALIBRATED_RATIO))
        })
    }

    pub(super) fn measured(&self, i: usize) -> bool {
        !self.ratios[i].is_empty()
    }

    pub(super) fn record(&mut self, i: usize, est: f64, ind: f64, k: usize) {
        if est.is_finite() && ind > 0.0 {
            let r = &mut self.ratios[i];
            if r.len() == WINDOW {
                r.remove(0);
            }
            r.push(est / ind);
            self.measured_at[i] = Some(k);
        }
    }

    pub(super) fn stale(&self, i: usize, k: usize, every: usize) -> bool {
        self.measured_at[i].is_none_or(|m| k >= m + every)
    }
}

/// The smallest rung at or above `from` whose predicted scaled indicator, extrapolated from
/// rung `base` (solved), meets `target`.
pub(super) fn predict(
    ladder: &Ladder,
    ctl: &Calibration,
    base: usize,
    from: usize,
    target: f64,
) -> usize {
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

/// The calibrated control (see [`ErrorControl::Calibrated`](super::ErrorControl::Calibrated)).
#[allow(clippy::too_many_arguments)]
pub(super) fn calibrated_step<L: Lagrangian>(
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
