//! The state of one step's solve: the Newton iterate in increments ΔQ_i = Q_i − u_i q_k, the
//! compensated parts of the state (q_k, p_k) and of the result, the step's total impulse, and
//! the stage residual already evaluated at the iterate.
//!
//! The iterate lives in increments from q_k so that q_{k+1} = q_k + ΔQ_{n−1} is known to full
//! relative accuracy (docs/DESIGN.md §4): the low part of ΔQ_{n−1} accumulated by the Newton
//! corrections is carried beside it, and so are the low parts of q_k and p_k when the step is
//! taken by `step_compensated`. Fields are private: the solvers read the iterate and apply
//! corrections through the methods below, which keep the hi + lo pairs together.

use super::dd::{dd_add, max_abs, two_sum};

/// The Newton iterate of one step, its compensation terms and its impulse.
#[derive(Debug, Clone)]
pub(crate) struct Iterate {
    /// The Newton unknowns: increments ΔQ_i = Q_i − u_i q_k, row i (n×D; ΔQ_0 = 0).
    increments: Vec<f64>,
    /// q_k, the start of the current step's curve (D).
    origin: Vec<f64>,
    /// Low-order part of the compensated q_k (zero unless the step is compensated).
    origin_lo: Vec<f64>,
    /// Low-order part of the compensated p_k (likewise).
    momentum_lo: Vec<f64>,
    /// Low-order part of ΔQ_{n−1} accumulated by the Newton corrections (D).
    last_lo: Vec<f64>,
    /// Total impulse h Σ_j b_j L_q(c_j) of the last evaluated residual (D) …
    impulse: Vec<f64>,
    /// … and its low-order part (the impulse is hi + lo to about twice the working precision).
    impulse_lo: Vec<f64>,
    /// The step's initial guess (n×D), kept for a retry with exact Newton when a structured
    /// solver fails from it.
    start: Vec<f64>,
    /// The stage residual of the iterate is already evaluated (its max-norm).
    ready_residual: Option<f64>,
}

impl Iterate {
    /// An iterate for n basis functions and D coordinates, all zero.
    pub(crate) fn new(n: usize, d: usize) -> Self {
        Iterate {
            increments: vec![0.0; n * d],
            origin: vec![0.0; d],
            origin_lo: vec![0.0; d],
            momentum_lo: vec![0.0; d],
            last_lo: vec![0.0; d],
            impulse: vec![0.0; d],
            impulse_lo: vec![0.0; d],
            start: vec![0.0; n * d],
            ready_residual: None,
        }
    }

    /// The increments ΔQ (n×D, row i = ΔQ_i).
    pub(crate) fn increments(&self) -> &[f64] {
        &self.increments
    }

    /// The increments, to be written (a guess, a solver's own iterate).
    pub(crate) fn increments_mut(&mut self) -> &mut [f64] {
        &mut self.increments
    }

    /// The increments and the low part of ΔQ_{n−1}, both to be written (the velocity form
    /// sets them together from its modes).
    pub(crate) fn increments_and_last_lo_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        (&mut self.increments, &mut self.last_lo)
    }

    /// q_k, the start of the step's curve.
    pub(crate) fn origin(&self) -> &[f64] {
        &self.origin
    }

    /// Start the step at q_k.
    pub(crate) fn set_origin(&mut self, q: &[f64]) {
        self.origin.copy_from_slice(q);
    }

    /// Low part of the compensated q_k (zero for an uncompensated step).
    pub(crate) fn origin_lo(&self) -> &[f64] {
        &self.origin_lo
    }

    /// Low part of the compensated p_k (zero for an uncompensated step).
    pub(crate) fn momentum_lo(&self) -> &[f64] {
        &self.momentum_lo
    }

    /// The low parts of a compensated state (q_k, p_k) for the next solve.
    pub(crate) fn set_compensation(&mut self, q_lo: &[f64], p_lo: &[f64]) {
        self.origin_lo.copy_from_slice(q_lo);
        self.momentum_lo.copy_from_slice(p_lo);
    }

    /// Back to an uncompensated state (after a compensated step).
    pub(crate) fn clear_compensation(&mut self) {
        self.origin_lo.iter_mut().for_each(|x| *x = 0.0);
        self.momentum_lo.iter_mut().for_each(|x| *x = 0.0);
    }

    /// Low part of ΔQ_{n−1}.
    pub(crate) fn last_lo(&self) -> &[f64] {
        &self.last_lo
    }

    /// A new solve: ΔQ_{n−1} has no low part yet.
    pub(crate) fn clear_last_lo(&mut self) {
        self.last_lo.iter_mut().for_each(|x| *x = 0.0);
    }

    /// The total impulse h Σ_j b_j L_q(c_j) of the last residual, hi and lo.
    pub(crate) fn impulse(&self) -> (&[f64], &[f64]) {
        (&self.impulse, &self.impulse_lo)
    }

    /// The impulse's hi and lo parts, to be written by a residual evaluation.
    pub(crate) fn impulse_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        (&mut self.impulse, &mut self.impulse_lo)
    }

    /// The step's end increments of coordinate r: ΔQ_{n−1} and the impulse, each as hi + lo.
    pub(crate) fn end_increments(&self, r: usize) -> [(f64, f64); 2] {
        let last = self.increments.len() - self.last_lo.len();
        [
            (self.increments[last + r], self.last_lo[r]),
            (self.impulse[r], self.impulse_lo[r]),
        ]
    }

    /// (q_{k+1}, p_{k+1}) of coordinate r, correctly rounded from (q_k, p_k) and the end
    /// increments (double-double sums; the low parts of q_k and p_k are given, zero for an
    /// uncompensated step). Returns ((q hi, q lo), (p hi, p lo)).
    pub(crate) fn advance(&self, r: usize, q: (f64, f64), p: (f64, f64)) -> [(f64, f64); 2] {
        let [dq, dp] = self.end_increments(r);
        [dd_add(q.0, q.1, dq.0, dq.1), dd_add(p.0, p.1, dp.0, dp.1)]
    }

    /// Keep the current iterate as the step's start (for a retry).
    pub(crate) fn save_start(&mut self) {
        self.start.copy_from_slice(&self.increments);
    }

    /// Back to the step's start; the residual there is not in the workspace.
    pub(crate) fn restore_start(&mut self) {
        self.increments.copy_from_slice(&self.start);
        self.ready_residual = None;
    }

    /// The residual norm already evaluated at this iterate, taken (it is used once).
    pub(crate) fn take_ready_residual(&mut self) -> Option<f64> {
        self.ready_residual.take()
    }

    /// The residual at this iterate has just been evaluated (norm `r`), or is no longer
    /// current (`None`).
    pub(crate) fn set_ready_residual(&mut self, r: Option<f64>) {
        self.ready_residual = r;
    }

    /// ΔQ_{first + i} += δ_i for the correction δ; with `compensated`, the unknowns of
    /// ΔQ_{n−1} are updated as hi + lo (TwoSum), since the corrections of the last iterations
    /// lie below its ulp and the compensated Legendre-transform row resolves them. Returns
    /// the correction's size and the scale of the unknowns (max-norms).
    pub(crate) fn apply_correction(
        &mut self,
        correction: &[f64],
        first: usize,
        compensated: bool,
    ) -> (f64, f64) {
        let last = self.increments.len() - self.last_lo.len();
        for (i, &delta) in correction.iter().enumerate() {
            let k = first + i;
            if k >= last && compensated {
                let (s, e) = two_sum(self.increments[k], delta);
                self.increments[k] = s;
                self.last_lo[k - last] += e;
            } else {
                self.increments[k] += delta;
            }
        }
        // The scale of the unknowns, the increments ΔQ (which the stage equations determine
        // to a relative accuracy far better than ε|q_k| when h is small).
        (
            max_abs(correction),
            max_abs(&self.increments).max(f64::MIN_POSITIVE),
        )
    }
}
